"""Kinematics, limits, collisions and tunnelling of bt_nav_sim.physics."""

from __future__ import annotations

import math

import pytest
from bt_nav_sim import RobotParams, RobotState, load_world, step, world_from_dict
from bt_nav_sim.physics import ClearanceMemo, wheel_limited
from hypothesis import given, settings
from hypothesis import strategies as st

P = RobotParams()
VOID = world_from_dict({"name": "void"})


def _run(state: RobotState, v: float, w: float, dt: float, n: int, world=VOID) -> RobotState:
    for _ in range(n):
        state, _ = step(state, v, w, dt, world)
    return state


def test_burger_defaults() -> None:
    assert (P.max_linear, P.max_angular, P.radius) == (0.22, 2.84, 0.12)


@pytest.mark.parametrize("dt", [0.01, 0.02, 0.05, 0.1])
def test_straight_line_with_accel_ramp(dt: float) -> None:
    # Ramp 0 -> 0.22 m/s at 2.5 m/s^2 takes 0.088 s and covers 0.22^2 / (2 * 2.5) = 0.00968 m, i.e.
    # 0.00968 m less than cruising the whole second: x(1 s) = 0.22 - 0.00968 = 0.21032, for any dt.
    s = _run(RobotState(0.0, 0.0, 0.0), 0.22, 0.0, dt, round(1.0 / dt))
    assert s.x == pytest.approx(0.21032, abs=1e-12)
    assert s.y == pytest.approx(0.0, abs=1e-15)
    assert s.yaw == 0.0
    assert s.v == pytest.approx(0.22)
    assert not s.colliding


def test_straight_line_along_heading() -> None:
    s = _run(RobotState(1.0, 2.0, math.pi / 2, v=0.22), 0.22, 0.0, 0.1, 10)
    assert (s.x, s.y) == pytest.approx((1.0, 2.22), abs=1e-12)


def test_rotate_in_place() -> None:
    # Ramp to 1 rad/s at 10 rad/s^2 loses 1 / (2 * 10) = 0.05 rad: yaw(1 s) = 0.95.
    s = _run(RobotState(0.3, -0.4, 0.0), 0.0, 1.0, 0.01, 100)
    assert s.yaw == pytest.approx(0.95, abs=1e-12)
    assert (s.x, s.y) == (0.3, -0.4)
    assert s.w == pytest.approx(1.0)


def test_yaw_wraps() -> None:
    s = _run(RobotState(0.0, 0.0, 3.0, w=1.0), 0.0, 1.0, 0.1, 3)
    assert s.yaw == pytest.approx(3.3 - 2 * math.pi)


@pytest.mark.parametrize("v, w", [(0.2, 0.5), (0.1, -2.0), (-0.15, 1.3), (0.22, 1e-12)])
def test_arc_matches_closed_form(v: float, w: float) -> None:
    x0, y0, th0, T = 0.5, -1.0, 0.3, 2.0
    s = _run(RobotState(x0, y0, th0, v=v, w=w), v, w, 0.05, 40)
    if abs(w) > 1e-9:
        ex = x0 + v / w * (math.sin(th0 + w * T) - math.sin(th0))
        ey = y0 - v / w * (math.cos(th0 + w * T) - math.cos(th0))
    else:
        ex, ey = x0 + v * T * math.cos(th0), y0 + v * T * math.sin(th0)
    assert (s.x, s.y) == pytest.approx((ex, ey), abs=1e-9)
    assert math.remainder(s.yaw - (th0 + w * T), 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    # One big step gives the same exact arc.
    one, _ = step(RobotState(x0, y0, th0, v=v, w=w), v, w, T, VOID)
    assert (one.x, one.y) == pytest.approx((ex, ey), abs=1e-9)


def test_arc_from_rest_heading_exact() -> None:
    # w ramps 0 -> 0.5 in 0.05 s, losing 0.5 * 0.05 / 2 = 0.0125 rad; the distance loses 0.2^2 / 5 = 0.008 m.
    s = _run(RobotState(0.0, 0.0, 0.0), 0.2, 0.5, 0.01, 200)
    assert s.yaw == pytest.approx(0.5 * 2.0 - 0.0125, abs=1e-12)
    chord = math.hypot(s.x, s.y)
    arc_len = 0.2 * 2.0 - 0.008
    assert chord < arc_len and chord == pytest.approx(arc_len, rel=0.05)


@pytest.mark.parametrize("cmd_v, cmd_w, ev, ew", [(1.0, 10.0, 0.22, 2.84), (-5.0, -99.0, -0.22, -2.84)])
def test_limits_clamp(cmd_v: float, cmd_w: float, ev: float, ew: float) -> None:
    s = _run(RobotState(0.0, 0.0, 0.0), cmd_v, cmd_w, 0.05, 20)
    assert (s.v, s.w) == pytest.approx((ev, ew))


def test_acceleration_limits_one_step() -> None:
    s, _ = step(RobotState(0.0, 0.0, 0.0), 0.22, 2.84, 0.02, VOID)
    assert s.v == pytest.approx(2.5 * 0.02)
    assert s.w == pytest.approx(10.0 * 0.02)
    s, _ = step(RobotState(0.0, 0.0, 0.0, v=0.22, w=2.0), 0.0, -2.0, 0.02, VOID)
    assert s.v == pytest.approx(0.22 - 0.05)
    assert s.w == pytest.approx(2.0 - 0.2)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, None, "fast"])
def test_bad_commands_mean_zero(bad) -> None:
    s0 = RobotState(0.0, 0.0, 0.0)
    s, collided = step(s0, bad, bad, 0.1, VOID)
    assert (s.x, s.y, s.yaw, s.v, s.w) == (0.0, 0.0, 0.0, 0.0, 0.0)
    assert not collided
    # A moving robot brakes towards 0 under the limits instead of jumping or crashing.
    s, _ = step(RobotState(0.0, 0.0, 0.0, v=0.2, w=1.0), bad, 0.5, 0.02, VOID)
    assert s.v == pytest.approx(0.15) and s.w == pytest.approx(0.8)  # w: 1.0 -> 0.5 at 10 rad/s^2


@pytest.mark.parametrize("dt", [0.0, -0.1, math.nan, math.inf])
def test_bad_dt_is_no_motion(dt: float) -> None:
    s, collided = step(RobotState(1.0, 1.0, 0.5, v=0.1), 0.22, 1.0, dt, VOID)
    assert (s.x, s.y, s.yaw) == (1.0, 1.0, 0.5)
    assert not collided


def test_input_state_not_mutated() -> None:
    s0 = RobotState(0.0, 0.0, 0.0)
    step(s0, 0.22, 1.0, 0.1, VOID)
    assert s0 == RobotState(0.0, 0.0, 0.0)


def test_drive_into_wall_never_penetrates_then_turns_away() -> None:
    world = load_world("empty_room")  # inner wall faces at +-2.0 m
    s = RobotState(0.0, 0.0, 0.0)
    hits = []
    for _ in range(200):  # 10 s at full speed
        s, collided = step(s, 0.22, 0.0, 0.05, world)
        assert world.clearance(s.x, s.y) >= P.radius - 1e-6
        assert s.colliding == collided
        hits.append(collided)
    first = hits.index(True)
    assert all(hits[first:])  # blocked on every step while pushing
    assert 0 < first < 200
    assert s.x == pytest.approx(2.0 - P.radius, abs=1e-6)  # stopped touching the wall
    assert s.v == 0.0

    # Still pushing, but turning: the position is held, the rotation is applied.
    before = (s.x, s.y)
    s, collided = step(s, 0.22, 2.84, 0.05, world)
    assert collided and (s.x, s.y) == pytest.approx(before, abs=1e-6) and s.yaw > 0.0

    # Turn around in place and drive off.
    while abs(math.remainder(s.yaw - math.pi, 2 * math.pi)) > 0.05:
        s, _ = step(s, 0.0, 2.0, 0.02, world)
    s = _run(s, 0.0, 0.0, 0.05, 10, world)
    assert (s.x, s.y) == pytest.approx(before, abs=1e-6)
    for _ in range(20):
        s, collided = step(s, 0.22, 0.0, 0.05, world)
    assert not collided and not s.colliding
    assert s.x < 2.0 - P.radius - 0.1


@pytest.mark.parametrize("thickness", [0.15, None])
@pytest.mark.parametrize(
    "params, dt",
    [(P, 0.1), (RobotParams(max_linear=20.0, max_linear_accel=1e4), 0.1)],
    ids=["burger", "20m/s"],
)
def test_no_tunnelling(thickness: float | None, params: RobotParams, dt: float) -> None:
    """A 0.15 m wall (or a zero-thickness segment) at x = 1 stops the robot even at 2 m per step."""
    if thickness is None:
        world = world_from_dict({"name": "thin", "segments": [[1.0, -3.0, 1.0, 3.0]]})
        face = 1.0
    else:
        world = world_from_dict(
            {"name": "wall", "boxes": [{"x": 1.0, "y": 0, "length": 6, "thickness": thickness, "yaw_deg": 90}]}
        )
        face = 1.0 - thickness / 2
    s = RobotState(0.0, 0.0, 0.0)
    collided_any = False
    for _ in range(100):
        s, collided = step(s, params.max_linear, 0.0, dt, world, params)
        collided_any |= collided
        assert s.x <= face - params.radius + 1e-9
    assert collided_any
    assert s.x == pytest.approx(face - params.radius, abs=1e-6)


def test_glancing_slide_along_wall_is_blocked_not_penetrating() -> None:
    world = load_world("empty_room")
    s = RobotState(0.0, 1.7, math.radians(30))
    for _ in range(100):
        s, _ = step(s, 0.22, 0.3, 0.1, world)
        assert world.clearance(s.x, s.y) >= P.radius - 1e-6


def test_robot_spawned_overlapping_can_back_out() -> None:
    world = world_from_dict({"name": "wall", "segments": [[1.0, -1.0, 1.0, 1.0]]})
    s = RobotState(0.95, 0.0, 0.0)  # 0.05 m from the wall: overlapping
    s, collided = step(s, 0.22, 0.0, 0.1, world)  # deeper: refused
    assert collided and s.x == 0.95
    s = RobotState(0.95, 0.0, math.pi)
    s = _run(s, 0.22, 0.0, 0.1, 10, world)  # away: allowed
    assert s.x < 0.95 - 0.1


@settings(max_examples=40, deadline=None)
@given(
    cmds=st.lists(
        st.tuples(
            st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-0.3, 0.3)),
            st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-3.0, 3.0)),
            st.floats(0.001, 0.1),
        ),
        min_size=1,
        max_size=60,
    )
)
def test_random_commands_never_penetrate(cmds: list[tuple[float, float, float]]) -> None:
    world = load_world("stage_4")
    s = RobotState(*world.spawn)
    for v, w, dt in cmds:
        s, _ = step(s, v, w, dt, world)
        assert all(math.isfinite(a) for a in (s.x, s.y, s.yaw, s.v, s.w))
        assert world.clearance(s.x, s.y) >= P.radius - 1e-6
        assert abs(s.v) <= P.max_linear and abs(s.w) <= P.max_angular
        assert -math.pi <= s.yaw < math.pi


@settings(max_examples=30, deadline=None)
@given(cmds=st.lists(st.tuples(st.floats(-0.3, 0.3), st.floats(-3.0, 3.0), st.floats(0.001, 0.5)),
                     min_size=1, max_size=80))
def test_the_clearance_memo_changes_no_step(cmds: list[tuple[float, float, float]]) -> None:
    """Steps that carry the last exact clearance over (the simulator's way) land exactly where steps that query
    it afresh do, bumps into walls included; a world whose version changed is not answered from the memo."""
    world = load_world("stage_4")
    memo = ClearanceMemo()
    fresh = kept = RobotState(*world.spawn)
    for v, w, dt in cmds:
        fresh, hit_fresh = step(fresh, v, w, dt, world)
        kept, hit_kept = step(kept, v, w, dt, world, P, memo)
        assert (kept, hit_kept) == (fresh, hit_fresh)
    assert memo.recall(world) is not None
    assert memo.recall(load_world("stage_4")) is None, "another world object"
    object.__setattr__(world, "version", world.version + 1)
    assert memo.recall(world) is None, "an object appeared"


# ------------------------------------------------------------------------------------------ burger kinematics
BURGER = RobotParams(kinematics="burger")


@pytest.mark.parametrize(("v", "w", "expected"), [
    (0.22, 0.0, (0.22, 0.0)),  # straight: both wheels at 0.22, under the 0.2272 limit
    (0.0, 2.84, (0.0, 2.84)),  # the published spin: both wheels exactly at the limit
    (0.0, -2.84, (0.0, -2.84)),
    (0.1, 1.0, (0.1, 1.0)),  # wheels 0.02 and 0.18: nothing to clamp
    # wheels 0.02 and 0.42 -> 0.02 and 0.2272: v = 0.1236, w = (0.2272 - 0.02) / 0.16 = 1.295
    (0.22, 2.5, (0.1236, 1.295)),
    (0.22, -2.5, (0.1236, -1.295)),
    (-0.22, 2.5, (-0.1236, 1.295)),
    # wheels -0.14 and 0.3 -> -0.14 and 0.2272: v = 0.0436, w = 2.295
    (0.08, 2.75, (0.0436, 2.295)),
])
def test_burger_clamps_each_wheel(v: float, w: float, expected: tuple[float, float]) -> None:
    assert wheel_limited(v, w, BURGER) == pytest.approx(expected, abs=1e-12)
    assert wheel_limited(v, w, P) == (v, w)  # ideal: the unicycle command as given


def test_burger_turning_at_speed_costs_forward_speed() -> None:
    ideal = _run(RobotState(0.0, 0.0, 0.0), 0.22, 2.5, 0.01, 200)
    burger = RobotState(0.0, 0.0, 0.0)
    for _ in range(200):
        burger, _ = step(burger, 0.22, 2.5, 0.01, VOID, BURGER)
    assert (ideal.v, ideal.w) == pytest.approx((0.22, 2.5))
    assert (burger.v, burger.w) == pytest.approx((0.1236, 1.295))
    # turning radius v / w is larger on the wheel-limited robot: 0.0954 m against 0.088 m
    assert burger.v / burger.w > ideal.v / ideal.w


@given(v=st.floats(-0.5, 0.5), w=st.floats(-4.0, 4.0))
@settings(max_examples=200, deadline=None)
def test_burger_wheels_never_exceed_the_limit(v: float, w: float) -> None:
    lin, ang = wheel_limited(max(-0.22, min(0.22, v)), max(-2.84, min(2.84, w)), BURGER)
    half = BURGER.wheel_separation / 2
    for wheel in (lin - ang * half, lin + ang * half):
        assert abs(wheel) <= BURGER.max_wheel_speed + 1e-12


def test_unknown_kinematics_is_refused() -> None:
    with pytest.raises(ValueError, match="kinematics"):
        RobotParams(kinematics="tank")
