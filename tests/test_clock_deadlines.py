"""The deadline rule of :class:`bt_nav.ros.clocktimer.Deadlines`: rclpy's own timer's, on a jumping clock (pure; the
comparison with rclpy's timer over DDS is in tests/ros/test_clock_timers.py)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bt_nav.ros.clocktimer import Deadlines

MS = 1_000_000


def _fires(deadlines: Deadlines, samples: list[int]) -> list[int]:
    """The sample times a timer fires at (asked again at the same sample, as an executor would: it must not fire)."""
    out = []
    for now in samples:
        while deadlines.take(now):
            out.append(now)
    return out


def test_a_timer_fires_on_the_first_sample_at_or_after_each_deadline() -> None:
    deadlines = Deadlines(50 * MS, 0)
    assert _fires(deadlines, [10 * MS, 49 * MS, 50 * MS, 60 * MS, 99 * MS, 101 * MS]) == [50 * MS, 101 * MS]
    assert deadlines.next == 150 * MS, "the grid is kept: the next deadline is not 101 + 50 ms"


def test_a_jump_over_several_deadlines_fires_once_and_keeps_the_grid() -> None:
    deadlines = Deadlines(50 * MS, 0)
    assert _fires(deadlines, [1234 * MS]) == [1234 * MS]
    assert deadlines.next == 1250 * MS


def test_a_sample_exactly_on_a_later_deadline_fires_once() -> None:
    deadlines = Deadlines(50 * MS, 0)
    assert _fires(deadlines, [100 * MS]) == [100 * MS] and deadlines.next == 150 * MS
    assert _fires(deadlines, [150 * MS, 151 * MS, 200 * MS]) == [150 * MS, 200 * MS]


def test_a_clock_that_goes_back_restarts_one_period_later() -> None:
    deadlines = Deadlines(50 * MS, 0)
    _fires(deadlines, [500 * MS])
    assert _fires(deadlines, [20 * MS, 69 * MS, 70 * MS]) == [70 * MS]
    assert _fires(deadlines, [500 * MS, 20 * MS, 40 * MS, 60 * MS, 100 * MS]) == [500 * MS, 100 * MS]


def test_a_period_must_be_positive() -> None:
    with pytest.raises(ValueError, match="positive"):
        Deadlines(0, 0)


@given(st.lists(st.integers(min_value=1, max_value=400), min_size=1, max_size=60),
       st.integers(min_value=1, max_value=200))
def test_a_monotonic_clock_never_fires_early_and_never_misses_a_deadline_it_passed(steps: list[int],
                                                                                 period_ms: int) -> None:
    samples, now = [], 0
    for step in steps:
        now += step * MS
        samples.append(now)
    period = period_ms * MS
    deadlines = Deadlines(period, 0)
    count = 0
    for now in samples:
        if deadlines.take(now):
            count += 1
            assert count <= now // period, "a call before its deadline"
        assert deadlines.next > now, "a deadline at or before this sample left unserved"
        assert deadlines.next - period <= now, "the next deadline is the first one after this sample"
