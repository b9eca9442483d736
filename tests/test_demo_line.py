"""``bt-nav demo``'s maneuver count line: a count of 0 says which trigger did not fire (the README's demo, stage_4
with maneuver C, fires none: the close / far driving turns away before the front is 0.30 m near)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli.demo import _robot_files, trigger_words
from bt_nav.mission.params import defaults


class _Rec:
    """What _robot_files reads of a recording."""

    def __init__(self, maneuvers: dict[str, int]) -> None:
        self.maneuvers, self.foreign_truth = maneuvers, 0

    def mission_trajectory(self, verdict: dict[str, Any]) -> tuple[None, dict[str, Any]]:
        return None, {}


def _line(tmp_path: Path, capsys: pytest.CaptureFixture, maneuver: str, fired: dict[str, int]) -> str:
    run = {"names": ["robot1"], "results": {"robot1": str(tmp_path / "results.json")}, "run_dir": tmp_path,
           "maneuver": maneuver, "parameters": defaults()}
    _robot_files(run, "robot1", _Rec(fired))
    return capsys.readouterr().out.strip()


def test_a_zero_count_names_the_trigger_that_did_not_fire(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    line = _line(tmp_path, capsys, "C", {})
    assert line == ("bt-nav demo: maneuvers fired: 0 (maneuver C, counted from the tree): its trigger, the front "
                    "(+-20 deg) nearer than pivot_distance 0.30 m, did not fire in this run (the close / far driving "
                    "steers away from obstacles, often before they are that near)")
    assert _line(tmp_path, capsys, "none", {}).endswith("(maneuver none, counted from the tree)")
    fired = _line(tmp_path, capsys, "C", {"Maneuver.SmartPivot": 1})
    assert fired.endswith("maneuvers fired: 1 (SmartPivot x1) (maneuver C, counted from the tree)")


def test_the_trigger_words_follow_the_parameters() -> None:
    values = {**defaults(), "safety_distance": 0.6}
    assert trigger_words("A", values) == "the front (+-20 deg) nearer than safety_distance 0.60 m"
    assert trigger_words("B", values) == "left and right both nearer than safety_distance 0.60 m"
