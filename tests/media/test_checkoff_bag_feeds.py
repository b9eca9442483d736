"""The bag check-off's pure feeds (sim/bt_nav_sim/feeds.py): readings from recorded scans at their own angles, the
silences of a topic, the commands a robot did not follow."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.feeds import ScanReadings, gaps, not_followed, usable_ranges
from bt_nav_sim.readings import SectorFamily

from bt_nav.mission.scan import Scan


def _scan(n: int, a0: float, ranges: np.ndarray, rmin: float = 0.0, rmax: float = 100.0) -> Scan:
    inc = 2 * math.pi / n
    return Scan(a0, a0 + (n - 1) * inc, inc, rmin, rmax, ranges.astype(np.float32))


def test_invalid_values_are_dropped_not_read_as_obstacles() -> None:
    r = np.array([0.0, np.nan, np.inf, 150.0, 0.05, 1.5, -np.inf])
    out = usable_ranges(Scan(0.0, 6 * 0.1, 0.1, 0.1, 100.0, r))
    assert np.isinf(out[:5]).all() and out[5] == pytest.approx(1.5)
    assert out[6] == pytest.approx(0.1)  # REP 117's -inf, "too close to measure", as the executive reads it


@pytest.mark.parametrize("n", [449, 460, 471])  # an LDS-02 publishes another beam count every scan
def test_the_front_is_found_from_each_scans_own_angles(n: int) -> None:
    angles = 0.3 + 2 * math.pi / n * np.arange(n)
    deg = np.degrees(np.remainder(angles + math.pi, 2 * math.pi) - math.pi)
    ranges = np.full(n, 3.0)
    ranges[np.abs(deg) <= 3.0] = 0.45  # the object straight ahead
    ranges[::5] = np.nan  # 20 % lost returns
    ranges[np.abs(deg - 90) < 2] = 0.0  # "no return" beside it, not an obstacle
    source = ScanReadings(SectorFamily(), half_width=0.18)
    source.add(1.0, _scan(n, 0.3, ranges))
    r = source.reading_at(1.1)
    assert r is not None and r.front == pytest.approx(0.45, abs=1e-6) and r.ahead == pytest.approx(0.45, abs=0.01)
    assert r.left == pytest.approx(3.0)


def test_the_reading_at_a_time_is_the_latest_scan_at_or_before_it_and_none_after_a_silence() -> None:
    source = ScanReadings(SectorFamily(), half_width=0.18, mount=(-0.032, 0.0))
    for t, d in ((1.0, 2.0), (1.2, 1.0), (1.4, 0.5)):
        source.add(t, _scan(360, 0.0, np.full(360, d)))
    source.add(1.3, _scan(360, 0.0, np.full(360, 9.0)))  # out of order: skipped
    assert source.reading_at(0.9) is None
    assert source.reading_at(1.25).front == pytest.approx(1.0)
    assert source.reading_at(1.4).front == pytest.approx(0.5)
    # the swept path's first return, from the robot's centre: a ring 0.5 m round the sensor meets the path's edge
    assert source.reading_at(1.4).ahead == pytest.approx(0.5 * math.cos(math.asin(0.18 / 0.5)) - 0.032, abs=0.01)
    assert source.reading_at(2.3) is not None and source.reading_at(2.5) is None and source.skipped == 1


def test_gaps_name_a_silence_and_not_a_hiccup() -> None:
    t = list(np.arange(0.0, 12.0, 0.2))
    t = [x for x in t if not 5.0 < x < 7.4] + [5.1]  # a 0.3 s hiccup is not a gap
    t = [x for x in t if not 5.15 < x < 7.4]
    found = gaps("/scan", t, within=(0.0, 14.0))
    assert [(round(g.start, 1), round(g.length, 1)) for g in found] == [(5.1, 2.3), (11.8, 2.2)]
    assert found[0].text(0.0) == "no /scan for 2.3 s from t=5.1 s"
    assert gaps("/scan", [], within=(0.0, 3.0))[0].length == 3.0


def _yaw(rates: list[tuple[float, float]], dt: float = 0.05, end: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """Yaw samples of a robot turning at the (from t, rate) pieces."""
    t = np.arange(0.0, end, dt)
    w = np.zeros_like(t)
    for start, rate in rates:
        w[t >= start] = rate
    return t, np.concatenate(([0.0], np.cumsum(w[:-1] * dt)))


def test_a_robot_that_follows_a_closed_loop_turn_is_not_flagged() -> None:
    t, yaw = _yaw([(1.1, -0.8), (4.1, 0.0)])
    cmds = [(x, 0.0, -0.8 + 0.3 * (x - 1.0) / 3.0) for x in np.arange(1.0, 4.0, 0.1)] + [(4.0, 0.05, 0.0)]
    assert not_followed(t, yaw, cmds) == []


def test_handled_stalled_and_uncommanded_turns_are_flagged() -> None:
    cmds = [(x, 0.0, -0.6) for x in np.arange(1.0, 8.0, 0.1)]
    t, yaw = _yaw([(1.1, -0.6), (3.0, +1.2), (5.0, -0.6)])  # a person turns it left for 2 s
    (found,) = not_followed(t, yaw, cmds)
    assert found.kind == "moved by hand" and found.start == pytest.approx(3.0, abs=0.3)
    assert found.turned_deg == pytest.approx(math.degrees(2.4), abs=8) and "against the command" in found.text(0.0)
    t, yaw = _yaw([(1.1, -0.6), (3.0, 0.0), (6.0, -0.6)])  # blocked for 3 s
    assert [d.kind for d in not_followed(t, yaw, cmds)] == ["stuck"]
    still = [(x, 0.0, 0.0) for x in np.arange(0.0, 10.0, 0.1)]
    t, yaw = _yaw([(4.0, 0.9), (6.0, 0.0)])
    assert [(d.kind, d.how) for d in not_followed(t, yaw, still)] == [("moved by hand", "with no turn commanded")]
    assert not_followed(t, yaw, [(0.0, 0.0, 0.0)]) == []  # a command 4 s old is not in force: a gap says that
