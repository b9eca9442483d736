"""``bt-nav demo --robots N``: N robots in one world over real DDS, each judged on its own, drawn together.

The graph is :func:`bt_nav.ros.bringup.robot_nodes`: one simulator hosting robot1 ... robotN (one
``/clock``), and per robot the unchanged executive and a referee in the robot's namespace. The referees are
started once the demo's recorders (one per robot, :class:`bt_nav.cli.demo.Recorder`) see every robot's
ground truth and commands; each referee arms its own robot, runs its own 50 s schedule and gives its own
verdict. The demo prints every referee's lines prefixed with the robot's name, then one summary line, and
writes ``results_<robot>.json``, ``trajectory_<robot>.json`` and one ``trajectory.png`` with every path in
its robot's colour. Exit code: 0 when every robot passed, 1 when one failed, 2 without a verdict.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from bt_nav.cli.demo import (
    _GRACE,
    _LOG_FORMAT,
    _STARTUP,
    Recorder,
    Recording,
    _Logs,
    _mission_slice,
    effective_maneuver,
    make_run_dir,
    rec_ready,
)
from bt_nav.ros.bringup import cmd_vel_stamped, parse_assignments, robot_nodes
from bt_nav.ros.supervise import (
    Child,
    Launcher,
    StopRequest,
    child_env,
    choose_domain_id,
    publish_zero_twist,
    use_domain_here,
)


def main_multi(opts: argparse.Namespace) -> int:
    """The several-robots demo (see the module docstring); returns its exit code."""
    from bt_nav_sim.multi import robot_names

    try:
        maneuver = effective_maneuver(opts.maneuver)
        domain = choose_domain_id(opts.domain_id)
        names = robot_names(opts.robots)
    except ValueError as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    if opts.bag:
        print("bt-nav demo: --bag records one robot: not with --robots > 1", file=sys.stderr)
        return 2
    world_label = Path(opts.world).stem if opts.world.endswith((".yaml", ".yml")) else opts.world
    name = opts.name or f"{time.strftime('%Y%m%d-%H%M%S')}_{world_label}_{maneuver}_seed{opts.seed}_{len(names)}robots"
    run_dir = make_run_dir(Path(opts.out), name)
    results = {r: str((run_dir / f"results_{r}.json").resolve()) for r in names}
    use_domain_here(domain)
    env = child_env(domain)
    env["RCUTILS_CONSOLE_OUTPUT_FORMAT"] = _LOG_FORMAT
    specs = robot_nodes("eval", names, world=opts.world, maneuver=maneuver if opts.maneuver is not None else None,
                        seed=opts.seed, rtf=opts.rtf, results_json=results, referee={"timeout": float(opts.timeout)},
                        sim=parse_assignments(opts.sim_param))
    print(f"bt-nav demo: {world_label}, {len(names)} robots ({', '.join(names)}), maneuver {maneuver}, seed "
          f"{opts.seed}, {'as fast as possible' if opts.rtf == 0 else f'{opts.rtf:g}x real time'}, "
          f"ROS_DOMAIN_ID={domain} (localhost only)\nbt-nav demo: run directory {run_dir}/", flush=True)
    wall0 = time.monotonic()
    stop = StopRequest().install()
    recorders = {r: Recorder(r) for r in names}
    logs = _Logs(run_dir, echo_logs=not opts.quiet, sim_time=recorders[names[0]].sim_time)
    stamped = cmd_vel_stamped(specs)
    launcher = Launcher(env, sink=logs.sink, stop=stop, last_word=lambda: [
        publish_zero_twist(domain, topic=f"/{r}/cmd_vel", stamped=stamped) for r in names])
    try:
        code = _supervise(launcher, specs, recorders, opts, logs, stop)
    finally:
        logs.quiet_from_now = True
        stop.closing = True
        launcher.shutdown()
        recs = {r: rec.close() for r, rec in recorders.items()}
        logs.close()
        stop.restore()
    return _report(run_dir, opts, maneuver, names, recs, code, time.monotonic() - wall0)


def _start(launcher: Launcher, spec: Any, logs: _Logs) -> Child:
    """Start one node; its log file and report lines carry its robot's name."""
    robot = spec.namespace

    def sink(name: str, line: str) -> None:
        if not robot:
            logs.sink(name, line)
        else:
            logs.sink(f"{robot}_{name}", line if line.startswith("[") else f"{robot}: {line}")

    return launcher.start(spec, sink=sink)


def _supervise(launcher: Launcher, specs: list[Any], recorders: dict[str, Recorder], opts: argparse.Namespace,
               logs: _Logs, stop: StopRequest) -> int:
    """Start the simulator and the executives, then the referees once every robot is seen; wait for every
    verdict. Returns 0 (every referee exited), 2 (no verdict) or 128 + signal."""
    try:
        for spec in specs:
            if spec.executable != "referee":
                _start(launcher, spec, logs)
        deadline = time.monotonic() + _STARTUP
        while not (all(rec_ready(r) for r in recorders.values()) or time.monotonic() > deadline or stop.requested
                   or any(c.poll() is not None for c in launcher.children)):
            time.sleep(0.02)
        if stop.requested:
            raise KeyboardInterrupt
        referees = [_start(launcher, spec, logs) for spec in specs if spec.executable == "referee"]
        end = time.monotonic() + opts.timeout + _GRACE
        while time.monotonic() < end and not stop.requested:
            if all(r.poll() is not None for r in referees):
                return 0
            other = next((c for c in launcher.children if c not in referees and c.poll() is not None), None)
            if other is not None:
                print(f"bt-nav demo: {other.spec.namespace}/{other.name} exited with {other.poll()} before the "
                      "verdicts", file=sys.stderr)
                return 2
            time.sleep(0.05)
        if stop.requested:
            raise KeyboardInterrupt
        print(f"bt-nav demo: no verdict within {opts.timeout + _GRACE:g} s wall; stopping", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"bt-nav demo: {stop.name or 'SIGINT'}: stopping every node", file=sys.stderr)
        return 128 + int(stop.signum or 2)


def _report(run_dir: Path, opts: argparse.Namespace, maneuver: str, names: list[str], recs: dict[str, Recording],
            code: int, wall: float) -> int:
    """The summary line, the files (results, trajectories, the picture); the exit code."""
    from bt_nav_sim import load_world
    from bt_nav_sim.plot import Trajectory, branch_of_tip, plot_robots

    verdicts: dict[str, dict[str, Any]] = {}
    runs = []
    written: list[Path] = []
    for robot in names:
        path = run_dir / f"results_{robot}.json"
        verdicts[robot] = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
        written += [path] if path.is_file() else []
        rec = recs[robot]
        start, end = _mission_slice(rec, verdicts[robot])
        traj = Trajectory(rec.t[start:end], rec.x[start:end], rec.y[start:end], rec.yaw[start:end],
                          [branch_of_tip(tip) for tip in rec.tip[start:end]])
        out = run_dir / f"trajectory_{robot}.json"
        out.write_text(json.dumps({**traj.to_dict(), "maneuvers": rec.maneuvers, "commands": rec.commands,
                                   "foreign_truth": rec.foreign_truth}) + "\n", encoding="utf-8")
        written.append(out)
        runs.append((robot, traj, verdicts[robot]))
        fired = sum(rec.maneuvers.values())
        print(f"bt-nav demo: {robot}: maneuvers fired: {fired} (maneuver {maneuver}, counted from the tree)")
    passed = [bool(verdicts[r].get("passed")) and bool(verdicts[r].get("done")) for r in names]
    judged = all(verdicts[r] and not verdicts[r].get("timed_out") for r in names)
    each = ", ".join(f"{r} {'PASSED' if p else 'FAILED'}" for r, p in zip(names, passed, strict=True))
    print(f"summary: {sum(passed)}/{len(names)} robots {'PASSED' if all(passed) else 'FAILED'} ({each})", flush=True)
    try:
        world = load_world(opts.world, seed=None if opts.seed < 0 else opts.seed)
        title = f"{world.name}, {len(names)} robots, maneuver {maneuver}, seed {opts.seed} (ROS, sim time)"
        written.append(plot_robots(world, runs, run_dir / "trajectory.png", title=title))
    except Exception as exc:  # a missing matplotlib must not hide the verdicts
        print(f"bt-nav demo: no trajectory picture: {exc}", file=sys.stderr)
    print(f"bt-nav demo: demo wall time {wall:.1f} s", flush=True)
    print("bt-nav demo: wrote " + ", ".join(str(p) for p in written), flush=True)
    if code != 0 or not judged:
        return 2 if code == 0 else code
    return 0 if all(passed) else 1
