"""A mission as a rosbag2 bag (MCAP storage), written through the maintained ``rosbags`` library.

Why rosbags: it writes real rosbag2 directories (``metadata.yaml``, an ``.mcap`` file with ``ros2msg``
schemas, CDR payloads and the offered QoS profiles) without a ROS install, so ``ros2 bag info/play``,
Foxglove and PlotJuggler open what lock-step writes in-process and what ``bt-nav record`` writes from
DDS. Nothing here encodes MCAP or CDR by hand, and nothing imports rclpy.

Every message is a standard ROS 2 type (:data:`TOPICS`). Timestamps are sim time in nanoseconds, and a
message's bag time is its time *at the source*: its header stamp where the type has one (lock-step writes the
two equal; ``bt-nav record`` takes the stamp, :func:`message_time_ns`), else the sim time at which it was sent
(:mod:`bt_nav.ros.simclock`), never the time a busy recorder got round to it. So a lock-step bag and a DDS
bag of the same mission look alike, and a turn recorded at 20x real time is seen turning.

How lock-step uses it (``bt-nav lockstep --bag DIR``): :class:`MissionBag` satisfies
:class:`bt_nav.run.sinks.MissionSink`, so pass it as ``sink``::

    with MissionBag(path, mission={"world": ..., "maneuver": ..., "seed": ..., "profile": ...}) as bag:
        result = run_mission(..., sink=bag)
        bag.event(result.sim_time, f"verdict: {'PASSED' if result.passed else 'FAILED'}")

``scan(t, Scan)``, ``odom(t, x, y, yaw, v, w)``, ``ground_truth(t, ...)``, ``cmd(t, v, w)``,
``clock(t)``, ``tree(t, snapshot)`` (a :mod:`bt_nav.mission.snapshot` document; the engine sends one when a
status or the tip changes, as the executive publishes ``~/tree``), ``announce(t, event)`` (the tree's events, as
``~/events``) and ``event(t, text)`` take sim seconds. ``close()`` writes ``metadata.yaml``;
a writer killed before that leaves an ``.mcap`` that :func:`bt_nav.media.bagread.read_bag` still reads
up to the last chunk written (:meth:`MissionBag.flush` closes a chunk early; the bag does so every
``flush_every`` sim seconds, and ``bt-nav record`` also every wall second).

Several robots in one bag (``bt-nav lockstep --robots N --bag DIR``): :meth:`MissionBag.robot` gives a sink
that writes the same messages into the same bag under the robot's namespace (``/robot1/scan``,
``/robot1/bt_nav_executive/tree``, ``/robot1/bt_nav_executive/events``, ``/robot1/bt_nav/events``, ...), as the
namespaced executives publish them on the DDS graph. /clock and /bt_nav/mission stay at the root, one per bag:
a robot's sink does not write /clock (the multi-robot runner writes it once per instant on the bag itself). A bag
without robot sinks has exactly the topics it always had. :func:`split_namespace` undoes the prefix when reading.
"""

from __future__ import annotations

import copy
import json
import math
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim.walkers import walkers_message

from bt_nav.mission.snapshot import snapshot_json

#: Topic names (absolute, as the default bringup publishes them).
CLOCK, SCAN, ODOM, TRUTH, CMD = "/clock", "/scan", "/odom", "/ground_truth_odom", "/cmd_vel"
TREE, EVENTS, MISSION, COLLISIONS, ROSOUT = ("/bt_nav_executive/tree", "/bt_nav/events", "/bt_nav/mission",
                                             "/collisions", "/rosout")
ANNOUNCEMENTS = "/bt_nav_executive/events"  # the executive's ``~/events``: its leaves' events as JSON (fields)
WALKERS = "/walkers"  # the simulator's people walking (JSON {"t", "circles"}), in worlds that have them
#: The file in a bag's directory that says when each topic's first message arrived: ``{topic: sim s}``, written by
#: its recorder as it happens (:mod:`bt_nav.run.bagrecorder`, :mod:`bt_nav.ros.nodes.hosted_bag`).
FIRST_MESSAGES = "first_messages.json"


def write_first_messages(bag: Path, first: dict[str, float]) -> None:
    """Rewrite :data:`FIRST_MESSAGES` in the bag directory ``bag`` whole; a file that cannot be written is skipped: the
    bag matters more than its note."""
    from bt_nav.mission.resources import written_whole

    try:
        with written_whole(Path(bag) / FIRST_MESSAGES) as stream:
            json.dump(first, stream)
    except OSError:
        pass


@dataclass(frozen=True)
class TopicSpec:
    """Type and offered QoS of one topic (QoS as the publishing node offers it)."""

    msgtype: str
    reliable: bool = True
    transient_local: bool = False
    depth: int = 10


#: What a mission bag holds. /bt_nav/events are the mission's log lines (arm call and reply, maneuver
#: start/end, deadline, evaluation, verdict); /bt_nav/mission is JSON about the run (world, seed, ...).
TOPICS: dict[str, TopicSpec] = {
    CLOCK: TopicSpec("rosgraph_msgs/msg/Clock", reliable=False, depth=1),
    SCAN: TopicSpec("sensor_msgs/msg/LaserScan", reliable=False, depth=5),
    ODOM: TopicSpec("nav_msgs/msg/Odometry"),
    TRUTH: TopicSpec("nav_msgs/msg/Odometry", depth=100),
    CMD: TopicSpec("geometry_msgs/msg/Twist"),
    TREE: TopicSpec("std_msgs/msg/String", transient_local=True, depth=1),
    ANNOUNCEMENTS: TopicSpec("std_msgs/msg/String", transient_local=True, depth=100),
    EVENTS: TopicSpec("std_msgs/msg/String", depth=100),
    MISSION: TopicSpec("std_msgs/msg/String", transient_local=True, depth=1),
    COLLISIONS: TopicSpec("std_msgs/msg/String", depth=50),
    WALKERS: TopicSpec("std_msgs/msg/String", depth=100),
}


#: Topics a robot publishes in its namespace (the others, /clock and /bt_nav/mission, exist once per bag).
ROBOT_TOPICS: tuple[str, ...] = (SCAN, ODOM, TRUTH, CMD, TREE, ANNOUNCEMENTS, EVENTS, COLLISIONS, WALKERS)


def split_namespace(topic: str) -> tuple[str, str]:
    """``/robot1/scan`` -> (``/robot1``, ``/scan``); a root or unknown topic -> ("", topic).

    Why by suffix: a robot's topic is one of :data:`ROBOT_TOPICS` behind its namespace, and the
    namespace may itself have several levels (``/fleet/robot1``).
    """
    for base in ROBOT_TOPICS:
        if topic.endswith(base) and len(topic) > len(base) + 1 and topic.startswith("/"):
            return topic[:-len(base)], base
    return "", topic


#: Sim seconds a message's own stamp may lie before the time it got into the bag (a recorder's backlog: up to
#: 2.8 s measured at 11x) and after it (clocks of two processes), and still be taken as its time. Outside, the
#: stamp is on another clock (a node stamping with wall time in a sim-time graph) and the bag's time stands.
STAMP_MAX_AGE, STAMP_MAX_LEAD = 60.0, 1.0
_STAMPED: dict[str, bool] = {}


def own_stamp_ns(msgtype: str, cdr: bytes) -> int | None:
    """The stamp a message carries, read from its CDR bytes: a ``std_msgs/Header`` or a ``Clock``'s time as its
    first field (Odometry, LaserScan, TwistStamped, Clock); None for a type without one or a stamp of 0.

    Why from the bytes: the first field of such a message is a builtin_interfaces/Time (int32 sec, uint32
    nanosec) right after CDR's 4-byte encapsulation header, whose second byte says the byte order; the
    recorder needs it for every message and must not deserialise them all. ``rcl_interfaces/Log``'s stamp is
    left out: it is the log call's wall time (see :mod:`bt_nav.ros.simclock`), not the graph's clock.
    """
    stamped = _STAMPED.get(msgtype)
    if stamped is None:
        try:
            fields = typestore().fielddefs[msgtype][1]
        except KeyError:
            fields = []
        first = fields[0][1][1] if fields else ""
        stamped = _STAMPED[msgtype] = first == "std_msgs/msg/Header" or msgtype == "rosgraph_msgs/msg/Clock"
    if not stamped or len(cdr) < 12:
        return None
    sec, nanosec = struct.unpack_from("<iI" if cdr[1] == 1 else ">iI", cdr, 4)
    ns = sec * 1_000_000_000 + nanosec
    return ns if ns > 0 else None


def message_time_ns(stamp_ns: int | None, bag_ns: int) -> int:
    """A message's time: its own stamp when it has one on the bag's clock (within :data:`STAMP_MAX_AGE` before
    and :data:`STAMP_MAX_LEAD` after ``bag_ns``), else ``bag_ns``. The one rule of the recorder and the reader."""
    if stamp_ns is not None and bag_ns - to_ns(STAMP_MAX_AGE) <= stamp_ns <= bag_ns + to_ns(STAMP_MAX_LEAD):
        return stamp_ns
    return bag_ns


class BagError(RuntimeError):
    """A bag that cannot be written or read; the message names the file."""


_TYPESTORE: Any = None


def typestore() -> Any:
    """The ROS 2 Jazzy message types of ``rosbags`` (built once: it is not free)."""
    global _TYPESTORE
    if _TYPESTORE is None:
        from rosbags.typesys import Stores, get_typestore

        _TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
    return _TYPESTORE


def qos_of(spec: TopicSpec) -> Any:
    """The rosbags ``Qos`` record of a :class:`TopicSpec` (what goes into ``offered_qos_profiles``)."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

    never = QosTime(0x7FFFFFFF, 0xFFFFFFFF)  # rmw's "infinite" duration, as ros2 bag writes it
    return Qos(QosHistory.KEEP_LAST, spec.depth,
               QosReliability.RELIABLE if spec.reliable else QosReliability.BEST_EFFORT,
               QosDurability.TRANSIENT_LOCAL if spec.transient_local else QosDurability.VOLATILE,
               never, never, QosLiveliness.AUTOMATIC, never, False)


def to_ns(t: float) -> int:
    """Sim seconds -> non-negative integer nanoseconds (a bag's timestamps are unsigned)."""
    return max(0, round(float(t) * 1e9))


class MissionBag:
    """Write one mission into a new rosbag2 directory ``path`` (MCAP storage); see the module docstring.

    Args:
        path: the bag directory; it must not exist (rosbag2 never overwrites a bag).
        mission: JSON-able facts about the run (world, maneuver, seed, profile), written on /bt_nav/mission.
        flush_every: sim seconds between two :meth:`flush` calls (what a kill can lose at most; 0: never).

    Raises:
        BagError: when the directory exists or cannot be created.
    """

    def __init__(self, path: str | Path, mission: dict[str, Any] | None = None, flush_every: float = 1.0) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer, WriterError

        self.path = Path(path)
        self.ts = typestore()
        try:
            self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
            self._writer.open()
        except (WriterError, OSError) as exc:
            raise BagError(f"cannot write bag {self.path}: {exc}") from exc
        self._connections: dict[str, Any] = {}
        self.namespace = ""  # "" for the bag itself, "/robot1" for a robot's sink (:meth:`robot`)
        self._root = self
        self.counts: dict[str, int] = {}
        self.closed = False
        self._flush_ns = to_ns(flush_every)
        self._flushed_at = 0
        T = self.ts.types
        self._Time, self._Header, self._String = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"], \
            T["std_msgs/msg/String"]
        if mission is not None:
            self.mission(0.0, mission)

    # ------------------------------------------------------------------ low level
    def connection(self, topic: str, msgtype: str | None = None, qos: Any = None) -> Any:
        """The writer's connection for ``topic`` (created on first use with :data:`TOPICS`' type and QoS)."""
        conn = self._connections.get(topic)
        if conn is None:
            spec = TOPICS.get(topic) or TOPICS.get(split_namespace(topic)[1])
            msgtype = msgtype or (spec.msgtype if spec else None)
            if msgtype is None:
                raise BagError(f"{self.path}: no message type known for topic {topic}")
            profiles = [qos] if qos is not None else ([qos_of(spec)] if spec else [])
            conn = self._writer.add_connection(topic, msgtype, typestore=self.ts, offered_qos_profiles=profiles)
            self._connections[topic] = conn
        return conn

    def write_raw(self, topic: str, t_ns: int, data: bytes, msgtype: str | None = None, qos: Any = None) -> None:
        """One already serialised (CDR) message, e.g. from an rclpy ``raw=True`` subscription."""
        if self._root is not self:  # a robot's sink: the bag itself counts and flushes
            self._root.write_raw(topic, t_ns, data, msgtype, qos)
            return
        self._writer.write(self.connection(topic, msgtype, qos), int(t_ns), data)
        self.counts[topic] = self.counts.get(topic, 0) + 1
        if self._flush_ns and t_ns - self._flushed_at >= self._flush_ns:
            self._flushed_at = int(t_ns)
            self.flush()

    def robot(self, name: str) -> MissionBag:
        """A sink for robot ``name`` writing into this bag under ``/name`` (see the module docstring).

        It shares this bag's writer, connections and :attr:`counts`; closing it does nothing, close the bag.
        """
        view = copy.copy(self)
        view.namespace = "/" + name.strip("/")
        view._root = self
        return view

    def topic(self, name: str) -> str:
        """The full name of ``name`` in this sink: the robot's namespace in front of a robot topic."""
        return self.namespace + name if self.namespace and name in ROBOT_TOPICS else name

    def write(self, topic: str, t: float, msg: Any) -> None:
        """One rosbags message object, serialised to CDR by rosbags (``topic`` as :meth:`topic` names it)."""
        topic = self.topic(topic)
        self.write_raw(topic, to_ns(t), bytes(self.ts.serialize_cdr(msg, msg.__msgtype__)), msg.__msgtype__)

    def _header(self, t: float, frame: str) -> Any:
        ns = to_ns(t)
        return self._Header(stamp=self._Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame)

    # ------------------------------------------------------------------ the mission's messages
    def clock(self, t: float) -> None:
        """/clock (rosgraph_msgs/Clock); a robot's sink writes none (one /clock per bag)."""
        if self.namespace:
            return
        ns = to_ns(t)
        clock = self.ts.types["rosgraph_msgs/msg/Clock"]
        self.write(CLOCK, t, clock(clock=self._Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)))

    def scan(self, t: float, scan: Any) -> None:
        """/scan (sensor_msgs/LaserScan) from a :class:`bt_nav.mission.scan.Scan` (or anything shaped like one)."""
        T = self.ts.types
        msg = T["sensor_msgs/msg/LaserScan"](
            header=self._header(t, "base_scan"), angle_min=float(scan.angle_min), angle_max=float(scan.angle_max),
            angle_increment=float(scan.angle_increment), time_increment=0.0, scan_time=0.0,
            range_min=float(scan.range_min), range_max=float(scan.range_max),
            ranges=np.asarray(scan.ranges, dtype=np.float32), intensities=np.zeros(0, dtype=np.float32))
        self.write(SCAN, t, msg)

    def _odometry(self, t: float, frame: str, x: float, y: float, yaw: float, v: float, w: float) -> Any:
        T = self.ts.types
        Vector3 = T["geometry_msgs/msg/Vector3"]
        pose = T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(0.5 * yaw), w=math.cos(0.5 * yaw)))
        twist = T["geometry_msgs/msg/Twist"](linear=Vector3(x=float(v), y=0.0, z=0.0),
                                             angular=Vector3(x=0.0, y=0.0, z=float(w)))
        cov = np.zeros(36, dtype=np.float64)
        return T["nav_msgs/msg/Odometry"](
            header=self._header(t, frame), child_frame_id="base_footprint",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=cov.copy()))

    def odom(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None:
        """/odom (nav_msgs/Odometry, frame ``odom``): what the executive sees, slip included."""
        self.write(ODOM, t, self._odometry(t, "odom", x, y, yaw, v, w))

    def ground_truth(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None:
        """/ground_truth_odom (nav_msgs/Odometry, frame ``world``): the referee's view."""
        self.write(TRUTH, t, self._odometry(t, "world", x, y, yaw, v, w))

    def cmd(self, t: float, v: float, w: float) -> None:
        """/cmd_vel (geometry_msgs/Twist)."""
        T = self.ts.types
        Vector3 = T["geometry_msgs/msg/Vector3"]
        self.write(CMD, t, T["geometry_msgs/msg/Twist"](linear=Vector3(x=float(v), y=0.0, z=0.0),
                                                         angular=Vector3(x=0.0, y=0.0, z=float(w))))

    def string(self, topic: str, t: float, text: str) -> None:
        """A std_msgs/String on ``topic``."""
        self.write(topic, t, self._String(data=str(text)))

    def tree(self, t: float, snapshot: dict[str, Any]) -> None:
        """/bt_nav_executive/tree: a tree snapshot (:mod:`bt_nav.mission.snapshot`) in its wire form, as the executive
        publishes ``~/tree``; the engine sends one only when a status or the tip changed
        (:meth:`bt_nav.mission.core.MissionCore.changed_snapshot`), so lock-step and DDS bags hold the same ones."""
        self.string(TREE, t, snapshot_json(snapshot))

    def announce(self, t: float, record: dict[str, Any]) -> None:
        """/bt_nav_executive/events: one of the tree's events (a maneuver's side and angle), as ``~/events``."""
        self.string(ANNOUNCEMENTS, t, snapshot_json(record))

    def event(self, t: float, text: str) -> None:
        """/bt_nav/events: one mission log line."""
        self.string(EVENTS, t, text)

    def collision(self, t: float, x: float, y: float, yaw: float = 0.0) -> None:
        """/collisions: the simulator's JSON collision event."""
        self.string(COLLISIONS, t, json.dumps({"t": round(t, 4), "x": x, "y": y, "yaw": yaw}))

    def walkers(self, t: float, circles: Any) -> None:
        """/walkers: where the people walking are, as the simulator node publishes it."""
        self.string(WALKERS, t, walkers_message(t, circles))

    def mission(self, t: float, info: dict[str, Any]) -> None:
        """/bt_nav/mission: JSON facts about the run (world, maneuver, seed, profile, verdict...)."""
        self.string(MISSION, t, json.dumps(info, sort_keys=True, default=str))

    # ------------------------------------------------------------------ life cycle
    def flush(self) -> None:
        """Put everything written so far on disk as a complete MCAP chunk, so a kill loses nothing before it.

        rosbags keeps the open chunk in memory until it reaches 1 MiB; closing it early costs one small
        chunk record. (Uses the MCAP storage's ``close_chunk``; a no-op if a rosbags version lacks it.)
        """
        storage = getattr(self._writer, "storage", None)
        chunk = getattr(storage, "chunk", None)
        if storage is None or chunk is None or not hasattr(storage, "close_chunk"):
            return
        if chunk.bio.tell():
            storage.close_chunk()
        storage.bio.flush()

    def close(self) -> None:
        """Finish the MCAP file and write ``metadata.yaml``; idempotent (a robot's sink: nothing to do)."""
        if self._root is self and not self.closed:
            self.closed = True
            self._writer.close()

    def __enter__(self) -> MissionBag:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
