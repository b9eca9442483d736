"""The check-off judge node's ``/rosout`` reader (CheckoffNode._on_log), one unit: which lines reach the judge as
announcements, and at what time (rclpy stamps its lines with the wall clock, so the arrival on the judge's clock
counts, unless the stamp is the judge's own sim time)."""

from __future__ import annotations

import threading
from types import SimpleNamespace
from typing import Any

from rcl_interfaces.msg import Log

from bt_nav.ros.nodes.checkoff import CheckoffNode


class _Judge:
    def __init__(self) -> None:
        self.heard: list[tuple[float, str, str]] = []

    def on_announcement(self, t: float, node: str, text: str) -> None:
        self.heard.append((t, node, text))


def _node(started: bool = True) -> Any:
    return SimpleNamespace(lock=threading.RLock(), started=started, now=lambda: 42.0, judge=_Judge())


def _log(name: str, sec: int, text: str = "Obstacle Detected! Executing rotation maneuver.") -> Log:
    msg = Log(name=name, msg=text)
    msg.stamp.sec = sec
    return msg


def test_the_graded_nodes_lines_reach_the_judge_at_their_arrival() -> None:
    node = _node()
    CheckoffNode._on_log(node, _log("reactive_navigator", 1_795_786_294))  # rclpy's wall-clock stamp
    CheckoffNode._on_log(node, _log("robot1.reactive_navigator", 41))  # a node logging on sim time: its stamp
    CheckoffNode._on_log(node, _log("bt_nav_executive", 1_795_786_294))  # bt_nav's own executive is graded too
    assert node.judge.heard == [(42.0, "reactive_navigator", "Obstacle Detected! Executing rotation maneuver."),
                                (41.0, "robot1.reactive_navigator", "Obstacle Detected! Executing rotation maneuver."),
                                (42.0, "bt_nav_executive", "Obstacle Detected! Executing rotation maneuver.")]


def test_the_judges_and_the_simulators_own_lines_and_lines_before_t0_do_not() -> None:
    node = _node()
    for name in ("bt_nav_checkoff", "bt_nav_sim", "lab.bt_nav_checkoff", "_hidden"):
        CheckoffNode._on_log(node, _log(name, 42))
    waiting = _node(started=False)
    CheckoffNode._on_log(waiting, _log("reactive_navigator", 42))
    assert node.judge.heard == [] and waiting.judge.heard == []


def test_a_wall_stamped_line_is_placed_at_its_stamp_on_the_sim_clock_not_at_its_arrival() -> None:
    """Issue 52: a line logged at wall 1000.5 s, when the sim clock read 40.5 s, arrives at sim 42 s (a busy machine
    delivered it late): it marks its maneuver at 40.5 s. A stamp the clock map does not cover is timed on arrival."""
    from bt_nav.judge.segments import ClockMap

    node = _node()
    node.clocks = ClockMap()
    for k in range(301):
        node.clocks.add(1000.0 + k * 0.01, 40.0 + k * 0.01)
    late = _log("reactive_navigator", 1000)
    late.stamp.nanosec = 500_000_000
    CheckoffNode._on_log(node, late)
    CheckoffNode._on_log(node, _log("reactive_navigator", 2000))
    assert [round(t, 3) for t, _, _ in node.judge.heard] == [40.5, 42.0]
