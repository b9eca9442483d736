"""The leaf base classes alone: the command output, the fast input path, the injected clock, Condition."""

from __future__ import annotations

import math

import pytest
from leafkit import Board, Events, Status, make, tick

from bt_nav.mission.behaviours.base import CMD_PORT, Condition, Leaf, port
from bt_nav.mission.datatypes import Command
from bt_nav.testing import FakeClock


class Echo(Leaf, register=False):
    """Commands what ``linear`` / ``angular`` hold; RUNNING."""

    INPUT_PORTS = {"linear": port(float, default=0.0), "angular": port(float, default=0.0)}
    OUTPUT_PORTS = dict(CMD_PORT)

    def update(self) -> Status:
        self.command(self.get_input("linear"), self.get_input("angular"))
        return Status.RUNNING


class Flag(Condition, register=False):
    """Answers ``flag``."""

    INPUT_PORTS = {"flag": port(bool, default=False)}
    OUTPUT_PORTS = {}

    def answer(self) -> bool:
        return bool(self.get_input("flag"))


def test_command_writes_a_twist_named_after_the_leaf() -> None:
    board = Board()
    board.set(linear=0.2, angular=-0.5)
    leaf = make(Echo, "Branch.Echo")
    assert tick(leaf) == Status.RUNNING
    assert board.get("cmd_vel") == Command(0.2, -0.5, "Echo")  # the label drops the parents' prefix


@pytest.mark.parametrize(("linear", "angular"), [(math.nan, 0.0), (0.1, math.inf), (-math.inf, math.nan)])
def test_a_non_finite_command_becomes_a_stop_and_one_error_line(linear: float, angular: float) -> None:
    board = Board()
    events = Events()
    board.set(linear=linear, angular=angular)
    tick(make(Echo, events=events))
    assert board.get("cmd_vel") == Command(0.0, 0.0, "Leaf")
    assert events.count("error", "non-finite command") == 1


def test_inputs_follow_the_blackboard_and_fall_back_to_the_port_default() -> None:
    board = Board()
    leaf = make(Echo)
    tick(leaf)
    assert board.get("cmd_vel") == Command(0.0, 0.0, "Leaf")  # nothing written yet: the defaults
    board.set(linear=0.1)
    tick(leaf)
    assert board.get("cmd_vel").linear == 0.1
    board.set(linear=0.15)  # the cached key sees a new value on the next tick
    tick(leaf)
    assert board.get("cmd_vel").linear == 0.15


def test_a_leaf_without_an_injected_clock_says_so() -> None:
    Board()
    leaf = Echo("NoClock")
    with pytest.raises(RuntimeError, match="no clock injected"):
        leaf.clock()
    clock = FakeClock(3.0)
    leaf.setup(clock=clock)
    assert leaf.clock() == 3.0 and leaf.node is None


def test_condition_answers_success_or_failure_never_running() -> None:
    board = Board()
    leaf = make(Flag)
    assert tick(leaf) == Status.FAILURE
    board.set(flag=True)
    assert tick(leaf) == Status.SUCCESS
    board.set(flag=False)
    assert tick(leaf) == Status.FAILURE


def test_the_base_condition_has_no_answer_of_its_own() -> None:
    with pytest.raises(NotImplementedError):
        Condition.answer(Flag("x"))
