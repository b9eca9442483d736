"""The executive's pieces in-process (no subprocess, no spinning): stats, helpers, last-line checks."""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import py_trees
import pytest
import rclpy.logging
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter

from bt_nav.mission import params as P
from bt_nav.mission.datatypes import Command
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.ros.executive import Executive
from bt_nav.ros.rosutil import (
    ConfigError,
    RclpyEventLog,
    claim_domain_id,
    domain_id_for,
    parameter_descriptor,
    route_py_trees_logging,
)
from bt_nav.ros.safety import ClockWatchdog
from bt_nav.ros.supervise import NoFreeDomainError
from bt_nav.ros.tick_stats import TickStats


@pytest.fixture
def executive(ros_context: Any) -> Iterator[Executive]:
    """An Executive on an in-process node that is never spun (its own name: no clash with subprocesses)."""
    node = Node("bt_nav_executive_unit", context=ros_context, start_parameter_services=False)
    try:
        yield Executive(node)
    finally:
        node.destroy_node()


def test_tick_stats_summary() -> None:
    stats = TickStats(period=0.05)
    for duration in [0.001] * 98 + [0.002, 0.06]:
        stats.record(duration)
    assert (stats.ticks, stats.overruns) == (100, 1)
    line = TickStats.describe(stats.take_window())
    assert line == "tick ms min/mean/p99/max 1.00/1.60/2.00/60.00 over 100"
    assert stats.window == [] and len(stats.history) == 100
    assert TickStats.describe([]) == "no ticks"
    assert "overruns 1 (period 50.0 ms), exceptions 2" in stats.counters(faults=2)


def test_tick_stats_periodic_line_follows_the_mission_clock() -> None:
    stats = TickStats(period=0.05)
    assert stats.periodic_line(10.0, 5.0, 0) is None  # the first tick opens the window
    stats.record(0.001)
    assert stats.periodic_line(14.9, 5.0, 0) is None
    line = stats.periodic_line(15.0, 5.0, 0)
    assert line is not None and line.startswith("stats: tick ms") and "over 1" in line
    assert stats.periodic_line(3.0, 5.0, 0) is None  # clock jumped back: a new window, no line
    assert stats.periodic_line(100.0, 0.0, 0) is None  # stats_period 0: never
    assert stats.final_line(0).startswith("final stats: tick ms")


def test_clock_watchdog_stops_once_and_notes_the_resumption() -> None:
    dog = ClockWatchdog(1.0)
    assert dog.due(5.0) is None  # no tick yet
    assert dog.ticked(10.0) is None
    assert dog.due(12.0) is None  # not moving: nothing to stop
    dog.moving = True
    assert dog.due(10.9) is None
    assert dog.due(11.5) == pytest.approx(1.5) and dog.stops == 1 and not dog.moving
    assert dog.due(13.0) is None  # one stop per stall
    assert dog.ticked(14.0) == pytest.approx(4.0)  # the tick that ends the stall says how long it was
    dog.timeout = 0.0
    dog.moving = True
    assert dog.due(100.0) is None  # 0 disables


@pytest.mark.parametrize("yaw", [0.0, 0.5, -2.0, math.pi - 1e-9])
def test_yaw_from_quaternion(yaw: float) -> None:
    assert yaw_from_quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)) == pytest.approx(yaw)
    assert yaw_from_quaternion(0.0, 0.0, 3 * math.sin(yaw / 2), 3 * math.cos(yaw / 2)) == pytest.approx(yaw)


def test_yaw_from_a_non_rotation_is_nan() -> None:
    assert math.isnan(yaw_from_quaternion(0.0, 0.0, 0.0, 0.0))
    assert math.isnan(yaw_from_quaternion(math.nan, 0.0, 0.0, 1.0))


def test_descriptors_follow_the_table() -> None:
    maneuver = parameter_descriptor(P.SPECS["maneuver"])
    assert maneuver.read_only and maneuver.type == ParameterType.PARAMETER_STRING
    assert "one of none, A, B, C" in maneuver.additional_constraints
    distance = parameter_descriptor(P.SPECS["safety_distance"])
    assert not distance.read_only and distance.description.endswith("[m]")
    assert (distance.floating_point_range[0].from_value, distance.floating_point_range[0].to_value) == (0.05, 10.0)
    retries = parameter_descriptor(P.SPECS["evaluation_retries"])
    assert retries.type == ParameterType.PARAMETER_INTEGER and retries.integer_range[0].to_value == 100


def test_domain_ids_stay_in_range() -> None:
    assert {domain_id_for(pid) for pid in range(1000)} == set(range(100, 200))
    assert 100 <= domain_id_for("gw3") <= 199


def test_claimed_domains_are_exclusive(tmp_path: Any) -> None:
    claimed = [claim_domain_id(220, 222, start=0, lock_dir=tmp_path) for _ in range(3)]
    assert sorted(claimed) == [220, 221, 222]  # each one locked: the next claim moves on
    with pytest.raises(NoFreeDomainError, match=r"no free ROS_DOMAIN_ID in range 220-222 \(each one is claimed"):
        claim_domain_id(220, 222, start=1, lock_dir=tmp_path)  # all taken: none handed out unclaimed


def _log_either(log: Any, ok: bool) -> None:
    (log.info if ok else log.warning)("same call site, two severities")


def test_event_log_allows_two_severities_from_one_call_site() -> None:
    raw = rclpy.logging.get_logger("bt_nav_test_events")
    _log_either(raw, True)
    with pytest.raises(ValueError, match="severity cannot be changed"):
        _log_either(raw, False)  # why RclpyEventLog exists: a leaf doing this would raise inside the tick
    events = RclpyEventLog(rclpy.logging.get_logger("bt_nav_test_events2"))
    _log_either(events, True)
    _log_either(events, False)


def test_py_trees_logging_is_routed_and_restored() -> None:
    class Sink:
        def __init__(self) -> None:
            self.lines: list[tuple[str, str]] = []

        def get_effective_level(self) -> int:
            return 20  # INFO

        def debug(self, msg: str) -> None:
            self.lines.append(("debug", msg))

        def info(self, msg: str) -> None:
            self.lines.append(("info", msg))

        def warning(self, msg: str) -> None:
            self.lines.append(("warning", msg))

        def error(self, msg: str) -> None:
            self.lines.append(("error", msg))

    sink = Sink()
    original = py_trees.logging.Logger.warning
    undo = route_py_trees_logging(sink)
    try:
        logger = py_trees.logging.Logger("Leaf")
        logger.debug("hidden at INFO")
        logger.info("hello")
        logger.warning("careful")
        logger.error("broken")
    finally:
        undo()
    assert sink.lines == [("info", "Leaf: hello"), ("warning", "Leaf: careful"), ("error", "Leaf: broken")]
    assert py_trees.logging.Logger.warning is original


def test_vet_stops_anything_the_robot_may_not_do(executive: Executive) -> None:
    assert executive.vet(Command(0.1, 0.0, "x")).is_zero  # disarmed
    executive.core.request_arm(True)
    assert executive.vet(Command(0.1, 0.5, "x")) == Command(0.1, 0.5, "x")
    assert executive.vet(Command(math.nan, 0.0, "x")).is_zero
    assert executive.vet(Command(0.5, 0.0, "x")).is_zero  # beyond max_linear_speed
    assert executive.vet(Command(0.0, -3.0, "x")).is_zero  # beyond the turn rates (2.5 and 2.84 rad/s)
    assert executive.stats.vetoed == 4


def test_unconvertible_scan_is_dropped_and_counted(executive: Executive) -> None:
    executive._on_scan(SimpleNamespace(ranges=[1.0]))  # no angle fields at all
    executive._on_scan(SimpleNamespace(angle_min="x", angle_max=0.0, angle_increment=0.1, range_min=0.1,
                                       range_max=3.0, ranges=[1.0]))
    assert (executive.scans, executive.bad_scans) == (0, 2)
    assert not executive.core.board.exists("/scan") or executive.core.value("scan") is None


def test_parameter_callbacks_check_then_apply(executive: Executive) -> None:
    gate = executive.parameters
    refused = gate._on_set_parameters([Parameter("close_distance", value=0.9)])
    assert not refused.successful and "far_distance" in refused.reason
    together = [Parameter("far_distance", value=1.2), Parameter("close_distance", value=0.9)]
    assert gate._on_set_parameters(together).successful
    assert executive.core.params["close_distance"] == 0.3  # checked only: nothing applied yet
    gate._after_set_parameters(together)
    assert (executive.core.params["close_distance"], executive.core.params["far_distance"]) == (0.9, 1.2)
    assert executive.core.value("far_distance") == 1.2  # the tree sees it
    assert gate._on_set_parameters([Parameter("use_sim_time", value=True)]).successful
    assert "cannot change" in gate._on_set_parameters([Parameter("trace_path", value="/tmp/x")]).reason


@pytest.mark.parametrize(("overrides", "reason"), [
    ([Parameter("close_distance", value=0.9)], "close_distance (0.9) must be smaller than far_distance (0.7)"),
    ([Parameter("safety_distance", value=-1.0)], "safety_distance must be >= 0.05 m, got -1.0"),
    ([Parameter("maneuver", value="Z")], "unknown maneuver 'Z'"),
])
def test_start_up_values_pass_the_same_gate_as_live_changes(ros_context: Any, overrides: list[Parameter],
                                                            reason: str) -> None:
    node = Node("bt_nav_executive_gate", context=ros_context, start_parameter_services=False,
                parameter_overrides=overrides)
    try:
        with pytest.raises(ConfigError) as refused:
            Executive(node)
        assert reason in str(refused.value)
        values = {p.name: p.value for p in overrides}
        live = P.check_changes(P.defaults(), values)[1]
        assert live is not None and reason in live, "the live gate judges the same values the same way"
    finally:
        node.destroy_node()


def test_an_integer_for_a_float_is_accepted_at_start_up(ros_context: Any) -> None:
    node = Node("bt_nav_executive_int", context=ros_context, start_parameter_services=False,
                parameter_overrides=[Parameter("safety_distance", value=1), Parameter("clock_watchdog", value=2)])
    try:
        executive = Executive(node)
        assert executive.core.params["safety_distance"] == 1.0 and isinstance(executive.core.params["safety_distance"],
                                                                              float)
        assert executive.watchdog.timeout == 2.0
        executive.close()
    finally:
        node.destroy_node()


def test_an_exception_in_a_leaf_stops_the_robot_and_the_node_lives_on(executive: Executive,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    from bt_nav.mission.behaviours import DriveForward
    from bt_nav.mission.core import find_leaf
    from bt_nav.mission.scan import Scan

    def broken() -> Any:
        raise RuntimeError("sensor driver returned garbage")

    monkeypatch.setattr(find_leaf(executive.core.root, DriveForward), "update", broken)  # shadows the method
    executive.core.request_arm(True)
    executive.core.feed_scan(Scan(ranges=[3.0] * 360, angle_min=0.0, angle_max=2 * math.pi * 359 / 360,
                                  angle_increment=2 * math.pi / 360, range_min=0.12, range_max=3.5))
    executive._on_tick()
    assert executive.core.faults == 1 and executive.core.last_command.is_zero
    assert executive.stats.ticks == 1 and executive.cmd.published == 1
    monkeypatch.undo()
    executive._on_tick()
    assert executive.core.last_command.linear > 0.0  # the next tick starts afresh


# ---------------------------------------------------------------------------------------------- QoS event handlers
def _handlers(node: Node) -> dict[str, int]:
    """Topic -> how many QoS event handlers its publisher or subscription still has in the node's wait set."""
    from rclpy.event_handler import EventHandler

    listed = [w for w in node.waitables if isinstance(w, EventHandler)]
    out = {}
    for entity in (*node.publishers, *node.subscriptions):
        out[entity.topic_name] = sum(1 for h in entity.event_handlers if h in listed)
    return out


def test_the_executive_keeps_qos_warnings_only_where_a_robot_may_differ(ros_context: Any) -> None:
    """On its own QuietNode (as ``bt-nav executive`` runs it): rclpy's warnings on scan, odom and cmd_vel only."""
    from bt_nav.ros.rosutil import QuietNode

    node = QuietNode("bt_nav_executive_quiet_unit", context=ros_context, start_parameter_services=False,
                     parameter_overrides=[Parameter("use_sim_time", value=True)])
    try:
        executive = Executive(node)
        handlers = _handlers(node)
        kept = {topic for topic, n in handlers.items() if n}
        assert "/clock" in handlers and "/parameter_events" in handlers
        assert kept == {"/cmd_vel", "/scan", "/odom"}, handlers
        assert all(handlers[topic] == 2 for topic in kept)  # incompatible QoS and incompatible type
        assert node.destroy_publisher(executive.tree_publisher)
    finally:
        node.destroy_node()


def test_a_quiet_node_has_no_qos_event_handlers(ros_context: Any) -> None:
    """The judges' mixin: none on any publisher or subscription, rclpy's own /clock and /parameter_events too."""
    from std_msgs.msg import String

    from bt_nav.ros.nodes.judging import JudgeNode
    from bt_nav.ros.rosutil import QuietQosEvents

    class Quiet(QuietQosEvents, Node):
        pass

    node = Quiet("bt_nav_quiet_unit", context=ros_context, start_parameter_services=False,
                 parameter_overrides=[Parameter("use_sim_time", value=True)])
    try:
        node.create_subscription(String, "collisions", lambda msg: None, 10)
        node.create_publisher(String, "sim_sync", 10)
        handlers = _handlers(node)
        assert {"/clock", "/parameter_events", "/collisions", "/sim_sync"} <= set(handlers), handlers
        assert not any(handlers.values()), handlers
        plain = Node("bt_nav_plain_unit", context=ros_context, start_parameter_services=False)
        assert _handlers(plain)["/parameter_events"] == 2  # what the mixin leaves out
        plain.destroy_node()
    finally:
        node.destroy_node()
    assert issubclass(JudgeNode, QuietQosEvents)
