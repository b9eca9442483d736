"""The motion leaves alone: Stop, DriveForward, TurnAway and RotateInPlace, fed by ProcessScan.

Each leaf writes the command of its branch; the tests check the command's shape (speeds within their
bounds, the turn away from the obstacle, zero forward speed when rotating in place), that the turn
direction chosen at the start is kept while the leaf runs, and what preemption does: a motion leaf's
``terminate()`` writes nothing, because the branch that preempts it wrote its own command earlier in the
same tick (a stop at the leaf's end would overwrite the winner's command).
"""

from __future__ import annotations

from typing import Any

import pytest
from leafkit import Board, Status, make, tick

from bt_nav.mission.behaviours.motion import (
    SIDE_MEMORY,
    SWITCH_MARGIN,
    DriveForward,
    RotateInPlace,
    Stop,
    TurnAway,
    TurnSide,
)
from bt_nav.mission.behaviours.perception import ProcessScan
from bt_nav.mission.datatypes import Command
from bt_nav.testing import FakeClock, synthetic_scan

SPEED, SLOW, TURN = 0.22, 0.12, 1.5


def scene(*obstacles: tuple[float, float]) -> Board:
    """A board holding what ProcessScan makes of a scan showing ``(angle_deg, distance)`` obstacles."""
    board = Board()
    clock = FakeClock(1.0)
    board.set(scan_timeout=0.5, front_half_angle_deg=30.0, side_center_deg=15.0, side_half_angle_deg=15.0,
              min_valid_beams=3, close_distance=0.3, far_distance=0.7, path_half_width=0.18,
              speed=SPEED, max_speed=SPEED, slow_speed=SLOW, angular_speed=TURN)
    board.set(scan=synthetic_scan(obstacles), scan_stamp=clock())
    tick(make(ProcessScan, "ProcessScan", clock=clock))
    return board


def rescan(board: Board, *obstacles: tuple[float, float]) -> None:
    """Show another scene to the same board."""
    clock = FakeClock(1.0)
    board.set(scan=synthetic_scan(obstacles), scan_stamp=clock())
    tick(make(ProcessScan, "ProcessScan", clock=clock))


def command(board: Board) -> Command:
    return board.get("cmd_vel")


def test_stop_is_an_exact_zero_and_success() -> None:
    board = scene()
    leaf = make(Stop, "Stop", reason="disarmed")
    assert tick(leaf) == Status.SUCCESS
    assert command(board) == Command(0.0, 0.0, "Stop") and leaf.feedback_message == "disarmed"


def test_drive_forward_runs_at_full_speed_straight_in_the_open() -> None:
    board = scene()
    leaf = make(DriveForward, "FullSpeed")
    assert tick(leaf) == Status.RUNNING and tick(leaf) == Status.RUNNING  # driving is never done
    assert command(board).linear == SPEED and command(board).angular == pytest.approx(0.0)


@pytest.mark.parametrize(("obstacle", "away"), [((-15.0, 0.5), 1.0), ((15.0, 0.5), -1.0)],
                         ids=["right-turns-left", "left-turns-right"])
def test_turn_away_keeps_driving_and_turns_away_from_the_obstacle(obstacle: tuple[float, float],
                                                                   away: float) -> None:
    board = scene(obstacle)
    leaf = make(TurnAway, "TurnAway")
    assert tick(leaf) == Status.RUNNING
    cmd = command(board)
    assert SLOW <= cmd.linear <= SPEED
    assert cmd.angular * away > 0.0 and abs(cmd.angular) <= TURN


def test_turn_away_slows_down_the_deeper_the_obstacle_is_in_the_far_band() -> None:
    speeds = []
    for distance in (0.65, 0.5, 0.35):
        board = scene((-10.0, distance))
        tick(make(TurnAway, "TurnAway"))
        speeds.append(command(board).linear)
    assert speeds[0] > speeds[1] > speeds[2] >= SLOW


@pytest.mark.parametrize(("obstacle", "away"), [((-10.0, 0.2), 1.0), ((10.0, 0.2), -1.0)],
                         ids=["right-turns-left", "left-turns-right"])
def test_rotate_in_place_has_no_forward_speed_and_turns_away(obstacle: tuple[float, float], away: float) -> None:
    board = scene(obstacle)
    leaf = make(RotateInPlace, "RotateInPlace")
    assert tick(leaf) == Status.RUNNING
    assert command(board).linear == 0.0 and command(board).angular == pytest.approx(away * TURN)


def test_rotate_in_place_keeps_its_direction_while_running_and_rechooses_after_preemption() -> None:
    board = scene((-10.0, 0.2))
    clock = FakeClock(1.0)
    leaf = make(RotateInPlace, "RotateInPlace", clock=clock)
    tick(leaf)
    assert command(board).angular > 0.0
    rescan(board, (10.0, 0.2))  # the scene mirrors mid-rotation (a square-on wall would dither)
    tick(leaf)
    assert command(board).angular > 0.0, "the direction chosen at the start is kept while running"
    leaf.stop(Status.INVALID)
    tick(leaf)
    assert command(board).angular > 0.0, "a rotation right after the last one keeps its side (SIDE_MEMORY)"
    leaf.stop(Status.INVALID)
    clock.now += SIDE_MEMORY + 0.05
    tick(leaf)
    assert command(board).angular < 0.0, "a later rotation chooses afresh"


@pytest.mark.parametrize(("first", "then"), [(TurnAway, RotateInPlace), (RotateInPlace, TurnAway)])
def test_the_avoiding_leaves_hand_their_side_over(first: Any, then: Any) -> None:
    """One leaf starting right after the other keeps its side, even when the scene alone says otherwise;
    after SIDE_MEMORY without either, the side is chosen afresh."""
    board = scene((-10.0, 0.5) if first is TurnAway else (-10.0, 0.2))  # obstacle right: turn left
    clock = FakeClock(1.0)
    leader = make(first, first.__name__, clock=clock)
    follower = make(then, then.__name__, clock=clock)  # (made first: making a leaf resets its output keys)
    tick(leader)
    assert command(board).angular > 0.0 and board.get("turn_side").side == 1.0
    leader.stop(Status.INVALID)
    rescan(board, (10.0, 0.5) if then is TurnAway else (10.0, 0.2))  # mirrored: alone it would turn right
    clock.now += 0.1
    tick(follower)
    assert command(board).angular > 0.0, "the side is handed over"
    follower.stop(Status.INVALID)
    clock.now += SIDE_MEMORY + 0.05
    tick(follower)
    assert command(board).angular < 0.0, "chosen afresh after SIDE_MEMORY"


@pytest.mark.parametrize("cls", [DriveForward, TurnAway, RotateInPlace])
def test_preempting_a_motion_leaf_leaves_the_winners_command_alone(cls: Any) -> None:
    board = scene((-10.0, 0.5))
    leaf = make(cls, cls.__name__)
    assert tick(leaf) == Status.RUNNING
    winner = Command(0.0, 1.8, "Randomizer")  # a higher branch wrote its command earlier this tick
    board.set(cmd_vel=winner)
    leaf.stop(Status.INVALID)
    assert leaf.status == Status.INVALID
    assert command(board) == winner


def test_a_remembered_side_gives_way_to_a_much_smaller_turn() -> None:
    """Memory is a preference, not a lock: when the other side's clear heading needs SWITCH_MARGIN less
    turning, a rotation starts that way (a lock turned a robot 200 deg the long way round)."""
    board = scene((-10.0, 0.2))
    clock = FakeClock(1.0)
    leaf = make(RotateInPlace, "RotateInPlace", clock=clock)
    board.set(turn_side=TurnSide(-1.0, clock()))  # the last avoiding tick turned right, just now
    board.set(scan=synthetic_scan([(-60.0, 0.4), (-30.0, 0.3), (0.0, 0.25)]), scan_stamp=clock())
    tick(make(ProcessScan, "ProcessScan", clock=clock))
    paths = board.get("paths")
    left, right = paths.steer(0.7, side=1), paths.steer(0.7, side=-1)
    assert left is not None and (right is None or abs(left) + SWITCH_MARGIN < abs(right))
    tick(leaf)
    assert command(board).angular > 0.0


def test_a_rotation_resumed_after_a_blip_of_driving_goes_on_the_same_way() -> None:
    """A post grazing the path's edge flips the path ahead between clear and close; a rotation in place
    that resumes within SIDE_MEMORY of the last one keeps its side outright (weighing the sides afresh
    turned it back and forth by ten degrees, for seconds)."""
    board = scene((-20.0, 0.2))  # clear at +60 deg, nothing clear within 90 deg on the right
    clock = FakeClock(1.0)
    leaf = make(RotateInPlace, "RotateInPlace", clock=clock)
    board.set(turn_side=TurnSide(-1.0, clock(), in_place=True))  # a rotation to the right, just now
    tick(leaf)
    assert command(board).angular < 0.0
    leaf.stop(Status.INVALID)
    board.set(turn_side=TurnSide(-1.0, clock(), in_place=False))  # steering right: weighed, and switched
    tick(leaf)
    assert command(board).angular > 0.0
