"""A student's ``feedback.md`` says how each re-run of a failed run ended (issue 44: it used to say nothing of them),
and a run that was not graded is named as such, not as the node's failure."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav.grading import realtime
from bt_nav.grading.feedback import feedback_markdown
from bt_nav.grading.handins import StudentResult


def _row(passed: bool, side: str, angle: float, where: str) -> dict[str, Any]:
    return {"job": "k", "world": "lab_object", "maneuver": "A", "lidar": "lds01", "seed": 0, "passed": passed,
            "outcome": "verdict", "reason": "passed" if passed else f"failed: maneuver 1 turned {angle:.0f} deg {side}",
            "findings": [], "run_dir": f"/{where}/0",
            "verdict": {"maneuvers": [{"t": 10.0, "settled": 12.0, "side": side, "passed": passed,
                                       "angle_deg": angle if side == "left" else -angle}]}}


def test_feedback_says_how_each_rerun_ended(tmp_path: Path) -> None:
    fast = _row(False, "right", 60.0, "fast")
    row, said = realtime.decide(fast, _row(True, "left", 135.0, "again"), _row(True, "left", 120.0, "slow"), 5.0, None)
    text = feedback_markdown(StudentResult("cara", tmp_path, "node.py", "A", None, [row], None, False))
    assert f"  - run again: {said}" in text.splitlines()
    assert "run again at 5x: passed; at 1x: passed: the runs differed" in text and "the failure stands" in text


def test_feedback_of_a_rerun_that_overturned_a_failure_says_it_as_its_finding(tmp_path: Path) -> None:
    fast = _row(False, "left", 114.0, "fast")
    slip = "the simulator stopped waiting for the node's commands at t=11.0 s, inside maneuver 1"
    row, said = realtime.decide(fast, _row(True, "left", 91.0, "again"), None, 5.0, slip)
    text = feedback_markdown(StudentResult("dan", tmp_path, "node.py", "A", None, [row], None, True))
    assert f"  - finding: {said}" in text.splitlines()  # the finding (and the reason, as every finding) says it
    assert not any(line.startswith("  - run again:") for line in text.splitlines())
