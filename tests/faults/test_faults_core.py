"""Faults that need no DDS: the mission core ticked in-process (bt_nav.testing), where thousands of inputs are cheap.

The ROS edge only ever hands the core a :class:`~bt_nav.mission.scan.Scan` built from a LaserScan; the core itself
is also driven by the lock-step runner, which builds Scans directly, so here the fuzzer may put anything in
a Scan (any dtype, any shape, any scalar) and checks that no leaf ever raises and that the command obeys
the same oracle as over DDS. The time-jump cases show what a backward ``/clock`` jump does to the two
timeouts that live inside leaves (a maneuver's time allowance, an evaluation attempt's timeout).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from conftest import LONG, FaultCases
from faultkit import expected_proximity
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_nav.mission.params import SPECS as _SPECS  # noqa: E402
from bt_nav.mission.scan import MAX_BEAMS, Proximity, Scan
from bt_nav.testing import LocalTriggerClient, TickHarness

V_MAX, W_TURN = float(_SPECS["max_linear_speed"].default), float(_SPECS["angular_speed"].default)
SLOW = float(_SPECS["slow_linear_speed"].default)
W_MAX = max(W_TURN, float(_SPECS["maneuver_angular_speed"].default))
FREE_LIMITS = {"max_linear_speed": V_MAX}


class Events:
    """Collects the core's one-line events (the rclpy logger's role off-ROS)."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def info(self, msg: str) -> None:  # noqa: D102
        self.lines.append(f"INFO {msg}")

    def warning(self, msg: str) -> None:  # noqa: D102
        self.lines.append(f"WARN {msg}")

    def error(self, msg: str) -> None:  # noqa: D102
        self.lines.append(f"ERROR {msg}")

    def matching(self, text: str) -> list[str]:
        """Lines containing ``text``."""
        return [line for line in self.lines if text in line]


# ---------------------------------------------------------------------------------------------- the fuzzer
SCALARS = st.one_of(st.floats(), st.floats(-10.0, 10.0), st.integers(-5, 5),
                    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, 1e308, -1e308, 5e-324]),
                    st.sampled_from([None, "1.0", "x", 1j, np.float32(0.5), np.float16(2.0), np.int64(3)]))
DTYPES = st.sampled_from([np.float64, np.float32, np.float16, np.int32, np.uint8, np.int8, np.bool_,
                          np.complex64, object])


@st.composite
def any_scan(draw: st.DrawFn) -> Scan:
    """A Scan with anything in it: plausible layouts most of the time, any field broken, any dtype or shape."""
    n = draw(st.one_of(st.integers(0, 5), st.integers(6, 800)))
    angle_min = draw(st.floats(-7.0, 7.0))
    increment = draw(st.floats(0.001, 0.1)) * draw(st.sampled_from([1.0, -1.0]))
    fields: dict[str, Any] = {"angle_min": angle_min, "angle_max": angle_min + increment * max(n - 1, 0),
                              "angle_increment": increment, "range_min": draw(st.floats(0.0, 1.0)),
                              "range_max": draw(st.floats(1.5, 40.0))}
    for name in draw(st.one_of(st.just(set()), st.sets(st.sampled_from(sorted(fields)), max_size=3))):
        fields[name] = draw(SCALARS)
    values = st.one_of(st.floats(0.0, 5.0), st.sampled_from([math.nan, math.inf, -math.inf, 0.0]), st.floats())
    ranges: Any = np.full(n, draw(values))
    for _ in range(draw(st.integers(0, 4))):
        if n:
            first = draw(st.integers(0, n - 1))
            ranges[first:first + draw(st.integers(1, max(1, n // 4)))] = draw(values)
    shape = draw(st.sampled_from(["1d", "1d", "1d", "2d", "0d", "list"]))
    if shape == "2d":
        ranges = ranges.reshape(1, -1)
    elif shape == "0d":
        ranges = np.array(draw(values))
    dtype = draw(st.one_of(st.just(np.float64), DTYPES))
    if shape != "list":
        with np.errstate(all="ignore"):
            ranges = ranges.astype(dtype) if dtype is not object else ranges.astype(object)
    else:
        ranges = ranges.tolist()
    return Scan(ranges=ranges, **fields)


def oracle(scan: Scan) -> str:
    """What the tree must do: 'stop' (malformed) or the front's proximity class."""
    return expected_proximity(scan)


def test_fuzz_scans_through_the_core(faults: FaultCases) -> None:
    examples = 5000 if LONG else 300
    checked = (f"hypothesis, {examples} examples: Scans with any dtype (float16..complex, object, bool), shape "
               "(0-d, 2-D, list), scalar (None, str, complex, 1e308, subnormal, NaN) straight into MissionCore; "
               "no leaf ever raises (core.faults stays 0), every command finite and within limits and matching "
               "the oracle (malformed -> stop, unknown/close -> rotate in place, far -> slow turn, free -> full)")
    with faults.case(f"scan fuzzer in-process ({examples} examples)", "scan", checked) as case:
        th = TickHarness("none", {"mission_duration": 3600.0}, events=Events())  # 5000 ticks stay before it
        th.tick()  # the clock starts (arming at t=0 is refused)
        assert th.arm()[0]
        seen: dict[str, int] = {}

        @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
        @given(scan=any_scan())
        def one(scan: Scan) -> None:
            kind = oracle(scan)
            seen[kind] = seen.get(kind, 0) + 1
            th.scan = scan
            command = th.tick().command
            assert th.core.faults == 0, f"a leaf raised on {scan!r}: {th.core.events.lines[-3:]}"
            assert command.is_finite() and abs(command.linear) <= V_MAX + 1e-9 and abs(command.angular) <= W_MAX + 1e-9
            if kind == "stop":
                assert command.is_zero, f"moved on a malformed scan: {command}"
            elif kind in (Proximity.UNKNOWN.value, Proximity.CLOSE.value):
                assert command.linear == 0.0 and abs(abs(command.angular) - W_TURN) < 1e-9, command
            elif kind == Proximity.FAR.value:
                assert SLOW - 1e-9 <= command.linear <= V_MAX + 1e-9 and command.angular != 0.0, command
            else:
                assert command.linear == V_MAX and abs(command.angular) <= W_TURN, command

        one()
        case.note("examples by expected reaction: " + ", ".join(f"{k} {v}" for k, v in sorted(seen.items())))


def test_absurd_beam_count_in_process(faults: FaultCases) -> None:
    with faults.case("scan: 1,000,001 beams (in-process)", "scan",
                     f"more than MAX_BEAMS ({MAX_BEAMS}) beams is malformed ('too many beams'): stop, one line; "
                     "the next good scan drives again"):
        events = Events()
        th = TickHarness("none", events=events)
        th.tick()
        assert th.arm()[0]
        assert th.tick().command.linear == V_MAX
        n = MAX_BEAMS + 1
        th.scan = Scan(0.0, 2 * math.pi * (n - 1) / n, 2 * math.pi / n, 0.12, 3.5, np.full(n, 3.0, np.float32))
        assert all(th.tick().command.is_zero for _ in range(3))
        assert len(events.matching("malformed scan: too many beams")) == 1, events.lines
        th.see()
        assert th.tick().command.linear == V_MAX
        assert th.core.faults == 0


# ---------------------------------------------------------------------------------------------- backward clock jumps
def test_backward_jump_and_the_maneuver_allowance(faults: FaultCases) -> None:
    with faults.case("clock back 100 s mid-maneuver, odometry frozen (stuck robot)", "timing",
                     "maneuver C cannot finish (odometry says it does not turn); after a 100 s backward jump it must "
                     "still give up within its allowance (90 deg / rate + 1 + 2 s of ticks) and stop") as case:
        events = Events()
        th = TickHarness("C", {"trigger_at_arming": True}, events=events)
        th.feed_odom = False
        th.tick()
        assert th.arm()[0]
        th.see((0.0, 0.2))  # front obstacle nearer than pivot_distance: SmartPivot starts
        th.core.feed_odom(0.0)
        th.tick()
        assert "SmartPivot" in th.core.tip, th.core.tip
        for _ in range(20):  # 1 s of turning on frozen odometry
            th.core.feed_odom(0.0)
            th.tick()
        th.clock.advance(-100.0)  # simulator reset
        ticks = 0
        while th.core.value("maneuver_active", False) and ticks < 3000:
            th.core.feed_odom(0.0)
            th.tick()
            ticks += 1
        elapsed = 1.0 + ticks * th.dt
        assert not th.core.value("maneuver_active", False), "the maneuver never ended"
        assert len(events.matching("SmartPivot: out of time")) == 1, events.lines
        case.bug_check(elapsed <= 3.9 + 0.5, f"gave up after {elapsed:.1f} s of ticks")


def test_backward_jump_and_the_evaluation_timeout(faults: FaultCases) -> None:
    with faults.case("clock back 100 s during a pending evaluation call", "timing",
                     "the first call is lost (never answered); after a 100 s backward jump the retry must still "
                     "come after evaluation_timeout + retry_delay (2.5 s of ticks); robot stays stopped") as case:
        th = TickHarness("none", {"mission_duration": 10.0}, client=LocalTriggerClient(["hang"]), events=Events())
        th.tick()
        assert th.arm()[0]
        th.run_until(lambda record: th.core.mission_over)
        th.tick()  # the request goes out on the tick after the stop
        assert len(th.client.calls) == 1
        th.tick(10)
        th.clock.advance(-100.0)
        ticks = 0
        while len(th.client.calls) < 2 and ticks < 3000:
            assert th.tick().command.is_zero
            ticks += 1
        assert len(th.client.calls) == 2, "no retry at all"
        elapsed = 0.5 + ticks * th.dt
        case.bug_check(elapsed <= 2.5 + 0.5, f"the retry came after {elapsed:.1f} s of ticks")


def test_fault_injection_hook_refuses_bad_specs() -> None:
    """The test-only hook (BT_NAV_FAULT_INJECT) refuses what it cannot arm, so a typo cannot silently test nothing."""
    from faultinject import InjectedFaultError, inject_faults

    from bt_nav.ros.rosutil import ConfigError

    th = TickHarness("none", events=Events())
    with pytest.raises(ConfigError, match="no tree node named 'Nope'"):
        inject_faults(th.core.root, "Nope")
    with pytest.raises(ConfigError, match="integer >= 1"):
        inject_faults(th.core.root, "FullSpeed@0")
    assert inject_faults(th.core.root, " FullSpeed@2 , StopBlind ") == ["FullSpeed@2", "StopBlind@1"]
    th.tick()
    assert th.arm()[0]
    commands = [th.tick().command for _ in range(3)]
    assert [c.is_zero for c in commands] == [False, True, False]  # the 2nd update of FullSpeed raised, once
    assert th.core.faults == 1
    assert len(th.core.events.matching("exception in leaf 'FullSpeed': InjectedFaultError")) == 1
    assert issubclass(InjectedFaultError, RuntimeError)
