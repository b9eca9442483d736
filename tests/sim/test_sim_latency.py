"""Actuation latency in SimCore: a command reaches the wheels ``actuation_latency`` later, exactly, with
the same physics; latency 0 is the old path bit for bit; merged steps never straddle a queued command."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.core import SimConfig, SimCore
from bt_nav_sim.multi import MultiSimCore
from bt_nav_sim.physics import RobotState, step

# A command sequence (v, w) per 10 ms step with changes at odd moments: straight, arc, spin, stop, back.
COMMANDS = ([(0.0, 0.0)] * 7 + [(0.2, 0.0)] * 53 + [(0.15, 0.8)] * 41 + [(0.0, 1.5)] * 77
            + [(0.0, 0.0)] * 23 + [(-0.1, -0.4)] * 30 + [(0.22, 0.0)] * 69)


def _physics_replay(core: SimCore, commands: list[tuple[float, float]]) -> list[tuple[float, ...]]:
    """The trajectory that physics.step alone gives for ``commands`` (one per step): the reference."""
    state = RobotState(*core.spawn)
    dt = core.step_ns * 1e-9
    out = []
    for v, w in commands:
        state, _ = step(state, v, w, dt, core.world, core.params)
        out.append((state.x, state.y, state.yaw, state.v, state.w))
    return out


def _core_run(core: SimCore, commands: list[tuple[float, float]]) -> list[tuple[float, ...]]:
    out = []
    for v, w in commands:
        core.advance(v, w)
        s = core.state
        out.append((s.x, s.y, s.yaw, s.v, s.w))
    return out


def _config(latency: float = 0.0, **kw) -> SimConfig:
    return SimConfig(world="empty_room", noise=False, actuation_latency=latency, **kw)


def test_latency_zero_is_the_physics_bit_for_bit() -> None:
    core = SimCore(_config(0.0))
    assert _core_run(core, COMMANDS) == _physics_replay(core, COMMANDS)
    assert core.in_force == COMMANDS[-1]


@pytest.mark.parametrize("latency, shift", [(0.1, 10), (0.15, 15), (0.123, 13)])
def test_a_command_takes_effect_exactly_latency_later(latency: float, shift: int) -> None:
    """Latency L: the physics under the sequence delayed by ceil(L / dt) steps (the first step starting
    at or after t + L), the first L under the command in force before (a stop)."""
    core = SimCore(_config(latency))
    delayed = [(0.0, 0.0)] * shift + COMMANDS[:-shift]
    assert _core_run(core, COMMANDS) == _physics_replay(core, delayed)


def test_the_effect_of_a_step_command_appears_at_t_plus_latency() -> None:
    core = SimCore(_config(0.15))
    core.advance(0.0, 0.0, 20)  # at rest until t = 0.2 s
    x0 = core.state.x
    moved_at = None
    for _ in range(40):
        core.advance(0.2, 0.0)
        if moved_at is None and core.state.x != x0:
            moved_at = core.t_ns - core.step_ns  # the step that moved started here
    assert moved_at == 350_000_000  # 0.2 s + 0.15 s


def _merged_run(core: SimCore, commands_at: dict[int, tuple[float, float]], end_ns: int,
                merge: bool) -> list[tuple[int, float, float, float, bool, bool]]:
    """Like lock-step: commands change at given times (ticks), the steps between merged or not; returns
    (t, x, y, yaw, scan due, odom due) at every output."""
    ticks = sorted(commands_at)
    cmd = (0.0, 0.0)
    out = []
    while core.t_ns < end_ns:
        cmd = commands_at.get(core.t_ns, cmd)
        nxt = next((t for t in ticks if t > core.t_ns), end_ns)
        steps = core.steps_until(nxt) if merge else 1
        o = core.advance(*cmd, steps)
        if merge or o.scan is not None or o.odom:
            out.append((core.t_ns, core.state.x, core.state.y, core.state.yaw, o.scan is not None, o.odom))
    return out


def test_merged_steps_match_single_steps_with_latency() -> None:
    ms = 1_000_000
    commands_at = {0: (0.2, 0.0), 250 * ms: (0.1, 1.2), 430 * ms: (0.0, -2.0), 910 * ms: (0.0, 0.0),
                   1200 * ms: (0.22, 0.3), 1750 * ms: (0.0, 0.0)}
    merged = _merged_run(SimCore(_config(0.13, profile="lab", odom_rate_hz=10.0)), commands_at, 3000 * ms, True)
    single = _merged_run(SimCore(_config(0.13, profile="lab", odom_rate_hz=10.0)), commands_at, 3000 * ms, False)
    assert len(merged) < 100  # 300 steps: merging did happen
    single_by_t = {row[0]: row for row in single}
    outputs = [row for row in merged if row[4] or row[5]]
    assert [r[0] for r in outputs] == [r[0] for r in single]  # same output schedule
    for row in outputs:
        ref = single_by_t[row[0]]
        assert row[4:] == ref[4:]
        assert math.hypot(row[1] - ref[1], row[2] - ref[2]) < 1e-9 and abs(row[3] - ref[3]) < 1e-9


def test_steps_until_stops_at_a_queued_command() -> None:
    core = SimCore(_config(0.15, profile="lab", odom_rate_hz=1.0))
    core.outputs()
    core.advance(0.2, 0.0)  # given at t = 0, effective at 0.15 s
    assert core.steps_until(10**10) == 14  # 0.01 s -> 0.15 s, not to the next scan at 0.2 s


def _spin_overshoot(latency: float, w: float = 1.5) -> tuple[float, float]:
    """(angle at the cut, final angle): spin at ``w`` until the true yaw has turned pi (a controller that
    sees its rotation without delay), then command a stop and let it settle."""
    core = SimCore(_config(latency))
    turned, last = 0.0, core.state.yaw
    while turned < math.pi:
        core.advance(0.0, w)
        turned += math.remainder(core.state.yaw - last, 2 * math.pi)
        last = core.state.yaw
    at_cut = turned
    for _ in range(200):
        core.advance(0.0, 0.0)
        turned += math.remainder(core.state.yaw - last, 2 * math.pi)
        last = core.state.yaw
    return at_cut, turned


@pytest.mark.parametrize("latency", [0.1, 0.15])
def test_a_spin_cut_at_its_angle_overshoots_by_w_times_latency(latency: float) -> None:
    w = 1.5
    _, final0 = _spin_overshoot(0.0, w)
    _, final = _spin_overshoot(latency, w)
    # the stop reaches the wheels L later: w * L more rotation (0.15 rad = 8.6 deg at 0.1 s, 12.9 deg at 0.15 s)
    assert final - final0 == pytest.approx(w * latency, abs=0.011)


def test_an_open_loop_timed_spin_is_late_not_longer() -> None:
    """Cut at the nominal time pi / w after the first command: latency shifts the spin, so at the cut the
    robot is short by w * L, and the stop arriving L later makes the total the same as without latency."""
    w, latency = 1.5, 0.15
    totals = []
    for lat in (0.0, latency):
        core = SimCore(_config(lat))
        yaws = [core.state.yaw]
        n = round(math.pi / w / 0.01)
        for i in range(n + 300):
            core.advance(0.0, w if i < n else 0.0)
            yaws.append(core.state.yaw)
        unwrapped = np.unwrap(yaws) - yaws[0]
        totals.append((unwrapped[n], unwrapped[-1]))
    (cut0, total0), (cut1, total1) = totals
    assert cut0 - cut1 == pytest.approx(w * latency, abs=0.02)
    assert total1 == pytest.approx(total0, abs=1e-9)


def test_latency_is_validated() -> None:
    for bad in (-0.01, math.nan, math.inf, 2.5):
        with pytest.raises(ValueError, match="actuation_latency"):
            SimCore(_config(bad))
    SimCore(_config(2.0))


def test_multi_robot_latency_per_robot() -> None:
    config = _config(0.0)
    multi = MultiSimCore(config, 2, latencies=(0.0, 0.1))
    assert [c.latency_ns for c in multi.cores] == [0, 100_000_000]
    x0 = [c.state.x for c in multi.cores]
    multi.advance([(0.2, 0.0), (0.2, 0.0)], 5)
    moved = [c.state.x - x for c, x in zip(multi.cores, x0, strict=True)]
    assert moved[0] > 0 and moved[1] == 0  # robot 2's command is still on its way
    multi.advance([(0.2, 0.0), (0.2, 0.0)], 10)
    assert multi.cores[1].state.x > x0[1]
    with pytest.raises(ValueError, match="latencies"):
        MultiSimCore(config, 2, latencies=(0.1,))
    # one robot: the single-robot core with its latency, merged steps allowed
    solo = MultiSimCore(_config(0.1))
    assert solo.cores[0].latency_ns == 100_000_000
