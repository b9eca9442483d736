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


# ----------------------------------------------------------------------------------- a lagging base
class LaggedBase:
    """A base whose wheels follow each turn-rate command ``latency`` s after it is given, ramping at
    ``accel`` rad/s^2, stepped in 5 ms; odometry (yaw) at 30 Hz."""

    def __init__(self, latency: float, accel: float = 10.0) -> None:
        self.latency, self.accel = latency, accel
        self.given: list[tuple[float, float]] = [(-math.inf, 0.0)]  # (time given, rate)
        self.yaw = self.rate = 0.0
        self.next_odom = self.next_scan = 1.0

    def run(self, clock: FakeClock, seconds: float, board: Board | None = None) -> None:
        step = 0.005
        for _ in range(round(seconds / step)):
            clock.now += step
            target = [w for t, w in self.given if t <= clock.now - self.latency][-1]
            self.rate += max(-self.accel * step, min(self.accel * step, target - self.rate))
            self.yaw += self.rate * step
            if board is not None and clock.now >= self.next_odom:
                board.set(odom=OdomSample(self.yaw, clock.now, 0.0, 0.0))
                self.next_odom += 1 / 30
            if board is not None and clock.now >= self.next_scan:  # an LDS-01 at 5 Hz
                board.set(scan_stamp=clock.now)
                self.next_scan += 0.2


def lagged_turn(cls: type, s: Sectors, *, true_latency: float, planned: float,
                moving: bool = False) -> tuple[float, float, list[Command]]:
    """Tick a maneuver at 20 Hz against a :class:`LaggedBase`; returns (rotation chosen, angle turned once
    the base is at rest, the commands)."""
    board = maneuver_board(s)
    board.set(angular_speed=1.5, latency=planned, cmd_vel=Command(0.05 if moving else 0.0, 0.0, "Creep"))
    clock = FakeClock(1.0)
    leaf = make(cls, clock=clock)
    base = LaggedBase(true_latency)
    commands: list[Command] = []
    for _ in range(400):
        status = tick(leaf)
        commands.append(board.get("cmd_vel"))
        base.given.append((clock.now, commands[-1].angular))
        if status != Status.RUNNING:
            break
        base.run(clock, 0.05, board)
    base.run(clock, 0.5)  # the base comes to rest on the last (zero) command
    assert leaf.status == Status.SUCCESS
    return leaf.rotation, base.yaw, commands


@pytest.mark.parametrize("true_latency", [0.0, 0.1, 0.15])
@pytest.mark.parametrize(("cls", "s"), [
    (RandomizerManeuver, sectors(front=0.4)),
    (RetreatManeuver, sectors(left=0.4, right=0.45)),
    (SmartPivotManeuver, sectors(front=0.25, left=1.0, right=0.5)),
])
def test_maneuvers_land_on_their_angle_on_a_lagging_base(cls: type, s: Sectors, true_latency: float) -> None:
    """Planned for 0.1 s, the turn ends within 6 deg of its angle whether the wheels lag 0, 0.1 or 0.15 s
    (the lab's limit is 10 deg); planned for none, a 0.15 s lag overshoots by rate x lag."""
    rotation, turned, commands = lagged_turn(cls, s, true_latency=true_latency, planned=0.1)
    assert abs(math.degrees(turned - rotation)) < 6.0, (math.degrees(rotation), math.degrees(turned))
    assert all(c.linear == 0.0 for c in commands)
    if true_latency == 0.15:
        blind_rotation, blind, _ = lagged_turn(cls, s, true_latency=0.15, planned=0.0)
        assert abs(math.degrees(blind - blind_rotation)) > abs(math.degrees(turned - rotation)) + 3.0


def test_a_lagging_maneuver_starts_from_rest_and_ends_at_rest() -> None:
    """Moving when it fires (the creep), the maneuver holds still for latency + SETTLE before it turns,
    and holds still as long after the turn before it ends: its rotation has no forward motion in it."""
    _, _, commands = lagged_turn(SmartPivotManeuver, sectors(front=0.25, left=1.0, right=0.5),
                                 true_latency=0.1, planned=0.1, moving=True)
    still = round((0.1 + SmartPivotManeuver.SETTLE) / 0.05)  # ticks; one more where the clock lands short
    first_turn = next(i for i, c in enumerate(commands) if not c.is_zero)
    last_turn = max(i for i, c in enumerate(commands) if not c.is_zero)
    assert still <= first_turn <= still + 1
    # the tick it stops, the still, the wait for a scan taken at rest (one LDS-01 period at most), the end
    assert still + 1 <= len(commands) - 1 - last_turn <= still + 2 + round(0.2 / 0.05)
    _, _, unlagged = lagged_turn(SmartPivotManeuver, sectors(front=0.25, left=1.0, right=0.5),
                                 true_latency=0.0, planned=0.0, moving=True)
    assert unlagged[0].angular != 0.0  # the homework tuning: no still


def test_smart_pivot_reads_the_side_sectors_when_told() -> None:
    """The lab's literal rule: the side whose sector reads farther, whatever the free paths say."""
    board = maneuver_board(sectors(front=0.25, left=0.6, right=1.2))
    board.set(paths=FreePaths(HEADINGS, np.where(HEADINGS > 0, 1.05, 0.3)), side_reading="side_sectors")
    leaf = make(SmartPivotManeuver, clock=FakeClock(1.0))
    tick(leaf)
    assert leaf.rotation == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize(("cls", "s", "hands_over"), [
    (SmartPivotManeuver, sectors(front=0.25, left=0.5, right=1.0), True),
    (RandomizerManeuver, sectors(front=0.4), True),
    (RetreatManeuver, sectors(left=0.4, right=0.45), False),
])
def test_a_rotation_in_place_after_a_maneuver_keeps_its_side(cls: type, s: Sectors, hands_over: bool) -> None:
    """A front still close after a quarter turn (or A's random turn) is rotated away from on the maneuver's
    side: choosing afresh turned the Smart Pivot back into the pocket it had turned away from (cluttered,
    seeds 1 and 15, short of 8 m). B's half turn says nothing about where the room is: it hands nothing over."""
    from bt_nav.mission.behaviours.motion import RotateInPlace, TurnSide

    board = maneuver_board(s)
    clock = FakeClock(1.0)
    rotate = make(RotateInPlace, clock=clock)  # built with the tree, before the maneuver runs (as in a tree)
    leaf = make(cls, clock=clock)
    yaw = 0.0
    while tick(leaf) == Status.RUNNING:
        clock.now += 0.05
        yaw += board.get("cmd_vel").angular * 0.05
        board.set(odom=OdomSample(yaw, clock.now, 0.0, 0.0))
    side = math.copysign(1.0, leaf.rotation)
    memory = board.get("turn_side", TurnSide())
    assert (memory.side, memory.in_place) == ((side, True) if hands_over else (0.0, False))
    # the close branch next: its own reading of the room (every heading's free path, more on the other side)
    board.set(paths=FreePaths(HEADINGS, np.where(side * HEADINGS > 0, 0.1, 0.25)), far_distance=0.7)
    clock.now += 0.05
    tick(rotate)
    assert math.copysign(1.0, board.get("cmd_vel").angular) == (side if hands_over else -side)
