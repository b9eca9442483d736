"""The judges' graph audit over real DDS, in-process: a student-like node with every fault the audit names,
a well-behaved one with none, and stand-ins for our simulator (its name and its endpoints' QoS)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from simtools import wait_until
from std_srvs.srv import SetBool

from bt_nav.ros.nodes import findings as kinds
from bt_nav.ros.nodes.audit import FLOOD_RATE, GraphAudit, is_ours

BEST_EFFORT = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)


@pytest.fixture
def graph(ros_context: Any) -> Iterator[tuple[Any, GraphAudit]]:
    """(student, audit): a fake simulator offering its topics as the simulator node does, the audit run from a
    node named like a judge, and a factory of the judged node (or, given a name, of any other). Each is a
    process of its own to DDS (its own context: one participant may not hold two types on one topic); all spin
    in one thread."""
    executors: list[SingleThreadedExecutor] = []
    made: list[Any] = []

    def make_node(name: str) -> Any:
        context = rclpy.Context()
        rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
        node = rclpy.create_node(name, context=context)
        executors.append(SingleThreadedExecutor(context=context))
        executors[-1].add_node(node)
        made.append(node)
        return node

    sim = make_node("bt_nav_sim")
    sim.create_publisher(LaserScan, "/scan", QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE))
    sim.create_publisher(Clock, "/clock", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    sim.create_subscription(Twist, "/cmd_vel", lambda msg: None, BEST_EFFORT)
    audit = GraphAudit(make_node("bt_nav_test_judge"), "/reactive_control/activate")
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            for executor in list(executors):
                executor.spin_once(timeout_sec=0.01)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    yield lambda name="reactive_control": make_node(name), audit
    stop.set()
    thread.join(timeout=2.0)
    for node, executor in zip(made, executors, strict=True):
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown(context=executor.context)


def _findings_once(audit: GraphAudit, *words: str, timeout: float = 20.0) -> list[str]:
    """The audit's findings once every one of ``words`` is in them (discovery takes a moment)."""
    found: list[str] = []

    def ready() -> bool:
        found[:] = audit.findings()
        return all(any(w in f for f in found) for w in words)

    wait_until(ready, timeout, f"findings naming {words}", lambda: "\n".join(found))
    return found


def test_ours_and_theirs() -> None:
    assert is_ours("bt_nav_sim") and is_ours("bt_nav_referee") and is_ours("bt_nav_demo_recorder")
    assert is_ours("_ros2cli_daemon_0") and not is_ours("reactive_control")
    assert not is_ours("bt_nav_executive"), "bt_nav's executive graded with --exe is the judged node"


def test_nothing_on_the_graph(graph: tuple[Any, GraphAudit]) -> None:
    _, audit = graph
    assert audit.findings() == ["no node besides the simulator and the judge ever appeared on the ROS graph (did "
                                "the command start a ROS 2 node in this ROS_DOMAIN_ID?)"]


def test_a_well_behaved_node_has_no_findings(graph: tuple[Any, GraphAudit]) -> None:
    student, audit = graph
    node = student()
    node.create_subscription(LaserScan, "scan", lambda msg: None, 10)  # the lab's template: reliable
    node.create_subscription(Clock, "/clock", lambda msg: None, BEST_EFFORT)  # what use_sim_time creates
    pub = node.create_publisher(Twist, "cmd_vel", 10)
    node.create_service(SetBool, "/reactive_control/activate", lambda req, res: res)
    node.create_timer(0.05, lambda: pub.publish(Twist()))
    wait_until(lambda: audit.sample(force=True) or (audit.commands.received > 0
                                                    and "/reactive_control/activate" in audit.offered), 20.0,
               "the node's commands and service seen by the audit", lambda: str(audit.findings()))
    assert audit.findings() == []


def test_observers_are_no_reference(graph: tuple[Any, GraphAudit]) -> None:
    """A best-effort command writer suits the simulator; that our recorder reads reliably (and so hears
    nothing) concerns the recording, not the robot: no finding, whichever of our readers was discovered first."""
    student, audit = graph
    recorder = student("bt_nav_recorder")
    recorder.create_subscription(Twist, "/cmd_vel", lambda msg: None, 10)
    node = student()
    node.create_subscription(LaserScan, "scan", lambda msg: None, 10)
    node.create_subscription(Clock, "/clock", lambda msg: None, BEST_EFFORT)
    pub = node.create_publisher(Twist, "cmd_vel", qos_profile_sensor_data)
    node.create_service(SetBool, "/reactive_control/activate", lambda req, res: res)
    node.create_timer(0.05, lambda: pub.publish(Twist()))

    def seen() -> bool:
        audit.sample(force=True)
        readers = {e.node_name for e in audit.node.get_subscriptions_info_by_topic("/cmd_vel")}
        return audit.commands.received > 0 and {"bt_nav_sim", "bt_nav_recorder"} <= readers

    wait_until(seen, 20.0, "the node's commands and both readers seen", lambda: str(audit.findings()))
    audit.sample(force=True)
    assert audit.findings() == []


def test_every_fault_is_named(graph: tuple[Any, GraphAudit]) -> None:
    """Transient-local scan reader (the simulator's writer is volatile), TwistStamped on a Twist topic, no /clock
    reader, the arm service under another name, NaN and a flood of commands."""
    student, audit = graph
    node = student()
    node.create_subscription(LaserScan, "scan", lambda msg: None,
                             QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    pub = node.create_publisher(TwistStamped, "cmd_vel", qos_profile_sensor_data)
    node.create_service(SetBool, "/activate", lambda req, res: res)
    wait_until(lambda: audit.sample(force=True) or audit.hears_commands, 20.0, "the audit's cmd_vel reader")
    time.sleep(0.5)  # the reader's match with the writer
    cmd = TwistStamped()
    cmd.twist.linear.x = math.nan
    start = time.monotonic()
    while time.monotonic() - start < 1.0:  # a flood: as fast as this loop turns, for a second
        pub.publish(cmd)
    time.sleep(0.5)  # what is on the wire is taken: the counts stand still from here
    found = _findings_once(audit, "incompatible QoS", "TwistStamped", "/clock", "never offered", "NaN", "flood")
    text = "\n".join(found)
    assert ("incompatible QoS on /scan: reactive_control subscribes to it reliable, transient_local, bt_nav_sim "
            "publishes it reliable, volatile (Volatile publisher and transient local subscription)") in text, text
    assert ("reactive_control publishes /cmd_vel as geometry_msgs/msg/TwistStamped, but bt_nav_sim reads "
            "geometry_msgs/msg/Twist") in text, text
    assert "no node subscribed to /clock: the node does not run on sim time" in text
    assert ("the service /reactive_control/activate was never offered (the node offers std_srvs/srv/SetBool as "
            "/activate)") in text
    flood = next(f for f in found if f.startswith("cmd_vel flood"))
    rate = float(flood.split()[2])  # the judge's clock is wall time here: per "sim" s is per wall s
    assert FLOOD_RATE < rate == pytest.approx(audit.commands.rates()[0], rel=0.01)
    nan = next(f for f in found if "NaN" in f)
    words = nan.split()  # "<non-finite> of <received> cmd_vel messages held NaN or inf values ..."
    assert words[0] == words[2] and int(words[0]) > 0, nan  # every one of them was NaN
    assert not any("/scan" in f and "no node subscribed" in f for f in found), "it does subscribe (wrongly)"
    # the same findings as data, for the grader's decisions (bt_nav.grading.realtime reads the kinds, not the words)
    records = {(r.kind, r.topic, r.clause) for r in audit.finding_records()}
    assert {(kinds.QOS_MISMATCH, "/scan", "incompatible QoS on /scan"),
            (kinds.TYPE_MISMATCH, "/cmd_vel", "reactive_control publishes /cmd_vel as geometry_msgs/msg/TwistStamped, "
                                              "but bt_nav_sim reads geometry_msgs/msg/Twist"),
            (kinds.NO_SUBSCRIBER, "/clock", "no node subscribed to /clock"),
            (kinds.SERVICE, "/reactive_control/activate", ""), (kinds.NON_FINITE, "/cmd_vel", ""),
            (kinds.FLOOD, "/cmd_vel", "")} <= records, records


def test_the_parameters_are_listed_and_read_back(graph: tuple[Any, GraphAudit]) -> None:
    """``ros2 param list`` and ``ros2 param get``, as the check-off's step 2: the names a node declares, and their
    values (what a grade compares with what it passed); a node that declares none lists only rclpy's own."""
    make, _ = graph
    audit = GraphAudit(make("bt_nav_param_judge"), "toggle_navigation", parameters=("safety_distance",))
    student = make("reactive_navigator")
    student.declare_parameter("safety_distance", 0.7)
    make("other_node")
    report: list[dict[str, Any]] = []

    def ready() -> bool:
        audit.sample(force=True)
        report[:] = audit.parameter_report()
        return len(report) == 2 and all(entry["values"] for entry in report)

    wait_until(ready, 20.0, "both nodes' parameters listed and read back", lambda: str(report))
    by_node = {entry["node"]: entry for entry in report}
    assert "safety_distance" in by_node["/reactive_navigator"]["names"]
    assert by_node["/reactive_navigator"]["values"]["safety_distance"] == 0.7
    assert "safety_distance" not in by_node["/other_node"]["names"]
    assert by_node["/other_node"]["values"]["use_sim_time"] is False
    assert audit.parameter_findings() == []  # one judged node declares it


def test_endpoints_are_read_again_when_the_outline_changes(graph: tuple[Any, GraphAudit], monkeypatch) -> None:
    """Between looks whose outline (topics, counts, nodes) is the same, no endpoint is read; an endpoint that comes
    later on a topic already there (a transient-local scan reader beside the node's volatile one) changes the counts,
    and the next look names its mismatch (the periodic full read is pushed out of the test's reach)."""
    from bt_nav.ros.nodes import audit as audit_module

    monkeypatch.setattr(audit_module, "SAMPLE_PERIOD", 0.0)
    monkeypatch.setattr(audit_module, "FULL_PERIOD", 1e9)
    student, audit = graph
    node = student()
    node.create_subscription(LaserScan, "scan", lambda msg: None, 10)
    reads = [0]
    endpoints = audit.node.get_publishers_info_by_topic

    def counted(topic: str) -> Any:
        reads[0] += 1
        return endpoints(topic)
    monkeypatch.setattr(audit.node, "get_publishers_info_by_topic", counted)
    outlines: list[Any] = []

    def settled() -> bool:
        audit.sample()
        outlines.append(audit._outline)
        return "/scan" in audit.subscribed and len(outlines) > 3 and outlines[-1] == outlines[-4] \
            and not audit._unnamed  # an endpoint without its node's name yet is read at every look

    wait_until(settled, 20.0, "the node's scan reader seen and the graph settled (every endpoint named)")
    for _ in range(20):  # a look whose outline stayed as it was (DDS may still name or add an endpoint meanwhile)
        before, outline = reads[0], audit._outline
        audit.sample()
        if audit._outline == outline and not audit._unnamed:
            break
    assert audit._outline == outline, "the graph never stood still for one look"
    assert reads[0] == before, "an unchanged outline read the endpoints again"
    node.create_subscription(LaserScan, "scan", lambda msg: None,
                             QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    wait_until(lambda: audit.sample() or any("incompatible QoS on /scan" in f for f in audit.findings()), 20.0,
               "the new reader's mismatch found by an unforced look", lambda: str(audit.findings()))
    assert reads[0] > before
