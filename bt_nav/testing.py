"""A deterministic harness for ticking the real mission tree step by step, without ROS.

Used by bt_nav's own tick-by-tick tests and meant for users who add leaves: a fake clock, synthetic
scans for any LiDAR layout, perfect odometry that integrates the commands, a local Trigger client whose
answers a test scripts (:mod:`bt_nav.mission.local_services`, re-exported here), and a recorder of what
every tick decided.

Also the one home of what the DDS tests and the benchmarks share: the ``sensor_msgs/LaserScan`` built
from a :class:`Scan` (:func:`laserscan_msg`; rclpy's message is imported only when called, so this
module and the core stay ROS-free) and the bounded poll (:func:`wait_until`).
"""

from __future__ import annotations

import array
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.geometry import wrap_angle
from bt_nav.mission.local_services import (  # noqa: F401 - re-exported: tests script the evaluation service
    Handler,
    LocalFuture,
    LocalTriggerClient,
    TriggerRequest,
    TriggerResponse,
    TriggerType,
)
from bt_nav.mission.scan import Scan


@dataclass(frozen=True)
class Layout:
    """The metadata of a LaserScan: where the beams point and what ranges are valid."""

    num_beams: int
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float

    @property
    def angle_max(self) -> float:
        """Angle of the last beam."""
        return self.angle_min + (self.num_beams - 1) * self.angle_increment


LDS01 = Layout(360, 0.0, 2 * math.pi / 360, 0.12, 3.5)  # TurtleBot3: 0..2pi
RPLIDAR = Layout(640, -math.pi, 2 * math.pi / 640, 0.15, 12.0)  # TurtleBot4: -pi..pi
REVERSED = Layout(720, math.pi, -2 * math.pi / 720, 0.1, 8.0)  # clockwise sweep
FRONT_270 = Layout(1081, -3 * math.pi / 4, 3 * math.pi / 2 / 1080, 0.02, 30.0)  # partial field of view


def synthetic_scan(obstacles: Iterable[tuple[float, float]] = (), *, layout: Layout = LDS01,
                   width_deg: float = 12.0, background: float = math.inf) -> Scan:
    """A scan seeing each ``(angle_deg, distance)`` obstacle over ``width_deg``, ``background`` elsewhere.

    ``distance`` may be NaN or +-inf to build REP 117 cases.
    """
    angles = layout.angle_min + np.arange(layout.num_beams) * layout.angle_increment
    ranges = np.full(layout.num_beams, background, dtype=np.float64)
    for angle_deg, distance in obstacles:
        offset = np.abs(wrap_angle(angles - math.radians(angle_deg)))
        hit = offset <= math.radians(width_deg) / 2 + 1e-9
        if math.isnan(distance):
            ranges[hit] = math.nan
        else:
            ranges[hit] = np.fmin(ranges[hit], distance)
    return Scan(layout.angle_min, layout.angle_max, layout.angle_increment, layout.range_min,
                layout.range_max, ranges)


def scan_from_ranges(ranges: Sequence[float], *, angle_min: float = 0.0, angle_increment: float | None = None,
                     angle_max: float | None = None, range_min: float = 0.12, range_max: float = 3.5) -> Scan:
    """A scan with exactly these fields, valid or not (defaults: a TurtleBot3 LDS-01, 0..2pi CCW, one beam
    per range: ``angle_increment`` 2pi / len(ranges), ``angle_max`` the last beam's angle).

    The ranges are kept as float32, the type a LaserScan carries (an ``array('f')`` is taken without a copy).
    """
    n = len(ranges)
    increment = (2.0 * math.pi / max(n, 1)) if angle_increment is None else angle_increment
    last = float(angle_min + increment * max(n - 1, 0)) if angle_max is None else float(angle_max)
    return Scan(float(angle_min), last, float(increment), float(range_min), float(range_max),
                np.asarray(ranges, dtype=np.float32))


def front_scan(front: float = 3.0, rest: float = 3.0, *, beams: int = 360,
               increment: float | None = None) -> Scan:
    """A TurtleBot3-like scan (0..2pi, CCW): ``front`` within +-30 deg of ahead, ``rest`` elsewhere.

    The cone is computed from ``2pi / beams`` whatever ``increment`` says (an odd increment only changes
    where the message claims the beams point).
    """
    ranges = [front if abs(math.degrees(math.remainder(i * 2.0 * math.pi / beams, 2.0 * math.pi))) <= 30.0
              else rest for i in range(beams)]
    return scan_from_ranges(ranges, angle_increment=increment)


def laserscan_msg(scan: Scan, *, stamp: tuple[int, int] | None = None, intensities: Sequence[float] = (),
                  frame_id: str = "base_scan") -> Any:
    """The ``sensor_msgs/LaserScan`` carrying ``scan`` field for field (``stamp``: sec, nanosec).

    The one place a test or benchmark builds the message; ImportError when rclpy's messages are missing.
    """
    from sensor_msgs.msg import LaserScan

    msg = LaserScan()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.angle_min, msg.angle_max = float(scan.angle_min), float(scan.angle_max)
    msg.angle_increment = float(scan.angle_increment)
    msg.range_min, msg.range_max = float(scan.range_min), float(scan.range_max)
    msg.ranges = array.array("f", np.asarray(scan.ranges, dtype=np.float32).tobytes())
    msg.intensities = array.array("f", intensities)
    return msg


def wait_until(predicate: Callable[[], bool], timeout: float, what: str, details: Callable[[], str] = lambda: "",
               *, step: Callable[[], Any] | None = None, interval: float = 0.01) -> None:
    """Poll ``predicate`` until true; AssertionError after ``timeout`` wall seconds naming ``what`` and ``details()``.

    Between polls ``step`` is called (a spin, a resend) and then ``interval`` seconds are slept (0: none,
    for a step that waits by itself, such as ``spin_once`` with a timeout).
    """
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:.1f} s waiting for {what}\n{details()}")
        if step is not None:
            step()
        if interval > 0:
            time.sleep(interval)


class FakeClock:
    """Seconds that move only when a test says so."""

    def __init__(self, start: float = 0.0) -> None:
        self.now = start

    def __call__(self) -> float:
        return self.now

    def advance(self, dt: float) -> float:
        """Move forward (or back, to simulate a reset) and return the new time."""
        self.now += dt
        return self.now


@dataclass
class TickRecord:
    """What one tick decided."""

    tick: int
    time: float
    tip: str
    command: Command
    statuses: dict[str, str] = field(repr=False)
    yaw: float = 0.0


class TickHarness:
    """The real tree from ``trees/mission.xml``, ticked at ``dt`` on a fake clock.

    Every tick: the clock advances, the current synthetic scan is fed (unless ``feed_scans`` is off),
    perfect odometry integrates the previous command (unless ``feed_odom`` is off), the tree ticks, and
    a :class:`TickRecord` is kept.
    """

    def __init__(self, maneuver: str = "none", overrides: dict[str, Any] | None = None, *,
                 layout: Layout = LDS01, dt: float = 0.05, client: LocalTriggerClient | None = None,
                 events: Any = None) -> None:
        self.clock = FakeClock()
        self.client = client if client is not None else LocalTriggerClient(clock=self.clock)
        if self.client.clock is None:
            self.client.clock = self.clock
        settings = {"maneuver": maneuver, "random_seed": 7, **(overrides or {})}
        self.core = MissionCore(settings, clock=self.clock, evaluation_client=self.client, events=events)
        self.layout = layout
        self.dt = dt
        self.obstacles: list[tuple[float, float]] = []
        self.scan: Scan | None = synthetic_scan(layout=layout)
        self.feed_scans = True
        self.feed_odom = True
        self.yaw = 0.0
        self.x = self.y = 0.0  # odometry position, integrated from the commands like the yaw
        self.records: list[TickRecord] = []

    def see(self, *obstacles: tuple[float, float], **scan_kwargs: Any) -> None:
        """From the next tick on, the scan shows these ``(angle_deg, distance)`` obstacles."""
        self.obstacles = list(obstacles)
        self.scan = synthetic_scan(obstacles, layout=self.layout, **scan_kwargs)

    def arm(self, data: bool = True) -> tuple[bool, str]:
        """Call the arm service."""
        return self.core.request_arm(data)

    def tick(self, n: int = 1) -> TickRecord:
        """Run ``n`` ticks; returns the last record."""
        for _ in range(n):
            self.clock.advance(self.dt)
            last = self.core.last_command
            self.x += last.linear * self.dt * math.cos(self.yaw)
            self.y += last.linear * self.dt * math.sin(self.yaw)
            self.yaw = wrap_angle(self.yaw + last.angular * self.dt)
            if self.feed_scans and self.scan is not None:
                self.core.feed_scan(self.scan)
            if self.feed_odom:
                self.core.feed_odom(self.yaw, x=self.x, y=self.y)
            command = self.core.tick()
            self.records.append(TickRecord(self.core.ticks, self.clock.now, self.core.tip, command,
                                           self.core.statuses(), self.yaw))
        return self.records[-1]

    def run_until(self, predicate: Callable[[TickRecord], bool], limit: int = 2000) -> TickRecord:
        """Tick until ``predicate(record)`` holds; fails loudly after ``limit`` ticks."""
        for _ in range(limit):
            record = self.tick()
            if predicate(record):
                return record
        raise AssertionError(f"condition not met within {limit} ticks; last tip {self.records[-1].tip}")
