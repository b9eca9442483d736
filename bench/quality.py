"""Benchmark 4: mission quality, graded by the referee over worlds x maneuvers x seeds (lock-step).

:func:`bt_nav.cli.grade.grade` runs every (world, maneuver, seed) in worker processes, with the
parameters of ``config/homework.yaml`` (what ``bt-nav demo`` runs) and the maneuver varied. Per
(world, maneuver): pass rate, collisions, travelled distance, and distance efficiency = travelled /
(max_linear_speed x time armed before the deadline stop) — 1.0 would be driving straight at full
speed the whole time; the median and the worst run, and which referee checks failed.

Only stage_4 is the homework's world and held to the targets (every run passes, no collision,
median efficiency >= 0.9 per maneuver); the other worlds are harder on purpose (a corridor, clutter,
an empty room whose walls force turns) and are reported as they are.
"""

from __future__ import annotations

import os
import time
from typing import Any

from bt_nav.cli.grade import grade, summarize

from .common import Target, at_least, homework_overrides, median

WORLDS = ("stage_4", "corridor", "cluttered", "empty_room")
MANEUVERS = ("none", "A", "B", "C")
HOMEWORK_WORLD = "stage_4"
TARGET_PASS_RATE = 1.0
TARGET_EFFICIENCY = 0.9


def run(quick: bool = False, jobs: int | None = None) -> dict[str, Any]:
    """The grid (20 seeds, 2 when quick) and its summary."""
    seeds = 2 if quick else 20
    jobs = jobs or max(1, os.cpu_count() or 1)
    overrides = homework_overrides()
    started = time.perf_counter()
    rows = grade(WORLDS, MANEUVERS, seeds, jobs=jobs, overrides=overrides)
    wall = time.perf_counter() - started
    summary = summarize(rows)
    for line in summary:
        runs = [r for r in rows if r["world"] == line["world"] and r["maneuver"] == line["maneuver"]]
        worst = min(runs, key=lambda r: r["efficiency"])
        line["efficiency_worst_seed"] = worst["seed"]
        line["errors"] = [r.get("error") for r in runs if "error" in r]
    per_world = []
    for world in WORLDS:
        runs = [r for r in rows if r["world"] == world]
        if not runs:
            continue
        per_world.append({
            "world": world, "runs": len(runs), "passed": sum(1 for r in runs if r["passed"]),
            "collisions": sum(r["collisions"] for r in runs),
            "efficiency_median": round(median([r["efficiency"] for r in runs]), 4),
            "efficiency_worst": min(r["efficiency"] for r in runs),
            "travelled_median": round(median([r["travelled"] for r in runs]), 3),
        })
    return {"worlds": list(WORLDS), "maneuvers": list(MANEUVERS), "seeds": seeds, "jobs": jobs,
            "overrides": overrides, "missions": len(rows), "wall_s": round(wall, 1),
            "summary": summary, "per_world": per_world}


def targets(result: dict[str, Any]) -> list[Target]:
    """On stage_4: every run passes, no collision, median efficiency >= 0.9 for every maneuver."""
    lines = [s for s in result["summary"] if s["world"] == HOMEWORK_WORLD]
    if not lines:
        return []
    runs = sum(s["runs"] for s in lines)
    passed = sum(s["passed"] for s in lines)
    collisions = sum(s["collisions"] for s in lines)
    worst_median = min(s["efficiency_median"] for s in lines)
    rate = passed / runs if runs else None
    return [
        Target("stage4_pass_rate", "quality", f"stage_4 pass rate ({runs} missions: maneuvers x seeds)",
               "100 %", None if rate is None else round(100 * rate, 2), "%",
               None if rate is None else rate >= TARGET_PASS_RATE),
        Target("stage4_collisions", "quality", "stage_4 collisions (all missions)", "0", collisions, "",
               collisions == 0),
        Target("stage4_efficiency", "quality", "stage_4 median distance efficiency (lowest maneuver median)",
               f">= {TARGET_EFFICIENCY}", round(worst_median, 4), "", at_least(worst_median, TARGET_EFFICIENCY)),
    ]
