"""``bt-nav lockstep``: missions in lock-step, the real trees and the simulator in one process, no DDS.

Deterministic per (world, maneuver, seed, profile, settings); one robot or several in one world
(``--robots N``: robot1, robot2, ... each with its own tree and referee). The engine is
:mod:`bt_nav.run.lockstep`; this module parses the options and prints. Exit 0 only if every robot passed.
"""

from __future__ import annotations

import argparse
import json
from contextlib import nullcontext
from pathlib import Path

from bt_nav_sim.multi import robot_names
from bt_nav_sim.physics import KINEMATICS

from bt_nav.cli.options import add_mission_options, bag_for, film
from bt_nav.mission.params import parse_assignments
from bt_nav.run.lockstep import run_robots
from bt_nav.run.result import RunResult
from bt_nav.run.settings import DEFAULT_JITTER, profile_maneuver


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="bt-nav lockstep", description=__doc__.splitlines()[0])
    add_mission_options(parser)
    parser.add_argument("--kinematics", default="", choices=("", *KINEMATICS),
                        help="ideal or burger (per-wheel limits); default: the profile's")
    parser.add_argument("--no-noise", action="store_true", help="no LiDAR noise and no odometry slip")
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds (default: until report)")
    parser.add_argument("--no-jitter", action="store_true", help="start exactly at the world's spawn")
    parser.add_argument("--trace", default=None, help="write the per-tick JSONL trace here (several robots: one "
                        "file per robot, the robot's name before the suffix)")
    parser.add_argument("--plot", default=None, help="write the trajectory picture here (.png/.svg)")
    parser.add_argument("--json", default=None, help="write results (with trajectory and every parameter) here")
    parser.add_argument("--bag", default=None, metavar="DIR", help="write the mission as a rosbag2 (MCAP) bag here")
    parser.add_argument("--video", default=None, metavar="FILE.mp4", help="film the mission (needs --bag or "
                        "writes a bag next to the video)")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per second of --video")
    parser.add_argument("--robots", type=int, default=1, help="robots in the world, each with its own tree and "
                        "referee (robot1, robot2, ...; default 1)")
    return parser


def trace_paths(trace: str | None, names: list[str]) -> list[str | None]:
    """Where each robot's trace goes: ``trace`` itself for one robot, ``<stem>_<robot><suffix>`` for several."""
    if trace is None:
        return [None] * len(names)
    if len(names) == 1:
        return [trace]
    path = Path(trace)
    return [str(path.with_name(f"{path.stem}_{name}{path.suffix}")) for name in names]


def _run(args: argparse.Namespace) -> tuple[RunResult, list[str | None]]:
    """The run, written to a bag while it runs when one is asked for; also the trace files."""
    from bt_nav.media.bag import MissionBag

    names = robot_names(args.robots)
    maneuver = profile_maneuver(args.profile, args.maneuver)
    traces = trace_paths(args.trace, names)
    options = {"robots": args.robots, "jitter": None if args.no_jitter else DEFAULT_JITTER,
               "kinematics": args.kinematics, "noise": not args.no_noise,
               "sim_params": parse_assignments(args.sim_param) or None}
    info = {"world": args.world, "maneuver": maneuver, "seed": args.seed, "profile": args.profile,
            **({"sim_params": options["sim_params"]} if options["sim_params"] else {}),
            **({"robots": names} if len(names) > 1 else {})}
    bag = MissionBag(args.bag, mission=info) if args.bag else None
    with bag if bag is not None else nullcontext():
        result = run_robots(args.world, maneuver, args.seed, parse_assignments(args.overrides), args.profile,
                            duration=args.duration, trace_paths=traces, sink=bag, **options)
        if bag is not None:
            for name, r in zip(result.names, result.results, strict=True):
                (bag if len(names) == 1 else bag.robot(name)).event(r.sim_time, f"verdict: {r.verdict()}")
    return result, traces


def print_result(result: RunResult) -> None:
    """Every referee's lines, then one line per robot (its name first when several)."""
    for line in result.report_lines():
        print(line)
    several = len(result.results) > 1
    for name, r in zip(result.names, result.results, strict=True):
        print(f"{name + ': ' if several else ''}{r.line()}")
    robots = f"{len(result.names)} robots, " if several else ""
    print(f"{robots}{result.sim_time:.1f} s simulated in {result.wall_time:.3f} s")


def main(argv: list[str] | None = None) -> int:
    """``bt-nav lockstep``: prints the referees' reports and the files written; exit 0 only if all passed."""
    from bt_nav.media.bag import BagError

    parser = _parser()
    args = parser.parse_args(argv)
    try:
        args.bag = bag_for(args.bag, args.video)
        result, traces = _run(args)
    except (ValueError, FileNotFoundError, BagError) as exc:
        parser.error(str(exc))
    print_result(result)
    if args.plot:
        result.plot(args.plot)
        print(f"picture: {args.plot}")
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result.to_dict(trajectory=True), indent=1))
        print(f"results: {args.json}")
    for trace in filter(None, traces):
        print(f"trace: {trace}")
    if args.bag:
        print(f"bag: {args.bag}")
    if args.video:
        film(args.bag, args.video, args.fps)
    return 0 if result.passed else 1
