"""A student's ``feedback.md`` says how a preview's failed run went when graded again at 1x (whose verdict it is),
and a run that was not graded is named as such, not as the node's failure."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav.grading.exe.realtime import not_real_time
from bt_nav.grading.feedback import feedback_markdown
from bt_nav.grading.handins import StudentResult


def _row(passed: bool, side: str, angle: float, where: str) -> dict[str, Any]:
    return {"job": "k", "world": "lab_object", "maneuver": "A", "lidar": "lds01", "seed": 0, "passed": passed,
            "outcome": "verdict", "reason": "passed" if passed else f"failed: maneuver 1 turned {angle:.0f} deg {side}",
            "findings": [], "run_dir": f"/{where}/0",
            "verdict": {"maneuvers": [{"t": 10.0, "settled": 12.0, "side": side, "passed": passed,
                                       "angle_deg": angle if side == "left" else -angle}]}}


def test_feedback_says_how_a_preview_failure_went_at_real_time(tmp_path: Path) -> None:
    row = {**_row(True, "left", 135.0, "realtime"),
           "preview": {"rtf": 9.3, "reason": "failed: maneuver 1 turned 60 deg right", "run_dir": "/fast/0"}}
    text = feedback_markdown(StudentResult("cara", tmp_path, "node.py", "A", None, [row], None, True))
    assert ("  - in the preview (at 9.3x) it failed (failed: maneuver 1 turned 60 deg right); graded again at 1x "
            "real time it passed") in text.splitlines()


def test_a_run_behind_real_time_twice_is_not_graded_not_failed(tmp_path: Path) -> None:
    row = not_real_time(_row(False, "right", 60.0, "again"), "its simulator fell behind real time")
    text = feedback_markdown(StudentResult("dan", tmp_path, "node.py", "A", None, [row], None, False))
    runs = [line for line in text.splitlines() if line.startswith("- **lab_object")]
    assert runs == [f"- **lab_object A lds01 seed 0: not graded (not yours)** ({row['reason']})"], text
    assert row["unkept"]["reason"] == "failed: maneuver 1 turned 60 deg right"
