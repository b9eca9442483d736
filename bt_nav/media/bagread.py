"""Read a mission bag back: :func:`read_bag` -> :class:`MissionRecord`, plain numpy arrays for replay, plots,
the video and the browser view.

Two ways in, both through maintained libraries:

1. a complete bag (``metadata.yaml`` + ``.mcap``): the ``rosbags`` reader;
2. a bag cut short (the recorder was killed: no ``metadata.yaml``, or an ``.mcap`` without its summary):
   the ``mcap`` package's stream reader walks the file record by record and stops at the cut, so
   everything up to the last complete chunk is kept; :attr:`MissionRecord.truncated` says so.

Either way the CDR payloads are decoded by rosbags' typestore. A sqlite3 rosbag2 bag or a ROS 1 .bag is read by
:func:`bt_nav.media.bagformats.decoded_messages` (the one home of reading bag formats; this module re-exports
:func:`~bt_nav.media.bagformats.iter_messages` and :func:`~bt_nav.media.bagformats.bag_files`). A file that yields
nothing raises :class:`~bt_nav.media.bag.BagError` naming the file. No rclpy.

Times: a message's time is its own header stamp where it has one on the bag's clock, else its bag time
(:func:`bt_nav.media.bag.message_time_ns`, the recorder's rule too; a tree snapshot's own stamp is its ``t``,
:func:`tree_time`), and every series is sorted by it. So a bag
that ``ros2 bag record`` (or an older ``bt-nav record``) wrote with receive times, seconds late when the recorder
fell behind, still shows the robot where it was at each instant.

A bag of several robots (``bt-nav lockstep --robots N --bag``; each robot's topics under its namespace,
``/robot1/ground_truth_odom``, ...) gives :attr:`MissionRecord.robots`: one record per namespace that has a
ground truth, in name order. Its top-level fields are the first robot's (plus the shared /clock and
/bt_nav/mission), so every reader written for one robot (``bt-nav view``, ``bt-nav replay``) shows robot1.
"""

from __future__ import annotations

import bisect
import contextlib
import json
import math
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim.walkers import read_walkers_message

from bt_nav.media.bag import (
    ANNOUNCEMENTS,
    CLOCK,
    CMD,
    COLLISIONS,
    EVENTS,
    MISSION,
    ODOM,
    SCAN,
    TREE,
    TRUTH,
    WALKERS,
    BagError,
    message_time_ns,
    own_stamp_ns,
    split_namespace,
    typestore,
)
from bt_nav.media.bagformats import bag_files, decoded_messages, is_mcap_only, iter_messages  # noqa: F401
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.snapshot import read_event, read_snapshot, snapshot_time


@dataclass
class Poses:
    """Odometry samples: time (sim s), pose and body twist, one entry per message."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    v: np.ndarray
    w: np.ndarray

    @classmethod
    def from_rows(cls, rows: list[tuple[float, ...]]) -> Poses:
        """From (t, x, y, yaw, v, w) rows."""
        a = np.asarray(rows, dtype=np.float64).reshape(-1, 6)
        return cls(*(a[:, i].copy() for i in range(6)))

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def at(self, t: float) -> tuple[float, float, float] | None:
        """The pose (x, y, yaw) at sim time ``t``, interpolated between the samples around it (None before the
        first sample; the last one after the end).

        Why interpolate: a scan or a frame rarely falls on a sample (ground truth at 30 Hz, scans at 5 Hz), and
        during a spin at 1.5 rad/s the nearest-earlier sample is up to 3 deg off. Yaw is interpolated unwrapped.
        """
        if len(self) == 0 or t < self.t[0]:
            return None
        if len(self) == 1 or t >= self.t[-1]:
            return float(self.x[-1]), float(self.y[-1]), float(self.yaw[-1])
        yaw = float(np.interp(t, self.t, self.unwrapped_yaw()))
        return float(np.interp(t, self.t, self.x)), float(np.interp(t, self.t, self.y)), math.remainder(yaw, math.tau)

    def unwrapped_yaw(self) -> np.ndarray:
        """Yaw without the jumps at +-pi (cached), for interpolation and for how far the robot has turned."""
        cached = getattr(self, "_unwrapped", None)
        if cached is None or cached.shape != self.yaw.shape:
            cached = np.unwrap(self.yaw)
            self._unwrapped = cached
        return cached

    def turned(self, t0: float, t1: float) -> float:
        """Heading change from ``t0`` to ``t1`` in degrees (+ is left), from the unwrapped yaw."""
        if len(self) == 0:
            return 0.0
        yaw = self.unwrapped_yaw()
        return math.degrees(float(np.interp(t1, self.t, yaw) - np.interp(t0, self.t, yaw)))

    def distance(self) -> np.ndarray:
        """Distance travelled up to each sample, m."""
        if len(self) < 2:
            return np.zeros(len(self))
        steps = np.hypot(np.diff(self.x), np.diff(self.y))
        return np.concatenate(([0.0], np.cumsum(steps)))


@dataclass
class Scans:
    """LaserScans: times, beam angles (from the first scan) and one row of ranges per scan (NaN = no return)."""

    t: np.ndarray
    angles: np.ndarray
    ranges: np.ndarray  # (n_scans, n_beams) float32
    range_max: float = 3.5


@dataclass
class MissionRecord:
    """Everything a mission bag holds, decoded."""

    path: Path
    counts: dict[str, int]
    truth: Poses
    odom: Poses
    scans: Scans
    cmd: np.ndarray  # (n, 3): t, v, w
    #: (t, snapshot) of the executive's ``~/tree`` (:mod:`bt_nav.mission.snapshot`); a bag recorded before the
    #: snapshots were JSON (unicode art) has none.
    trees: list[tuple[float, dict[str, Any]]] = field(default_factory=list)
    announcements: list[tuple[float, dict[str, Any]]] = field(default_factory=list)  # (t, event) of ``~/events``
    events: list[tuple[float, str]] = field(default_factory=list)
    collisions: list[dict[str, Any]] = field(default_factory=list)
    walkers: list[tuple[float, np.ndarray]] = field(default_factory=list)  # (t, circles (K, 3)): people walking
    mission: dict[str, Any] = field(default_factory=dict)
    start: float = 0.0
    end: float = 0.0
    truncated: bool = False
    robots: dict[str, MissionRecord] = field(default_factory=dict)  # name -> its record (several robots only)
    clock_start: float | None = None  # sim time of the first /clock message (None: the bag has none)

    @property
    def duration(self) -> float:
        """Sim seconds from the first to the last message."""
        return max(0.0, self.end - self.start)

    @property
    def origin(self) -> float:
        """Time zero of every picture of this bag: its first /clock (else its first message).

        Why one origin: a film's caption, its console and ``bt-nav video --still --at T`` must all count
        from the same instant, and the first /clock is where the bag's sim time begins (0 in lock-step).
        """
        return self.start if self.clock_start is None else self.clock_start

    def walkers_at(self, t: float) -> np.ndarray | None:
        """The people walking at ``t`` (circles (K, 3) of the latest sample at or before it); None if none."""
        if not self.walkers:
            return None
        k = bisect.bisect_right(self.walkers, t, key=lambda sample: sample[0]) - 1
        return self.walkers[k][1] if k >= 0 else None

    def scan_at(self, t: float) -> tuple[float, np.ndarray, np.ndarray] | None:
        """The latest scan at or before ``t`` as (its stamp, x, y): its returns in the world frame, placed from
        the ground-truth pose **at the scan's stamp** (misses dropped); None before the first scan or pose.

        Why the scan's stamp and not ``t``: scans come at 5 Hz, so a frame may show a scan 0.2 s old; drawn
        from the frame's pose during a 1.5 rad/s spin it would sit 17 deg off the walls it saw.
        """
        scans = self.scans
        k = int(np.searchsorted(scans.t, t, side="right")) - 1
        if k < 0 or scans.ranges.size == 0:
            return None
        stamp = float(scans.t[k])
        pose = self.truth.at(stamp)
        if pose is None:
            return None
        x, y, yaw = pose
        r = scans.ranges[k]
        ok = np.isfinite(r) & (r < scans.range_max)
        a = scans.angles[ok] + yaw
        return stamp, x + r[ok] * np.cos(a), y + r[ok] * np.sin(a)


def _pose_row(t: float, msg: Any) -> tuple[float, ...]:
    p, q, tw = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
    return t, p.x, p.y, yaw_from_quaternion(q.x, q.y, q.z, q.w), tw.linear.x, tw.angular.z


class _Collector:
    """Decoded messages sorted into the record's fields."""

    def __init__(self) -> None:
        self.truth: list[tuple[float, ...]] = []
        self.odom: list[tuple[float, ...]] = []
        self.scan_t: list[float] = []
        self.scan_rows: list[np.ndarray] = []
        self.scan_meta: tuple[float, float, float] | None = None
        self.cmd: list[tuple[float, float, float]] = []
        self.trees: list[tuple[float, dict[str, Any]]] = []
        self.announcements: list[tuple[float, dict[str, Any]]] = []
        self.events: list[tuple[float, str]] = []
        self.collisions: list[dict[str, Any]] = []
        self.walkers: list[tuple[float, np.ndarray]] = []
        self.mission: dict[str, Any] = {}
        self.counts: dict[str, int] = {}
        self.t_min, self.t_max = float("inf"), float("-inf")
        self.clock_start: float | None = None
        self.namespaces: dict[str, _Collector] = {}

    def add(self, topic: str, t: float, msg: Any) -> None:
        self.counts[topic] = self.counts.get(topic, 0) + 1
        self.t_min, self.t_max = min(self.t_min, t), max(self.t_max, t)
        namespace, base = split_namespace(topic)
        if namespace:  # a robot's topic: sorted into that robot's collector under its plain name
            self.namespaces.setdefault(namespace, _Collector()).add(base, t, msg)
        elif topic == CLOCK:
            self.clock_start = t if self.clock_start is None else min(self.clock_start, t)
        elif topic == TRUTH:
            self.truth.append(_pose_row(t, msg))
        elif topic == ODOM:
            self.odom.append(_pose_row(t, msg))
        elif topic == SCAN:
            self._scan(t, msg)
        elif topic == CMD:
            twist = getattr(msg, "twist", msg)  # geometry_msgs/Twist, or TwistStamped's twist
            self.cmd.append((t, twist.linear.x, twist.angular.z))
        elif topic == TREE:
            snapshot = read_snapshot(msg.data)
            if snapshot is not None:  # not a snapshot document (an older bag's art): no tree
                self.trees.append((tree_time(snapshot, t), snapshot))
        elif topic == ANNOUNCEMENTS:
            record = read_event(msg.data)
            if record is not None:
                self.announcements.append((t, record))
        elif topic == EVENTS:
            self.events.append((t, msg.data))
        elif topic == COLLISIONS:
            self.collisions.append(_json_or_text(msg.data))
        elif topic == WALKERS:
            with contextlib.suppress(ValueError):  # an unreadable sample is skipped, like an unknown topic
                self.walkers.append((t, read_walkers_message(msg.data)[1]))
        elif topic == MISSION:
            info = _json_or_text(msg.data)
            self.mission.update(info)

    def _scan(self, t: float, msg: Any) -> None:
        ranges = np.asarray(msg.ranges, dtype=np.float32)
        if self.scan_meta is None:
            self.scan_meta = (msg.angle_min, msg.angle_increment, msg.range_max)
        if self.scan_rows and ranges.shape != self.scan_rows[0].shape:
            return  # a scan of another geometry cannot share the table; the first one wins
        self.scan_t.append(t)
        self.scan_rows.append(ranges)

    def record(self, path: Path, truncated: bool) -> MissionRecord:
        """The record; with robots in namespaces, each robot's too (the first one's data at the top level)."""
        rec = self._own_record(path, truncated)
        for namespace in sorted(self.namespaces):
            sub = self.namespaces[namespace]
            if sub.truth:
                robot = sub._own_record(path, truncated)
                robot.counts = {namespace + topic: n for topic, n in sub.counts.items()}
                robot.mission, robot.start, robot.end = self.mission, rec.start, rec.end
                robot.clock_start = rec.clock_start
                rec.robots[namespace.strip("/")] = robot
        if rec.robots and not self.truth:
            first = next(iter(rec.robots.values()))
            for name in ("truth", "odom", "scans", "cmd", "trees", "announcements", "events", "collisions", "walkers"):
                setattr(rec, name, getattr(first, name))
        return rec

    def _sort(self) -> None:
        """Every series in time order (stable): stamps at the source arrive out of the bag's order."""
        for name in ("truth", "odom", "cmd", "trees", "announcements", "events", "walkers"):
            getattr(self, name).sort(key=lambda item: item[0])
        order = sorted(range(len(self.scan_t)), key=self.scan_t.__getitem__)
        self.scan_t = [self.scan_t[i] for i in order]
        self.scan_rows = [self.scan_rows[i] for i in order]

    def _own_record(self, path: Path, truncated: bool) -> MissionRecord:
        self._sort()
        n_beams = self.scan_rows[0].shape[0] if self.scan_rows else 0
        a0, da, rmax = self.scan_meta or (0.0, 0.0, 3.5)
        scans = Scans(np.asarray(self.scan_t), a0 + da * np.arange(n_beams),
                      np.vstack(self.scan_rows) if self.scan_rows else np.zeros((0, 0), np.float32), float(rmax))
        return MissionRecord(path=path, counts=self.counts, truth=Poses.from_rows(self.truth),
                             odom=Poses.from_rows(self.odom), scans=scans,
                             cmd=np.asarray(self.cmd, dtype=np.float64).reshape(-1, 3), trees=self.trees,
                             announcements=self.announcements,
                             events=self.events, collisions=self.collisions, walkers=self.walkers,
                             mission=self.mission,
                             start=self.t_min if self.counts else 0.0, end=self.t_max if self.counts else 0.0,
                             truncated=truncated, clock_start=self.clock_start)


def tree_time(snapshot: dict[str, Any], bag_t: float) -> float:
    """A tree snapshot's time: when it was taken (:func:`bt_nav.mission.snapshot.snapshot_time`) where that is on
    the bag's clock (:func:`bt_nav.media.bag.message_time_ns`, the rule of a header stamp), else its bag time. A
    ``std_msgs/String`` has no header, so a bag that ``ros2 bag record`` wrote holds it at its receive time."""
    own = snapshot_time(snapshot)
    own_ns = round(own * 1e9) if own is not None and own > 0 else None
    return message_time_ns(own_ns, round(bag_t * 1e9)) * 1e-9


def _json_or_text(text: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except ValueError:
        return {"text": text}
    return value if isinstance(value, dict) else {"value": value}


def read_bag(path: str | Path, skip: Collection[str] = ()) -> MissionRecord:
    """Decode a mission bag (a rosbag2 directory or its ``.mcap`` file) into a :class:`MissionRecord`; the messages of
    the topics in ``skip`` are not decoded at all (a trajectory picture needs no scans: they are most of the bytes).

    Raises:
        BagError: no such bag, not MCAP, or not one message could be read (the message names the file).
    """
    if not is_mcap_only(path):
        return _read_other_format(Path(path), skip)
    ts = typestore()
    status: dict[str, Any] = {}
    rec = _Collector()
    try:
        for topic, msgtype, t_ns, data in iter_messages(path, status):
            if topic in skip:
                continue
            try:
                msg = ts.deserialize_cdr(data, msgtype)
            except Exception:  # noqa: BLE001 - a corrupt payload or an unknown type: skip that message
                status["skipped"] = status.get("skipped", 0) + 1
                continue
            rec.add(topic, message_time_ns(own_stamp_ns(msgtype, data), t_ns) * 1e-9, msg)
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever a damaged file makes a library raise
        raise BagError(f"{path}: cannot read this bag: {exc}") from exc
    if not rec.counts:
        why = status.get("reason", "no messages")
        raise BagError(f"{path}: no readable message in this bag ({why})")
    return rec.record(Path(path), bool(status.get("truncated")))


def _read_other_format(path: Path, skip: Collection[str]) -> MissionRecord:
    """A sqlite3 rosbag2 bag or a ROS 1 bag, decoded by the one reader of those formats
    (:func:`bt_nav.media.robotbag.decoded_messages`); times by the same rule as an MCAP's."""
    from bt_nav.media.robotbag import stamp_ns

    rec = _Collector()
    try:
        for topic, _, t_ns, msg in decoded_messages(path):
            if topic and topic not in skip:
                rec.add(topic, message_time_ns(stamp_ns(msg), t_ns) * 1e-9, msg)
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - whatever a damaged file makes a library raise
        raise BagError(f"{path}: cannot read this bag: {exc}") from exc
    if not rec.counts:
        raise BagError(f"{path}: no readable message in this bag")
    return rec.record(path, False)
