"""bench/judge_agreement.py (``make judge-agreement``): one lock-step lab run with the real-robot effects, judged
from ground truth and from odometry alone, and the comparison that would report a disagreement."""

from __future__ import annotations

from bench.judge_agreement import compare, run_once, table


def test_one_run_is_judged_twice_and_agrees() -> None:
    row = run_once("lab_object", "C", 0)
    assert row.truth and row.odometry and row.maneuvers and not row.unmatched
    assert all(a == b and angle <= 3.0 and move <= 0.02 for a, b, angle, move in row.maneuvers), row.maneuvers
    assert "| 1 | 1 (100.0 %) | 0 |" in table([row], 1.0)


def _verdict(passed: bool, angle: float, t: float = 3.0) -> dict:
    m = {"t": t, "passed": passed, "angle_deg": angle, "forward_motion": 0.0}
    return {"passed": passed, "checks": [{"name": "maneuver 1", "passed": passed}], "maneuvers": [m],
            "judged_maneuvers": [m], "not_judged": [], "feed": {"t0": 10.0}}


def test_an_odometry_pass_of_a_ground_truth_failure_is_listed_with_its_cause() -> None:
    row = compare("cell", _verdict(False, 70.0), _verdict(True, 85.0, t=3.2), truth_t0=10.0)
    assert row.odometry and not row.truth and row.cause.startswith("ground truth fails maneuver 1")
    assert row.maneuvers == [(False, True, 15.0, 0.0)]
    text = table([row], 1.0)
    assert "| 1 | 0 (0.0 %) | 1 |" in text and "| cell | FAILED | PASSED | ground truth fails maneuver 1 |" in text
    shifted = compare("cell", _verdict(True, 90.0), _verdict(True, 90.0), truth_t0=0.0)  # another clock: 10 s apart
    assert shifted.unmatched == 1 and not shifted.maneuvers
