"""The bag check-off's pure feeds (bt_nav/judge/feeds.py): readings from recorded scans at their own angles, the
silences of a topic, the commands a robot did not follow."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_nav.judge.feeds import ScanReadings, SourceReadings, TriggerFeed, gaps, not_followed, story, usable_ranges
from bt_nav.judge.readings import SectorFamily
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



def test_a_robots_feed_gives_each_armed_pose_its_scans_reading_and_an_earlier_pose_one_only_when_asked() -> None:
    """The judge's feed over recorded scans (a :class:`TriggerFeed`): an armed sample reads the scan at or before it;
    a sample before the arming has no reading (``at``) unless an episode asks for it (``cast``), and then the scan
    of its own time, not a later one."""
    source = ScanReadings(SectorFamily(), half_width=0.18)
    for t, d in ((1.0, 2.0), (1.2, 1.0), (1.4, 0.5)):
        source.add(t, _scan(360, 0.0, np.full(360, d)))
    feed: TriggerFeed = SourceReadings(source)
    for t, armed in ((1.1, False), (1.3, True), (1.5, True), (0.5, True)):
        feed.add(0.0, 0.0, 0.0, t, armed)
    assert feed.at(0) is None and feed.cast(0).front == pytest.approx(2.0)
    assert feed.at(1).front == pytest.approx(1.0) and feed.cast(1) is feed.at(1)
    assert feed.at(2).front == pytest.approx(0.5)
    assert feed.at(3) is None  # armed, but no scan yet: nothing known then
    feed.on_walkers(1.0, [[0.0, 0.5, 0.2]])  # a robot's scans see people themselves: nothing changes
    assert feed.at(2).front == pytest.approx(0.5)

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


def test_a_stall_a_push_a_fast_spin_and_a_carry_are_each_set_apart() -> None:
    """Pure synthetic feeds (no DDS): each way a robot does not follow its command, named and timed."""
    cmds = [(x, 0.0, -0.22) for x in np.arange(1.0, 9.0, 0.1)]
    t, yaw = _yaw([(1.1, -0.22), (3.0, -0.02), (6.0, -0.22)])  # stuck 3 s: turning a tenth of the command
    (stall,) = not_followed(t, yaw, cmds)
    assert stall.kind == "stuck" and stall.text(0.0).startswith("stuck from t=3.")
    assert "while commanded -0.22 rad/s" in stall.text(0.0) and stall.end - stall.start >= 2.5
    t, yaw = _yaw([(1.1, -0.22), (4.0, 1.4), (4.6, -0.22)])  # +48 deg in 0.6 s against the command: a hand
    (push,) = not_followed(t, yaw, cmds)
    assert push.kind == "moved by hand" and push.how == "against the command" and push.turned_deg > 30
    t, yaw = _yaw([(1.1, -0.22), (4.0, -1.3), (5.5, -0.22)])  # six times the command: turned by hand
    (fast,) = not_followed(t, yaw, cmds)
    assert fast.kind == "moved by hand" and fast.how.startswith("faster than twice the command")
    t, yaw = _yaw([(1.1, -0.22), (4.0, -3.5), (4.3, -0.22)])  # faster than the base can turn at all
    assert any("faster" in d.how for d in not_followed(t, yaw, cmds))
    still = [(x, 0.0, 0.0) for x in np.arange(0.0, 10.0, 0.1)]
    t = np.arange(0.0, 10.0, 0.05)
    x = np.where(t < 4.0, 0.0, np.minimum(t - 4.0, 1.5) * 0.3)  # carried forward 0.45 m, no forward command
    (carry,) = not_followed(t, np.zeros_like(t), still, xy=np.column_stack([x, np.zeros_like(t)]))
    assert carry.kind == "carried" and carry.moved_m == pytest.approx(0.45, abs=0.05)
    assert "with no forward command" in carry.text(0.0)


def test_the_story_of_a_turn_says_what_happened_and_when() -> None:
    cmds = [(x, 0.0, -0.22) for x in np.arange(1.0, 9.0, 0.1)]
    t, yaw = _yaw([(1.1, -0.22), (2.0, 0.0), (6.0, 1.4), (6.6, -0.22)])
    said = story(not_followed(t, yaw, cmds), 0.0)
    assert said.startswith("stuck from t=2.") and "; then moved by hand at t=5.8 s: +4" in said  # span-smoothed
    assert "against the command" in said


@pytest.mark.parametrize("lag", [0.3, -0.3, 1795897414.86])
def test_header_stamps_ahead_of_behind_and_on_another_clock_are_read_as_stated(lag: float) -> None:
    from bt_nav.media.robotbag import _aligned

    receive = [int((100.0 + 0.1 * k + 0.02 * (k % 3)) * 1e9) for k in range(50)]
    rows = [(r, int(r - lag * 1e9), k) for k, r in enumerate(receive)]
    notes: list[str] = []
    out = _aligned(rows, "/odom", notes)
    assert [m for _, m in out] == list(range(50))  # the stamps' order and spacing kept, on the receiver's clock
    assert abs(out[0][0] - 100.0) < 0.05
    (note,) = notes
    if abs(lag) > 60:
        assert "on a clock of their own" in note and "1795897414" not in note
    else:
        assert f"0.30 s {'behind' if lag > 0 else 'ahead of'} their receive times" in note


def test_nan_and_inf_runs_and_a_beam_count_changing_every_scan_are_read_as_stated() -> None:
    source = ScanReadings(SectorFamily(), half_width=0.18)
    for k, n in enumerate((155, 234, 190, 171)):  # an LDS-02: another beam count every scan
        ranges = np.full(n, 2.0)
        ranges[: n // 5] = np.nan  # a run of lost returns
        ranges[n // 5: n // 3] = np.inf
        deg = np.degrees(np.remainder(2 * math.pi / n * np.arange(n) + math.pi, 2 * math.pi) - math.pi)
        ranges[np.abs(deg) <= 5.0] = 0.4 + 0.01 * k
        source.add(1.0 + 0.1 * k, _scan(n, 0.0, ranges))
    for k in range(4):
        r = source.reading_at(1.0 + 0.1 * k + 0.05)
        assert r is not None and r.front == pytest.approx(0.4 + 0.01 * k, abs=1e-5)
    assert source.skipped == 0 and source.reading_at(3.0) is None  # a gap: nothing known there
