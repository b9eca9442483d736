"""What the rules page (``bt_nav.grading.rules``, no rclpy) says of the ROS edge is what the edge does: the topics and
types the graph audit requires, the QoS the simulator offers ``scan`` with and reads ``cmd_vel`` with in a grade, the
services and parameters the judge nodes use. The page holds these as constants; a change here must change them."""

from __future__ import annotations

import inspect

from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

from bt_nav.grading import rules
from bt_nav.grading.exe.run import FOLLOW_NODE
from bt_nav.ros.bringup import HOMEWORK_ACTIVATE, HOMEWORK_EVALUATE, LAB_ARM
from bt_nav.ros.nodes import audit, referee
from bt_nav.ros.nodes.checkoff import CheckoffNode
from bt_nav.ros.nodes.referee import RefereeNode
from bt_nav.ros.nodes.simulator import SCAN_QOS, SimulatorNode, cmd_vel_qos


def _qos(profile: object) -> tuple[str, str, int]:
    return (profile.reliability.name.lower(), profile.durability.name.lower(), profile.depth)  # type: ignore[attr-defined]


def test_the_qos_the_page_names_is_the_simulator_s() -> None:
    assert _qos(SCAN_QOS) == rules.SCAN_QOS
    graded = cmd_vel_qos(str(FOLLOW_NODE["cmd_vel_reliability"]), bool(FOLLOW_NODE["follow"]))
    assert _qos(graded) == rules.COMMAND_QOS
    assert {SCAN_QOS.durability, graded.durability} == {DurabilityPolicy.VOLATILE}
    assert graded.reliability == ReliabilityPolicy.BEST_EFFORT
    assert SimulatorNode.PARAMETERS["cmd_vel_timeout"][0] == rules.COMMAND_TIMEOUT


def test_the_topics_and_types_the_page_names_are_the_audit_s() -> None:
    defaults = {name: p.default for name, p in inspect.signature(audit.GraphAudit.__init__).parameters.items()}
    assert dict(defaults["inputs"]) == dict([rules.SCAN, rules.CLOCK])
    assert defaults["command"] == rules.COMMAND[0] and audit.TWIST == rules.COMMAND[1]
    assert audit.SET_BOOL == rules.SET_BOOL


def test_the_services_and_parameters_the_page_names_are_the_judges() -> None:
    assert CheckoffNode.PARAMETERS["activate_service"][0] == LAB_ARM
    assert CheckoffNode.required_parameters == rules.LAB_PARAMETERS
    assert RefereeNode.PARAMETERS["activate_service"][0] == HOMEWORK_ACTIVATE
    assert RefereeNode.PARAMETERS["evaluate_service"][0] == HOMEWORK_EVALUATE
    assert rules.TRIGGER == f"std_srvs/srv/{referee.Trigger.__name__}"  # the type its evaluation server is made with
