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
def test_latch_fires_once_on_a_rising_edge() -> None:
    latch = EdgeLatch()
    assert latch.step(holds=True, cleared=False, rearm_distance=0.0)
    assert not any(latch.step(True, False, 0.0) for _ in range(100)), "a lasting condition re-fired"


def test_latch_rearms_only_past_the_hysteresis() -> None:
    latch = EdgeLatch()
    latch.step(True, False, 0.0)
    assert not latch.step(False, False, 0.0)  # released but inside the band: no re-arm
    assert not latch.step(True, False, 0.0)
    latch.step(False, True, 0.0)  # cleared beyond the band
    assert latch.step(True, False, 0.0), "a fresh condition after clearing must fire"


def test_latch_rearms_after_driving_far_enough() -> None:
    latch = EdgeLatch()
    latch.odometry(0.0, 0.0)
    latch.step(True, False, 1.0)
    for x in (0.3, 0.6, 0.9):
        latch.odometry(x, 0.0)
        assert not latch.step(True, False, 1.0)
    latch.odometry(float("nan"), 0.0)  # an unknown position adds nothing
    latch.odometry(1.05, 0.0)
    assert latch.travelled == pytest.approx(1.05)
    assert latch.step(True, False, 1.0)
    assert latch.travelled == 0.0


def test_latch_reset_makes_a_holding_condition_a_rising_edge() -> None:
    latch = EdgeLatch()
    latch.step(True, False, 0.0)
    latch.reset()
    assert latch.step(True, False, 0.0)


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
        self.client.set("rearm_distance", 2.0)

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
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(front=0.4))
    assert tick(leaf) == Status.SUCCESS and leaf.feedback_message == "fired"
    assert tick(leaf) == Status.FAILURE and "re-arm" in leaf.feedback_message
    board.set(sectors(front=0.55))  # above 0.5 but inside the 0.1 m hysteresis band
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
    board.set(sectors(front=math.nan))
    assert tick(leaf) == Status.SUCCESS
    assert tick(leaf) == Status.FAILURE  # still unknown: not a new edge, and unknown is not "cleared"


def test_squeeze_trigger_needs_both_sides_and_rearms_on_one_side_clearing() -> None:
    board = Board()
    leaf = make(SqueezeTrigger)
    board.set(sectors(left=0.4, right=0.9))
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.7))  # one side open beyond the band: no longer squeezed
    tick(leaf)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS


def test_motion_and_a_new_arming_rearm_the_leaf() -> None:
    board = Board()
    leaf = make(SqueezeTrigger)
    board.set(sectors(left=0.4, right=0.4))
    assert tick(leaf) == Status.SUCCESS
    for i in range(1, 5):  # 0.5 m per odometry sample, condition held throughout
        board.set(sectors(left=0.4, right=0.4), OdomSample(0.0, float(i), 0.5 * i, 0.0))
        status = tick(leaf)
    assert status == Status.SUCCESS, "2 m driven: the trigger must have re-armed and fired"
    assert tick(leaf) == Status.FAILURE
    board.set(sectors(left=0.4, right=0.4), arm_count=2)  # disarmed and armed again
    assert tick(leaf) == Status.SUCCESS
