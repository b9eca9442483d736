"""``bt-nav demo`` (``make demo``): the whole homework mission over real DDS in sim time, judged and drawn.

With ``--profile lab`` it is the lab's check-off instead: :mod:`bt_nav.cli.demo.lab`.

It starts the ``eval`` graph of :mod:`bt_nav.ros.bringup` — simulator (stage_4, homework LiDAR),
executive (``config/homework.yaml`` and any ``--set``) and referee; with ``--robots N`` one simulator
hosting robot1 ... robotN and per robot an executive and a referee in its namespace — as subprocesses on
this machine only, with the simulator as fast as the executives and referees keep up (``--rtf 0``).
:class:`bt_nav.run.rosmission.RosMission` starts the referees once this process's recorders see every
robot, and waits for every verdict.

It writes, under a run directory of its own (``<out>/<date>-<time>_<world>_<maneuver>_seed<seed>``, or
``<out>/<name>``; never overwritten): ``run.json`` (what ran: world, seed, robots and every parameter's
value), the referee's ``results.json`` and ``trajectory.json`` (several robots: ``results_<robot>.json``,
``trajectory_<robot>.json``), ``trajectory.png``, the tree as ``tree.dot``/``tree.svg`` (with graphviz) and
one ``<node>.log`` per process. Exit code: 0 when every robot passed, 1 when one failed, 2 without a verdict.

Time base: log lines carry sim time (the executive's clock) and wall time in brackets; the referee's report
lines count seconds from its own t0 (``results.json`` says so under ``time_base``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from bt_nav.cli import plain
from bt_nav.cli.options import add_mission_options, bag_truth_readers, check_mission_options
from bt_nav.mission.params import parse_assignments
from bt_nav.run.recorder import Recording, speed_line
from bt_nav.run.rosmission import GRACE, demo_mission, mission_graph
from bt_nav.run.rundir import Logs, make_run_dir
from bt_nav.run.session import DomainLease, read_verdict
from bt_nav.run.settings import effective_parameters, profile_maneuver, tree_settings


def build_parser() -> argparse.ArgumentParser:
    """Options of ``bt-nav demo``."""
    parser = argparse.ArgumentParser(prog="bt-nav demo", description=plain(__doc__.split("\n\n")[0]),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_mission_options(parser)
    parser.add_argument("--rtf", type=float, default=0.0,
                        help="real-time factor; 0 (default) = as fast as the executive keeps up; with --exe, 0 = real "
                        "time (1x, as graded and as on the robot)")
    parser.add_argument("--name", help="run directory name (default: <date>-<time>_<world>_<maneuver>_seed<seed>;"
                        " never overwritten: a suffix -2, -3 ... is added)")
    parser.add_argument("--out", default="runs", help="where run directories go (default runs/)")
    parser.add_argument("--timeout", type=float, default=120.0, help="wall-clock limit of the referee, s")
    parser.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID, else one no "
                        "other run on this machine holds, from $BT_NAV_DOMAIN_RANGE or 100-199)")
    parser.add_argument("--quiet", action="store_true", help="print only the verdict lines")
    parser.add_argument("--bag", metavar="DIR", help="also record the run as a rosbag2 (MCAP) bag (bt-nav record)")
    parser.add_argument("--video", metavar="MP4", help="also film the run (from its bag: --bag, else <MP4>_bag)")
    parser.add_argument("--robots", type=int, default=1, help="robots in the world (default 1); > 1: robot1, "
                        "robot2, ... each with its executive and referee in its namespace, a verdict each")
    parser.add_argument("--exe", metavar="CMD", help="run this robot node (your own, any command) instead of "
                        "bt_nav's executive, judged by the homework's referee or --profile lab's check-off judge (on "
                        "the maneuver its file's '# CHOICE: X' declares, unless --maneuver); "
                        "its log lines are shown at their sim time and the run is filmed (run directory's video.mp4, "
                        "or --video) for the hand-in")
    parser.add_argument("--launch", metavar="FILE", help="with --exe --profile lab: the launch file the run stands in "
                        "for (its package on the terminal's 'ros2 launch' line, its parameters given to the node; "
                        "default: turtlebot_bringup.launch.py beside the node's file)")
    parser.set_defaults(world=None)  # the lab's default arena depends on the maneuver; the homework's is stage_4
    return parser


def _prepare(opts: argparse.Namespace) -> dict[str, Any]:
    """Names, maneuver, domain (its lease, released by the caller), run directory, overrides and the graph
    (ValueError on a bad option)."""
    from bt_nav_sim.multi import robot_names

    if opts.profile != "homework":
        raise ValueError(f"--profile {opts.profile}: the demo runs the homework (its referee) or the lab (its "
                         "check-off judge), not this profile (lockstep and grade run every profile)")
    opts.world = opts.world or "stage_4"
    names = robot_names(opts.robots)
    maneuver = profile_maneuver("homework", opts.maneuver)  # the requested one, else the homework's
    overrides = parse_assignments(opts.overrides)
    parameters = effective_parameters(tree_settings(opts.profile, maneuver, opts.seed, overrides))
    lease = DomainLease(opts.domain_id)
    domain = lease.claim()
    label = Path(opts.world).stem if opts.world.endswith((".yaml", ".yml")) else opts.world
    several = f"_{len(names)}robots" if len(names) > 1 else ""
    run_dir = make_run_dir(Path(opts.out), opts.name or
                           f"{time.strftime('%Y%m%d-%H%M%S')}_{label}_{maneuver}_seed{opts.seed}{several}")
    results = {n: str((run_dir / (f"results_{n}.json" if several else "results.json")).resolve()) for n in names}
    specs = mission_graph(names, results, world=opts.world, maneuver=maneuver if opts.maneuver is not None else None,
                          seed=opts.seed, rtf=opts.rtf,
                          referee={"timeout": float(opts.timeout), **bag_truth_readers(opts.bag, opts.video)},
                          sim=parse_assignments(opts.sim_param), executive=overrides or None)
    run_info = {"world": opts.world, "maneuver": maneuver, "seed": opts.seed, "profile": opts.profile,
                "robots": names, "overrides": overrides, "parameters": parameters,
                "time_base": "logs: sim time (executive clock) [wall]; referee results: seconds from its t0"}
    (run_dir / "run.json").write_text(json.dumps(run_info, indent=1) + "\n", encoding="utf-8")
    return {"names": names, "maneuver": maneuver, "domain": domain, "lease": lease, "run_dir": run_dir,
            "specs": specs,
            "results": results, "label": label, "parameters": parameters}


def trigger_words(maneuver: str, parameters: dict[str, Any]) -> str:
    """The executive's trigger of ``maneuver`` in words, from the run's parameter values: a demo whose count is 0
    says what never happened (C's trigger is nearer than the close / far driving usually lets the robot get)."""
    from bt_nav.mission.maneuver_spec import maneuver_spec

    trigger = maneuver_spec(maneuver).trigger  # what the executive's trigger reads, and at which parameter
    what = (f"the front (+-{float(parameters['front_half_angle_deg']):g} deg)" if trigger.reads == "front"
            else f"{trigger.words} both")
    return f"{what} nearer than {trigger.distance} {float(parameters[trigger.distance]):.2f} m"


def main(argv: list[str] | None = None) -> int:
    """``bt-nav demo``; returns 0 (every robot PASSED), 1 (one FAILED) or 2 (no verdict)."""
    from bt_nav.cli.options import bag_for, film
    from bt_nav.run.bagrecorder import mission_topics, start_process, stop_process

    opts = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        check_mission_options(opts)
    except ValueError as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    if opts.exe is not None:  # an empty one is refused as such, not taken for bt_nav's executive
        from bt_nav.cli.demo.exe import run_exe_demo

        return run_exe_demo(opts)
    if opts.profile == "lab":
        from bt_nav.cli.demo.lab import run_lab

        return run_lab(opts)
    try:
        bag_dir = bag_for(opts.bag, opts.video)
        run = _prepare(opts)
    except ValueError as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    names, domain, run_dir = run["names"], run["domain"], run["run_dir"]
    robots = f", {len(names)} robots ({', '.join(names)})" if len(names) > 1 else ""
    print(f"bt-nav demo: {run['label']}{robots}, maneuver {run['maneuver']}, seed {opts.seed}, "
          f"{'as fast as possible' if opts.rtf == 0 else f'{opts.rtf:g}x real time'}, ROS_DOMAIN_ID={domain} "
          f"(localhost only)\nbt-nav demo: run directory {run_dir}/", flush=True)
    wall0 = time.monotonic()
    logs = Logs(run_dir, echo_logs=not opts.quiet)
    mission = demo_mission(run["specs"], names, list(run["results"].values()), domain, logs)
    stop, env = mission.session.stop, mission.session.env
    bag = start_process(bag_dir, env, "--seed", str(opts.seed), "--topics", *mission_topics(names)) if bag_dir \
        else None
    try:
        code = mission.supervise(opts.timeout + GRACE, run_dir)
    finally:
        logs.quiet_from_now = True  # the shutdown's lines go to the log files only
        stop.closing = True
        recs = mission.close()
        if bag is not None:
            print(f"bt-nav demo: bag {bag_dir}: {stop_process(bag)}", flush=True)
        stop.restore()
        run["lease"].release()
    if opts.video and bag_dir:
        film(bag_dir, opts.video, 10.0)
    return _report(run, opts, recs, code, time.monotonic() - wall0)


def _robot_files(run: dict[str, Any], name: str, rec: Recording) -> tuple[dict[str, Any], Any, list[Path]]:
    """One robot's verdict (read), trajectory (written) and the files; prints its maneuver count."""
    several = len(run["names"]) > 1
    path = run["run_dir"] / Path(run["results"][name]).name  # as the other files name it (the referee's is absolute)
    verdict = read_verdict(path) or {}
    traj, data = rec.mission_trajectory(verdict)
    out = run["run_dir"] / (f"trajectory_{name}.json" if several else "trajectory.json")
    out.write_text(json.dumps(data) + "\n", encoding="utf-8")
    fired = sum(rec.maneuvers.values())
    detail = ", ".join(f"{tip.rsplit('.', 1)[-1]} x{n}" for tip, n in sorted(rec.maneuvers.items()))
    why = ""
    if not fired and run["maneuver"] != "none":
        why = (f": its trigger, {trigger_words(run['maneuver'], run['parameters'])}, did not fire in this run "
               "(the close / far driving steers away from obstacles, often before they are that near)")
    print(f"bt-nav demo: {name + ': ' if several else ''}maneuvers fired: {fired}"
          + (f" ({detail})" if detail else "") + f" (maneuver {run['maneuver']}, counted from the tree){why}",
          flush=True)
    if rec.foreign_truth:
        print(f"bt-nav demo: {rec.foreign_truth} ground-truth messages came from another simulator in this ROS "
              "domain: this run's figures cannot be trusted; give each run its own ROS_DOMAIN_ID", file=sys.stderr)
    return verdict, traj, [p for p in (path, out) if p.is_file()]


def _report(run: dict[str, Any], opts: argparse.Namespace, recs: dict[str, Recording], code: int,
            wall: float) -> int:
    """Write the outputs and print the summary lines; the final exit code."""
    names, run_dir = run["names"], run["run_dir"]
    written: list[Path] = [run_dir / "run.json"]
    runs = []
    for name in names:
        verdict, traj, files = _robot_files(run, name, recs[name])
        runs.append((name, traj, verdict))
        written += files
    judged = all(v and v.get("done") and not v.get("timed_out") for _, _, v in runs)
    if recs[names[0]].foreign_truth or not judged:
        code = 2 if code in (0, 1) else code
    if len(names) > 1:
        each = ", ".join(f"{n} {'PASSED' if v.get('passed') and v.get('done') else 'FAILED'}" for n, _, v in runs)
        print(f"summary: {sum(bool(v.get('passed')) for _, _, v in runs)}/{len(names)} robots "
              f"{'PASSED' if code == 0 else 'FAILED'} ({each})", flush=True)
    written += _pictures(run, opts, runs)
    print(f"bt-nav demo: {speed_line(recs[names[0]], runs[0][2], wall)}", flush=True)
    print("bt-nav demo: wrote " + ", ".join(str(p) for p in written), flush=True)
    return code


def _pictures(run: dict[str, Any], opts: argparse.Namespace, runs: list[tuple[str, Any, dict[str, Any]]]
              ) -> list[Path]:
    """trajectory.png (every robot's path) and the tree files; notes on stderr when they cannot be made."""
    from bt_nav_sim import load_world

    from bt_nav.media.plot import plot_robots, plot_run

    written: list[Path] = []
    out = run["run_dir"] / "trajectory.png"
    try:
        world = load_world(opts.world, seed=None if opts.seed < 0 else opts.seed)
        robots = f", {len(runs)} robots" if len(runs) > 1 else ""
        title = f"{world.name}{robots}, maneuver {run['maneuver']}, seed {opts.seed} (ROS, sim time)"
        written.append(plot_run(world, runs[0][1], runs[0][2], out, title=title) if len(runs) == 1
                       else plot_robots(world, runs, out, title=title))
    except Exception as exc:  # a missing matplotlib must not hide the verdict
        print(f"bt-nav demo: no trajectory picture: {exc}", file=sys.stderr)
    try:
        from bt_nav.media.treedot import render

        dot = render(run["maneuver"], "dot")
        (run["run_dir"] / "tree.dot").write_text(dot if isinstance(dot, str) else dot.decode(), encoding="utf-8")
        written.append(run["run_dir"] / "tree.dot")
        svg = render(run["maneuver"], "svg")
        (run["run_dir"] / "tree.svg").write_bytes(svg if isinstance(svg, bytes) else svg.encode())
        written.append(run["run_dir"] / "tree.svg")
    except Exception as exc:  # graphviz missing: the dot file may still be there
        print(f"bt-nav demo: note: tree picture skipped: {exc}", file=sys.stderr)
    return written


if __name__ == "__main__":
    raise SystemExit(main())
