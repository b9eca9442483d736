"""Tap the live ROS graph for recorders and viewers: raw (CDR) subscriptions to topics found by discovery.

Shared by ``bt-nav record`` (hands every message to :meth:`bt_nav.media.bag.MissionBag.write_raw`) and
``bt-nav view`` (decodes them with rosbags' typestore, as the bag reader does, so the live page and a
bag's playback run one code path).

- Types come from the graph (``get_topic_names_and_types``), looked up again every half second, so a
  topic that appears late (the referee's, the executive's tree) is subscribed when it shows up.
- Each subscription takes the publishers' QoS (best effort if one offers only that, transient local if
  all keep history), and that offered QoS goes with each message, for the bag's metadata.
- Time is sim time *at the source* (:meth:`GraphTap.source_ns`): a message's header stamp where its type has
  one (ground truth, odometry, scans), else the sim time when it was sent (its DDS source timestamp mapped by
  :class:`bt_nav.ros.simclock.SimClock` from ``/clock``: commands, the tree, strings), and for a ``/rosout``
  line the sim time of its log call. Not the latest ``/clock`` on arrival, which ``ros2 bag record
  --use-sim-time`` takes: a recorder that falls behind (2.8 s of sim time at 11x, measured) would draw a turn
  late and then snap it. Without a ``/clock`` (``sim_time`` off) times are wall times.
- With ``sim_time``, what arrives before the first ``/clock`` (discovery can join the tap to the node before the
  simulator: 10 sim s at 20x on a loaded machine) waits and is handed on once that clock comes, timed against
  it, instead of at sim time 0. A graph with no ``/clock`` at all (:data:`EARLY_WAIT` wall s of messages without
  one) gets them at once, stamped 0 as before: a live view must not stay blank.
- ``/rosout`` lines of the graph's nodes (the robot node's too, whatever its name; not this recorder's own)
  become mission events (``[INFO] text``), the form lock-step writes on ``/bt_nav/events``.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from bt_nav.ros.simclock import SimClock

#: (topic, msgtype "pkg/msg/Name", sim time ns, CDR bytes, offered QoS as a rosbags Qos or None)
Handler = Callable[[str, str, int, bytes, Any], None]
_LEVELS = {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "FATAL"}
EXECUTIVE_NODE = "bt_nav_executive"
EARLY_MAX = 10_000  # messages kept while waiting for the first /clock (the oldest go beyond)
EARLY_WAIT = 3.0  # wall s of messages without any /clock after which the graph is taken to have none


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


#: /rosout lines not turned into events: the recording and viewing nodes' own.
OWN_NODES = ("bt_nav_recorder", "bt_nav_view", "bt_nav_demo")


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
        message_info: take each sample's DDS source timestamp (rclpy's MessageInfo). False for rclpy's
            ``EventsExecutor``, which fails on such callbacks in Jazzy (``SystemError: null argument to internal
            routine``, tried here): then /clock is mapped by its arrival (best effort, depth 1: the freshest
            sample) and a message without a stamp of its own gets the newest /clock on arrival.
    """

    def __init__(self, node: Any, topics: Iterable[str], handler: Handler, events_topic: str = "/bt_nav/events",
                 sim_time: bool = True, message_info: bool = True) -> None:
        from rclpy.serialization import serialize_message
        from std_msgs.msg import String

        self.node, self.handler, self.events_topic = node, handler, events_topic
        self.wanted = {t if t.startswith("/") else "/" + t for t in topics}
        self.subscribed: dict[str, str] = {}
        self.clock_ns: int | None = None
        self.clock = SimClock()
        self.first_clock: tuple[int, int] | None = None  # (wall ns, sim ns) of the first /clock seen
        self._serialize, self._String = serialize_message, String
        self.sim_time = sim_time
        self.message_info = message_info
        # what arrived before the first /clock (sim_time only): each a call that hands it on, timed when it runs
        self._early: deque[Callable[[], None]] | None = deque(maxlen=EARLY_MAX) if sim_time else None
        self._early_lock = threading.Lock()
        self._early_since: float | None = None  # monotonic s of the first message held
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

    def source_ns(self, msgtype: str, data: bytes, info: Any = None) -> int:
        """The sim time of a message at its source (see the module docstring): its own stamp when it is on the
        graph's clock (:func:`bt_nav.media.bag.message_time_ns`), else the sim time at its DDS source timestamp,
        else the newest /clock."""
        from bt_nav.media.bag import message_time_ns, own_stamp_ns

        sent = self.sent_ns(info.get("source_timestamp") if isinstance(info, dict) else None)
        return message_time_ns(own_stamp_ns(msgtype, data), sent)

    def sent_ns(self, wall_ns: int | None) -> int:
        """Sim time at wall instant ``wall_ns`` (a DDS source timestamp, a log call's stamp); the newest /clock
        when it cannot be mapped (no ``wall_ns``, or older than the map); wall time itself without a clock."""
        if wall_ns:
            if self.clock_ns is None and not self.sim_time:
                return int(wall_ns)
            sim = self.clock.sim_at(int(wall_ns))
            if sim is not None:
                return sim
            if self.first_clock is not None and wall_ns < self.first_clock[0]:
                return self.first_clock[1]  # before the first /clock seen (a log line's history): not the newest
        return self.now_ns()

    def _clock_sub(self) -> None:
        from rosgraph_msgs.msg import Clock

        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)

        def on_clock(msg: Any, info: Any) -> None:  # two parameters: rclpy passes the MessageInfo
            self.clock_ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
            sent = info.get("source_timestamp") if isinstance(info, dict) else None
            self.clock.add(sent or time.time_ns(), self.clock_ns)
            if self.first_clock is None:
                self.first_clock = (sent or time.time_ns(), self.clock_ns)
                self._release_early()

        self.node.create_subscription(Clock, "/clock", self._with_info(on_clock), qos)

    def _deliver(self, hand_on: Callable[[], None]) -> None:
        """Run ``hand_on`` now, or (sim time, no /clock yet) once the first /clock has come."""
        if self._early is not None:
            with self._early_lock:
                if self._early is not None:
                    self._early.append(hand_on)
                    self._early_since = self._early_since or time.monotonic()
                    if time.monotonic() - self._early_since < EARLY_WAIT:
                        return
            self.node.get_logger().warning(f"no /clock after {EARLY_WAIT:g} s of messages: times are 0 until one "
                                           "comes (a graph without a simulator wants wall time)")
            self._release_early()
            return
        hand_on()

    def _release_early(self) -> None:
        with self._early_lock:
            early, self._early = self._early, None
        for hand_on in early or ():
            hand_on()

    def _rosout_sub(self) -> None:
        from rcl_interfaces.msg import Log

        def on_log(msg: Any, info: Any) -> None:
            if msg.level >= 20 and not msg.name.startswith(OWN_NODES):
                data = self._serialize(self._String(data=event_text(msg.name, msg.level, msg.msg)))
                wall = msg.stamp.sec * 1_000_000_000 + msg.stamp.nanosec  # the log call's wall time
                self._deliver(lambda: self.handler(self.events_topic, "std_msgs/msg/String", self.sent_ns(wall),
                                                   data, None))

        self.subscribed["/rosout"] = "rcl_interfaces/msg/Log"
        # transient local, as Jazzy's /rosout publishers offer it: a node's lines logged before this recorder found it
        # (its start-up line) come as history
        qos = QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Log, "/rosout", self._with_info(on_log), qos)

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
            self.node.create_subscription(cls, topic, self._with_info(self._callback(topic, msgtype, offered)), qos,
                                          raw=True)
            self.subscribed[topic] = msgtype

    @staticmethod
    def _subscription_qos(offered: list[Any]) -> QoSProfile:
        best_effort = any(q.reliability == ReliabilityPolicy.BEST_EFFORT for q in offered)
        latched = all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL for q in offered)
        return QoSProfile(depth=100,
                          reliability=ReliabilityPolicy.BEST_EFFORT if best_effort else ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)

    def _with_info(self, callback: Callable[[Any, Any], None]) -> Callable[..., None]:
        """``callback(msg, info)`` as rclpy must call it: with the MessageInfo, or (``message_info`` off) without."""
        if self.message_info:
            return callback
        return lambda msg: callback(msg, None)

    def _callback(self, topic: str, msgtype: str, offered: Any) -> Callable[[bytes, Any], None]:
        def on_message(data: bytes, info: Any) -> None:
            raw = bytes(data)
            self._deliver(lambda: self.handler(topic, msgtype, self.source_ns(msgtype, raw, info), raw, offered))

        return on_message
