"""The perception leaves alone: ProcessScan's verdicts and the obstacle questions, on synthetic scans.

The obstacle questions read what ProcessScan wrote, so each test feeds a scan through ProcessScan first
(as the tree does) instead of building the sector and path values by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from leafkit import Board, Events, Status, make, tick

from bt_nav.mission.behaviours.perception import ObstacleClose, ObstacleFar, ProcessScan, ScanHealthy
from bt_nav.mission.scan import Scan
from bt_nav.testing import FakeClock, synthetic_scan


def perceive(board: Board, clock: FakeClock, events: Events | None = None) -> ProcessScan:
    """A ProcessScan with the default geometry (30 deg front cone, 0.5 s scan timeout)."""
    board.set(scan_timeout=0.5, front_half_angle_deg=30.0, side_center_deg=15.0, side_half_angle_deg=15.0,
              min_valid_beams=3, close_distance=0.3, far_distance=0.7, path_half_width=0.18)
    return make(ProcessScan, "ProcessScan", clock=clock, events=events)


def feed(board: Board, clock: FakeClock, scan: Scan) -> None:
    board.set(scan=scan, scan_stamp=clock())


def test_no_scan_yet_is_not_usable() -> None:
    board, clock = Board(), FakeClock(1.0)
    leaf = perceive(board, clock)
    assert tick(leaf) == Status.SUCCESS, "ProcessScan always succeeds: the verdict goes to scan_ok"
    assert board.get("scan_ok") is False and board.get("scan_status") == "no scan yet"


def test_a_fresh_scan_is_usable_and_a_stale_one_is_not() -> None:
    board, clock, events = Board(), FakeClock(1.0), Events()
    leaf = perceive(board, clock, events)
    feed(board, clock, synthetic_scan([(0.0, 1.0)]))
    tick(leaf)
    assert board.get("scan_ok") is True and board.get("scan_status") == "ok"
    assert board.get("sectors").front.min_range == pytest.approx(1.0)
    clock.advance(0.6)  # past scan_timeout without a new scan
    tick(leaf)
    assert board.get("scan_ok") is False and "stale scan" in board.get("scan_status")
    assert not board.get("sectors").front.known, "a stale scan's sectors read as unknown"
    feed(board, clock, synthetic_scan())
    tick(leaf)
    assert board.get("scan_ok") is True
    assert events.count("warning", "stale scan") == 1 and events.count("info", "usable again") == 2


def test_a_scan_stamped_in_the_future_is_not_usable() -> None:
    board, clock = Board(), FakeClock(10.0)
    leaf = perceive(board, clock)
    board.set(scan=synthetic_scan(), scan_stamp=11.0)  # the clock jumped back after it arrived
    tick(leaf)
    assert board.get("scan_ok") is False and "future" in board.get("scan_status")


def test_a_malformed_scan_is_not_usable() -> None:
    board, clock = Board(), FakeClock(1.0)
    leaf = perceive(board, clock)
    feed(board, clock, Scan(0.0, 1.0, 0.0, 0.1, 3.5, np.ones(10)))  # zero increment
    tick(leaf)
    assert board.get("scan_ok") is False and board.get("scan_status").startswith("malformed scan")


def test_a_blind_front_is_reported_once_and_its_recovery_once() -> None:
    board, clock, events = Board(), FakeClock(1.0), Events()
    leaf = perceive(board, clock, events)
    feed(board, clock, synthetic_scan([(0.0, math.nan)], width_deg=70.0))
    tick(leaf)
    tick(leaf)
    assert not board.get("sectors").front.known
    assert events.count("warning", "front sector unknown") == 1
    feed(board, clock, synthetic_scan())
    tick(leaf)
    assert events.count("info", "front sector known again") == 1


def test_scan_healthy_answers_scan_ok() -> None:
    board = Board()
    leaf = make(ScanHealthy)
    assert tick(leaf) == Status.FAILURE
    board.set(scan_ok=True)
    assert tick(leaf) == Status.SUCCESS


@pytest.mark.parametrize(("obstacle", "width_deg", "close", "far"), [
    ((0.0, 0.2), 12.0, Status.SUCCESS, Status.FAILURE),  # within close_distance
    ((0.0, 0.5), 12.0, Status.FAILURE, Status.SUCCESS),  # in the far band
    ((0.0, 2.5), 12.0, Status.FAILURE, Status.FAILURE),  # beyond far_distance
    ((90.0, 0.3), 12.0, Status.FAILURE, Status.FAILURE),  # beside the robot, not ahead
    ((0.0, math.nan), 70.0, Status.SUCCESS, Status.FAILURE),  # front unknown: treated as close
], ids=["close", "far", "clear", "beside", "blind"])
def test_obstacle_questions(obstacle: tuple[float, float], width_deg: float, close: Status, far: Status) -> None:
    board, clock = Board(), FakeClock(1.0)
    perception = perceive(board, clock)
    feed(board, clock, synthetic_scan([obstacle], width_deg=width_deg))
    tick(perception)
    assert (tick(make(ObstacleClose)), tick(make(ObstacleFar))) == (close, far)


def test_a_scan_without_a_single_return_blocks_every_path_and_says_so_once() -> None:
    """An LDS-01 reading 0.0 everywhere (dead, covered, or in a room wider than 3.5 m) cannot tell open space from a
    blind LiDAR: no path is free (the lab's brake holds, the homework rotates), while a scan with returns elsewhere
    and nothing within range ahead leaves the path ahead free (the lab creeps on into the open)."""
    board, clock, events = Board(), FakeClock(1.0), Events()
    leaf = perceive(board, clock, events)
    feed(board, clock, synthetic_scan(background=0.0))  # 0.0: below range_min, the LDS-01's "no return"
    tick(leaf)
    tick(leaf)
    assert board.get("scan_ok") is True and not board.get("sectors").front.known
    assert board.get("paths").ahead == 0.0, "drove on a scan with no return at all"
    assert events.count("warning", "no return in the whole scan") == 1
    feed(board, clock, synthetic_scan([(90.0, 0.5), (-90.0, 0.6)], width_deg=40.0, background=math.nan))  # LDS-02
    tick(leaf)
    assert not board.get("sectors").front.known and board.get("paths").ahead > 1.0
    assert events.count("info", "returns again") == 1
