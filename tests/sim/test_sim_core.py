"""The simulator node's ROS-free parts: SimCore's clock and schedules, odometry, collision edges, followers."""

from __future__ import annotations

import math

import pytest
from bt_nav_sim.core import SimConfig, SimCore
from bt_nav_sim.pacing import (
    DISARMED_SILENCE,
    FLOOR_WAIT,
    STAY_BACKOFF,
    STAY_FLOOR,
    STAY_GROWTH,
    STAY_GROWTH_STRAIGHT,
    STAY_REFRACTORY,
    Followers,
    StayBehind,
)

MS = 1_000_000


def _run(core: SimCore, v: float, w: float, seconds: float) -> list:
    return [core.advance(v, w) for _ in range(round(seconds / (core.step_ns * 1e-9)))]


@pytest.mark.parametrize("profile, scans_per_s", [("homework", 10), ("lab", 5)])
def test_schedules_land_on_the_grid(profile: str, scans_per_s: int) -> None:
    core = SimCore(SimConfig(profile=profile))
    first = core.outputs()
    assert first.t_ns == 0 and first.scan is not None and first.odom
    outs = _run(core, 0.0, 0.0, 10.0)
    assert core.t_ns == 10_000 * MS  # integer nanoseconds: no drift after 1000 steps
    scan_times = [o.t_ns for o in outs if o.scan is not None]
    assert len(scan_times) == 10 * scans_per_s
    assert {b - a for a, b in zip(scan_times, scan_times[1:], strict=False)} == {1000 * MS // scans_per_s}
    odom_times = [o.t_ns for o in outs if o.odom]
    assert len(odom_times) == 300  # 30 Hz on a 100 Hz grid: gaps of 30 and 40 ms
    assert {b - a for a, b in zip(odom_times, odom_times[1:], strict=False)} == {30 * MS, 40 * MS}


def test_noiseless_odometry_is_the_pose_relative_to_the_start() -> None:
    core = SimCore(SimConfig(noise=False, spawn_yaw=math.pi / 2))
    _run(core, 0.2, 0.5, 3.0)
    sx, sy, syaw = core.spawn
    dx, dy = core.state.x - sx, core.state.y - sy
    # odom frame = start pose: rotate the world displacement by -spawn_yaw
    ex, ey = math.cos(-syaw) * dx - math.sin(-syaw) * dy, math.sin(-syaw) * dx + math.cos(-syaw) * dy
    assert (core.odom_x, core.odom_y) == pytest.approx((ex, ey), abs=1e-9)
    assert core.odom_yaw == pytest.approx(math.remainder(core.state.yaw - syaw, 2 * math.pi), abs=1e-9)


def test_noisy_odometry_drifts_a_little_and_is_seeded() -> None:
    a, b = SimCore(SimConfig(seed=3)), SimCore(SimConfig(seed=3))
    _run(a, 0.2, 0.3, 5.0)
    _run(b, 0.2, 0.3, 5.0)
    assert (a.odom_x, a.odom_y, a.odom_yaw) == (b.odom_x, b.odom_y, b.odom_yaw)
    truth = math.hypot(a.state.x - a.spawn[0], a.state.y - a.spawn[1])
    assert 0.0 < abs(math.hypot(a.odom_x, a.odom_y) - truth) < 0.02 * truth


def test_collision_events_are_rising_edges() -> None:
    core = SimCore(SimConfig(noise=False, spawn_x=-0.3))  # 0.309 m in front of the wall at x = 0.129
    outs = _run(core, 0.22, 0.0, 4.0)
    assert sum(o.collision for o in outs) == 1 and core.collisions == 1
    assert core.state.x == pytest.approx(0.129 - 0.12, abs=1e-6)
    _run(core, -0.1, 0.0, 1.0)
    outs = _run(core, 0.22, 0.0, 2.0)
    assert sum(o.collision for o in outs) == 1 and core.collisions == 2


def test_nan_commands_are_stops() -> None:
    core = SimCore(SimConfig(noise=False))
    _run(core, math.nan, math.inf, 1.0)
    assert (core.state.x, core.state.y) == core.spawn[:2]


def test_bad_config_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown profile"):
        SimCore(SimConfig(profile="gazebo"))
    with pytest.raises(ValueError, match="physics_rate_hz"):
        SimCore(SimConfig(physics_rate_hz=0.0))
    with pytest.raises(FileNotFoundError, match="bundled worlds"):
        SimCore(SimConfig(world="atlantis"))


def test_followers_bound_the_lead_and_time_out() -> None:
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    assert f.blocking(10**9, wall=0.0) == (None, [])
    assert f.report("cmd_vel", 1000 * MS, False, wall=0.0)  # joins
    assert f.blocking(1050 * MS, wall=0.1) == (None, [])  # exactly one period ahead is allowed
    assert f.blocking(1060 * MS, wall=0.1) == ("cmd_vel", [])
    assert f.blocking(1060 * MS, wall=1.2) == (None, ["cmd_vel"])  # silent too long: dropped
    assert not f.any_active()
    assert f.report("cmd_vel", 1070 * MS, False, wall=1.3)  # speaks again: rejoins
    assert f.blocking(1190 * MS, wall=1.3) == (None, [])  # the 70 ms across its silence is its period now
    assert f.blocking(1200 * MS, wall=1.3) == ("cmd_vel", [])  # (plus the 50 ms lead)


def test_a_disarmed_node_standing_still_is_not_waited_for_long() -> None:
    """Disarmed by its judge with its latest command a stop, a silent node is dropped after DISARMED_SILENCE wall
    seconds; moving, or armed again, after the whole silence (it may still owe its stop)."""
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    f.disarmed("cmd_vel", True)  # no such follower yet: nothing to do
    assert f.report("cmd_vel", 1000 * MS, False, wall=0.0, still=False)
    f.disarmed("cmd_vel", True)
    quick = DISARMED_SILENCE + 0.01
    assert f.blocking(1060 * MS, wall=quick) == ("cmd_vel", []), "its latest command turns the robot: waited for"
    assert not f.report("cmd_vel", 1050 * MS, False, wall=0.05, still=True), "followed already"
    assert f.blocking(1160 * MS, wall=0.05 + quick) == (None, ["cmd_vel"]), "standing still and disarmed: dropped"
    assert f.report("cmd_vel", 1170 * MS, False, wall=0.5, still=True)
    f.disarmed("cmd_vel", False)
    assert f.blocking(1280 * MS, wall=0.5 + quick) == ("cmd_vel", []), "armed again: the whole silence"
    assert f.blocking(1280 * MS, wall=1.51) == (None, ["cmd_vel"])


def test_a_follower_slower_than_the_lead_learns_its_period_across_the_silence() -> None:
    """A node on a 5 Hz timer behind a 0.15 s lead (a 10 Hz LiDAR's): its first gap spans a silence (sim time
    waited for it while it was given up for silent), and still is its period, so from then on sim time reaches its
    next message time (when the gap was forgotten at every rejoin, it was given up before every message)."""
    f = Followers(max_lag_ns=150 * MS, silence_s=1.0, hold_s=5.0, margin_ns=150 * MS)
    f.report("cmd_vel", 1000 * MS, False, wall=0.0)
    assert f.blocking(1160 * MS, wall=1.1) == (None, ["cmd_vel"])
    f.report("cmd_vel", 1200 * MS, False, wall=1.2)
    assert f.lead_ns("cmd_vel") == 350 * MS and f.blocking(1400 * MS, wall=1.2) == (None, [])


def test_followers_learn_a_longer_period() -> None:
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    for k in range(5):  # a 10 Hz follower
        f.report("slow", k * 100 * MS, False, wall=0.0)
    assert f.lead_ns("slow") == 150 * MS  # its period and the lead
    assert f.blocking(500 * MS, wall=0.0) == (None, [])
    f.report("slow", 520 * MS, False, wall=0.0)  # one short gap: the shortest gap wins
    assert f.lead_ns("slow") == 150 * MS
    f.report("slow", 610 * MS, False, wall=0.0)  # an arrival 20 ms late shortens the next gap: still led past it
    assert f.blocking(610 * MS + 140 * MS, wall=0.0) == (None, [])


def test_a_node_answering_its_scans_is_led_until_the_next_scan_is_out_and_no_further() -> None:
    """A robot's cmd_vel follower answers a 5 Hz LiDAR (scans every 200 ms): sim time may run on to the next scan
    after its latest command plus the small lead (never giving it up for silent while it waits for that scan), and
    past that only once it has answered; a node on a fast timer is held at the small lead in between (its turns,
    timed on its ROS clock, then last what it meant them to)."""
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    f.floors["cmd_vel"] = lambda t: (t // (200 * MS) + 1) * 200 * MS
    f.report("cmd_vel", 1010 * MS, False, wall=0.0)  # its answer to the scan of 1.0 s
    assert f.blocking(1250 * MS, wall=0.1) == (None, [])  # the 1.2 s scan must go out
    assert f.blocking(1260 * MS, wall=0.1) == ("cmd_vel", [])  # not past it before the node has answered
    # it answers while sim time is held for it: its 205 ms gap counts less the margin (155 ms: a lead of 205 ms),
    # and the next scan's floor leads it further, to 1.4 s plus 50 ms
    f.report("cmd_vel", 1215 * MS, False, wall=0.2)
    assert f.lead_ns("cmd_vel") == 205 * MS and not f.on_timer("cmd_vel")
    assert f.blocking(1450 * MS, wall=0.2) == (None, []) and f.blocking(1460 * MS, wall=0.2) == ("cmd_vel", [])
    # no sensor floor: the small lead alone
    g = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    g.report("timer", 1010 * MS, False, wall=0.0)
    assert g.blocking(1070 * MS, wall=0.1) == ("timer", [])


def test_one_stray_message_does_not_cut_a_timer_node_s_lead_short() -> None:
    """A 10 Hz node that once sends a zero twist 30 ms after a tick (from a service callback): its lead stays its
    period and the margin, so sim time still reaches its next tick (the shortest gap made it 80 ms: it stopped 20 ms
    short of every tick and was given up for silent, a wall second each, until 20 gaps later)."""
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    for t in (0, 100, 200, 300, 330, 400, 500):
        f.report("node", t * MS, False, wall=0.0)
    assert f.lead_ns("node") == 150 * MS and f.blocking(600 * MS, wall=0.0) == (None, [])


def test_a_node_slower_than_the_simulator_keeps_its_lead() -> None:
    """A 20 Hz node that always answers at the limit (the simulator is faster than it): each gap is its lead, which
    counts less the margin, so the lead stays 50 + 50 ms instead of growing by the margin message after message."""
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    t = 0
    for _ in range(4):  # free gaps: its period
        f.report("node", t, False, wall=0.0)
        t += 50 * MS
    for _ in range(60):  # held at its limit each time, answering there
        limit = f.limit_ns("node")
        assert f.blocking(limit + 10 * MS, wall=0.0) == ("node", [])
        f.report("node", limit, False, wall=0.0)
    assert f.lead_ns("node") == 100 * MS


def test_a_node_on_a_timer_faster_than_its_lidar_is_led_its_own_period_not_to_the_next_scan() -> None:
    """A 50 Hz node of a 5 Hz LiDAR's robot: once it has spoken twice with no scan in between, sim time may lead it
    its period and the margin only (led to the next scan, its ROS-timed turns ran on by up to a scan period at high
    speed); a node that answers each scan with a burst of two messages keeps the floor (it can say nothing before
    the next scan)."""
    scans = lambda t: (t // (200 * MS) + 1) * 200 * MS  # noqa: E731 - the 5 Hz scan grid
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    f.floors["cmd_vel"] = scans
    f.report("cmd_vel", 1000 * MS, False, wall=0.0)
    f.report("cmd_vel", 1020 * MS, False, wall=0.0)
    assert not f.on_timer("cmd_vel") and f.limit_ns("cmd_vel") == 1250 * MS, "one gap: led to the next scan still"
    f.report("cmd_vel", 1040 * MS, False, wall=0.0)
    assert f.on_timer("cmd_vel")
    assert f.limit_ns("cmd_vel", 0.0) == 1040 * MS + 70 * MS, "its period (20 ms) and the margin, not the 1.2 s scan"
    assert f.blocking(1120 * MS, wall=0.5) == ("cmd_vel", [])
    assert f.blocking(1120 * MS, wall=0.5 + FLOOR_WAIT * 0.9) == ("cmd_vel", [])
    # silent at its lead for FLOOR_WAIT: it waits for a scan (after a maneuver), so it is led to the next one
    assert f.blocking(1250 * MS, wall=0.5 + FLOOR_WAIT * 1.01) == (None, [])
    f.report("cmd_vel", 1205 * MS, False, wall=0.7)  # it answered the scan: its own lead again
    assert f.limit_ns("cmd_vel", 0.7) == 1205 * MS + 70 * MS
    g = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    g.floors["cmd_vel"] = scans
    for k in range(6):  # each scan answered twice within 2 ms
        g.report("cmd_vel", 1005 * MS + k * 200 * MS, False, wall=0.0)
        g.report("cmd_vel", 1007 * MS + k * 200 * MS, False, wall=0.0)
    # led past the next scan (2.2 s, plus 50 ms): its own period (198 ms between bursts) and the margin reach 2.255 s
    assert not g.on_timer("cmd_vel") and g.limit_ns("cmd_vel") == 2007 * MS + 248 * MS


def test_a_message_that_came_while_sim_time_waited_for_its_sender_is_at_the_limit() -> None:
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0, margin_ns=50 * MS)
    f.report("node", 0, False, wall=0.0)
    f.report("node", 20 * MS, False, wall=0.0)
    assert not f.members["node"].at_limit, "answered before sim time reached its lead"
    assert f.blocking(200 * MS, wall=0.0) == ("node", [])
    f.report("node", 70 * MS, False, wall=0.01)
    assert f.members["node"].at_limit, "sim time was waiting for it"
    assert f.blocking(80 * MS, wall=0.01) == (None, [])
    f.report("node", 90 * MS, False, wall=0.02)
    assert not f.members["node"].at_limit


def test_stay_behind_grows_while_the_node_keeps_up_and_backs_off_when_it_answers_at_its_limit() -> None:
    pace = StayBehind(cap=0.0, start=4.0)
    assert pace.rate(10.0, turning=True) == 4.0
    assert pace.rate(10.5, turning=True) == 4.0 + 0.5 * STAY_GROWTH and pace.rate(11.0, turning=True) == \
        4.0 + STAY_GROWTH, "keeping up"
    assert pace.rate(14.5, turning=True) == 4.0 + 2 * STAY_GROWTH, \
        "a wall second at most between two steps (a stall says nothing)"
    before = pace.value
    pace.at_limit(14.6)
    assert pace.value == pytest.approx(before * STAY_BACKOFF) and pace.backoffs == 1
    pace.at_limit(14.6 + STAY_REFRACTORY / 2)  # each message of a 50 Hz node: once per refractory period only
    assert pace.backoffs == 1
    for k in range(1, 40):
        pace.at_limit(14.6 + k * STAY_REFRACTORY)
    assert pace.value == STAY_FLOOR and pace.rate(14.6 + 39 * STAY_REFRACTORY) == STAY_FLOOR, "no growth meanwhile"


def test_stay_behind_grows_faster_while_the_robot_does_not_turn_and_starts_a_turn_at_the_last_turns_speed() -> None:
    pace = StayBehind(cap=0.0, start=4.0)
    pace.rate(0.0, turning=True)
    pace.at_limit(0.5)  # the first turn ends at 3.0x
    assert pace.rate(0.5, turning=True) == 3.0 and pace.turn_value == 3.0
    assert pace.rate(1.0) == 3.0 + 0.5 * STAY_GROWTH_STRAIGHT, "creeping: the straight growth"
    assert pace.rate(1.5) == 3.0 + STAY_GROWTH_STRAIGHT > STAY_GROWTH + 3.0
    assert pace.rate(1.6, turning=True) == 3.0 and pace.value == pytest.approx(3.0 + 0.1 * STAY_GROWTH), \
        "a new turn starts at the last turn's speed"
    slow = StayBehind(cap=0.0, start=4.0)
    slow.rate(0.0)
    for k in range(1, 6):
        slow.at_limit(k * STAY_REFRACTORY)
    assert slow.value < 2.0 and slow.rate(1.0, turning=True) == round(slow.value / 0.5) * 0.5, \
        "never faster than the straight speed when that is lower"


def test_stay_behind_keeps_under_its_cap_and_does_not_grow_while_the_node_is_not_followed() -> None:
    pace = StayBehind(cap=5.0, start=4.0)
    assert pace.rate(0.0) == 4.0 and pace.rate(1.0) == 5.0 and pace.rate(9.0) == 5.0
    quiet = StayBehind(cap=0.0, start=4.0)
    quiet.rate(0.0)
    quiet.idle()
    assert quiet.rate(30.0) == 4.0, "30 s of a silent node taught nothing"
    assert StayBehind(cap=0.5).rate(0.0) == 0.5, "a cap under the floor wins"


def test_without_a_margin_the_learnt_period_is_the_lead_as_lock_step_predicts() -> None:
    """bt_nav's own executive (sim-run, demo): no margin, so a 20 Hz follower is led exactly its period."""
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0)
    for k in range(5):
        f.report("exec", k * 100 * MS, False, wall=0.0)
    assert f.lead_ns("exec") == 100 * MS and f.limit_ns("exec") == 500 * MS


def test_holds_block_until_released_or_too_long() -> None:
    f = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0)
    f.report("referee", 0, True, wall=0.0)
    assert f.blocking(10 * MS, wall=4.0) == ("referee", [])
    f.report("referee", 0, False, wall=4.5)
    assert f.blocking(10 * MS, wall=4.5) == (None, [])
    f.report("referee", 0, True, wall=5.0)
    assert f.blocking(10 * MS, wall=10.1) == (None, ["referee"])
    assert f.leave("referee") and not f.leave("referee")
