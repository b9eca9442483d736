"""Batch grading: lock-step missions over worlds x maneuvers x seeds, in parallel processes.

py_trees' blackboard is process-global, so each worker process runs one mission at a time; the grid
is spread over ``jobs`` processes with :class:`concurrent.futures.ProcessPoolExecutor`. Every mission
is deterministic per (world, maneuver, seed), so a grade is reproducible and two grades can be
compared run by run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections import Counter
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from bt_nav_sim.physics import KINEMATICS
from bt_nav_sim.world import list_worlds

from bt_nav.cli.lockstep import DEFAULT_JITTER, parse_overrides, run_mission
from bt_nav.mission.params import normalise_maneuver
from bt_nav.mission.profiles import PROFILE_FILES

Job = tuple[str, str, int, dict[str, Any] | None, str, tuple[float, float] | None, str]


def _run_one(job: Job) -> dict[str, Any]:
    """One mission's summary (module level so worker processes can unpickle it)."""
    world, maneuver, seed, overrides, profile, jitter, kinematics = job
    try:
        return run_mission(world, maneuver, seed, overrides, profile, jitter=jitter, kinematics=kinematics).summary()
    except Exception as exc:  # one broken mission must not sink the whole grade
        return {"world": world, "maneuver": maneuver, "seed": seed, "profile": profile, "passed": False,
                "error": repr(exc), "travelled": 0.0, "efficiency": 0.0, "collisions": 0,
                "failed_checks": ["error"], "wall_time": 0.0}


def seed_list(seeds: int | Iterable[int]) -> list[int]:
    """``20`` means seeds 0..19; an iterable is taken as is."""
    return list(range(seeds)) if isinstance(seeds, int) else [int(s) for s in seeds]


def grade(worlds: Sequence[str], maneuvers: Sequence[str], seeds: int | Iterable[int], jobs: int = 2,
          overrides: dict[str, Any] | None = None, profile: str = "homework",
          jitter: tuple[float, float] | None = DEFAULT_JITTER, kinematics: str = "") -> list[dict[str, Any]]:
    """Run every (world, maneuver, seed); returns one summary dict per mission, in grid order."""
    grid = [(w, normalise_maneuver(m), s, overrides, profile, jitter, kinematics)
            for w in worlds for m in maneuvers for s in seed_list(seeds)]
    if jobs <= 1:
        return [_run_one(job) for job in grid]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(_run_one, grid, chunksize=max(1, len(grid) // (4 * jobs))))


def _median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One line per (world, maneuver): pass rate, collisions, distances, efficiency, failures, time."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["world"], row["maneuver"]), []).append(row)
    out = []
    for (world, maneuver), runs in groups.items():
        travelled = [r["travelled"] for r in runs]
        efficiency = [r["efficiency"] for r in runs]
        failures = Counter(name for r in runs for name in r.get("failed_checks", ()))
        out.append({
            "world": world, "maneuver": maneuver, "runs": len(runs),
            "passed": sum(1 for r in runs if r["passed"]),
            "pass_rate": sum(1 for r in runs if r["passed"]) / len(runs),
            "collisions": sum(r["collisions"] for r in runs),
            "runs_with_collisions": sum(1 for r in runs if r["collisions"]),
            "travelled_median": _median(travelled), "travelled_min": min(travelled),
            "efficiency_median": _median(efficiency), "efficiency_worst": min(efficiency),
            "failed_checks": dict(failures.most_common()),
            "failed_seeds": [r["seed"] for r in runs if not r["passed"]],
            "wall_time_mean": statistics.fmean(r.get("wall_time", 0.0) for r in runs),
        })
    return out


def overall(rows: Sequence[dict[str, Any]], summary: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The grid's headline figures: what the homework targets are stated in."""
    efficiency = [r["efficiency"] for r in rows]
    worst_cell = min(summary, key=lambda s: s["pass_rate"], default=None)
    return {
        "runs": len(rows), "passed": sum(1 for r in rows if r["passed"]),
        "pass_rate": sum(1 for r in rows if r["passed"]) / len(rows) if rows else float("nan"),
        "collisions": sum(r["collisions"] for r in rows),
        "runs_with_collisions": sum(1 for r in rows if r["collisions"]),
        "efficiency_median": _median(efficiency), "efficiency_worst": min(efficiency, default=float("nan")),
        "worst_cell": (f"{worst_cell['world']} {worst_cell['maneuver']} {worst_cell['passed']}/{worst_cell['runs']}"
                       if worst_cell else ""),
    }


def format_overall(total: dict[str, Any]) -> str:
    """One line with the headline figures."""
    return (f"{total['passed']}/{total['runs']} passed ({100 * total['pass_rate']:.1f} %), "
            f"{total['collisions']} collisions in {total['runs_with_collisions']} runs, efficiency median "
            f"{total['efficiency_median']:.3f} worst {total['efficiency_worst']:.3f}; worst cell {total['worst_cell']}")


def format_table(summary: Sequence[dict[str, Any]]) -> str:
    """The summary as a fixed-width text table."""
    head = (f"{'world':<11} {'man':<4} {'pass':>7} {'coll':>5} {'trav med':>8} {'trav min':>8} "
            f"{'eff med':>7} {'eff min':>7} {'wall/run':>8}  failed checks")
    lines = [head, "-" * len(head)]
    for s in summary:
        failed = ", ".join(f"{name} x{n}" for name, n in s["failed_checks"].items()) or "-"
        lines.append(
            f"{s['world']:<11} {s['maneuver']:<4} {s['passed']:>3}/{s['runs']:<3} {s['collisions']:>5} "
            f"{s['travelled_median']:>8.2f} {s['travelled_min']:>8.2f} {s['efficiency_median']:>7.3f} "
            f"{s['efficiency_worst']:>7.3f} {s['wall_time_mean']:>7.3f}s  {failed}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav grade``: prints the table; exit 0 only if every mission passed."""
    parser = argparse.ArgumentParser(prog="bt-nav grade", description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", default="stage_4", help="comma-separated world names, or 'all' (bundled)")
    parser.add_argument("--maneuvers", default="none,A,B,C", help="comma-separated: none, A, B, C")
    parser.add_argument("--seeds", type=int, default=20, help="seeds 0..N-1")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--profile", default="homework", choices=sorted(PROFILE_FILES),
                        help="params files and simulated robot (homework, lab, turtlebot3)")
    parser.add_argument("--kinematics", default="", choices=("", *KINEMATICS),
                        help="ideal or burger (per-wheel limits); default: the profile's")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter override for every mission (repeatable)")
    parser.add_argument("--no-jitter", action="store_true", help="start exactly at each world's spawn")
    parser.add_argument("--json", default=None, help="write every run and the summary here")
    args = parser.parse_args(argv)
    worlds = [w.strip() for w in args.worlds.split(",") if w.strip()]
    if worlds == ["all"]:
        worlds = list_worlds()
    try:
        maneuvers = [normalise_maneuver(m.strip()) for m in args.maneuvers.split(",") if m.strip()]
        overrides = parse_overrides(args.overrides) or None
    except ValueError as exc:
        parser.error(str(exc))
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    started = time.perf_counter()
    rows = grade(worlds, maneuvers, seeds, args.jobs, overrides, args.profile,
                 None if args.no_jitter else DEFAULT_JITTER, args.kinematics)
    elapsed = time.perf_counter() - started
    summary = summarize(rows)
    print(format_table(summary))
    errors = [r for r in rows if "error" in r]
    for r in errors[:5]:
        print(f"error in {r['world']} {r['maneuver']} seed {r['seed']}: {r['error']}", file=sys.stderr)
    total = overall(rows, summary)
    print(format_overall(total))
    print(f"{len(rows)} missions ({args.profile} profile, {args.kinematics or 'profile'} kinematics) in "
          f"{elapsed:.1f} s wall with {args.jobs} jobs")
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        settings = {"profile": args.profile, "kinematics": args.kinematics, "seeds": list(seeds),
                    "worlds": worlds, "maneuvers": maneuvers, "overrides": overrides or {}}
        path.write_text(json.dumps({"settings": settings, "overall": total, "summary": summary, "runs": rows},
                                   indent=1))
    return 0 if total["passed"] == total["runs"] else 1
