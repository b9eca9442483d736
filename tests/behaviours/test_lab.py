"""The lab family alone: the creep, the emergency-braking guard and leaf, and the mode guard."""

from __future__ import annotations

import math

import numpy as np

from bt_nav.mission.behaviours.lab import Creep, EmergencyStop, InMode, PathBlocked
from bt_nav.mission.datatypes import Command
from bt_nav.mission.paths import HEADINGS, FreePaths
from bt_nav.testing import FakeClock
from tests.behaviours.leafkit import Board, Events, Status, make, tick


def paths(ahead: float, left: float = 1.0, right: float = 0.3) -> FreePaths:
    """Free paths: ``ahead`` straight on, ``left`` on every left heading, ``right`` on every right one."""
    free = np.where(HEADINGS > 0, left, np.where(HEADINGS < 0, right, ahead)).astype(float)
    free[np.isclose(HEADINGS, 0.0)] = ahead
    return FreePaths(HEADINGS, free)


def test_in_mode_answers_for_its_own_mode_only() -> None:
    board = Board()
    guard = make(InMode, "LabMode?", mode="lab")
    board.set(current="lab")
    assert tick(guard) == Status.SUCCESS
    board.set(current="homework")
    assert tick(guard) == Status.FAILURE


def test_creep_drives_straight_at_its_speed_and_never_finishes() -> None:
    board = Board()
    board.set(speed=0.05)
    leaf = make(Creep)
    for _ in range(3):
        assert tick(leaf) == Status.RUNNING
        assert board.get("cmd_vel") == Command(0.05, 0.0, "Leaf")


def test_path_blocked_compares_the_free_path_ahead() -> None:
    board = Board()
    guard = make(PathBlocked)
    board.set(distance=0.1, paths=paths(0.09))
    assert tick(guard) == Status.SUCCESS
    board.set(paths=paths(0.11))
    assert tick(guard) == Status.FAILURE


def aeb(board: Board, clock: FakeClock, events: Events) -> EmergencyStop:
    board.set(distance=0.1, hold=1.0, angular_speed=1.0, paths=paths(0.05))
    return make(EmergencyStop, "AEB", clock=clock, events=events)


def test_emergency_stop_brakes_stands_then_turns_towards_the_room_until_clear() -> None:
    board, clock, events = Board(), FakeClock(10.0), Events()
    leaf = aeb(board, clock, events)
    assert tick(leaf) == Status.RUNNING
    assert board.get("cmd_vel").is_zero and board.get("active") is True
    assert events.count("warning", "emergency stop") == 1
    clock.advance(0.95)
    assert tick(leaf) == Status.RUNNING and board.get("cmd_vel").is_zero  # still standing
    clock.advance(0.1)
    assert tick(leaf) == Status.RUNNING
    command = board.get("cmd_vel")
    assert command.linear == 0.0 and command.angular == 1.0  # left: the side with room
    assert events.count("info", "turning left") == 1
    board.set(paths=paths(0.25))  # better, but not clear by the margin: keep turning
    clock.advance(0.05)
    assert tick(leaf) == Status.RUNNING and board.get("cmd_vel").angular == 1.0
    board.set(paths=paths(0.31))
    clock.advance(0.05)
    assert tick(leaf) == Status.SUCCESS
    assert board.get("cmd_vel").is_zero and board.get("active") is False


def test_emergency_stop_resumes_without_turning_when_the_way_clears_while_standing() -> None:
    """A person walking past: the path clears during the hold, the robot goes on straight."""
    board, clock, events = Board(), FakeClock(10.0), Events()
    leaf = aeb(board, clock, events)
    tick(leaf)
    clock.advance(0.5)
    board.set(paths=paths(0.8))
    assert tick(leaf) == Status.SUCCESS
    assert events.count("info", "turning") == 0


def test_emergency_stop_preempted_stops_and_releases_its_branch() -> None:
    board, clock, events = Board(), FakeClock(10.0), Events()
    board.set(paths=paths(0.05, left=0.2, right=1.0))
    leaf = aeb(board, clock, events)
    board.set(paths=paths(0.05, left=0.2, right=1.0))
    tick(leaf)
    clock.advance(1.1)
    tick(leaf)
    assert board.get("cmd_vel").angular == -1.0  # right has the room here
    leaf.stop(Status.INVALID)
    assert board.get("cmd_vel").is_zero and board.get("active") is False
    assert not math.isnan(board.get("cmd_vel").linear)
