"""The trigger family alone: the latch (EdgeLatch, Odometer) and FrontTrigger / SqueezeTrigger, each ticked on
a small blackboard with a fake clock."""

from __future__ import annotations

import math

import pytest

from bt_nav.mission.behaviours.triggers import EdgeLatch, FrontTrigger, Odometer, Rearm, SqueezeTrigger
from bt_nav.mission.datatypes import Command, OdomSample
from bt_nav.mission.scan import SectorReading, Sectors
from bt_nav.testing import FakeClock
from tests.behaviours.leafkit import Board, Status, make, tick

NEVER_BY_DRIVING = Rearm(clear_away=1.0, distance=0.0)


def reading(distance: float) -> SectorReading:
    """A known reading, or an unknown one for NaN."""
    return SectorReading(distance, 10, 10) if not math.isnan(distance) else SectorReading(math.nan, 0, 10)


def sectors(front: float = math.inf, left: float = math.inf, right: float = math.inf) -> Sectors:
    return Sectors(reading(front), reading(left), reading(right))


# ----------------------------------------------------------------------------------- the latch
def test_latch_fires_once_on_a_rising_edge_and_not_while_the_condition_lasts() -> None:
    latch = EdgeLatch()
    assert latch.step(holds=True, cleared=False, rearm=NEVER_BY_DRIVING)
    assert not any(latch.step(True, False, NEVER_BY_DRIVING) for _ in range(200)), "a lasting condition re-fired"


def test_an_arming_fires_a_condition_that_already_holds_or_waits_for_a_clear() -> None:
    latch = EdgeLatch()
    latch.step(True, False, NEVER_BY_DRIVING)
    latch.reset()  # default: a new arming is a new situation
    assert latch.step(True, False, NEVER_BY_DRIVING)
    latch.reset(fire_at_once=False)
    assert not any(latch.step(True, False, NEVER_BY_DRIVING) for _ in range(10))
    latch.step(False, True, NEVER_BY_DRIVING)  # seen clear once, on the spot: armed
    assert latch.step(True, False, NEVER_BY_DRIVING)


def test_a_clearing_rearms_only_away_from_where_it_fired() -> None:
    latch = EdgeLatch(position=(0.0, 0.0))
    assert latch.step(True, False, NEVER_BY_DRIVING)
    assert latch.fired_at == (0.0, 0.0)
    latch.step(False, True, NEVER_BY_DRIVING)  # cleared on the spot (a spin sweeps the sectors): no
    assert not latch.step(True, False, NEVER_BY_DRIVING)
    latch.position = (0.6, 0.79)  # 0.99 m away: still no
    latch.step(False, True, NEVER_BY_DRIVING)
    assert not latch.step(True, False, NEVER_BY_DRIVING)
    latch.position = (0.6, 0.8)
    latch.step(False, False, NEVER_BY_DRIVING)  # 1 m away, but inside the hysteresis band: not cleared
    assert not latch.step(True, False, NEVER_BY_DRIVING)
    latch.step(False, True, NEVER_BY_DRIVING)
    assert latch.step(True, False, NEVER_BY_DRIVING), "cleared 1 m away: a fresh condition must fire"
    assert latch.fired_at == (0.6, 0.8)


def test_driving_rearms_a_condition_that_never_clears() -> None:
    rearm = Rearm(clear_away=1.0, distance=3.0)
    latch = EdgeLatch()
    assert latch.step(True, False, rearm)
    latch.driven = 2.99
    assert not latch.step(True, False, rearm)
    latch.driven = 3.0
    assert latch.step(True, False, rearm), "3 m driven under a lasting condition: fires again"
    assert latch.driven == 0.0
    latch.driven = 50.0
    assert not latch.step(True, False, NEVER_BY_DRIVING), "distance 0 turns the driving rule off"


def test_without_positions_the_path_driven_stands_in_for_the_distance_away() -> None:
    latch = EdgeLatch()
    latch.step(True, False, NEVER_BY_DRIVING)
    assert latch.fired_at is None
    latch.driven = 0.5
    latch.step(False, True, NEVER_BY_DRIVING)
    assert not latch.step(True, False, NEVER_BY_DRIVING)
    latch.driven = 1.0
    latch.step(False, True, NEVER_BY_DRIVING)
    assert latch.step(True, False, NEVER_BY_DRIVING)


# ----------------------------------------------------------------------------------- the odometer
def odom(x: float, y: float, stamp: float) -> OdomSample:
    return OdomSample(0.0, stamp, x, y)


def test_odometer_sums_the_path_from_positions() -> None:
    meter = Odometer()
    go = Command(0.22, 0.0)
    assert meter.observe(0.0, odom(0.0, 0.0, 0.0), 0.5, go) == 0.0
    assert meter.observe(0.1, odom(0.3, 0.4, 0.1), 0.5, go) == pytest.approx(0.5)
    assert meter.observe(0.2, odom(0.3, 0.4, 0.1), 0.5, go) == 0.0, "the same sample is not counted twice"
    assert meter.observe(0.3, odom(0.0, 0.4, 0.3), 0.5, go) == pytest.approx(0.3), "path, not displacement"


def test_odometer_integrates_the_command_without_positions_and_counts_no_stop() -> None:
    meter = Odometer()
    nan = math.nan
    meter.observe(0.0, odom(nan, nan, 0.0), 0.5, Command(0.2, 0.0))
    assert meter.observe(0.1, odom(nan, nan, 0.1), 0.5, Command(0.2, 0.0)) == pytest.approx(0.02)
    assert meter.observe(0.2, odom(nan, nan, 0.2), 0.5, Command(-0.2, 0.0)) == pytest.approx(0.02)
    assert meter.observe(0.3, odom(nan, nan, 0.3), 0.5, Command(0.0, 2.8)) == 0.0, "a spin is no driving"
    assert meter.observe(10.3, odom(nan, nan, 10.3), 0.5, Command(0.2, 0.0)) == pytest.approx(0.1), \
        "a long pause is capped at MAX_DT"


def test_odometer_bridges_stale_odometry_without_counting_the_jump() -> None:
    meter = Odometer()
    go = Command(0.2, 0.0)
    meter.observe(0.0, odom(0.0, 0.0, 0.0), 0.5, go)
    assert meter.observe(1.0, odom(0.0, 0.0, 0.0), 0.5, go) == pytest.approx(0.2 * Odometer.MAX_DT)
    assert meter.position is None
    assert meter.observe(1.1, odom(5.0, 0.0, 1.1), 0.5, go) == 0.0, "a new chain starts: no jump"
    assert meter.observe(1.2, odom(5.02, 0.0, 1.2), 0.5, go) == pytest.approx(0.02)


# ----------------------------------------------------------------------------------- the trigger leaves
def trigger_board(**values: object) -> Board:
    """Trigger distance 0.5, hysteresis 0.1, clearings count 1 m from the firing, re-arm after 2 m driven."""
    board = Board()
    board.set(sectors=sectors(), odom=odom(0.0, 0.0, 1.0), arm_count=1, distance=0.5, hysteresis=0.1,
              clear_away=1.0, rearm_distance=2.0, odom_timeout=0.5, cmd_vel=Command(), fire_at_arming=True)
    board.set(**values)
    return board


def test_front_trigger_fires_on_its_edge_and_rearms_beyond_the_hysteresis_band() -> None:
    board = trigger_board()
    clock = FakeClock(1.0)
    leaf = make(FrontTrigger, clock=clock)
    board.set(sectors=sectors(front=0.4))
    assert tick(leaf) == Status.SUCCESS and leaf.feedback_message == "fired"
    assert tick(leaf) == Status.FAILURE and "re-arm" in leaf.feedback_message
    clock.now = 2.0
    board.set(sectors=sectors(front=0.55), odom=odom(1.5, 0.0, 2.0))  # 1.5 m on, inside the band
    tick(leaf)
    board.set(sectors=sectors(front=0.4))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors=sectors(front=0.65))
    assert tick(leaf) == Status.FAILURE and leaf.feedback_message == "armed"
    board.set(sectors=sectors(front=0.4))
    assert tick(leaf) == Status.SUCCESS


def test_front_trigger_rearms_after_driving_under_a_lasting_condition() -> None:
    board = trigger_board(sectors=sectors(front=0.4))
    clock = FakeClock(1.0)
    leaf = make(FrontTrigger, clock=clock)
    assert tick(leaf) == Status.SUCCESS
    for i in range(1, 20):  # 0.1 m per odometry sample, the front stays near
        clock.now = 1.0 + 0.1 * i
        board.set(odom=odom(0.1 * i, 0.0, clock.now))
        assert tick(leaf) == Status.FAILURE, f"re-fired after {0.1 * i:.1f} m"
    clock.now = 3.0
    board.set(odom=odom(2.0, 0.0, 3.0))
    assert tick(leaf) == Status.SUCCESS


def test_an_unknown_front_neither_fires_nor_clears() -> None:
    """An LDS-01 reads 0.0 (an LDS-02 NaN) where nothing is within range: no reading fires no maneuver, and a
    fired trigger is not re-armed by it either (only a reading beyond the hysteresis band clears)."""
    board = trigger_board(sectors=sectors(front=math.nan), rearm_distance=0.0)
    clock = FakeClock(1.0)
    leaf = make(FrontTrigger, clock=clock)
    assert tick(leaf) == Status.FAILURE, "fired on no reading"
    board.set(sectors=sectors(front=0.3))
    assert tick(leaf) == Status.SUCCESS
    board.set(sectors=sectors(front=math.nan))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors=sectors(front=0.3))
    assert tick(leaf) == Status.FAILURE, "unknown cleared the trigger"


def test_one_wall_and_open_space_is_no_squeeze() -> None:
    """B beside one wall with nothing within range on the other side (LDS-01 0.0): not squeezed."""
    trigger_board(sectors=sectors(left=0.3, right=math.nan))
    leaf = make(SqueezeTrigger, clock=FakeClock(1.0))
    assert tick(leaf) == Status.FAILURE


def test_squeeze_trigger_needs_both_sides_and_rearms_on_one_side_clearing() -> None:
    board = trigger_board(sectors=sectors(left=0.4, right=0.9))
    clock = FakeClock(1.0)
    leaf = make(SqueezeTrigger, clock=clock)
    assert tick(leaf) == Status.FAILURE
    board.set(sectors=sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
    assert tick(leaf) == Status.FAILURE
    clock.now = 2.0
    board.set(sectors=sectors(left=0.4, right=0.7), odom=odom(1.2, 0.0, 2.0))  # one side open, 1.2 m on
    tick(leaf)
    board.set(sectors=sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS


@pytest.mark.parametrize("fire_at_arming", [True, False])
def test_a_new_arming_resets_the_latch(fire_at_arming: bool) -> None:
    board = trigger_board(sectors=sectors(left=0.4, right=0.4), fire_at_arming=fire_at_arming)
    leaf = make(SqueezeTrigger)
    assert (tick(leaf) == Status.SUCCESS) == fire_at_arming, "the first arming"
    board.set(sectors=sectors(left=0.4, right=0.7))  # cleared, but on the spot
    tick(leaf)
    board.set(sectors=sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.FAILURE or not fire_at_arming
    board.set(arm_count=2)  # disarmed and armed again while still squeezed
    assert (tick(leaf) == Status.SUCCESS) == fire_at_arming
    if not fire_at_arming:
        board.set(sectors=sectors(left=0.4, right=0.7))
        tick(leaf)  # seen clear once after the arming, wherever the robot is: armed
        board.set(sectors=sectors(left=0.4, right=0.4))
        assert tick(leaf) == Status.SUCCESS


def test_trigger_integrates_the_command_when_odometry_has_no_position() -> None:
    trigger_board(sectors=sectors(front=0.4), odom=OdomSample(), cmd_vel=Command(0.2, 0.0))
    clock = FakeClock(1.0)
    leaf = make(FrontTrigger, clock=clock)
    assert tick(leaf) == Status.SUCCESS
    fired_after = None
    for i in range(1, 300):  # 0.2 m/s in ticks of 0.1 s: 2 m after 10 s
        clock.now = 1.0 + 0.1 * i
        if tick(leaf) == Status.SUCCESS:
            fired_after = 0.1 * i
            break
    assert fired_after == pytest.approx(10.0, abs=0.11)




def test_a_repeating_front_trigger_fires_whenever_it_is_ticked_while_its_condition_holds() -> None:
    """The lab's front triggers (trigger_repeat): the tree ticks them only when no maneuver runs, so a
    front still blocked after a turn fires the next turn; a clear front does not fire."""
    board = Board()
    board.set(sectors=sectors(front=0.4), distance=0.5, repeat=True)
    trigger = make(FrontTrigger, clock=FakeClock(1.0))
    assert [tick(trigger) for _ in range(3)] == [Status.SUCCESS] * 3
    board.set(sectors=sectors(front=0.7))
    assert tick(trigger) == Status.FAILURE
    board.set(sectors=sectors(front=0.4), repeat=False)
    assert tick(trigger) == Status.SUCCESS and tick(trigger) == Status.FAILURE  # the edge rule again
