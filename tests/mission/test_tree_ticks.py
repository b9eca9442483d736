"""Tick-by-tick tests of the real mission tree (trees/mission.xml) on a fake clock.

Each test states, per tick, which leaf is the tip, the statuses that matter and the commanded twist.
"""

from __future__ import annotations

import math

import pytest

from bt_nav.testing import FRONT_270, LDS01, REVERSED, RPLIDAR, LocalTriggerClient, TickHarness

LAYOUTS = {"lds01": LDS01, "rplidar": RPLIDAR, "reversed": REVERSED, "front270": FRONT_270}


class Events:
    """Collects the one-line event messages."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def info(self, msg: str) -> None:
        self.lines.append(("info", msg))

    def warning(self, msg: str) -> None:
        self.lines.append(("warning", msg))

    def error(self, msg: str) -> None:
        self.lines.append(("error", msg))

    def text(self) -> str:
        return "\n".join(msg for _, msg in self.lines)


def armed_harness(maneuver: str = "none", **kwargs) -> TickHarness:
    """Armed, and one tick with whatever the scan shows (clear by default): a maneuver's condition
    that holds at the arming fires at once (trigger_at_arming), so tests arm with a clear view."""
    h = TickHarness(maneuver, **kwargs)
    h.tick()
    ok, message = h.arm()
    assert ok and "mission timer started" in message
    h.tick()
    return h


# ---------------------------------------------------------------- arming and reactive driving
def test_arming_before_the_clock_starts_is_refused() -> None:
    """Under use_sim_time the node clock reads 0 until /clock arrives: no timer may start from there."""
    h = TickHarness()
    ok, message = h.arm()
    assert not ok and "clock has not started" in message
    assert h.tick().command.is_zero
    assert h.arm()[0]


def test_still_before_arming() -> None:
    h = TickHarness()
    for _ in range(40):
        r = h.tick()
        assert r.tip == "StopDisarmed"
        assert (r.command.linear, r.command.angular) == (0.0, 0.0)
        assert r.statuses["Disarmed"] == "SUCCESS"
        assert r.statuses["FullSpeed"] == "INVALID"
    assert math.isnan(h.core.value("first_armed_at"))


@pytest.mark.parametrize("layout", LAYOUTS.values(), ids=LAYOUTS.keys())
def test_arm_gives_full_speed(layout) -> None:
    h = armed_harness(layout=layout)
    r = h.tick()
    assert r.tip == "FullSpeed"
    assert (r.command.linear, r.command.angular) == (0.22, 0.0)
    assert r.statuses["Priorities"] == "RUNNING"
    assert r.statuses["Disarmed"] == "FAILURE"


@pytest.mark.parametrize("layout", LAYOUTS.values(), ids=LAYOUTS.keys())
@pytest.mark.parametrize("side", [+1, -1], ids=["obstacle-left", "obstacle-right"])
def test_far_obstacle_turns_away_from_closer_side(layout, side: int) -> None:
    h = armed_harness(layout=layout)
    h.see((side * 12.0, 0.5))
    r = h.tick()
    assert r.tip == "TurnAway"
    assert r.statuses["ObstacleFar?"] == "SUCCESS"
    assert 0.12 <= r.command.linear < 0.22
    assert r.command.angular * side < 0, "turns away from the side the obstacle is on"


@pytest.mark.parametrize("layout", LAYOUTS.values(), ids=LAYOUTS.keys())
@pytest.mark.parametrize("side", [+1, -1], ids=["obstacle-left", "obstacle-right"])
def test_close_obstacle_rotates_in_place(layout, side: int) -> None:
    h = armed_harness(layout=layout)
    h.see((side * 10.0, 0.2))
    r = h.tick()
    assert r.tip == "RotateInPlace"
    assert r.command.linear == 0.0
    assert r.command.angular * side < 0


def test_turn_direction_is_kept_while_rotating() -> None:
    """Once chosen, a rotation keeps its side even when the readings flip (no dithering)."""
    h = armed_harness()
    h.see((10.0, 0.2))
    first = h.tick().command.angular
    h.see((-10.0, 0.2))
    for _ in range(5):
        r = h.tick()
        assert r.tip == "RotateInPlace" and r.command.angular == first


def test_rotating_in_place_right_after_steering_keeps_the_steering_side() -> None:
    """TurnAway steering left hands its side to the rotation in place that follows it at once, even
    where the close obstacle alone would say right (a cornered robot alternated sides for seconds)."""
    h = armed_harness()
    h.see((-10.0, 0.5))
    r = h.tick()
    assert r.tip == "TurnAway" and r.command.angular > 0
    h.see((5.0, 0.25))  # alone: rotate right (clear at -55 deg vs +65 deg: within SWITCH_MARGIN)
    r = h.tick()
    assert r.tip == "RotateInPlace" and r.command.angular > 0


def test_unknown_front_is_treated_as_close() -> None:
    h = armed_harness()
    h.see((0.0, math.nan), width_deg=70.0)
    r = h.tick()
    assert r.statuses["ObstacleClose?"] == "SUCCESS"
    assert r.tip == "RotateInPlace" and r.command.linear == 0.0


def test_far_band_speed_is_graded() -> None:
    h = armed_harness()
    speeds = []
    # the free path of the robot's width ends ~path_half_width before the obstacle: these are all in the band
    for distance in (0.85, 0.7, 0.55):
        h.see((5.0, distance))
        r = h.tick()
        assert r.tip == "TurnAway"
        speeds.append(r.command.linear)
    assert speeds[0] > speeds[1] > speeds[2] >= 0.12


# ---------------------------------------------------------------- maneuvers
def run_maneuver(h: TickHarness, leaf: str) -> list:
    """Tick from the trigger to the maneuver's end; returns the maneuver's records."""
    first = h.tick()
    assert first.tip == leaf, f"expected {leaf} to start, tip {first.tip}"
    records = [first]
    h.see()  # the obstacle vanishes at once: reclassification must not abort the turn
    while True:
        r = h.tick()
        records.append(r)
        if r.statuses[leaf] != "RUNNING":
            break
        assert len(records) < 200
    return records


@pytest.mark.parametrize(
    ("maneuver", "leaf", "obstacles", "check"),
    [
        ("A", "Randomizer", [(0.0, 0.45)], lambda rot: math.radians(90) <= abs(rot) <= math.radians(180)),
        ("B", "Retreat", [(8.0, 0.4), (-20.0, 0.45)], lambda rot: abs(rot) == pytest.approx(math.pi)),
        ("C", "SmartPivot", [(-10.0, 0.25), (20.0, 1.5)], lambda rot: rot == pytest.approx(math.pi / 2)),
    ],
)
def test_maneuver_from_trigger_to_completion(maneuver, leaf, obstacles, check) -> None:
    h = armed_harness(maneuver)
    h.tick()
    h.see(*obstacles)
    yaw0 = h.yaw
    records = run_maneuver(h, leaf)
    leaf_node = next(n for n in h.core.root.iterate() if n.name == leaf)
    assert check(leaf_node.rotation)
    assert records[-1].statuses[leaf] == "SUCCESS"
    for r in records:
        assert r.command.linear == 0.0, "rotation only"
        assert r.tip == leaf
    turned = h.yaw - yaw0
    error = math.remainder(turned - leaf_node.rotation, 2 * math.pi)
    assert abs(error) <= math.radians(3.0) + 1e-9
    assert records[-1].command.angular == 0.0
    assert h.core.value("maneuver_active") is False
    assert h.tick().tip == "FullSpeed"


def test_smart_pivot_turns_towards_the_clearer_side() -> None:
    h = armed_harness("C")
    h.see((10.0, 0.25), (-25.0, 1.2))  # left half blocked, right half clearer
    h.tick()
    leaf = next(n for n in h.core.root.iterate() if n.name == "SmartPivot")
    assert leaf.rotation == pytest.approx(-math.pi / 2)


def test_randomizer_is_seedable() -> None:
    rotations = []
    for _ in range(2):
        h = armed_harness("A", overrides={"random_seed": 1234})
        h.see((0.0, 0.4))
        h.tick()
        rotations.append(next(n for n in h.core.root.iterate() if n.name == "Randomizer").rotation)
    assert rotations[0] == rotations[1]


@pytest.mark.parametrize("preempt", ["disarm", "deadline"])
def test_maneuver_is_preempted_with_a_zero_twist(preempt: str) -> None:
    h = armed_harness("A", overrides={"mission_duration": 5.0, "stop_margin": 0.0})
    h.clock.now = 4.5 if preempt == "deadline" else h.clock.now
    h.see((0.0, 0.4))
    r = h.tick(3)
    assert r.tip == "Randomizer" and r.command.angular != 0.0
    if preempt == "disarm":
        h.arm(False)
        r = h.tick()
        assert r.tip == "StopDisarmed"
    else:
        h.clock.now = 5.0
        r = h.tick()
        assert r.tip in ("EvaluateMission", "StopAtDeadline")
    assert (r.command.linear, r.command.angular) == (0.0, 0.0)
    assert r.statuses["Randomizer"] == "INVALID"
    assert h.core.value("maneuver_active") is False
    if preempt == "disarm":
        h.see()
        h.arm(True)
        assert h.tick().tip == "FullSpeed", "a preempted maneuver does not resume"


def test_maneuver_fails_after_its_time_allowance() -> None:
    """Odometry that never moves (wheels slipping) ends the turn with a stop, not a spin forever."""
    h = armed_harness("C")
    h.see((0.0, 0.25))
    h.tick()
    h.see()
    leaf = next(n for n in h.core.root.iterate() if n.name == "SmartPivot")
    h.feed_odom = True
    frozen_yaw = h.yaw
    ticks = 0
    while leaf.status.value == "RUNNING":
        h.clock.advance(h.dt)
        h.core.feed_scan(h.scan)
        h.core.feed_odom(frozen_yaw)
        r = h.core.tick()
        ticks += 1
        if leaf.status.value == "RUNNING":
            assert r.linear == 0.0 and r.angular != 0.0
        assert ticks < 400
    assert leaf.status.value == "FAILURE"
    assert "out of time" in leaf.feedback_message
    assert h.core.value("maneuver_active") is False
    assert h.core.tip == "FullSpeed", "the failed branch hands over to the next priority in the same tick"
    allowance = (abs(leaf.rotation) / h.core.params["maneuver_angular_speed"] + 1.0
                 + h.core.params["maneuver_time_margin"])
    assert ticks * h.dt == pytest.approx(allowance, abs=2 * h.dt)


def test_maneuver_without_odometry_runs_open_loop() -> None:
    h = armed_harness("C")
    h.feed_odom = False
    h.see((0.0, 0.25))
    records = run_maneuver(h, "SmartPivot")
    leaf = next(n for n in h.core.root.iterate() if n.name == "SmartPivot")
    assert records[-1].statuses["SmartPivot"] == "SUCCESS"
    # the last odometry sample (before the maneuver) goes stale after odom_timeout = 10 ticks
    assert leaf.open_loop_ticks >= len(records) - 10 > 0
    assert abs(math.remainder(h.yaw - leaf.rotation, 2 * math.pi)) <= math.radians(3.0)


# ---------------------------------------------------------------- deadline and evaluation
def test_deadline_stops_and_evaluates_once() -> None:
    h = armed_harness()
    start = h.core.value("first_armed_at")
    r = h.run_until(lambda r: r.tip != "FullSpeed")
    due = h.core.value("mission_duration") - h.core.value("stop_margin")
    assert r.time == pytest.approx(start + due, abs=h.dt + 1e-9)
    assert (r.command.linear, r.command.angular) == (0.0, 0.0)
    assert r.statuses["DeadlineReached?"] == "SUCCESS"
    for _ in range(200):
        r = h.tick()
        assert (r.command.linear, r.command.angular) == (0.0, 0.0)
    assert len(h.client.calls) == 1
    assert h.core.evaluation_calls == 1
    assert h.core.value("evaluation_result").startswith("succeeded")


def test_evaluation_is_retried_after_refusal_and_exception() -> None:
    client = LocalTriggerClient(script=["refuse", "raise", "ok"])
    h = armed_harness(client=client, overrides={"mission_duration": 2.0})
    h.run_until(lambda r: h.core.evaluation_calls == 1, limit=400)
    assert len(client.calls) == 3
    gaps = [b - a for a, b in zip(client.calls, client.calls[1:], strict=False)]
    assert all(g >= 0.5 - 1e-9 for g in gaps), "retry delay respected"
    h.tick(50)
    assert len(client.calls) == 3


def test_evaluation_waits_for_a_late_server() -> None:
    client = LocalTriggerClient(absent_until=3.2)
    h = armed_harness(client=client, overrides={"mission_duration": 2.0, "evaluation_timeout": 5.0})
    h.run_until(lambda r: h.core.evaluation_calls == 1, limit=400)
    assert len(client.calls) == 1 and client.calls[0] >= 3.2


def test_evaluation_timeout_drops_the_pending_request_and_gives_up() -> None:
    client = LocalTriggerClient(default="hang")
    events = Events()
    h = armed_harness(client=client, events=events,
                      overrides={"mission_duration": 2.0, "evaluation_timeout": 0.5, "evaluation_retries": 2})
    h.run_until(lambda r: r.statuses["EvaluateMission"] == "FAILURE", limit=400)
    assert len(client.calls) == 3 and len(client.removed) == 3
    assert h.core.value("evaluation_result").startswith("failed")
    assert "no retries left" in events.text()
    for _ in range(100):
        r = h.tick()
        assert r.command.is_zero
    assert len(client.calls) == 3


def test_arming_after_the_mission_is_refused() -> None:
    h = armed_harness(overrides={"mission_duration": 2.0})
    h.run_until(lambda r: h.core.evaluation_calls == 1, limit=200)
    ok, message = h.arm(True)
    assert not ok and "mission ended" in message
    for _ in range(20):
        assert h.tick().command.is_zero


def test_deadline_counts_from_the_first_arming_and_fires_while_disarmed() -> None:
    h = armed_harness(overrides={"mission_duration": 3.0, "stop_margin": 0.0})
    h.tick(10)
    h.arm(False)
    h.tick(10)
    h.arm(True)
    r = h.run_until(lambda r: r.statuses["DeadlineReached?"] == "SUCCESS", limit=200)
    assert r.time == pytest.approx(h.core.value("first_armed_at") + 3.0, abs=h.dt + 1e-9)
    h2 = armed_harness(overrides={"mission_duration": 2.0})
    h2.arm(False)
    h2.run_until(lambda r: h2.core.evaluation_calls == 1, limit=200)


# ---------------------------------------------------------------- bad input and faults
def test_stale_scan_stops_until_a_fresh_one_arrives() -> None:
    events = Events()
    h = armed_harness(events=events)
    assert h.tick().tip == "FullSpeed"
    h.feed_scans = False
    r = h.tick(11)  # 0.55 s without a scan > scan_timeout 0.5 s
    assert r.tip == "StopBlind" and r.command.is_zero
    assert "stale scan" in events.text()
    h.feed_scans = True
    assert h.tick().tip == "FullSpeed"


def test_malformed_scan_is_a_safe_stop_with_a_reason() -> None:
    from bt_nav.mission.scan import Scan

    h = armed_harness()
    h.tick()
    h.scan = Scan(0.0, 1.0, 0.0, 0.1, 3.5, h.scan.ranges)
    r = h.tick()
    assert r.tip == "StopBlind" and r.command.is_zero
    assert "malformed scan" in h.core.value("scan_status")


def test_exception_in_a_leaf_is_logged_with_its_name_and_stops() -> None:
    events = Events()
    h = armed_harness(events=events)
    assert h.tick().command.linear > 0
    leaf = next(n for n in h.core.root.iterate() if n.name == "FullSpeed")

    def explode():
        raise RuntimeError("boom")

    leaf.update = explode
    r = h.tick()
    assert r.command.is_zero
    assert "exception in leaf 'FullSpeed'" in events.text()
    assert h.core.faults == 1
    del leaf.update
    assert h.tick().command.linear > 0, "the next tick starts afresh"


def test_live_parameter_update_and_refusals() -> None:
    h = armed_harness()
    h.see((0.0, 0.5))
    assert h.tick().tip == "TurnAway"
    assert "smaller than far_distance" in h.core.set_param("close_distance", 0.8)
    assert h.core.set_param("far_distance", 1.0) is None
    assert h.core.set_param("close_distance", 0.6) is None
    assert h.tick().tip == "RotateInPlace"
    assert "must be >=" in h.core.set_param("safety_distance", -1.0)
    assert "finite" in h.core.set_param("safety_distance", math.nan)
    assert "cannot change" in h.core.set_param("maneuver", "B")
    assert "unknown maneuver" in h.core.set_param("maneuver", "Z")


def test_a_clock_jumping_back_does_not_stretch_the_maneuver_allowance() -> None:
    h = armed_harness("C")
    h.see((0.0, 0.25))
    h.tick()
    h.see()
    leaf = next(n for n in h.core.root.iterate() if n.name == "SmartPivot")
    frozen = h.yaw
    h.clock.advance(-100.0)  # simulator reset while the robot is stuck
    ticks = 0
    while leaf.status.value == "RUNNING":
        h.clock.advance(h.dt)
        h.core.feed_scan(h.scan)
        h.core.feed_odom(frozen)
        h.core.tick()
        ticks += 1
        assert ticks < 200, "the allowance must count ticks, not clock differences"
    assert leaf.status.value == "FAILURE"


def test_a_request_in_flight_survives_a_tree_reset() -> None:
    """An exception elsewhere resets the tree; the evaluation already sent must not be sent again."""
    client = LocalTriggerClient(default="hang")
    h = armed_harness(client=client, overrides={"mission_duration": 2.0, "evaluation_timeout": 30.0})
    h.run_until(lambda r: len(client.calls) == 1, limit=100)
    stop = next(n for n in h.core.root.iterate() if n.name == "StopAtDeadline")

    def explode():
        raise RuntimeError("boom")

    stop.update = explode
    assert h.tick().command.is_zero
    del stop.update
    pending = client.pending[0]
    pending.set_result(type("R", (), {"success": True, "message": "ok"})())
    h.run_until(lambda r: h.core.evaluation_calls == 1, limit=20)
    assert len(client.calls) == 1 and not client.removed


def test_evaluation_retry_delay_survives_a_clock_jump_back() -> None:
    client = LocalTriggerClient(script=["refuse"], default="ok")
    h = armed_harness(client=client, overrides={"mission_duration": 2.0})
    h.run_until(lambda r: len(client.calls) == 1, limit=100)
    h.clock.advance(-50.0)
    h.run_until(lambda r: len(client.calls) == 2, limit=30)


def test_blind_front_and_open_loop_are_said_in_one_line_each() -> None:
    events = Events()
    h = armed_harness("C", overrides={"trigger_rearm_distance": 0.0, "trigger_clear_away": 0.0}, events=events)
    h.see((0.0, math.nan), width_deg=70.0)
    h.tick(5)
    assert sum("front sector unknown" in m for _, m in events.lines) == 1
    h.see()
    h.tick()
    assert sum("front sector known again" in m for _, m in events.lines) == 1
    h.run_until(lambda r: r.tip == "FullSpeed", limit=200)
    h.feed_odom = False
    h.see((0.0, 0.25))
    assert h.tick().tip == "SmartPivot"
    h.see()
    h.run_until(lambda r: r.tip == "FullSpeed", limit=200)
    assert sum("open loop" in m for _, m in events.lines) == 1


# ---------------------------------------------------------------- maneuver triggers (rising edge, re-arm)
SIDES = {"side_center_deg": 60.0, "side_half_angle_deg": 30.0}
TRIGGER_CASES = [  # maneuver, its leaf, a scan meeting its condition, one clearing it beyond the hysteresis
    ("A", "Randomizer", [(0.0, 0.45)], [(0.0, 0.8)]),
    ("B", "Retreat", [(60.0, 0.4), (-60.0, 0.4), (0.0, 0.9)], [(60.0, 0.4), (-60.0, 0.9), (0.0, 0.9)]),
    ("C", "SmartPivot", [(0.0, 0.25), (30.0, 1.0)], [(0.0, 0.5), (30.0, 1.0)]),
]
SQUEEZED = [(60.0, 0.4), (-60.0, 0.4), (0.0, 5.0)]  # a long corridor: both walls near, nothing ahead
OPENING = [(60.0, 0.4), (-60.0, 2.0), (0.0, 5.0)]  # a side opening


def finish(h: TickHarness, leaf: str) -> list:
    """Ticks from the maneuver's start to its end (the scan stays as it is); all rotation only."""
    records = [h.tick()]
    assert records[0].tip == leaf, f"{leaf} did not start: tip {records[0].tip}"
    while records[-1].statuses[leaf] == "RUNNING" or len(records) == 1:
        records.append(h.tick())
        assert len(records) < 300
    assert all(r.command.linear == 0.0 for r in records), "rotation only"
    return records


@pytest.mark.parametrize(("maneuver", "leaf", "condition", "clear"), TRIGGER_CASES)
def test_a_persisting_condition_does_not_refire(maneuver, leaf, condition, clear) -> None:
    h = armed_harness(maneuver, overrides={**SIDES, "trigger_rearm_distance": 0.0})
    h.see(*condition)
    finish(h, leaf)
    after = [h.tick() for _ in range(60)]  # 3 s with the same condition: the reactive branches act
    assert all(r.tip != leaf for r in after), "the maneuver re-fired while its condition merely persisted"


@pytest.mark.parametrize(("maneuver", "leaf", "condition", "clear"), TRIGGER_CASES)
def test_a_fresh_condition_fires_again_after_clearing_beyond_the_hysteresis(maneuver, leaf, condition,
                                                                            clear) -> None:
    h = armed_harness(maneuver, overrides={**SIDES, "trigger_rearm_distance": 0.0, "trigger_clear_away": 0.0})
    h.see(*condition)
    finish(h, leaf)
    h.see(*clear)
    h.tick(3)
    h.see(*condition)
    finish(h, leaf)


def test_a_reading_inside_the_hysteresis_band_does_not_rearm() -> None:
    h = armed_harness("A", overrides={"trigger_rearm_distance": 0.0, "trigger_clear_away": 0.0,
                                      "trigger_hysteresis": 0.2})
    h.see((0.0, 0.45))
    finish(h, "Randomizer")
    h.see((0.0, 0.65))  # above safety_distance, not above safety_distance + hysteresis
    h.tick(3)
    h.see((0.0, 0.45))
    assert all(h.tick().tip != "Randomizer" for _ in range(20))


def test_driving_rearms_a_squeeze_that_never_clears_and_a_clearing_on_the_spot_does_not() -> None:
    h = armed_harness("B", overrides={**SIDES, "trigger_rearm_distance": 2.0, "trigger_clear_away": 1.0})
    h.see(*SQUEEZED)
    finish(h, "Retreat")
    x0, y0 = h.x, h.y
    h.see(*OPENING)  # cleared on the spot (as a spin sweeps the sectors): no re-arm
    h.tick()
    h.see(*SQUEEZED)
    fired_at = None
    for _ in range(400):
        r = h.tick()
        if r.tip == "Retreat":
            fired_at = ((h.x - x0) ** 2 + (h.y - y0) ** 2) ** 0.5
            break
    assert fired_at is not None, "a squeeze lasting 2 m of driving must fire again"
    assert 2.0 <= fired_at <= 2.0 + 0.22 * 2 * h.dt


def test_a_maneuver_never_restarts_while_it_runs() -> None:
    h = armed_harness("A", overrides={"trigger_rearm_distance": 0.0, "trigger_clear_away": 0.0})
    h.see((0.0, 0.45))
    assert h.tick().tip == "Randomizer"
    leaf = next(n for n in h.core.root.iterate() if n.name == "Randomizer")
    rotation, turned = leaf.rotation, []
    for _ in range(5):  # the condition flickers: cleared and fresh again, mid-turn
        h.see((0.0, 0.8))
        r = h.tick()
        h.see((0.0, 0.45))
        r2 = h.tick()
        assert r.tip == r2.tip == "Randomizer" and leaf.rotation == rotation
        assert r.command.linear == r2.command.linear == 0.0
        turned.append(leaf.turned)
    assert turned == sorted(turned, key=abs), "the turn went on, it did not start over"


@pytest.mark.parametrize("at_arming", [True, False])
def test_disarm_and_rearm_reset_the_trigger(at_arming: bool) -> None:
    h = armed_harness("C", overrides={"trigger_rearm_distance": 50.0, "trigger_clear_away": 50.0,
                                      "trigger_at_arming": at_arming})
    h.see((0.0, 0.25), (30.0, 1.0))
    finish(h, "SmartPivot")
    assert all(h.tick().tip != "SmartPivot" for _ in range(5))
    h.arm(False)
    h.tick(3)
    h.arm(True)
    r = h.tick()
    assert (r.tip == "SmartPivot") == at_arming, "a condition holding at a new arming"
    if not at_arming:
        h.see()
        h.tick()  # seen clear once after the new arming: armed, however near the last firing
        h.see((0.0, 0.25), (30.0, 1.0))
        assert h.tick().tip == "SmartPivot"
