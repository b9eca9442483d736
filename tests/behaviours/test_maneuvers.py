"""The maneuver family alone: the three rotation leaves, each ticked on a small blackboard with a fake clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_nav.mission.behaviours.maneuvers import RandomizerManeuver, RetreatManeuver, SmartPivotManeuver
from bt_nav.mission.datatypes import Command, OdomSample
from bt_nav.mission.paths import HEADINGS, FreePaths
from bt_nav.mission.scan import SectorReading, Sectors
from bt_nav.mission.turning import approach_rate
from bt_nav.testing import FakeClock
from tests.behaviours.leafkit import Board, Status, make, tick


def reading(distance: float) -> SectorReading:
    """A known reading, or an unknown one for NaN."""
    return SectorReading(distance, 10, 10) if not math.isnan(distance) else SectorReading(math.nan, 0, 10)


def sectors(front: float = math.inf, left: float = math.inf, right: float = math.inf) -> Sectors:
    return Sectors(reading(front), reading(left), reading(right))


# ----------------------------------------------------------------------------------- the rotations
def maneuver_board(s: Sectors, odom_at_start: bool = True) -> Board:
    board = Board()
    start = OdomSample(0.0, 1.0, 0.0, 0.0) if odom_at_start else OdomSample()
    board.set(sectors=s, odom=start, angular_speed=2.84, tolerance_deg=3.0, time_margin=2.0, odom_timeout=0.5)
    return board


@pytest.mark.parametrize(("cls", "s", "check"), [
    (RandomizerManeuver, sectors(front=0.4), lambda rot: math.radians(90) <= abs(rot) <= math.radians(180)),
    (RetreatManeuver, sectors(left=0.4, right=0.45), lambda rot: rot == pytest.approx(-math.pi)),
    (SmartPivotManeuver, sectors(front=0.25, left=1.0, right=0.5), lambda rot: rot == pytest.approx(math.pi / 2)),
])
@pytest.mark.parametrize("odom_at_start", [True, False])
def test_rotations_are_the_labs_and_never_drive(cls: type, s: Sectors, check, odom_at_start: bool) -> None:
    """Closed loop on odometry yaw; when the first sample comes only after the start, the tick before
    it is dead-reckoned (not lost)."""
    board = maneuver_board(s, odom_at_start)
    clock = FakeClock(1.0)
    leaf = make(cls, clock=clock)
    yaw, ticks = 0.0, 0
    while tick(leaf) == Status.RUNNING:
        command = board.get("cmd_vel")
        assert command.linear == 0.0, "rotation only"
        clock.now += 0.05
        yaw += command.angular * 0.05
        board.set(odom=OdomSample(yaw, clock.now, 0.0, 0.0))
        ticks += 1
        assert ticks < 200
    assert check(leaf.rotation)
    assert leaf.status == Status.SUCCESS and board.get("cmd_vel").linear == 0.0
    assert abs(yaw - leaf.rotation) <= math.radians(3.0) + 1e-9


@pytest.mark.parametrize(("left_free", "right_free", "expected"), [
    (0.3, 1.05, -1.0),  # the cones beside the front say left, the room at +-90 deg says right: right
    (1.05, 0.3, 1.0),
    (1.05, 1.05, 1.0),  # equal readings: the cones decide (left reads 1.0 m, right 0.5 m)
])
def test_smart_pivot_turns_towards_the_side_it_will_face(left_free: float, right_free: float, expected: float) -> None:
    """The "clearer side" is read where the robot faces after the quarter turn: the free path along
    +-90 deg, not the cones beside the front (which turned a cornered robot towards the near wall)."""
    free = np.where(HEADINGS > 0, left_free, right_free)
    board = maneuver_board(sectors(front=0.25, left=1.0, right=0.5))
    board.set(paths=FreePaths(HEADINGS, free))
    leaf = make(SmartPivotManeuver, clock=FakeClock(1.0))
    tick(leaf)
    assert leaf.rotation == pytest.approx(expected * math.pi / 2)
    assert board.get("cmd_vel").linear == 0.0


@pytest.mark.parametrize(("turning", "expected"), [
    (2.5, 1.0),  # already turning left: the spin goes on that way, though the right reads clearer
    (-2.5, -1.0),
    (0.0, -1.0),  # not turning: towards the clearer side (right reads 0.45 m, left 0.4 m)
])
def test_retreat_spins_the_way_the_robot_already_turns(turning: float, expected: float) -> None:
    """Either way round ends facing back; reversing a rotation in place first costs time and turn."""
    board = maneuver_board(sectors(left=0.4, right=0.45))
    leaf = make(RetreatManeuver, clock=FakeClock(1.0))
    board.set(cmd_vel=Command(0.0, turning, "RotateInPlace"))  # the previous tick's command
    tick(leaf)
    assert leaf.rotation == pytest.approx(expected * math.pi)


def test_the_approach_brakes_as_late_as_it_can() -> None:
    """Full rate until the braking distance at DECEL, then sqrt(2 DECEL remaining), never below the floor."""
    decel, peak, floor = RetreatManeuver.DECEL, 2.84, RetreatManeuver.MIN_RATE
    assert approach_rate(math.pi, peak, decel, floor) == peak
    assert approach_rate(-0.2, peak, decel, floor) == pytest.approx(-math.sqrt(2 * decel * 0.2))
    assert approach_rate(1e-4, peak, decel, floor) == floor
    braking = peak ** 2 / (2 * decel)
    assert approach_rate(braking * 0.99, peak, decel, floor) < peak <= approach_rate(braking * 1.01, peak, decel, floor)
