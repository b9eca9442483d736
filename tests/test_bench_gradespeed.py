"""The grade-speed benchmark's logic (bench.grade_speed, issue 52), without a grade: the pairing (the sides' medians
over alternating pairs, every pair's verdicts compared, a class's wrong ones apart), what a row says beyond one
attempt and its simulated seconds, the targets and the table."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bench.grade_speed import CORRECT_WALL_S, GRID, compare, decision, grid, markdown, paired, sim_seconds, targets


def _grade(wall: float, passed: dict[str, bool], **extra: Any) -> dict[str, Any]:
    return {"wall_s": wall, "runs": len(passed), "passed": sum(passed.values()),
            "verdicts": {run: {"passed": ok, "decision": None} for run, ok in passed.items()}, **extra}


def _runs(n: int, ok: bool = True) -> dict[str, bool]:
    return {f"job{i}": ok for i in range(n)}


def _class(wall: float, right_ok: bool, wrong_ok: bool) -> dict[str, Any]:
    passed = {"right_plain/j": True, "right_scan_only/j": right_ok, "wrong_side/j": wrong_ok}
    students = {"right_plain": True, "right_scan_only": right_ok, "wrong_side": wrong_ok}
    return _grade(wall, passed, student_verdicts=students, students=3)


def test_the_grid_is_each_sides_default_for_c_and_quick_narrows_it() -> None:
    assert "--worlds" not in GRID and "--rtf" not in grid(False) and grid(False) == list(GRID)
    assert grid(True)[-4:] == ["--lidars", "lds01", "--seeds", "1"]


def test_three_pairs_give_the_medians_their_ratio_and_every_difference() -> None:
    same = {"a": True, "b": False}
    repeats = [{"before": _grade(60.0, same), "after": _grade(35.0, same)},
               {"before": _grade(56.0, same), "after": _grade(40.0, {"a": True, "b": True})},
               {"before": _grade(70.0, same), "after": _grade(33.0, same)}]
    result = paired(repeats)
    assert (result["before_median_s"], result["after_median_s"]) == (60.0, 35.0)
    assert result["after_over_before"] == round(35.0 / 60.0, 3)  # not a pair's ratio: 35/60, 40/56, 33/70
    assert result["before"]["wall_s"] == 60.0 and result["after"]["wall_s"] == 35.0
    assert result["comparison"]["measured"] and not result["comparison"]["identical"]
    assert result["comparison"]["differences"] == [{"run": "b", "before": False, "after": True}]
    assert [p["after_s"] for p in result["pairs"]] == [35.0, 40.0, 33.0] and "focus" not in result


def test_runs_only_one_side_graded_are_apart_not_differences() -> None:
    """The after side's default grid may have gained a cell: its runs are listed, never counted as a difference."""
    result = compare(_grade(30.0, {"a": True}), _grade(50.0, {"a": True, "slant": False}))
    assert result["identical"] and result["only_after"] == ["slant"] and result["only_before"] == []
    assert not compare(_grade(30.0, {"a": True}), _grade(50.0, {"slant": True}))["measured"]


def test_a_grade_without_a_wall_time_or_with_an_error_leaves_the_side_unmeasured() -> None:
    result = paired([{"before": _grade(60.0, {"a": True}), "after": {"error": "crashed"}}])
    assert "after_over_before" not in result and "after_median_s" not in result
    assert not result["comparison"]["measured"]
    stopped = paired([{"before": _grade(60.0, {"a": True}), "after": _grade(1200.0, {"a": True}, error="stopped")}])
    assert "after_median_s" not in stopped and stopped["before_median_s"] == 60.0


def test_a_class_compares_its_wrong_ones_apart_from_the_right_ones() -> None:
    result = paired([{"before": _class(700.0, right_ok=False, wrong_ok=False),
                      "after": _class(500.0, right_ok=True, wrong_ok=False)}], "wrong_")
    assert not result["comparison"]["identical"]  # a right one failed before and passes now: information
    assert result["focus"]["identical"] and result["focus"]["differences"] == []
    turned = paired([{"before": _class(700.0, True, False), "after": _class(500.0, True, True)}], "wrong_")
    assert turned["focus"]["differences"] == [{"run": "wrong_side/j", "before": False, "after": True}]
    result = {"grid_runs": {"before": 1, "after": 1}, "scenarios": {"class": turned}}
    wrong = {t.id: t for t in targets(result)}["gradespeed_class_wrong_verdicts"]
    assert wrong.value == 2 and wrong.met is False  # its one run, and the hand-in's own verdict


def test_what_happened_beyond_one_attempt_is_read_from_both_commits_rows() -> None:
    assert decision({"passed": True}) is None
    assert decision({"not_graded": "not graded: fell behind, twice"}) == "not graded"
    assert decision({"notes": ["run again: its first run (x): fell behind"]}) == "run again"
    assert decision({"preview": {"rtf": 0.0, "said": "passed in the preview"}}) is None
    assert decision({"preview": {"rtf": 4.0, "reason": "turned 80 deg"}}) == "preview failed, 1x"
    assert decision({"rerun": {"decision": "wall clock"}}) == "wall clock"  # b6541ee's re-runs


def test_simulated_seconds_come_from_the_row_else_the_runs_pace_file(tmp_path: Path) -> None:
    assert sim_seconds({"speed": {"set": 1.0, "sim_s": 41.5}}, tmp_path) == 41.5
    run_dir = tmp_path / "lab_beside_C_0"
    run_dir.mkdir()
    (run_dir / "pace.json").write_text(json.dumps({"t_end": 38.25, "wall_s": 39.0}), encoding="utf-8")
    assert sim_seconds({"run_dir": str(run_dir)}, tmp_path) == 38.25
    assert sim_seconds({"run_dir": "lab_beside_C_0"}, tmp_path) == 38.25  # relative to the grade's --out
    assert sim_seconds({"run_dir": ""}, tmp_path) is None and sim_seconds({"run_dir": "gone"}, tmp_path) is None


def _result(correct_after: list[float], runs: int = 12) -> dict[str, Any]:
    repeats = [{"before": _grade(30.0, _runs(runs)), "after": _grade(wall, _runs(runs), sim_s_max=45.0,
                                                                       sim_s_median=40.0)}
               for wall in correct_after]
    wall_after = _grade(80.0, {**_runs(11), "late": False})
    return {"grid_runs": {"before": 12, "after": 12},
            "class": {"right_plain": [], "right_scan_only": [], "wrong_side": []}, "scenarios": {
        "correct": paired(repeats),
        "wallclock": paired([{"before": _grade(300.0, _runs(12)), "after": wall_after}]),
        "class": paired([{"before": _class(700.0, True, False), "after": _class(650.0, True, False)}], "wrong_")}}


def test_the_targets_of_issue_52() -> None:
    found = {t.id: t for t in targets(_result([58.0, 64.0, 55.0]))}
    assert found["gradespeed_correct_s"].value == 58.0 and found["gradespeed_correct_s"].met is True
    assert found["gradespeed_class_ratio"].value == round(650.0 / 700.0, 3) and found["gradespeed_class_ratio"].met
    assert found["gradespeed_class_wrong_verdicts"].value == 0 and found["gradespeed_class_wrong_verdicts"].met
    assert found["gradespeed_class_right_passing"].value == 2 and found["gradespeed_class_right_passing"].met
    assert found["gradespeed_wallclock_failed"].value == 1 and found["gradespeed_wallclock_failed"].met is False
    slow = {t.id: t for t in targets(_result([61.0, 64.0, 70.0]))}["gradespeed_correct_s"]
    assert slow.value == 64.0 and slow.met is False and f"<= {CORRECT_WALL_S:g} s" == slow.goal


def test_a_grade_of_other_runs_than_the_grids_measures_nothing() -> None:
    found = {t.id: t for t in targets(_result([40.0], runs=2))}
    assert found["gradespeed_correct_s"].value is None and found["gradespeed_correct_s"].met is None


def test_unrun_scenarios_are_unmeasured_targets() -> None:
    result = _result([40.0])
    del result["scenarios"]["class"], result["scenarios"]["wallclock"]
    found = {t.id: t for t in targets(result)}
    assert found["gradespeed_correct_s"].met is True
    assert all(found[name].met is None for name in ("gradespeed_class_ratio", "gradespeed_class_wrong_verdicts",
                                                     "gradespeed_class_right_passing", "gradespeed_wallclock_failed"))


def test_the_table_says_the_simulated_share_and_the_class_apart() -> None:
    result = _result([50.0])
    result["grid"], result["node"] = list(GRID), "node.py"
    text = "\n".join(markdown(result))
    assert "45.0 / 40.0" in text and "| 0.9 |" in text  # the longest run's 45 sim s of a 50 s grade
    assert "90 % of its 50.0 s wall" in text
    assert "the wrong hand-ins' run verdicts: identical; right hand-ins passing after: 2/2" in text
