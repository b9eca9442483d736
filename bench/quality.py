"""Benchmark 4: mission quality, graded by the referee over every bundled world x maneuver x seed (lock-step).

Two grids, as issue 11 states the targets:

- ``ideal``: the homework profile (``config/homework.yaml``, the homework simulator's LiDAR) on an ideal
  unicycle. Targets: >= 98 % of all runs pass, 0 collisions, every world x maneuver cell >= 18/20, median
  distance efficiency >= 0.97 and worst >= 0.90.
- ``burger``: the real-robot profile (``--profile turtlebot3``: homework.yaml + turtlebot3.yaml, LDS-01) with
  per-wheel speed limits. Target: 0 collisions; the pass rate is reported as it is (in the section, not
  as a target).

Efficiency = travelled / (max_linear_speed x time armed before the deadline stop): 1.0 would be driving
straight at full speed the whole time. :func:`bt_nav.cli.grade.grade` spreads the runs over processes.
"""

from __future__ import annotations

import os
import time
from typing import Any

from bt_nav_sim.world import list_worlds

from bt_nav.grading.grid import grade, overall, summarize
from bt_nav.mission.params import MANEUVERS

from .common import Target, at_least

#: grid name -> (profile, kinematics)
GRIDS: dict[str, tuple[str, str]] = {"ideal": ("homework", "ideal"), "burger": ("turtlebot3", "burger")}
TARGET_PASS_RATE = 0.98
TARGET_CELL_PASSES = 18 / 20
TARGET_EFFICIENCY_MEDIAN = 0.97
TARGET_EFFICIENCY_WORST = 0.90


def _grid(profile: str, kinematics: str, seeds: int, jobs: int) -> dict[str, Any]:
    worlds = list_worlds()
    started = time.perf_counter()
    rows = grade(worlds, MANEUVERS, seeds, jobs=jobs, profile=profile, kinematics=kinematics)
    wall = time.perf_counter() - started
    summary = summarize(rows)
    for line in summary:
        runs = [r for r in rows if r["world"] == line["world"] and r["maneuver"] == line["maneuver"]]
        line["efficiency_worst_seed"] = min(runs, key=lambda r: r["efficiency"])["seed"]
        line["errors"] = [r.get("error") for r in runs if "error" in r]
    return {"profile": profile, "kinematics": kinematics, "worlds": worlds, "maneuvers": list(MANEUVERS),
            "seeds": seeds, "missions": len(rows), "wall_s": round(wall, 1), "overall": overall(rows, summary),
            "summary": summary}


def run(quick: bool = False, jobs: int | None = None) -> dict[str, Any]:
    """Both grids (20 seeds, 2 when quick) and their summaries."""
    seeds = 2 if quick else 20
    jobs = jobs or max(1, os.cpu_count() or 1)
    return {"jobs": jobs, "grids": {name: _grid(profile, kinematics, seeds, jobs)
                                    for name, (profile, kinematics) in GRIDS.items()}}


def targets(result: dict[str, Any]) -> list[Target]:
    """Issue 11's targets: the ideal grid's pass rates and efficiency, no collision in either grid."""
    out: list[Target] = []
    ideal = result["grids"].get("ideal")
    if ideal:
        total, summary = ideal["overall"], ideal["summary"]
        worst_cell = min((s["pass_rate"] for s in summary), default=None)
        out += [
            Target("ideal_pass_rate", "quality", f"ideal kinematics: runs passed ({total['runs']} missions)",
                   ">= 98 %", round(100 * total["pass_rate"], 2), "%", total["pass_rate"] >= TARGET_PASS_RATE),
            Target("ideal_worst_cell", "quality", "ideal kinematics: worst world x maneuver cell pass rate",
                   ">= 90 % (18/20)", None if worst_cell is None else round(100 * worst_cell, 1), "%",
                   None if worst_cell is None else worst_cell >= TARGET_CELL_PASSES - 1e-9),
            Target("ideal_efficiency_median", "quality", "ideal kinematics: median distance efficiency", ">= 0.97",
                   round(total["efficiency_median"], 4), "", at_least(total["efficiency_median"],
                                                                       TARGET_EFFICIENCY_MEDIAN)),
            Target("ideal_efficiency_worst", "quality", "ideal kinematics: worst distance efficiency", ">= 0.90",
                   round(total["efficiency_worst"], 4), "", at_least(total["efficiency_worst"],
                                                                      TARGET_EFFICIENCY_WORST)),
        ]
    for name, grid in result["grids"].items():
        total = grid["overall"]
        out.append(Target(f"{name}_collisions", "quality", f"{name} kinematics ({grid['profile']} profile): "
                          f"collisions over {total['runs']} missions", "0", total["collisions"], "",
                          total["collisions"] == 0))
    return out
