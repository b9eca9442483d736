"""A real robot's bag read for the check-off (``bt-nav checkoff --bag``): /odom, /scan, /cmd_vel, the
``toggle_navigation`` service events and /tf's LiDAR mount, as a :class:`bt_nav.judge.recorded.Recording`.

Why not :func:`bt_nav.media.bagread.read_bag`: that reads the bags bt_nav writes (MCAP, one scan geometry, sim
time). A TurtleBot3's bag is whatever ``ros2 bag record`` (sqlite3 or MCAP) or ``rosbag record`` (ROS 1) wrote on
the robot: an LDS-02 scan has its own beam count every time, the robot's clock is not the recorder's, and types
vary (Twist or TwistStamped). ``rosbags``' ``AnyReader`` reads all three formats and decodes with the bag's own
message definitions (the Jazzy types where a rosbag2 bag has none); a cut-short MCAP without its summary is walked
record by record (:mod:`bt_nav.media.bagformats`, the one home of reading bag formats).

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.judge.recorded import Recording, ServiceCall
from bt_nav.media.bag import BagError
from bt_nav.media.bagformats import SETBOOL_EVENT, bag_topics, decoded_messages, robot_typestore  # noqa: F401
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.scan import Scan

ODOMETRY, LASERSCAN = "nav_msgs/msg/Odometry", "sensor_msgs/msg/LaserScan"
TWISTS = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
ROSOUT = "/rosout"  # the nodes' log lines: the judged node's are the judge's announcements (marks, never readings)
#: Loggers of a TurtleBot3's own bringup and of the recorder, whose lines are no node's maneuver marks.
INFRASTRUCTURE = ("turtlebot3", "diff_drive", "robot_state_publisher", "hlds", "ld08", "lds", "rplidar", "rosbag2",
                  "_ros2cli", "launch", "rviz", "transform_listener", "bt_nav", "gazebo", "gz", "rosout")
TF_TOPICS = ("/tf_static", "/tf")  # where the LiDAR's mount is read (also under the robot's namespace)
#: A bag that was simulated, not recorded on a robot, says so on this std_msgs/String topic (tests/media/robotsynth.py)
SYNTHETIC = "/synthetic"
#: service_msgs/ServiceEventInfo event types
REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED = 0, 1, 2, 3
#: The percentile of (receive - stamp) taken as a stamped topic's clock offset (its fastest arrivals).
OFFSET_PERCENTILE = 5.0
#: s: stamps further than this from their receive times are on another clock, not a late or early one.
OTHER_CLOCK = 60.0

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
        note = clock_note(topic, median, offset)
        if note:
            notes.append(note)
        out = [(s * 1e-9 + offset if s is not None else r * 1e-9, m) for r, s, m in rows]
    out.sort(key=lambda item: item[0])
    return out


def clock_note(topic: str, median: float, offset: float) -> str:
    """What a topic's header stamps say against the receive times (s: their median difference, and the offset the
    stamps are shifted by), or nothing when they agree. Two computers' clocks a fraction of a second apart are named
    as such; stamps more than :data:`OTHER_CLOCK` s off are on another clock altogether (a simulator's, a robot's
    unset one): their difference says nothing about the network, so the note gives the arrivals' spread instead,
    which both sides of the same clock give (once printed as ``1795897414.86 s behind``)."""
    if abs(median) <= 0.05:
        return ""
    placed = f"placed on the recorder's clock by their fastest arrivals ({offset:+.3f} s)"
    if abs(median) > OTHER_CLOCK:
        return (f"{topic}: header stamps on a clock of their own, not the receiver's (a simulator's or an unset "
                f"robot clock); {placed.replace(f'({offset:+.3f} s)', '')}(arrivals {median - offset:.2f} s after "
                "the fastest, median)")
    ahead = "behind" if median > 0 else "ahead of"
    return f"{topic}: header stamps {abs(median):.2f} s {ahead} their receive times (median); {placed}"


#: ROS 1's rosgraph_msgs/Log levels (1 DEBUG, 2 INFO, 4 WARN, 8 ERROR, 16 FATAL) as ROS 2's (10 ... 50).
ROS1_LEVELS = {1: 10, 2: 20, 4: 30, 8: 40, 16: 50}


def log_level(msg: Any) -> int:
    """A /rosout line's severity on ROS 2's scale (a ROS 1 Log, which lists its ``topics``, has its own numbers)."""
    level = int(getattr(msg, "level", 20))
    return ROS1_LEVELS.get(level, level) if hasattr(msg, "topics") else level


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


def read_robot_bag(path: str | Path, topics: Topics = Topics(),  # noqa: B008 - frozen
                   about: dict[str, Any] | None = None) -> Recording:
    """A real robot's bag as a :class:`Recording` (see the module docstring). Raises BagError (one line).
    ``about`` (a dict) receives the bag's ``types`` ({topic: type}) and ``synthetic``: the text of its
    :data:`SYNTHETIC` topic (a simulated bag says so there), or None."""
    p = Path(path)
    if not p.exists():
        raise BagError(f"{p}: no such bag (a rosbag2 directory, an .mcap or .db3 file, or a ROS 1 .bag)")
    names = topics.names()
    wanted = {*names.values(), *TF_TOPICS, *(topics.resolve(t.lstrip("/")) for t in TF_TOPICS), ROSOUT, SYNTHETIC}
    notes: list[str] = []
    raw: dict[str, list[tuple[int, int | None, Any]]] = {}
    types: dict[str, str] = {}
    try:
        for topic, msgtype, t_ns, msg in decoded_messages(p, wanted, notes):
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
    if about is not None:
        said = [str(getattr(m, "data", "")) for _, _, m in raw.get(SYNTHETIC, [])]
        about.update(types=types, synthetic=said[0] if said else (SYNTHETIC if SYNTHETIC in types else None))
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
    log = [(t, log_level(m), str(m.name), str(m.msg))
           for t, m in _aligned(raw.get(ROSOUT, []), ROSOUT, notes)
           if not str(m.name).lstrip("/").startswith(INFRASTRUCTURE)]
    return Recording(poses, [(t, _scan(m)) for t, m in scans], commands, calls, mount or (0.0, 0.0),
                     dict(names), notes, [(t, name, text) for t, _, name, text in log], log)
