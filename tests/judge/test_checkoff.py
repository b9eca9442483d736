"""The lab's check-off judge on synthetic runs: a tiny kinematic driver plays a command script in a small
world, feeding the judge commands (20 Hz), ground truth (~33 Hz) and the schedule's service calls."""

from __future__ import annotations

import math
import re

import pytest
from bt_nav_sim.world import world_from_dict

from bt_nav.judge.checkoff_core import CheckoffConfig, CheckoffJudge
from tests.judge.truthkit import truth_judge

DT = 0.01  # physics step of the synthetic driver
ROOM = [[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]]


def _world(*segments: list[float]):
    return world_from_dict({"name": "test", "segments": ROOM + list(segments)})


def _run(judge: CheckoffJudge, script: list[tuple[float, float, float]], *, start=(0.0, 0.0, 0.0),
         collide_at: float | None = None, end: float = 40.0,
         between: tuple[float, float] | None = None, accel: float | None = None) -> CheckoffJudge:
    """Play ``script`` ((seconds, v, w), each started at once; the robot follows its command instantly)
    from t = 0 until the judge reports. Commands are published every 0.05 s from t = 0; with ``between``, a
    second publisher of the node sends that command 0.02 s after each turning one (and the robot follows it); with
    ``accel`` (rad/s^2) the turn rate follows the command at most that fast (the Burger's 10 rad/s^2)."""
    x, y, yaw = start
    judge.start(0.0)
    timeline, t_at = [], 0.0
    for seconds, v, w in script:
        timeline.append((t_at, v, w))
        t_at += seconds
    cmd, rate = (0.0, 0.0), 0.0
    for k in range(round(end / DT) + 1):
        t = k * DT
        if k % 50 == 0:  # 2 Hz
            for action in judge.step(t):
                judge.on_activate_result(t, action.data, True)
        if judge.done:
            break
        if k % 5 == 0:  # 20 Hz commands
            cmd = next(((v, w) for t0, v, w in reversed(timeline) if t0 <= t + 1e-9), (0.0, 0.0))
            judge.on_command(t, *cmd)
        if between is not None and k % 5 == 2 and abs(cmd[1]) > 0.0 and cmd != between:
            judge.on_command(t, *between)
            cmd = (between[0], cmd[1])
        if k % 3 == 0:
            judge.observe(t, x, y, yaw)
        if collide_at is not None and abs(t - collide_at) < DT / 2:
            judge.on_collision(t, x, y)
        v, w = cmd
        if accel is not None:
            rate = w = rate + max(-accel * DT, min(accel * DT, w - rate))
        x += v * DT * math.cos(yaw)
        y += v * DT * math.sin(yaw)
        yaw = math.remainder(yaw + w * DT, 2 * math.pi)
    assert judge.done
    return judge


def _cfg(maneuver: str, **kw) -> CheckoffConfig:
    """Armed at 5 s (the scripts are timed to it), disarm at 25 s, report at 29 s; no toggle cycle unless asked (the
    scripts play on whatever the judge calls: the cycle's own tests, in test_checkoff_chains.py, play a node that obeys
    it; the run as long as its checks need, in test_checkoff_schedule.py)."""
    return CheckoffConfig(**{"maneuver": maneuver, "activate_at": 5.0, "armed_for": 20.0, "toggle_off_for": 0.0, **kw})


def _line(judge: CheckoffJudge, prefix: str) -> str:
    return next(line for line in judge.report_lines() if line.startswith(prefix))


WALL_AHEAD = [1.0, -2.0, 1.0, 2.0]  # a wall across the room 1 m ahead of the spawn
# creep 10.2 s at 0.05 m/s from t = 5: x = 0.51, front 0.49 m < 0.5 m
A_SCRIPT = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (2.0, 0.0, 1.0), (7.8, 0.05, 0.0), (10.0, 0.0, 0.0)]


def test_a_correct_randomizer_passes() -> None:
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), A_SCRIPT)
    assert judge.passed, judge.report_lines()
    res = judge.results()
    (m,) = res["maneuvers"]
    assert m["angle_deg"] == pytest.approx(math.degrees(2.0), abs=1.0) and m["side"] == "left"
    assert m["readings"]["front"] == pytest.approx(0.49, abs=0.01)
    assert res["travelled"] == pytest.approx(0.05 * 18.0, abs=0.02)
    assert res["collisions"] == 0 and res["done"]
    names = [c["name"] for c in res["checks"]]
    assert names == ["static before activation", "toggle_navigation answered", "maneuvers performed",
                     "maneuver 1", "creep while armed", "no collision", "static after deactivation"]
    assert judge.report_lines()[-1] == "overall: PASSED"
    line = _line(judge, "maneuver 1")
    assert line.endswith(": PASSED") and "front 0.49 m < 0.5 m (+0.05 m sensor-noise tolerance)" in line


def test_a_correct_retreat_passes() -> None:
    """B in a dead-end passage 0.7 m wide: squeezed from the start, a 180 deg spin, out again."""
    world = _world([-1.5, 0.35, 1.5, 0.35], [-1.5, -0.35, 1.5, -0.35], [1.5, -0.35, 1.5, 0.35])
    script = [(5.0, 0.0, 0.0), (3.0, 0.05, 0.0), (math.pi / 1.2 + 0.01, 0.0, -1.2), (5.0, 0.05, 0.0),
              (20.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("B"), world), script)
    assert judge.passed, judge.report_lines()
    (m,) = judge.results()["maneuvers"]
    assert abs(m["angle_deg"]) == pytest.approx(180.0, abs=3.0) and m["side"] == "right"
    assert "left 0.35 m and right 0.35 m < 0.5 m (+0.05 m sensor-noise tolerance)" in _line(judge, "maneuver 1")


BOX_AHEAD = [1.0, -0.15, 1.0, 0.15]  # a 0.3 m box face 1 m ahead: unlike a wall, no side sector sees it
C_WORLD = _world(BOX_AHEAD, [0.0, -0.3, 1.0, -0.3])  # a wall on the right: the left has more room


def _c_script(w: float) -> list[tuple[float, float, float]]:
    # creep to x = 0.72 (front 0.28 m < 0.3 m), a 90 deg turn in 1.6 s, creep on
    return [(5.0, 0.0, 0.0), (14.4, 0.05, 0.0), (1.6, 0.0, w), (4.0, 0.05, 0.0), (10.0, 0.0, 0.0)]


def test_a_correct_smart_pivot_passes() -> None:
    judge = _run(truth_judge(_cfg("C"), C_WORLD), _c_script(math.pi / 2 / 1.6))
    assert judge.passed, judge.report_lines()
    (m,) = judge.results()["maneuvers"]
    assert m["angle_deg"] == pytest.approx(90.0, abs=2.0) and m["rule"] == "90 +- 10 deg left"


def test_a_smart_pivot_to_the_wrong_side_fails() -> None:
    judge = _run(truth_judge(_cfg("C"), C_WORLD), _c_script(-math.pi / 2 / 1.6))
    line = _line(judge, "maneuver 1")
    assert line.endswith("FAILED") and "turned 90 deg right, rule 90 +- 10 deg left" in line
    assert "the Smart Pivot needs 90 +- 10 deg left" in line and not judge.passed


def test_a_wrong_angle_fails() -> None:
    script = list(A_SCRIPT)
    script[2] = (1.0, 0.0, 1.0)  # 57 deg
    script[3] = (8.8, 0.05, 0.0)
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    line = _line(judge, "maneuver 1")
    assert "turned 57 deg left, rule 80-190 deg either side" in line
    assert "turned 57 deg left; the Randomizer needs 80-190 deg either side" in line
    assert judge.report_lines()[-1] == "overall: FAILED"


def test_forward_creep_during_a_turn_fails() -> None:
    script = list(A_SCRIPT)
    script[2] = (2.0, 0.02, 1.0)  # still a rotation episode (|v| <= 0.03), but it drives
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    line = _line(judge, "maneuver 1")
    assert "forward command 0.020 m/s" in line and line.endswith("FAILED")
    assert "drove forward during the turn (commanded up to 0.02 m/s, moved 0.03 m)" in line
    assert judge.results()["maneuvers"][0]["forward_motion"] > 0.01


def test_a_turn_without_its_trigger_fails() -> None:
    script = [(5.0, 0.0, 0.0), (2.0, 0.05, 0.0), (2.0, 0.0, 1.0), (16.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    line = _line(judge, "maneuver 1")
    assert "front 0.90 m < 0.5 m (+0.05 m sensor-noise tolerance) did not hold" in line
    assert ("turned although its trigger did not hold (front 0.90 m < 0.5 m (+0.05 m sensor-noise tolerance) "
            "is not true)") in line
    assert judge.results()["maneuvers"][0]["kind"] == "maneuver"


def test_a_collision_fails() -> None:
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), A_SCRIPT, collide_at=16.0)
    assert _line(judge, "no collision").startswith("no collision (1 collision, t=16.0 s")
    assert _line(judge, "no collision").endswith("FAILED") and judge.results()["collisions"] == 1
    assert not judge.passed


def test_motion_before_arming_and_after_disarm_fail() -> None:
    early = [(2.0, 0.0, 0.0)] + A_SCRIPT
    early[1] = (3.0, 0.05, 0.0)  # creeps from t = 2 s
    early[2] = (7.2, 0.05, 0.0)
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), early)
    assert _line(judge, "static before activation").endswith("FAILED")
    assert _line(judge, "static after deactivation").endswith("PASSED")
    late = A_SCRIPT[:3] + [(20.0, 0.05, 0.0)]  # never stops
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), late)
    assert _line(judge, "static before activation").endswith("PASSED")
    assert _line(judge, "static after deactivation").startswith("static after deactivation (peak 0.050 m/s")
    assert _line(judge, "static after deactivation").endswith("FAILED")


def test_no_maneuver_fails_and_no_move_on_is_a_finding_unless_strict() -> None:
    """Issue 52: the sheet asks for no moving on after the maneuver (a robot its brake stopped at a wall stands
    there), so standing after the turn is a finding; ``strict_findings`` moved_on makes it the maneuver's failure."""
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0)])
    assert _line(judge, "maneuvers performed (0 performed, required >= 1)").endswith("FAILED")
    stuck = A_SCRIPT[:3] + [(30.0, 0.0, 0.0)]  # turns, then stands still though armed for 8 more s
    judge = _run(truth_judge(_cfg("A", armed_for=30.0), _world(WALL_AHEAD)), stuck, end=45.0)
    line = _line(judge, "maneuver 1")
    assert "moved on: travelled 0.000 m in 10 s" in line and line.endswith("PASSED")
    res = judge.results()
    assert res["findings"] == ["maneuver 1 did not move on after the turn (travelled 0.000 m in 10 s): the sheet "
                               "asks for none, so it passed"]
    assert [f["kind"] for f in res["finding_kinds"]] == ["moved_on"]
    judge = _run(truth_judge(_cfg("A", armed_for=30.0, strict_findings="moved_on"), _world(WALL_AHEAD)), stuck,
                 end=45.0)
    line = _line(judge, "maneuver 1")
    assert "did not move on after the turn (travelled 0.000 m in 10 s)" in line and line.endswith("FAILED")
    assert judge.results()["findings"] == []


def test_an_emergency_stop_turn_is_a_recovery_not_a_maneuver() -> None:
    """B in an open room: the robot braked 0.3 m before a box (B's trigger cannot hold), stood 1 s and
    turns away: listed as a recovery turn, checked only for forward motion. Without the standstill the
    same turn is judged as a maneuver (whose trigger did not hold)."""
    unbraked = [(5.0, 0.0, 0.0), (14.0, 0.05, 0.0), (1.6, 0.0, 1.0), (4.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    res = _run(truth_judge(_cfg("B"), _world(BOX_AHEAD)), unbraked).results()
    assert len(res["maneuvers"]) == 1 and not res["maneuvers"][0]["trigger"]
    script = [(5.0, 0.0, 0.0), (14.0, 0.05, 0.0), (1.0, 0.0, 0.0), (1.6, 0.0, 1.0), (3.0, 0.05, 0.0),
              (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("B"), _world(BOX_AHEAD)), script)
    res = judge.results()
    assert res["maneuvers"] == [] and len(res["recovery_turns"]) == 1
    rec = res["recovery_turns"][0]
    assert rec["kind"] == "recovery" and rec["passed"] and rec["readings"]["ahead"] == pytest.approx(0.3, abs=0.01)
    assert _line(judge, "recovery turns (1 emergency-stop recovery turn, 0 with forward motion)").endswith("PASSED")
    assert _line(judge, "maneuvers performed").endswith("FAILED")


def test_no_evaluation_service_and_the_schedule() -> None:
    judge = truth_judge(_cfg("A"), _world(WALL_AHEAD))
    assert judge.on_evaluate(1.0) == (False, "the lab has no evaluation service")
    judge.start(10.0)
    assert judge.step(14.9) == []
    assert [a.data for a in judge.step(15.0)] == [True]
    judge.on_activate_result(15.0, True, False)  # failed: asked again
    assert [a.data for a in judge.step(15.5)] == [True]
    judge.on_activate_result(15.5, True, True)
    assert judge.step(16.0) == [] and judge.activated == 15.5
    assert [a.data for a in judge.step(35.0)] == [False]
    assert [a.data for a in judge.step(35.5)] == [False]  # until answered
    judge.on_activate_result(35.5, False, True)
    assert judge.step(36.0) == [] and not judge.done
    judge.step(39.4)  # the disarm took effect when answered (35.5): 1 s to brake, 3 s still from there
    assert not judge.done
    judge.step(39.5)
    assert judge.done and judge.results()["evaluation_calls"] == 1
    with pytest.raises(ValueError, match="maneuver"):
        CheckoffConfig(maneuver="D")


def test_a_smart_pivot_with_as_much_room_on_both_sides_may_turn_either_way() -> None:
    """Left 0.56 m and right 0.56 m (the wall ahead seen at +-60 deg): a tie, so a right turn passes."""
    judge = _run(truth_judge(_cfg("C"), _world(WALL_AHEAD)), _c_script(-math.pi / 2 / 1.6))
    assert judge.passed, judge.report_lines()
    assert judge.results()["maneuvers"][0]["rule"] == "90 +- 10 deg either side"


def test_a_brake_turn_where_the_trigger_holds_only_within_the_margin_is_a_recovery() -> None:
    """B beside walls 0.52 m away (the margin's 0.55 m says squeezed, the lab's 0.5 m does not), braked
    0.3 m before a wall: the executive's way out, judged as a recovery, not as a 180 deg Retreat."""
    world = _world(WALL_AHEAD, [-1.5, 0.52, 1.5, 0.52], [-1.5, -0.52, 1.5, -0.52])
    script = [(5.0, 0.0, 0.0), (14.0, 0.05, 0.0), (1.0, 0.0, 0.0), (1.6, 0.0, 1.0), (3.0, 0.05, 0.0),
              (10.0, 0.0, 0.0)]
    res = _run(truth_judge(_cfg("B"), world), script).results()
    assert res["maneuvers"] == [] and len(res["recovery_turns"]) == 1
    strict = _run(truth_judge(_cfg("B"), _world(WALL_AHEAD, [-1.5, 0.45, 1.5, 0.45],
                                                  [-1.5, -0.45, 1.5, -0.45])), script).results()
    assert len(strict["maneuvers"]) == 1 and not strict["maneuvers"][0]["angle_ok"]  # squeezed: B's rule applies


def test_a_maneuver_cut_short_by_the_disarm_is_not_judged_on_its_angle() -> None:
    """The disarm must stop a turn; the angle reached by then is no failure (its trigger still is judged)."""
    # creep to front 0.49 m at 15.2 s, turn left at 0.3 rad/s until the disarm at 25 s (9.8 s: 168 deg by then)
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (9.8, 0.0, 0.3), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    (m,) = judge.results()["maneuvers"]
    assert m["interrupted"] and m["passed"] and "interrupted by the disarm" in _line(judge, "maneuver 1")
    early = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (0.5, 0.0, 0.25), (19.3, 0.0, 0.0)]
    (m,) = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), early).results()["maneuvers"]
    assert not m["interrupted"] and not m["angle_ok"]  # stopped on its own, 7 deg: judged, failed


def test_a_turn_that_never_stops_fails_though_the_disarm_ends_it() -> None:
    """A node that, once turning, never stops: the disarm ends a turn that is already past A's 180 deg (280 deg
    by then), so its angle is judged, and the line says it was still turning."""
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (9.8, 0.0, 0.5), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    (m,) = judge.results()["maneuvers"]
    assert m["interrupted"] and not m["passed"] and not judge.passed
    assert "and it was still turning at the disarm" in _line(judge, "maneuver 1")


def test_a_trigger_acted_on_late_fails() -> None:
    """A node that ignores its safety_distance (here 0.6 m; it turns at 0.5 m): it crept 0.1 m on with its
    trigger holding, so the maneuver is late, and the line asks whether the parameter is read."""
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (math.pi / 2, 0.0, 1.0), (8.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A", safety_distance=0.6), _world(WALL_AHEAD)), script)
    (m,) = judge.results()["maneuvers"]
    assert m["late"] and m["crept_with_trigger"] >= 0.09 and not judge.passed
    assert re.search(r"turned late: triggered at front 0\.\d\d m with safety_distance 0\.\d0: "
                     r"it crept on 0\.1\d m over 2\.\d s", _line(judge, "maneuver 1"))
    on_time = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)  # its 0.5 m is the judge's: on time
    assert on_time.passed, on_time.report_lines()


def test_a_fast_creep_reacting_within_a_scan_is_not_late() -> None:
    """Creeping at 0.2 m/s (four times the template's), a node that turns 0.25 s after its trigger holds (its next
    5 Hz scan) has crept 5 cm: more than ``late_distance`` but in a reaction time no node can beat, so on time."""
    # creeping on until 24.4 s (the disarm at 25 s: no standstill while armed, the creep check)
    script = [(5.0, 0.0, 0.0), (2.8, 0.2, 0.0), (math.pi / 2, 0.0, 1.0), (15.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    (m,) = [e for e in judge.results()["maneuvers"] if e["kind"] == "maneuver"]
    assert m["crept_with_trigger"] >= 0.04 and m["trigger_held_for"] < 0.6, m
    assert not m.get("late") and judge.passed, judge.report_lines()


def test_forward_motion_while_turning_is_a_turn_judged_for_it() -> None:
    """Driving at the creep speed while turning 90 deg is still a turn, failed for its forward motion with the
    figures (it was once not found as a turn at all)."""
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (math.pi / 2 / 0.6, 0.05, 0.6), (8.0, 0.05, 0.0),
              (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script)
    (m,) = judge.results()["maneuvers"]
    assert not m["forward_ok"] and abs(abs(m["angle_deg"]) - 90) < 5
    assert "drove forward during the turn (commanded up to 0.05 m/s, moved 0.1" in _line(judge, "maneuver 1")
    steer = [(5.0, 0.0, 0.0), (3.0, 0.05, 0.15), (10.0, 0.05, 0.0), (10.0, 0.0, 0.0)]  # 26 deg: a steer? no: a turn
    gentle = [(5.0, 0.0, 0.0), (2.0, 0.05, 0.12), (10.0, 0.05, 0.0), (10.0, 0.0, 0.0)]  # 14 deg while driving
    assert _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), gentle).results()["maneuvers"] == []
    assert len(_run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), steer).results()["maneuvers"]) == 1


# ----------------------------------------------------------------------------------------- every reasonable reading
def test_a_smart_pivot_where_the_aeb_braked_at_safety_distance_passes_and_says_which_reading() -> None:
    """The sheet's C pivots at 0.3 m, its AEB brakes at safety_distance: a node that brakes at 0.5 m and pivots
    there is a reasonable reading and passes; the line says it was judged at either distance. A pivot 0.7 m
    from the box (neither reading) still did not hold."""
    brake_and_pivot = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (0.5, 0.0, 0.0), (1.6, 0.0, math.pi / 2 / 1.6),
                       (7.0, 0.05, 0.0), (10.0, 0.0, 0.0)]  # creeps on until 24.3 s (the creep check)
    judge = _run(truth_judge(_cfg("C"), C_WORLD), brake_and_pivot)
    assert judge.passed, judge.report_lines()
    assert "front 0.49 m < 0.5 m (+0.05 m sensor-noise tolerance)" in _line(judge, "maneuver 1")
    assert "the sheet's pivot_distance 0.30 m or safety_distance 0.50 m" in judge.config.trigger_rule()
    too_early = [(5.0, 0.0, 0.0), (6.0, 0.05, 0.0), (1.6, 0.0, math.pi / 2 / 1.6), (4.0, 0.05, 0.0),
                 (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("C"), C_WORLD), too_early)
    assert ("turned although its trigger did not hold (front 0.60 m < 0.5 m (+0.05 m sensor-noise tolerance) "
            "is not true)") in _line(judge, "maneuver 1")


@pytest.mark.parametrize("pause", [0.0, 0.5, 1.0, 2.0])
def test_a_pause_before_a_right_pivot_keeps_it_the_maneuver(pause: float) -> None:
    """A node that stands still before it turns (a pause, an AEB stop) at 0.31 m: 1 cm beyond the sheet's
    0.3 m, inside every other reading. It was once classed as an emergency-stop recovery after 0.5 s."""
    script = [(5.0, 0.0, 0.0), (13.8, 0.05, 0.0), (pause, 0.0, 0.0), (1.6, 0.0, math.pi / 2 / 1.6),
              (2.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("C"), C_WORLD), script)
    res = judge.results()
    assert judge.passed and len(res["maneuvers"]) == 1 and res["recovery_turns"] == [], judge.report_lines()
    assert res["maneuvers"][0]["readings"]["front"] == pytest.approx(0.31, abs=0.01)


def test_a_braked_turn_that_is_not_the_maneuver_stays_a_recovery_and_the_count_says_why() -> None:
    """Both readings of a turn after a stop with the path blocked: a half pivot there is the brake's way out (not
    every reading held C's trigger), and the maneuver count names it; the same half pivot where every reading held
    (front 0.25 m) is the maneuver, failed for its angle."""
    half = [(5.0, 0.0, 0.0), (13.8, 0.05, 0.0), (1.0, 0.0, 0.0), (0.8, 0.0, math.pi / 2 / 1.6), (4.0, 0.05, 0.0),
            (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("C"), C_WORLD), half)
    res = judge.results()
    assert res["maneuvers"] == [] and len(res["recovery_turns"]) == 1
    assert "turned 45 deg left; the Smart Pivot needs 90 +- 10 deg left" in _line(judge, "maneuvers performed")
    deeper = [(5.0, 0.0, 0.0), (14.9, 0.05, 0.0), (1.0, 0.0, 0.0), *half[3:]]
    res = _run(truth_judge(_cfg("C"), C_WORLD), deeper).results()
    assert len(res["maneuvers"]) == 1 and not res["maneuvers"][0]["angle_ok"] and res["recovery_turns"] == []


OBLIQUE = [0.55, 0.25, 1.5, 0.25]  # a wall beside the path, 0.25 m left of it: seen at 20-30 deg, never dead ahead


def test_late_only_when_every_front_reading_held() -> None:
    """Creeping past a wall that only a wide front sector sees (+-30 deg reads it below 0.5 m for seconds, +-5
    deg never): a node reading +-15 deg turns later than a +-30 deg one and is not late. The same creep towards
    a wall dead ahead (every reading holds) is late."""
    script = [(5.0, 0.0, 0.0), (14.0, 0.05, 0.0), (math.pi / 2, 0.0, -1.0), (3.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(OBLIQUE)), script)
    (m,) = judge.results()["maneuvers"]
    assert m["trigger"] and not m.get("late") and judge.passed, judge.report_lines()
    ahead = [(5.0, 0.0, 0.0), (12.0, 0.05, 0.0), (math.pi / 2, 0.0, 1.0), (3.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    (m,) = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), ahead).results()["maneuvers"]
    assert m["late"] and m["crept_with_trigger"] >= 0.09


def test_did_not_hold_only_when_no_side_reading_held() -> None:
    """B at the mouth of a passage whose walls are seen only ahead of abeam (60 +- 30 deg reads their corners at
    0.5 m, 90 +- 30 deg nothing near): a node reading its sides centred at 60 deg is squeezed, so its Retreat's
    trigger held."""
    funnel = _world([0.6, 0.4, 1.6, 0.4], [0.6, -0.4, 1.6, -0.4])  # the passage begins 0.3 m ahead of the turn
    # creeps on until 24.1 s (the creep check)
    script = [(5.0, 0.0, 0.0), (6.0, 0.05, 0.0), (math.pi, 0.0, 1.0), (10.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("B"), funnel), script)
    (m,) = judge.results()["maneuvers"]
    assert m["trigger"] and m["readings"]["left"] < 0.55 < m["readings"]["left_all"], m
    assert judge.passed, judge.report_lines()


def test_forward_figures_come_from_the_turns_own_window() -> None:
    """A node whose second publisher keeps creeping while its timer turns: every turning command says 0 m/s, the
    creep commands between them do not, and the line gives those figures together (it once said "commanded up
    to 0.00 m/s, moved 0.02 m")."""
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (math.pi / 2, 0.0, 1.0), (8.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), script, between=(0.05, 0.0))
    fails = [line for line in judge.report_lines() if line.startswith("maneuver ") and line.endswith("FAILED")]
    assert fails and all("drove forward during the turn (commanded up to 0.05 m/s, moved 0.0" in f for f in fails)


CORNER = _world(WALL_AHEAD, [-2.0, 0.45, 2.0, 0.45])  # a wall ahead and one 0.45 m to the left: a corner


def test_back_to_back_maneuvers_are_two_turns_and_a_closed_loops_correction_is_part_of_one() -> None:
    """A Randomizer whose trigger still holds after its first turn turns again at once: the other way without a
    stop (two maneuvers, each judged on its own angle), or the same way after one creep command on its next
    scan. A closed loop that overshot by 5 deg and turns back is one maneuver of 90 deg."""
    reverse = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (2.1, 0.0, 1.0), (2.3, 0.0, -1.0), (3.0, 0.05, 0.0),
               (20.0, 0.0, 0.0)]
    res = _run(truth_judge(_cfg("A"), CORNER), reverse).results()
    assert [round(m["angle_deg"] / 10) for m in res["maneuvers"]] == [12, -13], res["maneuvers"]
    again = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (1.6, 0.0, 1.0), (0.2, 0.05, 0.0), (1.7, 0.0, 1.0),
             (3.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    res = _run(truth_judge(_cfg("A"), CORNER), again).results()
    assert len(res["maneuvers"]) == 2, res["maneuvers"]
    corrected = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (math.radians(95.0), 0.0, 1.0), (0.45, 0.0, -0.2),
                 (3.0, 0.05, 0.0), (20.0, 0.0, 0.0)]
    (m,) = _run(truth_judge(_cfg("A"), _world(WALL_AHEAD)), corrected).results()["maneuvers"]
    assert m["angle_deg"] == pytest.approx(92.0, abs=1.0) and m["passed"], m  # 97 deg on the 20 Hz grid, 5 back


@pytest.mark.parametrize("yaw_deg", [-8.0, 0.0, 8.0])
def test_c_requires_a_side_only_where_every_reading_agrees(yaw_deg: float) -> None:
    """lab_side at C's pivot: a wall 0.5 m to the left, the room 2 m to the right. Read 30-150 deg wide (a reasonable
    reading, issue 52), the right side sees the box C pivots from (0.33 m) once the robot's yaw puts its corner
    there (yawed 8 deg left) and calls the left clearer: then either side passes. Straight or yawed right, every
    side reading says right, so right is required; the line shows the sides beside the robot."""
    from bt_nav_sim.world import load_world

    judge = truth_judge(CheckoffConfig(maneuver="C"), load_world("lab_side"), update_world=False)
    r = judge.readings.read(-0.31, 0.0, math.radians(yaw_deg))
    assert judge._clearer_side(r) == ("either side" if yaw_deg > 0 else "right"), r.sides
    assert r.left_abeam == pytest.approx(0.5, abs=0.01) and r.right_abeam > 1.9


def test_a_fast_turn_reversed_at_once_is_split_where_the_robot_turned_back() -> None:
    """At 2 rad/s and 10 rad/s^2 the robot coasts 11 deg after the command flips: the first turn is measured to the
    yaw's extremum (115 deg) and the second from it (92 deg: its first 0.2 s stopped the first turn); measured at
    the command's flip they were 103 and 80 deg, and a right Randomizer failed."""
    script = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (1.0, 0.0, 2.0), (1.0, 0.0, -2.0), (3.0, 0.05, 0.0),
              (20.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("A"), CORNER), script, accel=10.0)
    res = judge.results()
    assert [m["angle_deg"] for m in res["maneuvers"]] == pytest.approx([115.0, -92.0], abs=2.0), res["maneuvers"]
    assert judge.passed, judge.report_lines()


def test_the_creep_sent_while_an_open_loop_turn_coasts_is_moving_on_not_forward_motion() -> None:
    """An open-loop 2 rad/s pivot whose node creeps on as soon as its timed turn ends: the robot's yaw coasts on
    for a moment (here 0.4 s at 5 rad/s^2) and the creep moves it a centimetre before the yaw settles. That is
    the node moving on, not forward motion during the turn (a right node was failed "commanded up to 0.00 m/s,
    moved 0.01 m"); a creep sent during the turn's commands still fails."""
    coast = [(5.0, 0.0, 0.0), (14.4, 0.05, 0.0), (0.70, 0.0, 2.0), (4.0, 0.05, 0.0), (10.0, 0.0, 0.0)]
    judge = _run(truth_judge(_cfg("C"), C_WORLD), coast, accel=5.0)
    (m,) = judge.results()["maneuvers"]
    assert judge.passed and m["forward_motion"] < 0.005, (m, judge.report_lines())
    during = coast[:2] + [(0.60, 0.0, 2.0), (0.10, 0.05, 2.0)] + coast[3:]
    judge = _run(truth_judge(_cfg("C"), C_WORLD), during, accel=5.0)
    assert not judge.passed and "drove forward during the turn" in " ".join(judge.report_lines())


def test_a_refused_disarm_is_named_a_refusal() -> None:
    """toggle_navigation(false) answered with success false: "refused", with the node's own message, never "false
    never answered"."""
    judge = truth_judge(_cfg("C"), C_WORLD)
    judge.start(0.0)
    for k in range(0, 70):
        t = k * 0.5
        for action in judge.step(t):
            judge.on_activate_result(t, action.data, bool(action.data), message="" if action.data else "busy")
        judge.observe(t, 0.0, 0.0, 0.0)
    line = _line(judge, "toggle_navigation answered")
    assert "toggle_navigation(false) refused" in line and "('busy')" in line and "never answered" not in line, line


def test_the_forward_rule_speaks_in_figures_that_agree() -> None:
    """No forward command but motion is said as such, never "commanded up to 0.00 m/s, moved 0.02 m"."""
    from bt_nav.judge.checkoff_core import _forward_text

    rolled = _forward_text({"forward_command": 0.0, "forward_motion": 0.0213})
    assert rolled.startswith("moved 0.021 m during the turn (ground truth) though none of its commands asked for "
                             "forward speed") and "commanded up to" not in rolled
    assert _forward_text({"forward_command": 0.004, "forward_motion": 0.0})[:52] == \
        "drove forward during the turn (commanded up to 0.004"


LATE_SCRIPT = [(5.0, 0.0, 0.0), (10.2, 0.05, 0.0), (math.pi / 2, 0.0, 1.0), (8.0, 0.05, 0.0), (10.0, 0.0, 0.0)]


@pytest.mark.parametrize(("maneuver", "segments", "script", "kw"), [
    ("A", [WALL_AHEAD], A_SCRIPT, {}),
    ("A", [WALL_AHEAD], LATE_SCRIPT, {"safety_distance": 0.6}),
    ("C", [BOX_AHEAD, [0.0, -0.3, 1.0, -0.3]], _c_script(math.pi / 2 / 1.6), {}),
], ids=["randomizer", "late", "smart_pivot"])
def test_readings_cast_when_an_episode_asks_judge_as_those_cast_at_every_sample(maneuver, segments, script, kw) -> None:
    """In a world that cannot change, a sample's trigger reading is cast when an episode first asks for it: far
    fewer casts than armed samples, and the same verdict, figure for figure, as the same run in the same world with
    one more object that could appear (never near enough to), where every armed sample is cast as it comes."""
    def judged(extra_circles: list[dict]) -> tuple[CheckoffJudge, list[int]]:
        world = world_from_dict({"name": "test", "segments": ROOM + segments, "circles": extra_circles})
        judge = truth_judge(_cfg(maneuver, **kw), world)
        casts, cast = [0], judge.readings.caster.true_ranges

        def counted(*args, **kwargs):
            casts[0] += 1
            return cast(*args, **kwargs)
        judge.readings.caster.true_ranges = counted
        return _run(judge, script), casts

    lazy, lazy_casts = judged([])
    eager, eager_casts = judged([{"x": -1.8, "y": 1.8, "r": 0.05, "appear_within": 0.3}])
    armed = sum(eager._armed_at(t) for t in eager._t)
    assert eager_casts[0] >= armed > 300
    assert 0 < lazy_casts[0] < armed / 5, (lazy_casts, armed)
    assert lazy.results() == eager.results() and lazy.report_lines() == eager.report_lines()
