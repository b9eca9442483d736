"""The advice a student reads, per kind of failure (issue 54): keyed on what failed, true for any node, accepting any
method the sheet allows (no advice against timed turns), and the rule beside a failure is that failure's."""

from __future__ import annotations

import re

import pytest

from bt_nav.grading import hints
from bt_nav.grading.grid import maneuvers_text
from bt_nav.judge.checkoff_core import MANEUVERS
from bt_nav.judge.checkoff_words import ANGLE, FORWARD, LATE, SIDE, STILL_TURNING, TRIGGER, maneuver_check

AGAINST_TIMING = re.compile(r"rather than tim|instead of tim|not tim|never tim|don't tim|avoid tim|stop tim|"
                            r"measured from odometry", re.IGNORECASE)
KINDS = (TRIGGER, LATE, ANGLE, SIDE, STILL_TURNING, FORWARD)


def every_advice() -> list[str]:
    """Every piece of advice the grader can give: per check, per maneuver and kind, per finding, per ending."""
    said = [*hints.CHECK_HINTS.values(), *hints.LAUNCH_HINTS.values(), *hints.FINDING_HINTS.values(),
            *(h for _, h in hints.ENDING_HINTS), hints.not_graded_hint("fell behind real time")]
    said += [hints.kind_advice(kind, m) or "" for m in MANEUVERS for kind in KINDS]
    return said


def test_no_advice_tells_a_student_to_stop_timing_turns() -> None:
    said = every_advice()
    assert len(said) > 30 and all(said)
    assert [s for s in said if AGAINST_TIMING.search(s)] == []
    angle = hints.kind_advice(ANGLE, "C") or ""
    assert "a turn timed at the rate you command" in angle and "odometry" in angle, angle


def _episode(**changes: object) -> dict:
    e = {"t": 3.0, "t0": 0.0, "trigger": True, "trigger_detail": "left 0.42 m and right 0.94 m < 0.5 m",
         "angle_deg": 181.0, "side": "left", "angle_ok": True, "rule": "180 +- 10 deg either side", "size_ok": True,
         "trigger_rule": "held: left and right < 0.5 m by any of ...", "forward_command": 0.0,
         "forward_motion": 0.0, "forward_ok": True, "moved_on": True, "moved_on_detail": "travelled 0.10 m",
         "swung_deg": 0.0, "readings": {"front": 1.0, "left": 0.42, "right": 0.94}, "passed": False}
    e.update(changes)
    return e


@pytest.mark.parametrize(("changes", "kind", "rule", "advice"), [
    ({"trigger": False}, TRIGGER, "held: left and right", "turn only when the sheet's trigger holds: the left sector "
                                                          "AND the right sector"),
    ({"angle_ok": False, "size_ok": False, "angle_deg": 120.0}, ANGLE, "180 +- 10 deg", "turn by 180 +- 10 deg."),
    ({"forward_ok": False, "forward_command": 0.05, "forward_motion": 0.1}, FORWARD, "no forward command",
     "send `linear.x = 0`"),
])
def test_a_maneuver_failure_gets_its_own_kind_rule_and_advice(changes: dict, kind: str, rule: str,
                                                             advice: str) -> None:
    """The judge names the fault's kind and the rule it broke; the advice is keyed on the kind."""
    check = maneuver_check(1, "B", _episode(**changes))
    assert check["kinds"] == [kind] and hints.check_rule(check).startswith(rule), check
    assert hints.check_hints(check, "B")[0].startswith(advice), hints.check_hints(check, "B")


def test_a_side_and_a_turn_never_ended_are_told_apart_from_the_angle() -> None:
    side = maneuver_check(1, "C", _episode(angle_ok=False, size_ok=True, angle_deg=92.0, rule="90 +- 10 deg right"))
    assert side["kinds"] == [SIDE] and "towards the side with more room" in hints.check_hints(side, "C")[0]
    never = maneuver_check(1, "C", _episode(angle_ok=False, size_ok=False, angle_deg=456.0,
                                            rule="90 +- 10 deg right, and it was still turning at the disarm"))
    assert never["kinds"] == [STILL_TURNING] and hints.check_hints(never, "C")[0].startswith("end the turn")


def test_a_grade_written_before_the_kinds_is_read_from_its_words() -> None:
    old = {"name": "maneuver 1", "passed": False, "required": "180 +- 10 deg either side",
           "reason": "maneuver 1 turned although its trigger did not hold (left 0.42 m ...)"}
    assert hints.check_kinds(old) == [TRIGGER]
    assert hints.check_kinds({"name": "creep while armed", "passed": False}) == ["creep while armed"]


def test_a_run_not_graded_says_what_the_grader_could_not_do() -> None:
    said = hints.not_graded_hint("not graded: another program is on ROS_DOMAIN_ID 7: ...")
    assert said.startswith("the grader could not keep the run's ROS domain to itself") and "not your node's" in said


def test_the_header_names_the_maneuver_chosen() -> None:
    assert maneuvers_text([{"maneuver": "C"}, {"maneuver": "C"}]) == "maneuver C"
    assert maneuvers_text([{"maneuver": "none"}]) == ""
    assert maneuvers_text([{"maneuver": "A"}, {"maneuver": "C"}]) == "maneuvers A, C"
