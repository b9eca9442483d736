"""The lab's check-off in a run: which judge a lab run gets, and how far each maneuver landed from its angle.

Why here: a lock-step run of the ``lab`` profile is judged by the lab's check-off judge
(:class:`bt_nav.judge.checkoff_core.CheckoffJudge`), not by the homework's referee, and grading wants to know, per
maneuver, the angle the executive chose (its maneuver event: :mod:`bt_nav.mission.snapshot`, ``side`` and
``angle_deg``, the whole degrees its log line ``Randomizer: front 0.49 m: turning right 143 deg`` says)
against the angle the robot really turned (the judge measures it on ground truth, at rest). Both lock-step
and grading use these, so they live once, in the run layer.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from bt_nav_sim.truth import truth_feed
from bt_nav_sim.world import World

from bt_nav.judge.checkoff_core import MANEUVERS, CheckoffConfig, CheckoffJudge

#: s: an announcement this long before a judged turn's first turning command is that turn's (the still
#: before a lagging turn is latency + 0.1 s; a repeated maneuver follows its predecessor at once).
MATCH_WINDOW = 1.0


def lab_judge(maneuver: str, world: World, config: CheckoffConfig | None = None, lidar: str = ""
              ) -> Callable[[int, str], CheckoffJudge]:
    """A referee factory (index, name) -> the check-off judge of ``maneuver`` fed the simulator's truth in
    ``world`` (the simulator's own object, which reveals appearing objects itself), reading along the robot's
    ``lidar``."""
    if maneuver not in MANEUVERS:
        raise ValueError(f"the lab's check-off judges maneuver A, B or C, not {maneuver!r}")
    cfg = config or CheckoffConfig(maneuver=maneuver, lidar=lidar)

    def make(_index: int, _name: str) -> CheckoffJudge:
        return CheckoffJudge(cfg, truth_feed(cfg, world, update_world=False))

    return make


def announced_turns(announcements: Sequence[dict[str, Any]]) -> list[tuple[float, float]]:
    """(sim time, signed degrees, + = left) of every maneuver the executive announced (its maneuver events)."""
    return [(float(e["t"]), float(e["angle_deg"]) * (1.0 if e["side"] == "left" else -1.0))
            for e in announcements if e.get("event") == "maneuver"]


def angle_errors(announcements: Sequence[dict[str, Any]], judged: Sequence[dict[str, Any]]) -> list[float]:
    """Degrees between each judged maneuver's true angle and the angle announced for it (turns the disarm
    cut short, and turns with no announcement within :data:`MATCH_WINDOW`, have none)."""
    announced = announced_turns(announcements)
    errors = []
    for turn in judged:
        if turn.get("kind") != "maneuver" or turn.get("interrupted"):
            continue
        mine = [deg for t, deg in announced if turn["t"] - MATCH_WINDOW <= t <= turn["t"] + 1e-6]
        if mine:
            errors.append(round(turn["angle_deg"] - mine[-1], 2))
    return errors


def checkoff_summary(results: dict[str, Any], announcements: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The check-off's figures for a grid cell: judged maneuvers, how many obeyed their rule, recovery
    turns, and the angle errors against the announced angles."""
    judged = results.get("maneuvers", [])
    return {"maneuvers": len(judged), "angles_ok": sum(1 for m in judged if m.get("angle_ok")),
            "recoveries": len(results.get("recovery_turns", [])), "angle_errors": angle_errors(announcements, judged)}
