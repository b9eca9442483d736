"""A real robot's bag read for the check-off (``bt-nav checkoff --bag``): /odom, /scan, /cmd_vel, the
``toggle_navigation`` service events and /tf's LiDAR mount, as a :class:`bt_nav_sim.recorded.Recording`.

Why not :func:`bt_nav.media.bagread.read_bag`: that reads the bags bt_nav writes (MCAP, one scan geometry, sim
time). A TurtleBot3's bag is whatever ``ros2 bag record`` (sqlite3 or MCAP) or ``rosbag record`` (ROS 1) wrote on
the robot: an LDS-02 scan has its own beam count every time, the robot's clock is not the recorder's, and types
vary (Twist or TwistStamped). ``rosbags``' ``AnyReader`` reads all three formats and decodes with the bag's own
message definitions (the Jazzy types where a rosbag2 bag has none); a cut-short MCAP without its summary is walked
record by record as :func:`bt_nav.media.bagread.iter_messages` does.

Times: every series on the recorder's clock. A stamped message (Odometry, LaserScan, TwistStamped) keeps its own
stamp's spacing (Wi-Fi bunches messages up on arrival; the robot stamped them when they happened), shifted onto the
recorder's clock by the topic's offset: the 5th percentile of (receive time - stamp), i.e. its fastest arrivals taken
as instant. So a robot whose clock runs a fraction of a second ahead, or sits in 1970, still lines its poses up
with the commands, which carry no stamp (their receive time stands).

Everything that goes wrong is a :class:`bt_nav.media.bag.BagError` with one line naming the file: no such bag,
not a bag, damaged, no /odom or /scan, a topic of an unexpected type.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim.recorded import Recording, ServiceCall

from bt_nav.media.bag import BagError
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.scan import Scan

ODOMETRY, LASERSCAN = "nav_msgs/msg/Odometry", "sensor_msgs/msg/LaserScan"
TWISTS = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
ROSOUT = "/rosout"  # the nodes' log lines: the judged node's are the judge's announcements (marks, never readings)
#: Loggers of a TurtleBot3's own bringup and of the recorder, whose lines are no node's maneuver marks.
INFRASTRUCTURE = ("turtlebot3", "diff_drive", "robot_state_publisher", "hlds", "ld08", "lds", "rplidar", "rosbag2",
                  "_ros2cli", "launch", "rviz", "transform_listener", "bt_nav", "gazebo", "gz", "rosout")
TF_TOPICS = ("/tf_static", "/tf")  # where the LiDAR's mount is read (also under the robot's namespace)
SETBOOL_EVENT = "std_srvs/srv/SetBool_Event"
#: service_msgs/ServiceEventInfo event types
REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED = 0, 1, 2, 3
#: The percentile of (receive - stamp) taken as a stamped topic's clock offset (its fastest arrivals).
OFFSET_PERCENTILE = 5.0

#: std_srvs/SetBool's request, response and service event (rosbag2's service introspection), which rosbags lacks.
_SETBOOL_TYPES = {"std_srvs/srv/SetBool_Request": "bool data\n",
                  "std_srvs/srv/SetBool_Response": "bool success\nstring message\n",
                  SETBOOL_EVENT: "service_msgs/msg/ServiceEventInfo info\nstd_srvs/srv/SetBool_Request[<=1] request\n"
                                 "std_srvs/srv/SetBool_Response[<=1] response\n"}


@dataclass(frozen=True)
class Topics:
    """The topic names the check-off reads (relative names are put under ``namespace``)."""

    odom: str = "odom"
    scan: str = "scan"
    cmd: str = "cmd_vel"
    service: str = "toggle_navigation/_service_event"
    namespace: str = ""

    def resolve(self, name: str) -> str:
        if name.startswith("/"):
            return name
        ns = self.namespace.strip("/")
        return f"/{ns}/{name}" if ns else f"/{name}"

    def names(self) -> dict[str, str]:
        return {role: self.resolve(getattr(self, role)) for role in ("odom", "scan", "cmd", "service")}


def robot_typestore() -> Any:
    """The Jazzy types plus std_srvs/SetBool's service event (rosbags has no service event types)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    parsed: dict[str, Any] = {}
    for name, text in _SETBOOL_TYPES.items():
        parsed.update(get_types_from_msg(text, name))
    # the parser files a srv's types under std_srvs/srv/msg/; rosbag2 names them std_srvs/srv/SetBool_Event
    store.register({key.replace("/srv/msg/", "/srv/"): _renamed(value) for key, value in parsed.items()})
    return store


def _renamed(value: Any) -> Any:
    """A parsed type definition with ``std_srvs/srv/msg/`` references as ``std_srvs/srv/``."""
    if isinstance(value, str):
        return value.replace("/srv/msg/", "/srv/")
    if isinstance(value, tuple | list):
        return type(value)(_renamed(v) for v in value)
    return value


def _decoded(path: Path, wanted: set[str], notes: list[str]) -> Iterator[tuple[str, str, int, Any]]:
    """(topic, msgtype, receive ns, message) of the ``wanted`` topics, any bag format; the bag's topic table first
    as ("", "", 0, {topic: type})."""
    store = robot_typestore()
    if path.is_file() and path.suffix in (".db3", ".mcap") and (path.parent / "metadata.yaml").exists():
        path = path.parent  # a rosbag2 bag's file: the bag is its directory
    if path.is_file() and path.suffix == ".bag":
        from rosbags.rosbag1 import Reader as Reader1
        from rosbags.typesys import Stores, get_typestore

        reader, store, decode = Reader1(path), get_typestore(Stores.ROS1_NOETIC), "deserialize_ros1"
    elif path.is_dir() and (path / "metadata.yaml").exists():
        from rosbags.rosbag2 import Reader

        reader, decode = Reader(path), "deserialize_cdr"
    else:
        yield from _stream_decoded(path, wanted, store, notes)
        return
    try:
        reader.open()
    except Exception as exc:  # noqa: BLE001 - a cut MCAP (no summary) is still read record by record
        if not (path.is_dir() and any(path.glob("*.mcap"))):
            raise
        notes.append(f"the bag's index is unreadable ({type(exc).__name__}: {exc}): read record by record")
        yield from _stream_decoded(path, wanted, store, notes)
        return
    try:
        yield "", "", 0, {c.topic: c.msgtype for c in reader.connections}
        conns = [c for c in reader.connections if c.topic in wanted]
        if decode == "deserialize_ros1":
            _register_bag_types(store, conns)
        skipped = 0
        for conn, t_ns, raw in reader.messages(connections=conns):
            try:
                msg = getattr(store, decode)(bytes(raw), conn.msgtype)
            except Exception:  # noqa: BLE001 - a damaged payload or a type the store lacks: skip it
                skipped += 1
                continue
            yield conn.topic, conn.msgtype, t_ns, msg
        if skipped:
            notes.append(f"{skipped} messages could not be decoded and were skipped")
    finally:
        reader.close()


def _register_bag_types(store: Any, conns: list[Any]) -> None:
    """A ROS 1 bag's own message definitions (Noetic's store lacks tf2_msgs, for one): each connection's type
    registered from the definition text the bag carries, where the store does not have it."""
    from rosbags.typesys import get_types_from_msg

    for conn in conns:
        text = getattr(conn.msgdef, "data", "")
        if conn.msgtype in store.fielddefs or not text:
            continue
        try:
            store.register(get_types_from_msg(text, conn.msgtype))
        except Exception:  # noqa: BLE001 - a definition rosbags cannot parse: its messages are skipped, and counted
            continue


def _stream_decoded(path: Path, wanted: set[str], store: Any, notes: list[str]) -> Iterator[tuple[str, str, int, Any]]:
    """A cut-short rosbag2 MCAP (no metadata.yaml or no summary), record by record."""
    from bt_nav.media.bagread import iter_messages

    status: dict[str, Any] = {}
    types: dict[str, str] = {}
    rows = []
    for topic, msgtype, t_ns, data in iter_messages(path, status):
        types[topic] = msgtype
        if topic in wanted:
            rows.append((topic, msgtype, t_ns, data))
    if not types and status.get("reason"):
        raise BagError(f"nothing readable before the damage: {status['reason']}")
    yield "", "", 0, types
    for topic, msgtype, t_ns, data in rows:
        try:
            yield topic, msgtype, t_ns, store.deserialize_cdr(data, msgtype)
        except Exception:  # noqa: BLE001 - unknown type or damaged payload
            continue
    if status.get("reason"):
        notes.append(f"read up to where the bag is cut: {status['reason']}")


def stamp_ns(msg: Any, stamp: Any = None) -> int | None:
    """A message's own header stamp, or ``stamp`` (a Log's) (ns; None without either or with a zero stamp)."""
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", stamp)
    if stamp is None:
        return None
    ns = int(getattr(stamp, "sec", 0)) * 1_000_000_000 + int(getattr(stamp, "nanosec", getattr(stamp, "nsec", 0)))
    return ns if ns > 0 else None


def _aligned(rows: list[tuple[int, int | None, Any]], topic: str, notes: list[str]) -> list[tuple[float, Any]]:
    """(t, msg) on the recorder's clock, sorted: stamps shifted by the topic's offset (module docstring), else the
    receive times."""
    if not rows:
        return []
    stamped = [(r, s) for r, s, _ in rows if s is not None]
    if len(stamped) * 2 < len(rows):
        out = [(r * 1e-9, m) for r, _, m in rows]
    else:
        lag = np.asarray([r - s for r, s in stamped], dtype=np.float64) * 1e-9
        offset = float(np.percentile(lag, OFFSET_PERCENTILE))
        median = float(np.median(lag))
        if abs(median) > 0.05:
            ahead = "behind" if median > 0 else "ahead of"
            notes.append(f"{topic}: header stamps {abs(median):.2f} s {ahead} their receive times (median); "
                         f"placed on the recorder's clock by their fastest arrivals ({offset:+.3f} s)")
        out = [(s * 1e-9 + offset if s is not None else r * 1e-9, m) for r, s, m in rows]
    out.sort(key=lambda item: item[0])
    return out


def _scan(msg: Any) -> Scan:
    return Scan(float(msg.angle_min), float(msg.angle_max), float(msg.angle_increment), float(msg.range_min),
                float(msg.range_max), np.asarray(msg.ranges, dtype=np.float32))


def _check_types(types: dict[str, str], names: dict[str, str], path: Path) -> None:
    """A one-line error for a missing /odom or /scan, or a topic of a type the judge cannot read."""
    expected = {"odom": (ODOMETRY,), "scan": (LASERSCAN,), "cmd": TWISTS, "service": (SETBOOL_EVENT,)}
    listed = ", ".join(sorted(types)[:12]) + (" ..." if len(types) > 12 else "") or "none"
    for role in ("odom", "scan", "cmd"):
        if names[role] not in types:
            raise BagError(f"{path}: no {names[role]} topic (topics: {listed}); name it with --{role}-topic or "
                           "--namespace")
    for role, allowed in expected.items():
        found = types.get(names[role])
        if found is not None and found not in allowed:
            raise BagError(f"{path}: {names[role]} is {found}, not {' or '.join(allowed)}")


def _calls(rows: list[tuple[float, Any]]) -> list[ServiceCall]:
    """toggle_navigation calls from service events: one per (client, sequence number), its request's time and data,
    its response's time and success (client or server side, whichever was introspected)."""
    calls: dict[tuple[bytes, int], dict[str, Any]] = {}
    for t, msg in rows:
        info = msg.info
        key = (bytes(np.asarray(getattr(info.client_gid, "data", info.client_gid), dtype=np.uint8)),
               int(info.sequence_number))
        call = calls.setdefault(key, {"t": t})
        call["t"] = min(call["t"], t)
        if info.event_type in (REQUEST_SENT, REQUEST_RECEIVED) and len(msg.request):
            call["data"] = bool(msg.request[0].data)
        if info.event_type in (RESPONSE_SENT, RESPONSE_RECEIVED):
            call["answered"] = min(call.get("answered", t), t)
            if len(msg.response):
                call["success"] = bool(msg.response[0].success)
                call["message"] = str(msg.response[0].message)
    out = [ServiceCall(c["t"], c["data"], c.get("answered"), c.get("success", c.get("answered") is not None),
                       c.get("message", "")) for c in calls.values() if "data" in c]
    return sorted(out, key=lambda c: c.t)


def _mount(tf_rows: list[Any], frame: str) -> tuple[float, float] | None:
    """The scan frame's (x, y) on the robot from a /tf or /tf_static transform base_link/base_footprint -> it."""
    for msg in tf_rows:
        for tr in msg.transforms:
            if tr.child_frame_id.strip("/") == frame and tr.header.frame_id.strip("/") in ("base_link",
                                                                                          "base_footprint"):
                return float(tr.transform.translation.x), float(tr.transform.translation.y)
    return None


def read_robot_bag(path: str | Path, topics: Topics = Topics()) -> Recording:  # noqa: B008 - frozen
    """A real robot's bag as a :class:`Recording` (see the module docstring). Raises BagError (one line)."""
    p = Path(path)
    if not p.exists():
        raise BagError(f"{p}: no such bag (a rosbag2 directory, an .mcap or .db3 file, or a ROS 1 .bag)")
    names = topics.names()
    wanted = {*names.values(), *TF_TOPICS, *(topics.resolve(t.lstrip("/")) for t in TF_TOPICS), ROSOUT}
    notes: list[str] = []
    raw: dict[str, list[tuple[int, int | None, Any]]] = {}
    types: dict[str, str] = {}
    try:
        for topic, msgtype, t_ns, msg in _decoded(p, wanted, notes):
            if not topic:
                types = msg
                if not types:
                    raise BagError(f"{p}: not a bag, or not one topic in it could be read")
                _check_types(types, names, p)
                continue
            stamp = None if msgtype == SETBOOL_EVENT else stamp_ns(msg, getattr(msg, "stamp", None))
            raw.setdefault(topic, []).append((t_ns, stamp, msg))
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever a damaged or foreign file makes a reader raise
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise BagError(f"{p}: cannot read this bag ({type(exc).__name__}: {detail})") from exc
    return recording_from(raw, names, notes, str(p))


def recording_from(raw: dict[str, list[tuple[int, int | None, Any]]], names: dict[str, str], notes: list[str],
                   source: str) -> Recording:
    """The :class:`Recording` of decoded messages, per topic (receive ns, own stamp ns or None, message): a bag's,
    or what ``bt-nav checkoff --robot`` heard live (``source`` names it in errors). BagError: no /odom or /scan."""
    odom = _aligned(raw.get(names["odom"], []), names["odom"], notes)
    scans = _aligned(raw.get(names["scan"], []), names["scan"], notes)
    cmds = _aligned(raw.get(names["cmd"], []), names["cmd"], notes)
    if not odom or not scans:
        raise BagError(f"{source}: {names['odom'] if not odom else names['scan']} holds no readable message")
    poses = []
    for t, m in odom:
        q, pos = m.pose.pose.orientation, m.pose.pose.position
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        if all(math.isfinite(v) for v in (pos.x, pos.y, yaw)):
            poses.append((t, float(pos.x), float(pos.y), float(yaw)))
    commands = [(t, float(getattr(m, "twist", m).linear.x), float(getattr(m, "twist", m).angular.z)) for t, m in cmds]
    service = raw.get(names["service"])
    calls = _calls([(r * 1e-9, m) for r, _, m in service]) if service else None
    frame = str(scans[0][1].header.frame_id).strip("/")
    tf = [m for topic, rows in raw.items() if topic.endswith(TF_TOPICS) for _, _, m in rows]
    mount = _mount(tf, frame)
    if mount is None:
        notes.append(f"no /tf from base_link to the scan's frame {frame!r}: the LiDAR taken at the robot's centre")
    lines = [(t, str(m.name), str(m.msg)) for t, m in _aligned(raw.get(ROSOUT, []), ROSOUT, notes)
             if not str(m.name).lstrip("/").startswith(INFRASTRUCTURE)]
    return Recording(poses, [(t, _scan(m)) for t, m in scans], commands, calls, mount or (0.0, 0.0),
                     dict(names), notes, lines)
