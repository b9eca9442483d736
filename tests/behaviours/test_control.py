"""The BehaviorTree.CPP control nodes alone: reactive (memory-less) sequence and fallback, ForceSuccess.

The children are py_trees' scripted behaviours, so each test says exactly what every child returns.
"""

from __future__ import annotations

import py_trees
from leafkit import Status

from bt_nav.mission.behaviours.control import ForceSuccess, ReactiveFallback, ReactiveSequence


class Scripted(py_trees.behaviour.Behaviour):
    """Returns ``self.result`` on every tick; counts updates and terminations."""

    def __init__(self, name: str, result: Status) -> None:
        super().__init__(name)
        self.result = result
        self.updates = 0
        self.terminated: list[Status] = []

    def update(self) -> Status:
        self.updates += 1
        return self.result

    def terminate(self, new_status: Status) -> None:
        self.terminated.append(new_status)


def run(root: py_trees.behaviour.Behaviour) -> Status:
    root.tick_once()
    return root.status


def test_reactive_sequence_rechecks_its_guard_and_preempts_the_running_action() -> None:
    guard, action = Scripted("guard", Status.SUCCESS), Scripted("action", Status.RUNNING)
    root = ReactiveSequence("Seq", children=[guard, action])
    assert run(root) == Status.RUNNING and run(root) == Status.RUNNING
    assert guard.updates == 2, "memory-less: the guard is ticked again on every tick"
    guard.result = Status.FAILURE
    assert run(root) == Status.FAILURE
    assert action.status == Status.INVALID and Status.INVALID in action.terminated, "the action was preempted"


def test_reactive_sequence_succeeds_when_every_child_does() -> None:
    root = ReactiveSequence("Seq", children=[Scripted("a", Status.SUCCESS), Scripted("b", Status.SUCCESS)])
    assert run(root) == Status.SUCCESS


def test_reactive_fallback_lets_a_higher_priority_preempt_a_running_lower_one() -> None:
    high, low = Scripted("high", Status.FAILURE), Scripted("low", Status.RUNNING)
    root = ReactiveFallback("Fallback", children=[high, low])
    assert run(root) == Status.RUNNING and low.status == Status.RUNNING
    high.result = Status.RUNNING
    assert run(root) == Status.RUNNING
    assert root.current_child is high
    assert low.status == Status.INVALID and Status.INVALID in low.terminated
    high.result, low.result = Status.FAILURE, Status.FAILURE
    assert run(root) == Status.FAILURE, "fails only when every child does"


def test_force_success_turns_failure_into_success_and_keeps_running() -> None:
    child = Scripted("child", Status.FAILURE)
    root = ForceSuccess("Force", child=child)
    assert run(root) == Status.SUCCESS
    child.result = Status.RUNNING
    assert run(root) == Status.RUNNING
    child.result = Status.SUCCESS
    assert run(root) == Status.SUCCESS


def test_control_nodes_declare_no_ports() -> None:
    for cls in (ReactiveSequence, ReactiveFallback, ForceSuccess):
        assert cls.INPUT_PORTS == {} and cls.OUTPUT_PORTS == {}
