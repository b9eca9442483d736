"""ArmService's replies as a person arming sees them: mission time, and why the robot may not move yet."""

from __future__ import annotations

from leafkit import Board, Events, make

from bt_nav.mission.behaviours.mission import ArmService
from bt_nav.testing import FakeClock


def test_arming_without_a_usable_scan_is_accepted_with_a_warning_and_the_reason() -> None:
    board = Board()
    events = Events()
    leaf = make(ArmService, clock=FakeClock(4.0), events=events)
    board.set(scan_ok=False, scan_status="no scan for 0.8 s")
    ok, message = leaf.handle(True)
    assert ok and board.get("armed") is True
    assert "no usable scan yet (no scan for 0.8 s)" in message and "will not move" in message
    assert events.count("warning", "no usable scan yet") == 1


def test_arming_with_a_scan_says_nothing_about_scans() -> None:
    board = Board()
    events = Events()
    leaf = make(ArmService, clock=FakeClock(4.0), events=events)
    board.set(scan_ok=True, scan_status="ok")
    ok, message = leaf.handle(True)
    assert ok and "scan" not in message and events.count("warning") == 0


def test_replies_carry_mission_time_not_epoch_seconds() -> None:
    board = Board()
    clock = FakeClock(1_712_345_678.25)  # a wall clock (use_sim_time false)
    leaf = make(ArmService, clock=clock)
    board.set(scan_ok=True)
    ok, message = leaf.handle(True)
    assert ok and "1712345678" not in message and "mission t=0.00 s" in message
    clock.advance(12.5)
    leaf.handle(False)
    ok, message = leaf.handle(True)
    assert ok and "mission t=12.50 s" in message and "1712345678" not in message


def test_sim_time_replies_also_name_the_clock_reading() -> None:
    Board().set(scan_ok=True)
    ok, message = make(ArmService, clock=FakeClock(37.65)).handle(True)
    assert ok and "mission timer started at t=37.65 s" in message
