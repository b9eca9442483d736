"""What a judged robot node did wrong that the judge's checks cannot see: found on the ROS graph and on ``cmd_vel``.

The checks judge motion, so a node that never heard a scan, or that the simulator never heard, only gets
"travelled 0.00 m". :class:`GraphAudit` names the cause in words a student can act on. From the judge's
node, about once per wall second (:meth:`GraphAudit.sample`), it looks at

- every node that is not ours (ours: hidden ``_`` names and ``bt_nav_*`` names, the simulator, judges and
  recorders, except the executive, which is graded like any node): which topics it subscribes and publishes
  (with which message type), which services it offers;
- every pair of one of its endpoints and one of ours on a topic: a different message type (TwistStamped on a
  Twist ``cmd_vel``) or QoS policies that cannot match (:func:`rclpy.qos.qos_check_compatible`, e.g. a
  reliable reader of a best-effort writer, a transient-local reader of a volatile writer): either way not
  one message passes, and DDS says so only in the process that loses them;
- the robot's commands, through a best-effort reader of ``cmd_vel`` (it hears reliable and best-effort
  writers): messages holding NaN or inf are counted, and the writer's publication sequence numbers give its
  rate even when this reader cannot keep up with a flood.

:meth:`GraphAudit.findings` turns the whole run into sentences: nothing on the graph at all, no
subscription to ``scan`` or ``/clock`` (not on sim time), no publisher on ``cmd_vel``, the arm service never
offered or offered with another type, a type or QoS mismatch, non-finite commands, a flood (more than
:data:`FLOOD_RATE` commands per sim second). An absence is judged over the whole run (a node may subscribe
late); a mismatch seen once is a finding, and is logged when it is first seen. :meth:`GraphAudit.finding_records`
gives each with its kind (:mod:`bt_nav.ros.nodes.findings`), for the programs that decide on one.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from geometry_msgs.msg import Twist, TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSCompatibility, QoSProfile, ReliabilityPolicy, qos_check_compatible

from bt_nav.ros.domain_guard import DomainGuard
from bt_nav.ros.nodes.findings import (
    FLOOD,
    NO_NODE,
    NO_PUBLISHER,
    NO_SUBSCRIBER,
    NON_FINITE,
    QOS_MISMATCH,
    SERVICE,
    TYPE_MISMATCH,
    Finding,
)

#: Commands per sim second beyond any controller (bt_nav's executive sends 20, the homework's suggested 10).
FLOOD_RATE = 1000.0
#: Wall seconds between two looks at the graph.
SAMPLE_PERIOD = 1.0
#: Wall seconds after which a look reads every endpoint again though the graph's outline is unchanged (a node that
#: replaced one of its endpoints by another of the same topic between two looks).
FULL_PERIOD = 5.0
#: Names of ours start so; the executive is the graded node when bt_nav's own is graded with ``--exe``.
OUR_PREFIX = "bt_nav_"
GRADED = frozenset({"bt_nav_executive"})
#: Ours that only watch (record, view, print): a writer they cannot read still reaches the robot's world, so
#: they are no reference for the type and QoS checks (and naming one would depend on discovery order).
OBSERVERS = frozenset({"bt_nav_recorder", "bt_nav_viewer", "bt_nav_tree_watcher", "bt_nav_demo_terminal"})
TWIST, TWIST_STAMPED = "geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"
COMMAND_TYPES = {TWIST: Twist, TWIST_STAMPED: TwistStamped}
SET_BOOL = "std_srvs/srv/SetBool"
#: What the graph calls the node of an endpoint discovered before the node itself.
UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"


def is_ours(name: str) -> bool:
    """Whether a node name is one of ours (or hidden): its endpoints are the reference, not the judged."""
    return name.startswith("_") or (name.startswith(OUR_PREFIX) and name not in GRADED)


def describe_qos(qos: QoSProfile) -> str:
    """The policies that decide matching and that the graph reports (depth is not carried by discovery)."""
    return f"{qos.reliability.name.lower()}, {qos.durability.name.lower()}"


@dataclass
class CommandStats:
    """What the audit's reader heard on ``cmd_vel``: counts, and the writer's sequence numbers over time."""

    received: int = 0
    non_finite: int = 0
    first: tuple[int, float, float] | None = None  # (sequence number, sim s, wall s) of the rate's baseline
    last: tuple[int, float, float] | None = None

    def add(self, values: tuple[float, ...], seq: int | None, sim: float, wall: float) -> None:
        """One command; a sequence number that does not grow is another writer: the rate starts over."""
        self.received += 1
        if not all(math.isfinite(v) for v in values):
            self.non_finite += 1
        if seq is None:
            return
        if self.last is None or seq <= self.last[0]:
            self.first = (seq, sim, wall)
        self.last = (seq, sim, wall)

    def rates(self) -> tuple[float, float] | None:
        """(published per sim s, per wall s) since the baseline, once half a sim second has passed."""
        if self.first is None or self.last is None or self.last[1] - self.first[1] < 0.5:
            return None
        count = self.last[0] - self.first[0]
        return count / (self.last[1] - self.first[1]), count / max(1e-6, self.last[2] - self.first[2])


class GraphAudit:
    """The audit of one judged robot (see the module docstring), run from the judge's node.

    Args:
        node: the judge's node (its namespace resolves the relative names; its name is ours).
        service: the robot's arm service (SetBool), as the judge calls it.
        inputs: topics the robot must subscribe, with the message type expected there.
        command: the topic the robot must publish its commands on (Twist or TwistStamped).
    """

    def __init__(self, node: Node, service: str, inputs: tuple[tuple[str, str], ...] = (
            ("scan", "sensor_msgs/msg/LaserScan"), ("/clock", "rosgraph_msgs/msg/Clock")),
            command: str = "cmd_vel", parameters: tuple[str, ...] = (),
            now: Callable[[], float] | None = None, message_info: bool = True) -> None:
        self.node = node
        # Each command's DDS sequence number (rclpy's MessageInfo): the command rate then counts what the node sent,
        # not what reached this best-effort reader. Off: what arrived (a lower bound), for rclpy's EventsExecutor,
        # which cannot pass MessageInfo in Jazzy.
        self.message_info = message_info
        # sim seconds of a heard command (the command rate is per sim second): the node clock, or the judge's own
        self.now = now if now is not None else (lambda: node.get_clock().now().nanoseconds * 1e-9)
        self.parameters = parameters  # parameters the assignment asks the node to declare (the lab: safety_distance)
        self.declared: dict[str, set[str] | None] = {}  # foreign node -> its parameter names (None: not answered)
        self._asked: dict[str, Any] = {}  # foreign node -> the pending ListParameters future
        self._clients: dict[str, Any] = {}  # foreign node -> its list_parameters client (one, kept until answered)
        self.values: dict[str, dict[str, Any]] = {}  # foreign node -> its parameters' values (GetParameters)
        self._getting: dict[str, tuple[Any, Any, list[str]]] = {}  # foreign node -> (client, future, names asked)
        self.service = node.resolve_service_name(service)
        self.inputs = tuple((node.resolve_topic_name(topic), kind) for topic, kind in inputs)
        self.command = node.resolve_topic_name(command)
        self.nodes: set[str] = set()  # foreign nodes ever seen
        self.subscribed: dict[str, set[str]] = {}  # topic -> message types foreign nodes subscribe it with
        self.published: dict[str, set[str]] = {}
        self.offered: dict[str, set[str]] = {}  # service -> types foreign nodes offer it with
        self.problems: dict[str, Finding] = {}  # mismatches seen, by what they concern (logged when first seen)
        self.commands = CommandStats()
        self._reader: Any = None
        self._reader_failed = False
        self._last = -math.inf
        self._outline: tuple[Any, ...] | None = None  # the graph's outline when its endpoints were last read
        self._read_at = -math.inf  # ... and when
        self._unnamed = False  # that read met an endpoint whose node had no name yet
        self.guard = DomainGuard()  # every endpoint's process: the run's own, or another program's

    # -------------------------------------------------------------- sampling
    def sample(self, force: bool = False) -> None:
        """Look at the graph (at most once per :data:`SAMPLE_PERIOD` wall s unless ``force``); its endpoints are read
        when its outline changed (or an endpoint had no node name yet, or :data:`FULL_PERIOD` passed, or ``force``)."""
        now = time.monotonic()
        if not force and now - self._last < SAMPLE_PERIOD:
            return
        self._last = now
        try:
            nodes = tuple(self.node.get_node_names_and_namespaces())
            self._sample_nodes(nodes)
            outline = self._graph_outline(nodes)
            if force or outline != self._outline or self._unnamed or now - self._read_at >= FULL_PERIOD:
                self._sample_topics([topic for topic, *_ in outline[0]])
                self._outline, self._read_at = outline, now
            self._watch_commands()
        except Exception as exc:  # the graph changing under a query (a node leaving), or rclpy shutting down
            self.node.get_logger().debug(f"graph audit skipped a sample: {exc!r}")

    def _sample_nodes(self, nodes: tuple[tuple[str, str], ...]) -> None:
        for name, namespace in nodes:
            if is_ours(name):
                continue
            full = f"{namespace.rstrip('/')}/{name}"
            self.nodes.add(full)
            for service, types in self.node.get_service_names_and_types_by_node(name, namespace):
                self.offered.setdefault(service, set()).update(types)
            if self.parameters:
                self._ask_parameters(full)

    def _ask_parameters(self, full: str) -> None:
        """Ask a foreign node once for its parameter names (``ros2 param list``, the check-off's step 2); the answer
        arrives on the judge's executor and is read by :meth:`findings`."""
        from rcl_interfaces.srv import ListParameters

        future = self._asked.get(full)
        if future is None:
            # One client per node, kept until it is ready: one made at every sample while the node's service was
            # not up yet would stay in the judge's wait set (each wake-up of its executor walks them all)
            client = self._clients.get(full)
            if client is None:
                client = self._clients[full] = self.node.create_client(ListParameters, f"{full}/list_parameters")
            if client.service_is_ready():
                self._asked[full] = client.call_async(ListParameters.Request())
                self.declared[full] = None
        elif future.done() and self.declared.get(full) is None:
            result = future.result()
            self.declared[full] = set(result.result.names) if result is not None else set()
        elif future.done():
            self._ask_values(full)

    def _ask_values(self, full: str) -> None:
        """Ask a foreign node once for the values of the parameters it listed (``ros2 param get``): what the grade
        compares with what it passed (``-p NAME:=VALUE``), to say whether each was applied."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python

        names = sorted(self.declared.get(full) or ())
        if not names or full in self.values:
            return
        asked = self._getting.get(full)
        if asked is None:
            client = self.node.create_client(GetParameters, f"{full}/get_parameters")
            self._getting[full] = (client, None, names)
            asked = self._getting[full]
        client, future, names = asked
        if future is None:
            if client.service_is_ready():
                self._getting[full] = (client, client.call_async(GetParameters.Request(names=names)), names)
        elif future.done():
            result = future.result()
            values = list(result.values) if result is not None else []
            self.values[full] = {name: parameter_value_to_python(value) for name, value in zip(names, values,
                                                                                                 strict=False)}

    def _graph_outline(self, nodes: tuple[tuple[str, str], ...]) -> tuple[Any, ...]:
        """What changes when an endpoint comes or goes: each topic with its types and its writer and reader counts, and
        the nodes. Cheap queries; reading every endpoint's info (:meth:`_sample_topics`) cost ~9 ms a look, a tenth of
        a CPU second a graded run (measured), so it is read again only when the outline changed."""
        node = self.node
        topics = tuple((topic, tuple(types), node.count_publishers(topic), node.count_subscribers(topic))
                       for topic, types in node.get_topic_names_and_types())
        return topics, nodes

    def _sample_topics(self, topics: list[str]) -> None:
        self._unnamed = False
        for topic in topics:
            publishers = self.node.get_publishers_info_by_topic(topic)
            subscriptions = self.node.get_subscriptions_info_by_topic(topic)
            for endpoint in (*publishers, *subscriptions):
                self.guard.see(endpoint)
                self._unnamed = self._unnamed or endpoint.node_name == UNKNOWN_NODE
            # An endpoint discovered before its node's name is nobody's yet: the next sample names it.
            publishers = [e for e in publishers if e.node_name != UNKNOWN_NODE]
            subscriptions = [e for e in subscriptions if e.node_name != UNKNOWN_NODE]
            theirs_pub = [e for e in publishers if not is_ours(e.node_name)]
            theirs_sub = [e for e in subscriptions if not is_ours(e.node_name)]
            for endpoint in theirs_pub:
                self.published.setdefault(topic, set()).add(endpoint.topic_type)
            for endpoint in theirs_sub:
                self.subscribed.setdefault(topic, set()).add(endpoint.topic_type)
            ours_pub = [e for e in publishers if is_ours(e.node_name) and e.node_name not in OBSERVERS]
            ours_sub = [e for e in subscriptions if is_ours(e.node_name) and e.node_name not in OBSERVERS]
            for theirs in theirs_sub:
                for ours in ours_pub:
                    self._check_pair(topic, ours, theirs, theirs_publish=False)
            for theirs in theirs_pub:
                for ours in ours_sub:
                    self._check_pair(topic, theirs, ours, theirs_publish=True)

    def _check_pair(self, topic: str, publisher: Any, subscription: Any, theirs_publish: bool) -> None:
        """A finding when a writer and a reader of one topic, one theirs and one ours, can never match."""
        theirs, ours = (publisher, subscription) if theirs_publish else (subscription, publisher)
        verb, our_verb = ("publishes", "reads") if theirs_publish else ("subscribes to", "publishes")
        who = theirs.node_name
        if publisher.topic_type != subscription.topic_type:
            key = f"type {topic} {who} {theirs.topic_type}"
            clause = f"{who} {verb} {topic} as {theirs.topic_type}, but {ours.node_name} {our_verb} {ours.topic_type}"
            found = Finding(TYPE_MISMATCH, f"{clause}: not one message passes", topic, clause)
        else:
            compatibility, reason = qos_check_compatible(publisher.qos_profile, subscription.qos_profile)
            if compatibility != QoSCompatibility.ERROR:
                return
            key = f"qos {topic} {who} {describe_qos(theirs.qos_profile)}"
            clause = f"incompatible QoS on {topic}"
            found = Finding(QOS_MISMATCH, f"{clause}: {who} {verb} it {describe_qos(theirs.qos_profile)}, "
                            f"{ours.node_name} {our_verb} it {describe_qos(ours.qos_profile)} "
                            f"({reason.removeprefix('ERROR: ').rstrip(';')}): not one message passes", topic, clause)
        if key not in self.problems:
            self.problems[key] = found
            self.node.get_logger().warning(f"finding: {found.text}")

    def _watch_commands(self) -> None:
        """Read ``cmd_vel`` best effort (every writer matches) once a foreign node publishes a command type there."""
        if self._reader is not None or self._reader_failed:
            return
        kinds = sorted(self.published.get(self.command, set()) & set(COMMAND_TYPES))
        if not kinds:
            return
        stamped = kinds[0] == TWIST_STAMPED
        if self.message_info:
            def read(msg: Any, info: Any) -> None:
                seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
                self._on_command(msg.twist if stamped else msg, seq)
        else:
            def read(msg: Any) -> None:  # type: ignore[misc]
                self._on_command(msg.twist if stamped else msg, self.commands.received)  # what arrived, in order
        try:
            self._reader = self.node.create_subscription(
                COMMAND_TYPES[kinds[0]], self.command, read,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT))
        except Exception as exc:  # this process already uses cmd_vel with the other type: DDS refuses a second
            self._reader_failed = True
            self.node.get_logger().warning(f"graph audit: cannot read {self.command} as {kinds[0]}: {exc}")

    @property
    def hears_commands(self) -> bool:
        """Whether the audit's own ``cmd_vel`` reader exists (a foreign command publisher was seen)."""
        return self._reader is not None

    def _on_command(self, twist: Any, seq: int | None) -> None:
        """One command heard, with the writer's sequence number (or this reader's count of arrivals)."""
        values = (twist.linear.x, twist.linear.y, twist.linear.z, twist.angular.x, twist.angular.y, twist.angular.z)
        self.commands.add(values, seq, self.now(), time.monotonic())

    # -------------------------------------------------------------- findings
    def service_hint(self) -> str:
        """What the foreign nodes offer instead of the arm service (`` (...)``), or ""."""
        types = self.offered.get(self.service)
        if types:
            return f" (offered as {', '.join(sorted(types))}, not {SET_BOOL})" if SET_BOOL not in types else ""
        others = sorted(name for name, kinds in self.offered.items() if SET_BOOL in kinds)
        return f" (the node offers {SET_BOOL} as {', '.join(others)})" if others else ""

    def findings(self, exclude: tuple[str, ...] = ()) -> list[str]:
        """Everything found over the run, in words, after a last look (``exclude``: ``service`` when said
        elsewhere): the sentences of :meth:`finding_records`."""
        return [found.text for found in self.finding_records(exclude)]

    def finding_records(self, exclude: tuple[str, ...] = ()) -> list[Finding]:
        """Everything found over the run with its kind, after a last look (``exclude`` as :meth:`findings`)."""
        self.sample(force=True)
        if not self.nodes:
            return [Finding(NO_NODE, "no node besides the simulator and the judge ever appeared on the ROS graph (did "
                                     "the command start a ROS 2 node in this ROS_DOMAIN_ID?)")]
        found = [self._missing_input(topic, kind) for topic, kind in self.inputs if topic not in self.subscribed]
        if self.command not in self.published:
            found.append(Finding(NO_PUBLISHER, f"no node published on {self.command}" + self._elsewhere(
                self.published, set(COMMAND_TYPES), "publishes"), self.command))
        if "service" not in exclude and SET_BOOL not in self.offered.get(self.service, set()):
            found.append(Finding(SERVICE, f"the service {self.service} " + (
                f"was offered as {', '.join(sorted(self.offered[self.service]))}, not {SET_BOOL}"
                if self.service in self.offered else f"was never offered{self.service_hint()}"), self.service))
        found += list(self.problems.values())
        found += self._command_findings()
        return found

    def parameter_findings(self) -> list[str]:
        """A parameter the assignment asks for that no judged node declares (only nodes that answered count): a
        failed check of the verdict, not only a finding (the check-off's ``ros2 param list`` step)."""
        self.sample(force=True)
        answered = {node: names for node, names in self.declared.items() if names is not None}
        if not answered:
            return []
        return [f"no node declares the parameter {name} (ros2 param list on {', '.join(sorted(answered))} does not "
                f"show it; the lab's launch file must pass it)" for name in self.parameters
                if not any(name in names for names in answered.values())]

    def parameter_report(self) -> list[dict[str, Any]]:
        """Every judged node that answered ``ros2 param list``: its name, the names it lists and (once it answered
        ``ros2 param get``) their values, JSON-able (what a grade shows and compares with what it passed)."""
        self.sample(force=True)
        return [{"node": node, "names": sorted(names),
                 "values": {k: _plain(v) for k, v in self.values.get(node, {}).items()}}
                for node, names in sorted(self.declared.items()) if names is not None]

    def _missing_input(self, topic: str, kind: str) -> Finding:
        hint = self._elsewhere(self.subscribed, {kind}, "subscribes")
        clause = f"no node subscribed to {topic}"
        if topic.endswith("/clock"):
            return Finding(NO_SUBSCRIBER, f"{clause}: the node does not run on sim time (use_sim_time:=true was "
                           f"given with --ros-args; does it pass its arguments to rclpy.init?){hint}", topic, clause)
        return Finding(NO_SUBSCRIBER, f"{clause}: the node never received one message from it{hint}", topic, clause)

    @staticmethod
    def _elsewhere(endpoints: dict[str, set[str]], kinds: set[str], verb: str) -> str:
        """`` (it <verb> <type> on <topics>)`` for foreign endpoints of the wanted types on other topics."""
        seen = [f"{', '.join(sorted(types & kinds))} on {topic}" for topic, types in sorted(endpoints.items())
                if types & kinds]
        return f" (it {verb} {'; '.join(seen)})" if seen else ""

    def _command_findings(self) -> list[Finding]:
        stats = self.commands
        found = []
        if stats.non_finite:
            found.append(Finding(NON_FINITE, f"{stats.non_finite} of {stats.received} cmd_vel messages held NaN or "
                                 "inf values (the simulator takes them as a stop)", self.command))
        rates = stats.rates()
        if rates is not None and rates[0] > FLOOD_RATE:
            found.append(Finding(FLOOD, f"cmd_vel flood: {rates[0]:.0f} messages per sim s ({rates[1]:.0f} per wall "
                                 "s); a controller sends 10 to 50", self.command))
        return found


def _plain(value: Any) -> Any:
    """A parameter's value as JSON holds it (arrays as lists, bytes as integers)."""
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, bytes):
        return list(value)
    return value if value is None or isinstance(value, bool | int | float | str) else str(value)
