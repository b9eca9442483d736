"""Tap the live ROS graph for recorders and viewers: raw (CDR) subscriptions to topics found by discovery.

Shared by ``bt-nav record`` (hands every message to :meth:`bt_nav.media.bag.MissionBag.write_raw`) and
``bt-nav view`` (decodes them with rosbags' typestore, as the bag reader does, so the live page and a
bag's playback run one code path).

- Types come from the graph (``get_topic_names_and_types``), looked up again every half second, so a
  topic that appears late (the referee's, the executive's tree) is subscribed when it shows up.
- Each subscription takes the publishers' QoS (best effort if one offers only that, transient local if
  all keep history), and that offered QoS goes with each message, for the bag's metadata.
- Time is sim time: the latest ``/clock`` (wall time until a clock runs), as ``ros2 bag record
  --use-sim-time`` stamps messages.
- ``/rosout`` lines of the bt_nav nodes become mission events (``[INFO] text``), the form lock-step
  writes on ``/bt_nav/events``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

#: (topic, msgtype "pkg/msg/Name", sim time ns, CDR bytes, offered QoS as a rosbags Qos or None)
Handler = Callable[[str, str, int, bytes, Any], None]
_LEVELS = {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "FATAL"}
EXECUTIVE_NODE = "bt_nav_executive"


def rosbags_qos(profile: Any) -> Any:
    """An rclpy QoS profile (as discovery reports it) as rosbags' ``Qos`` for ``offered_qos_profiles``."""
    from bt_nav.media.bag import TopicSpec, qos_of

    return qos_of(TopicSpec("", reliable=profile.reliability == ReliabilityPolicy.RELIABLE,
                            transient_local=profile.durability == DurabilityPolicy.TRANSIENT_LOCAL,
                            depth=max(1, int(profile.depth or 10))))


def get_message(msgtype: str) -> Any:
    """The rclpy message class of ``pkg/msg/Name`` (what rosidl_runtime_py does, which pip installs lack)."""
    import importlib

    package, kind, name = msgtype.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def event_text(name: str, level: int, msg: str) -> str:
    """A /rosout line as a mission event: ``[INFO] text`` for the executive, ``[INFO] referee: text`` else."""
    who = "" if name == EXECUTIVE_NODE else name.removeprefix("bt_nav_") + ": "
    return f"[{_LEVELS.get(level, str(level))}] {who}{msg}"


class GraphTap:
    """Subscribe ``node`` to ``topics`` (absolute names) as they appear; every message goes to ``handler``.

    Args:
        node: an rclpy node (its executor must spin; callbacks run there).
        topics: the topics to tap; "/rosout" is turned into events (``events_topic``) instead.
        handler: called with (topic, msgtype, t_ns, cdr, qos) for each message.
        events_topic: where /rosout lines of ``bt_nav*`` nodes go (as std_msgs/String CDR).
        sim_time: stamp messages before the first /clock with 0 (False: with wall time, for a graph
            without a simulator).
    """

    def __init__(self, node: Any, topics: Iterable[str], handler: Handler, events_topic: str = "/bt_nav/events",
                 sim_time: bool = True) -> None:
        from rclpy.serialization import serialize_message
        from std_msgs.msg import String

        self.node, self.handler, self.events_topic = node, handler, events_topic
        self.wanted = {t if t.startswith("/") else "/" + t for t in topics}
        self.subscribed: dict[str, str] = {}
        self.clock_ns: int | None = None
        self._serialize, self._String = serialize_message, String
        self.sim_time = sim_time
        self._clock_sub()
        if "/rosout" in self.wanted:
            self._rosout_sub()
        self._discover()
        node.create_timer(0.5, self._discover)

    def now_ns(self) -> int:
        """Sim time of the latest /clock (before the first: 0, or wall time when not ``sim_time``)."""
        if self.clock_ns is not None:
            return self.clock_ns
        return 0 if self.sim_time else time.time_ns()

    def _clock_sub(self) -> None:
        from rosgraph_msgs.msg import Clock

        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)

        def on_clock(msg: Any) -> None:
            self.clock_ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec

        self.node.create_subscription(Clock, "/clock", on_clock, qos)

    def _rosout_sub(self) -> None:
        from rcl_interfaces.msg import Log

        def on_log(msg: Any) -> None:
            if msg.name.startswith("bt_nav") and msg.level >= 20:
                data = self._serialize(self._String(data=event_text(msg.name, msg.level, msg.msg)))
                self.handler(self.events_topic, "std_msgs/msg/String", self.now_ns(), data, None)

        self.subscribed["/rosout"] = "rcl_interfaces/msg/Log"
        self.node.create_subscription(Log, "/rosout", on_log, QoSProfile(depth=100))

    def _discover(self) -> None:
        for topic, types in self.node.get_topic_names_and_types():
            if topic not in self.wanted or topic in self.subscribed or not types:
                continue
            msgtype = types[0]
            infos = self.node.get_publishers_info_by_topic(topic)
            if not infos:
                continue
            qos = self._subscription_qos([i.qos_profile for i in infos])
            offered = rosbags_qos(infos[0].qos_profile)
            try:
                cls = get_message(msgtype)
            except (AttributeError, ImportError, ValueError) as exc:
                self.node.get_logger().warning(f"cannot tap {topic} ({msgtype}): {exc}")
                self.subscribed[topic] = msgtype
                continue
            self.node.create_subscription(cls, topic, self._callback(topic, msgtype, offered), qos, raw=True)
            self.subscribed[topic] = msgtype

    @staticmethod
    def _subscription_qos(offered: list[Any]) -> QoSProfile:
        best_effort = any(q.reliability == ReliabilityPolicy.BEST_EFFORT for q in offered)
        latched = all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL for q in offered)
        return QoSProfile(depth=100,
                          reliability=ReliabilityPolicy.BEST_EFFORT if best_effort else ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)

    def _callback(self, topic: str, msgtype: str, offered: Any) -> Callable[[bytes], None]:
        def on_message(data: bytes) -> None:
            self.handler(topic, msgtype, self.now_ns(), bytes(data), offered)

        return on_message
