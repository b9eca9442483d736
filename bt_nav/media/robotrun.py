"""A robot's run as a film or a page shows it: a bag with no ground truth and no world file (a real TurtleBot's, or
one that says it was simulated), read by :func:`bt_nav.media.robotbag.read_robot_bag`, with where its data came
from and, given the maneuver, the check-off's lines at the times they were decided.

Why its own module: :mod:`bt_nav.media.bagread` is the simulator's bags (ground truth, one scan geometry, sim
time); a robot's bag has only its odometry and its own scans, with an LDS-02's beam count changing scan to scan.
So the picture of the room is the scans laid out from the odometry (:meth:`RobotRun.scan_points`), and the
check-off's lines come from the same judge as ``bt-nav checkoff --bag`` (:func:`bt_nav.judge.recorded.judge_recording`).

Where the data came from, said on every frame (:attr:`RobotRun.source`): :data:`REAL_LABEL`, or
:data:`SYNTHETIC_LABEL` for a bag with a ``/synthetic`` topic (tests/media/robotsynth.py writes one),
:data:`bt_nav.media.console.SIM_LABEL` for a bag bt_nav's simulator recorded (it has a ground truth topic),
:data:`GAZEBO_LABEL` for Gazebo's (its /gazebo or /gz topics), :data:`CLOCK_LABEL` for any other bag with a /clock
(simulated time: a robot's own graph has none). Only a bag with none of these is called a real robot's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.judge.recorded import Recording
from bt_nav.media.bag import TRUTH
from bt_nav.media.console import SIM_LABEL

REAL_LABEL = "real robot bag"
SYNTHETIC_LABEL = "simulated bag (its /synthetic topic says so): not a real robot"
GAZEBO_LABEL = "simulated bag (Gazebo: its /gazebo or /gz topics say so): not a real robot"
CLOCK_LABEL = "bag on simulated time (it has /clock): not known to be a real robot"
#: The time base of every time a robot's film shows.
ROBOT_TIME_BASE = "s since the bag's first /odom, /scan or /cmd_vel message"
#: s: a command older than this is not the node's current one (a lab node sends at 10 Hz or so; a Wi-Fi gap or a
#: node that stopped sending leaves the last one standing): the caption then says how long none has come.
COMMAND_STALE = 0.5
#: The kinds of :class:`Mark` after which the odometry no longer places the scans in the room (the robot was moved
#: by something its wheels did not feel): the film stops adding them to its picture of the room.
HANDLED = ("moved by hand", "carried")


def source_label(types: dict[str, str], synthetic: str | None) -> str:
    """Where a bag's data came from, in the words every frame shows (see the module docstring)."""
    if synthetic is not None:
        return SYNTHETIC_LABEL
    if any(topic.endswith(TRUTH) for topic in types):
        return SIM_LABEL
    if any(topic.startswith(("/gazebo/", "/gz/")) for topic in types):
        return GAZEBO_LABEL
    if "/clock" in types:  # a robot's own graph has no /clock; a simulator's does
        return CLOCK_LABEL
    return REAL_LABEL


def is_robot_bag(path: str | Path) -> bool:
    """True for a bag with no ground truth (a robot's): filmed from its odometry; False for bt_nav's simulator bags
    and for what cannot be opened here (:func:`bt_nav.media.bagread.read_bag` then says why)."""
    from bt_nav.media.robotbag import bag_topics

    try:
        types = bag_topics(path)
    except Exception:  # noqa: BLE001 - not readable this way: the simulator's reader reports it
        return False
    return bool(types) and not any(topic.endswith(TRUTH) for topic in types)


@dataclass
class TimedLine:
    """One line of the check-off at the time the judge decided it (absolute, on the recording's clock)."""

    t: float
    text: str


@dataclass(frozen=True)
class Mark:
    """An interval the judge set apart (its verdict's ``events``: a silent topic, the robot stuck, moved by hand or
    carried), absolute times on the recording's clock, and the judge's words for it."""

    kind: str
    start: float
    end: float
    text: str


@dataclass
class RobotRun:
    """A robot's recording, where it came from, and the check-off's lines (none without a maneuver)."""

    path: Path
    rec: Recording
    source: str
    maneuver: str | None = None
    verdict: dict[str, Any] | None = None
    lines: list[TimedLine] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    marks: list[Mark] = field(default_factory=list)
    report: list[str] = field(default_factory=list)  # the verdict's lines in the terminal's order

    @property
    def origin(self) -> float:
        return self.rec.start

    @property
    def end(self) -> float:
        return self.rec.end

    def pose_at(self, t: float) -> tuple[float, float, float] | None:
        """The odometry pose (x, y, yaw) at ``t``, interpolated (yaw unwrapped); None before the first."""
        odom = self.rec.odom
        if not odom or t < odom[0][0]:
            return None
        arr = self._odom_array()
        if t >= arr[-1, 0]:
            return float(arr[-1, 1]), float(arr[-1, 2]), float(odom[-1][3])
        yaw = float(np.interp(t, arr[:, 0], arr[:, 3]))
        return float(np.interp(t, arr[:, 0], arr[:, 1])), float(np.interp(t, arr[:, 0], arr[:, 2])), \
            math.remainder(yaw, math.tau)

    def _odom_array(self) -> np.ndarray:
        cached = getattr(self, "_odom_cache", None)
        if cached is None:
            cached = np.asarray(self.rec.odom, dtype=np.float64).reshape(-1, 4)
            cached[:, 3] = np.unwrap(cached[:, 3])
            self._odom_cache = cached
        return cached

    def path_xy(self) -> np.ndarray:
        """(n, 3): t, x, y of the odometry."""
        return self._odom_array()[:, :3]

    def scan_points(self, k: int) -> tuple[float, np.ndarray, np.ndarray]:
        """Scan ``k``'s returns in the odometry frame: (its time, x, y), placed from the odometry pose at the scan's
        own time and the LiDAR's mount (misses, NaN and out-of-range beams dropped)."""
        t, scan = self.rec.scans[k]
        pose = self.pose_at(t)
        if pose is None:
            return t, np.zeros(0), np.zeros(0)
        x, y, yaw = pose
        r = np.asarray(scan.ranges, dtype=np.float64)
        a = scan.angle_min + scan.angle_increment * np.arange(r.size)
        ok = np.isfinite(r) & (r >= scan.range_min) & (r <= scan.range_max)
        mx, my = self.rec.mount
        lx, ly = mx + r[ok] * np.cos(a[ok]), my + r[ok] * np.sin(a[ok])
        c, s = math.cos(yaw), math.sin(yaw)
        return t, x + c * lx - s * ly, y + s * lx + c * ly

    def command_at(self, t: float) -> tuple[float, float] | None:
        """The latest command (v, w) at or before ``t``; None before the first."""
        latest = self._latest_command(t)
        return (latest[1], latest[2]) if latest else None

    def _latest_command(self, t: float) -> tuple[float, float, float] | None:
        cmds = self.rec.commands
        k = int(np.searchsorted([c[0] for c in cmds], t, side="right")) - 1
        return cmds[k] if k >= 0 else None

    def current_command(self, t: float) -> tuple[float, float] | None:
        """The command in force at ``t``: the latest, if not older than :data:`COMMAND_STALE` s; else None."""
        latest = self._latest_command(t)
        return (latest[1], latest[2]) if latest and t - latest[0] <= COMMAND_STALE else None

    def command_words(self, t: float) -> str:
        """The caption's command: the current one, or how long none has come (and the last one, which a base may
        still be executing)."""
        latest = self._latest_command(t)
        if latest is None:
            return "no command yet"
        ct, v, w = latest
        said = f"v {v:+.2f} m/s  w {w:+.2f} rad/s"
        return f"cmd {said}" if t - ct <= COMMAND_STALE else f"no command for {t - ct:.1f} s (last: {said})"

    def marks_at(self, t: float) -> list[Mark]:
        """The intervals set apart that are happening at ``t``."""
        return [m for m in self.marks if m.start <= t <= m.end]

    @property
    def room_until(self) -> float | None:
        """Until when the scans are laid out into the room: the start of the first :data:`HANDLED` mark (None:
        the whole run)."""
        return min((m.start for m in self.marks if m.kind in HANDLED), default=None)

    def lines_at(self, t: float) -> list[str]:
        """The check-off's lines decided by ``t``, each with its time on the film's time base."""
        return [f"[{line.t - self.origin:6.1f}] {line.text}" for line in self.lines if line.t <= t + 1e-9]


def checkoff_timeline(res: dict[str, Any]) -> list[TimedLine]:
    """The verdict's lines (:func:`bt_nav.judge.recorded.report_lines`) at the times they were decided: each
    maneuver's line (judged, or why not) when its turn settled, each data line when its interval ended, the rest (the
    static checks, the count, what was not judged, the overall verdict) at the window's end. Absolute times (the
    verdict's ``feed.t0`` plus its own)."""
    from bt_nav.judge.recorded import report_lines

    t0 = float(res["feed"]["t0"])
    end = t0 + float(res["feed"]["window"][1])  # the window's times are on the report's one time zero
    when: dict[str, float] = {}
    for number, e in enumerate(res["maneuvers"], 1):
        when[f"maneuver {number}"] = t0 + float(e.get("settled", e["t"]))
    for event in res.get("events", []):  # a data line when its interval is over (it is known then)
        when[f"data: {event['text']}"] = min(end, t0 + float(event["end"]))
    out = []
    for line in report_lines(res):
        name = line if line.startswith("data: ") else line.split(" (", 1)[0].split(":", 1)[0]
        out.append(TimedLine(when.get(name, end), line))
    out.sort(key=lambda line: line.t)
    return out


def load_robot_run(path: str | Path, maneuver: str | None = None) -> RobotRun:
    """Read a robot's bag and, given the maneuver, judge it. BagError: unreadable (one line)."""
    from bt_nav.judge.checkoff_core import CheckoffConfig
    from bt_nav.judge.recorded import judge_recording, report_lines
    from bt_nav.media.robotbag import read_robot_bag

    about: dict[str, Any] = {}
    rec = read_robot_bag(path, about=about)
    run = RobotRun(Path(path), rec, source_label(about.get("types", {}), about.get("synthetic")), maneuver)
    if maneuver is None:
        run.notes.append("no check-off lines: give --maneuver X (or --node FILE) to judge the run")
        return run
    try:
        run.verdict = judge_recording(rec, CheckoffConfig(maneuver=maneuver))
    except ValueError as exc:
        run.notes.append(f"no check-off lines: {exc}")
        return run
    run.lines = checkoff_timeline(run.verdict)
    run.report = report_lines(run.verdict)
    t0 = float(run.verdict["feed"]["t0"])
    run.marks = [Mark(e["kind"], t0 + float(e["start"]), t0 + float(e["end"]), e["text"])
                 for e in run.verdict.get("events", [])]
    return run
