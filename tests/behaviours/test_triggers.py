"""The maneuver triggers alone: EdgeLatch's rules, and FrontTrigger / SqueezeTrigger ticked on a small blackboard."""

from __future__ import annotations

import math

import py_trees
import pytest

from bt_nav.mission.behaviours.triggers import EdgeLatch, FrontTrigger, SqueezeTrigger
from bt_nav.mission.datatypes import OdomSample
from bt_nav.mission.scan import SectorReading, Sectors
from bt_nav.testing import FakeClock

Status = py_trees.common.Status


def reading(distance: float) -> SectorReading:
    return SectorReading(distance, 10, 10) if not math.isnan(distance) else SectorReading(math.nan, 0, 10)


def sectors(front: float = math.inf, left: float = math.inf, right: float = math.inf) -> Sectors:
    return Sectors(reading(front), reading(left), reading(right))


# ----------------------------------------------------------------------------------- the latch
def armed_latch() -> EdgeLatch:
    """A latch after a new arming that has seen its condition clear once."""
    latch = EdgeLatch()
    latch.reset()
    latch.odometry(0.0, 0.0)
    assert not latch.step(holds=False, cleared=True, rearm_distance=1.0)
    assert latch.armed
    return latch


def test_a_condition_holding_at_arming_is_not_an_edge() -> None:
    latch = EdgeLatch()
    latch.reset()
    assert not any(latch.step(holds=True, cleared=False, rearm_distance=1.0) for _ in range(10))
    latch.step(holds=False, cleared=True, rearm_distance=1.0)  # seen clear once: armed, wherever it is
    assert latch.step(holds=True, cleared=False, rearm_distance=1.0)


def test_latch_fires_once_on_a_rising_edge() -> None:
    latch = armed_latch()
    assert latch.step(holds=True, cleared=False, rearm_distance=1.0)
    assert not any(latch.step(True, False, 1.0) for _ in range(100)), "a lasting condition re-fired"


def test_latch_rearms_only_when_cleared_away_from_where_it_fired() -> None:
    latch = armed_latch()
    latch.step(True, False, 1.0)
    assert latch.fired_at == (0.0, 0.0)
    latch.step(False, True, 1.0)  # cleared, but on the spot (a rotation sweeps the sectors)
    assert not latch.step(True, False, 1.0)
    latch.odometry(0.6, 0.8)  # 1.0 m away ...
    assert not latch.step(True, False, 1.0)  # ... but the condition has not cleared there
    latch.odometry(float("nan"), 5.0)  # an unknown position changes nothing
    assert latch.away == pytest.approx(1.0)
    latch.step(False, False, 1.0)  # released inside the hysteresis band: not cleared
    assert not latch.step(True, False, 1.0)
    latch.step(False, True, 1.0)
    assert latch.step(True, False, 1.0), "cleared 1 m away: a fresh condition must fire"
    assert latch.fired_at == (0.6, 0.8)


def test_without_positions_clearing_alone_rearms() -> None:
    latch = EdgeLatch()
    latch.reset()
    latch.step(False, True, 1.0)
    assert latch.step(True, False, 1.0) and latch.fired_at is None
    assert latch.away == float("inf")
    latch.step(False, True, 1.0)
    assert latch.step(True, False, 1.0)


# ----------------------------------------------------------------------------------- the leaves
class Board:
    """A blackboard holding just what a trigger reads."""

    def __init__(self) -> None:
        py_trees.blackboard.Blackboard.clear()
        self.client = py_trees.blackboard.Client(name="test")
        for key in ("sectors", "odom", "arm_count", "distance", "hysteresis", "rearm_distance"):
            self.client.register_key(key, access=py_trees.common.Access.WRITE)
        self.set(sectors(), OdomSample(0.0, 0.0, 0.0, 0.0), 1)
        self.client.set("distance", 0.5)
        self.client.set("hysteresis", 0.1)
        self.client.set("rearm_distance", 2.0)  # the leaves re-arm 2 m from where they fired

    def set(self, s: Sectors, odom: OdomSample | None = None, arm_count: int | None = None) -> None:
        self.client.set("sectors", s)
        if odom is not None:
            self.client.set("odom", odom)
        if arm_count is not None:
            self.client.set("arm_count", arm_count)


def make(cls: type) -> py_trees.behaviour.Behaviour:
    """The leaf with its ports on the blackboard keys of the same names (distance 0.5, hysteresis 0.1,
    rearm_distance 2.0, set by :class:`Board`)."""
    leaf = cls("T")
    leaf.setup_ports({name: f"/{name}" for name in leaf.input_ports()})
    leaf.setup(clock=FakeClock())
    return leaf


def tick(leaf: py_trees.behaviour.Behaviour) -> Status:
    leaf.tick_once()
    return leaf.status


def test_front_trigger_statuses() -> None:
    board = Board()
    leaf = make(FrontTrigger)
    board.set(sectors(front=0.4))
    assert tick(leaf) == Status.FAILURE  # holding at the (new) arming: not an edge
    board.set(sectors(front=2.0))
    assert tick(leaf) == Status.FAILURE and leaf.feedback_message == "armed"
    board.set(sectors(front=0.4))
    assert tick(leaf) == Status.SUCCESS and leaf.feedback_message == "fired"
    assert tick(leaf) == Status.FAILURE and "re-arm" in leaf.feedback_message
    board.set(sectors(front=0.55), OdomSample(0.0, 1.0, 3.0, 0.0))  # far away, inside the hysteresis band
    tick(leaf)
    board.set(sectors(front=0.4))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(front=0.65))
    tick(leaf)
    board.set(sectors(front=0.4))
    assert tick(leaf) == Status.SUCCESS


def test_unknown_front_holds_but_never_clears() -> None:
    board = Board()
    leaf = make(FrontTrigger)
    tick(leaf)  # clear: armed
    board.set(sectors(front=math.nan))
    assert tick(leaf) == Status.SUCCESS
    board.set(sectors(front=math.nan), OdomSample(0.0, 1.0, 5.0, 0.0))
    assert tick(leaf) == Status.FAILURE  # still unknown: not a new edge, and unknown is not "cleared"


def test_squeeze_trigger_needs_both_sides_and_rearms_on_one_side_clearing() -> None:
    board = Board()
    leaf = make(SqueezeTrigger)
    tick(leaf)
    board.set(sectors(left=0.4, right=0.9))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.7), OdomSample(0.0, 1.0, 2.5, 0.0))  # one side open, 2.5 m on
    tick(leaf)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS


def test_a_new_arming_starts_afresh() -> None:
    board = Board()
    leaf = make(SqueezeTrigger)
    tick(leaf)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
    board.set(sectors(left=0.4, right=0.7))  # cleared, but on the spot: not re-armed
    tick(leaf)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.7), arm_count=2)  # disarmed and armed again: clearing suffices
    tick(leaf)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
