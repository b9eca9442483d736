"""The grade-speed benchmark's pairing (bench.grade_speed.paired): the ratio of the sides' medians over alternating
pairs, the median grade of each side for the table, every pair's verdicts compared."""

from __future__ import annotations

from typing import Any

from bench.grade_speed import paired


def _grade(wall: float, passed: dict[str, bool]) -> dict[str, Any]:
    return {"wall_s": wall, "verdicts": {run: {"passed": ok, "decision": "kept"} for run, ok in passed.items()}}


def test_three_pairs_give_the_ratio_of_the_medians_and_every_difference() -> None:
    same = {"a": True, "b": False}
    repeats = [{"before": _grade(60.0, same), "after": _grade(35.0, same)},
               {"before": _grade(56.0, same), "after": _grade(40.0, {"a": True, "b": True})},
               {"before": _grade(70.0, same), "after": _grade(33.0, same)}]
    result = paired(repeats)
    assert result["after_over_before"] == round(35.0 / 60.0, 3)  # not a pair's ratio: 35/60, 40/56, 33/70
    assert result["before"]["wall_s"] == 60.0 and result["after"]["wall_s"] == 35.0
    assert result["comparison"]["measured"] and not result["comparison"]["identical"]
    assert result["comparison"]["differences"] == [{"run": "b", "before": False, "after": True}]
    assert [p["after_s"] for p in result["pairs"]] == [35.0, 40.0, 33.0]


def test_a_grade_without_a_wall_time_leaves_the_ratio_unmeasured() -> None:
    repeats = [{"before": _grade(60.0, {"a": True}), "after": {"error": "crashed"}}]
    result = paired(repeats)
    assert "after_over_before" not in result and not result["comparison"]["measured"]
