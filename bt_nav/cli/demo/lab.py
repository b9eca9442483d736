"""``bt-nav demo --profile lab --maneuver A|B|C``: the lab's check-off over real DDS, as the lab's terminal shows it.

It starts the ``checkoff`` graph of :mod:`bt_nav.ros.bringup` (what ``launch/lab_checkoff.launch.py`` starts):
the simulator with the lab's LDS-01 LiDAR in a lab arena (default: the one for the maneuver, ``lab_object``
for A and C, ``lab_dead_end`` for B), the executive with ``config/lab.yaml`` (and any ``--set``) armed through
``toggle_navigation``, and the check-off judge (:mod:`bt_nav.ros.nodes.checkoff`), which calls
``toggle_navigation`` and judges every maneuver from ground truth and the commands. The terminal shows the
launch, the service calls and replies, the maneuver and emergency-brake lines, stamped with sim time
(:class:`bt_nav.run.terminal.LabTerminal`), then the verdict and ``maneuvers fired: N`` (the judge's count).
``--bag``/``--video`` record the run with exactly those lines as its events; ``--video`` films the bag.

Run directory as the homework demo's: ``run.json``, the judge's ``results.json``, ``trajectory.json``,
``trajectory.png`` and one ``<node>.log`` per process. Exit code: 0 PASSED, 1 FAILED, 2 no verdict.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from bt_nav.mission.assignments import LAB
from bt_nav.mission.maneuver_spec import letters_text
from bt_nav.mission.params import MANEUVER_TITLES, parse_assignments
from bt_nav.ros.bringup import CHECKOFF_WORLDS
from bt_nav.run.settings import effective_parameters, profile_maneuver, tree_settings

#: Terminal lines of the executive's start-up: the parameters the lab asks to verify.
SHOWN_PARAMETERS = (("safety_distance", "m"), ("pivot_distance", "m"), ("creep_speed", "m/s"))


def _prepare(opts: argparse.Namespace) -> dict[str, Any]:
    """Maneuver, world, domain (its lease, released by the caller), run directory, parameters and the graph
    (ValueError on a bad option)."""
    from bt_nav.cli.options import bag_truth_readers
    from bt_nav.run.rosmission import mission_graph
    from bt_nav.run.rundir import make_run_dir
    from bt_nav.run.session import DomainLease

    if opts.robots != 1:
        raise ValueError("--profile lab checks off one robot (--robots 1)")
    maneuver = profile_maneuver("lab", opts.maneuver)
    if maneuver not in CHECKOFF_WORLDS:
        raise ValueError(f"--profile lab checks off maneuver {letters_text()}, not {maneuver!r}")
    world = opts.world or CHECKOFF_WORLDS[maneuver]
    overrides = parse_assignments(opts.overrides)
    parameters = effective_parameters(tree_settings("lab", maneuver, opts.seed, overrides))
    lease = DomainLease(opts.domain_id)
    domain = lease.claim()
    label = Path(world).stem if world.endswith((".yaml", ".yml")) else world
    run_dir = make_run_dir(Path(opts.out), opts.name or
                           f"{time.strftime('%Y%m%d-%H%M%S')}_{label}_{maneuver}_seed{opts.seed}_lab")
    results = str((run_dir / "results.json").resolve())
    judge = {"timeout": float(opts.timeout), **LAB.judge.given(parameters),  # its triggers: the executive's
             **bag_truth_readers(opts.bag, opts.video)}
    specs = mission_graph(["robot1"], {"robot1": results}, "checkoff", world=world, maneuver=maneuver,
                          seed=opts.seed, rtf=opts.rtf, referee=judge, sim=parse_assignments(opts.sim_param),
                          executive=overrides or None)
    run_info = {"world": world, "maneuver": maneuver, "seed": opts.seed, "profile": "lab", "robots": ["robot1"],
                "overrides": overrides, "parameters": parameters, "judge": "bt_nav_checkoff",
                "time_base": "logs and terminal: sim time [wall]; judge results: seconds from its t0 (t0_sim)"}
    (run_dir / "run.json").write_text(json.dumps(run_info, indent=1) + "\n", encoding="utf-8")
    return {"maneuver": maneuver, "world": world, "label": label, "domain": domain, "lease": lease, "run_dir": run_dir,
            "specs": specs, "results": results, "parameters": parameters}


def launch_line(run: dict[str, Any]) -> str:
    """The executive's start-up as the terminal shows it: node, params file, maneuver, trigger distances."""
    executive = next(s for s in run["specs"] if s.executable == "executive")
    files = ", ".join(Path(f).relative_to(Path.cwd()).as_posix() if Path(f).is_relative_to(Path.cwd()) else f
                      for f in executive.parameter_files) or "none"
    values = ", ".join(f"{name} {run['parameters'][name]:g} {unit}" for name, unit in SHOWN_PARAMETERS)
    arm = dict(executive.remappings).get("arm", str(run["parameters"].get("arm_service", "arm")))
    return (f"[INFO] [{executive.name}]: up: params file {files}, maneuver {MANEUVER_TITLES[run['maneuver']]}, "
            f"{values}, arm service /{arm.lstrip('/')} (std_srvs/SetBool)")


def run_lab(opts: argparse.Namespace) -> int:
    """The lab demo; 0 PASSED, 1 FAILED, 2 no verdict (or a bad option)."""
    from bt_nav.cli.options import bag_for
    from bt_nav.ros.supervise import use_domain_here
    from bt_nav.run.bagrecorder import start_process, stop_process
    from bt_nav.run.rosmission import GRACE, demo_mission
    from bt_nav.run.rundir import Logs
    from bt_nav.run.terminal import LabTerminal, TerminalNode

    try:
        bag_dir = bag_for(opts.bag, opts.video)
        run = _prepare(opts)
    except (ValueError, FileNotFoundError) as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    domain, run_dir = run["domain"], run["run_dir"]
    pace = "as fast as possible" if opts.rtf == 0 else f"{opts.rtf:g}x real time"
    print(f"bt-nav demo: lab check-off of maneuver {MANEUVER_TITLES[run['maneuver']]} in {run['label']}, seed "
          f"{opts.seed}, {pace}, ROS_DOMAIN_ID={domain} (localhost only)\nbt-nav demo: run directory {run_dir}/\n"
          f"$ ros2 launch bt_nav lab_checkoff.launch.py maneuver:={run['maneuver']} world:={run['world']} "
          "(simulator, executive, check-off judge)", flush=True)
    wall0 = time.monotonic()
    use_domain_here(domain)  # the event node in this process too (and the recorder: demo_mission)
    logs = Logs(run_dir, echo_logs=False)
    events = TerminalNode(publish=bool(bag_dir))  # the nodes' events and tree in; with a bag, the lines out
    terminal = LabTerminal(logs, launch_line(run), events)
    mission = demo_mission(run["specs"], ["robot1"], [run["results"]], domain, logs, sink=terminal.sink)
    stop, env = mission.session.stop, mission.session.env
    bag = start_process(bag_dir, env, "--seed", str(opts.seed), "--topics", *_bag_topics()) if bag_dir else None
    if bag_dir and not events.wait_for_reader():
        print("bt-nav demo: the recorder did not subscribe to the terminal's lines within 20 s; the bag may "
              "miss or reorder the first ones", flush=True)
    try:
        code = mission.supervise(opts.timeout + GRACE, run_dir)
        verdict = _verdict(run)
        fired = _fired_line(run, verdict)
        print(f"bt-nav demo: {fired}", flush=True)
        terminal.event(fired)
    finally:
        logs.quiet_from_now = True  # the shutdown's lines go to the log files only
        stop.closing = True
        recs = mission.close()
        events.close()
        if bag is not None:
            print(f"bt-nav demo: bag {bag_dir}: {stop_process(bag)}", flush=True)
        stop.restore()
        run["lease"].release()
    if not verdict.get("done") or verdict.get("timed_out"):
        code = 2 if code in (0, 1) else code
    _finish(run, opts, recs["robot1"], verdict, bag_dir, time.monotonic() - wall0)
    return code


def _bag_topics() -> list[str]:
    """The mission bag's topics, with the terminal's lines (/bt_nav/events) instead of /rosout's."""
    from bt_nav.media.bag import EVENTS
    from bt_nav.run.bagrecorder import DEFAULT_TOPICS

    return [t for t in DEFAULT_TOPICS if t != "/rosout"] + [EVENTS]


def _verdict(run: dict[str, Any]) -> dict[str, Any]:
    """The judge's verdict (empty: none was written, or it cannot be read)."""
    from bt_nav.run.session import read_verdict

    return read_verdict(Path(run["results"])) or {}


def _fired_line(run: dict[str, Any], verdict: dict[str, Any]) -> str:
    """``maneuvers fired: N`` as the judge counted them (its maneuver episodes), recovery turns apart."""
    fired = len(verdict.get("maneuvers") or [])
    recoveries = len(verdict.get("recovery_turns") or [])
    return (f"maneuvers fired: {fired} (maneuver {MANEUVER_TITLES[run['maneuver']]}, counted by the check-off "
            f"judge; {recoveries} emergency-stop recovery turn{'s' if recoveries != 1 else ''})")


def _finish(run: dict[str, Any], opts: argparse.Namespace, rec: Any, verdict: dict[str, Any], bag_dir: str | None,
            wall: float) -> None:
    """trajectory.json and .png, the video, the speed line and the files written."""
    from bt_nav.cli.options import film
    from bt_nav.run.recorder import speed_line

    run_dir = run["run_dir"]
    # The judge's times count from its t0; the recorder's samples are on the sim clock.
    window = {"times": {"t0": verdict.get("t0_sim"), "report": (verdict.get("times") or {}).get("report")}}
    traj, data = rec.mission_trajectory(window)
    (run_dir / "trajectory.json").write_text(json.dumps(data) + "\n", encoding="utf-8")
    results = run_dir / Path(run["results"]).name  # as the other files name it (the referee's path is absolute)
    written = [run_dir / "run.json", *[p for p in (results, run_dir / "trajectory.json") if p.is_file()]]
    try:
        from bt_nav_sim import load_world

        from bt_nav.media.plot import plot_run, start_circle

        world = load_world(run["world"], seed=None if opts.seed < 0 else opts.seed)
        title = f"{world.name}, lab check-off of maneuver {run['maneuver']}, seed {opts.seed} (ROS, sim time)"
        written.append(plot_run(world, traj, verdict, run_dir / "trajectory.png", title=title,
                                min_distance=start_circle("lab")))
    except Exception as exc:  # a missing matplotlib must not hide the verdict
        print(f"bt-nav demo: no trajectory picture: {exc}", file=sys.stderr)
    if opts.video and bag_dir:
        film(bag_dir, opts.video, 10.0)
    print(f"bt-nav demo: {speed_line(rec, window, wall)}", flush=True)
    print("bt-nav demo: wrote " + ", ".join(str(p) for p in written), flush=True)
