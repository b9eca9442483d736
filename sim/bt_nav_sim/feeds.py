"""The check-off judge's feeds from a recording: trigger readings from the robot's own LaserScans, and what the
recording says about itself (gaps, commands the robot did not follow). Pure: NumPy and the mission's scan module.

Why a second feed: in the simulator the judge casts its readings noise-free from ground truth
(:meth:`bt_nav_sim.checkoff_core.CheckoffJudge._read`). On a real TurtleBot3 there is no ground truth and no world
map; what there is, is the scans the robot recorded and its odometry. :class:`ScanReadings` turns each recorded
scan into the same :class:`bt_nav_sim.readings.Reading` (the whole reasonable-sector family, over *that scan's*
angles, so an LDS-02 with a different beam count every scan reads right), and the judge takes "the reading at a
pose's time" as the latest scan at or before it. The rules do not change; only where the readings come from.

Odometry is not ground truth: the wheels slip during a pivot and odometry drifts a few centimetres, so a feed of
odometry poses allows :data:`ODOMETRY_FORWARD_MOTION_MAX` of displacement during a turn (the ground-truth judge
keeps its ``forward_motion_max`` of 0.01 m). The commanded checks are the same for every feed.

A recording can contradict itself, and the judge must say so rather than judge through it:
:func:`gaps` finds where a topic fell silent (Wi-Fi), :func:`not_followed` where the robot's yaw did not do what its
commands asked (a person picked it up and turned it, or a turn stalled against an obstacle).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bt_nav.mission.scan import Scan, ScanError, beam_angles, clean_validated, validate_scan
from bt_nav_sim.readings import Reading, SectorFamily, SectorReader

#: m: displacement allowed during a turn when the poses are odometry (a pivot's wheel slip drifts it by a few cm
#: on a real TurtleBot3); the ground-truth judge keeps its own ``forward_motion_max``.
ODOMETRY_FORWARD_MOTION_MAX = 0.03
#: s: a scan older than this at a pose's time is not that pose's reading (a Wi-Fi gap: nothing is known there).
SCAN_MAX_AGE = 1.0


class ReadingSource(Protocol):
    """Where a judge takes its trigger readings when it does not cast them from a world."""

    def reading_at(self, t: float) -> Reading | None:
        """The readings at time ``t`` (None: none known then)."""
        ...


def usable_ranges(scan: Scan) -> np.ndarray:
    """A scan's ranges with every value that says nothing about an obstacle as +inf (nothing seen there): NaN,
    +-inf, 0 (the LDS-01's no return, and the LDS-02 publishes range_min 0) and anything outside [range_min,
    range_max] (REP 117's cleaning, :func:`bt_nav.mission.scan.clean_validated`, then the zeros and NaN dropped)."""
    clean = clean_validated(scan)
    clean[~(clean > 0.0)] = np.inf  # NaN (no information) and 0 (no return, or -inf's range_min of 0)
    return clean


@dataclass
class ScanReadings:
    """A :class:`ReadingSource` over recorded scans: the family's readings of each scan at its own angles, from the
    LiDAR's mount (``mount``: its (x, y) on the robot, from /tf when the recording has it), computed once per scan.

    Scans must be added in time order; a scan whose geometry cannot be trusted is skipped and counted.
    """

    family: SectorFamily
    half_width: float
    mount: tuple[float, float] = (0.0, 0.0)
    max_age: float = SCAN_MAX_AGE

    def __post_init__(self) -> None:
        self.t: list[float] = []
        self.readings: list[Reading] = []
        self.skipped = 0
        self._readers: dict[tuple[float, float, int], tuple[SectorReader, np.ndarray, np.ndarray]] = {}

    def add(self, t: float, scan: Scan) -> None:
        """One recorded scan at time ``t``; out-of-order and malformed scans are skipped."""
        if self.t and t <= self.t[-1]:
            self.skipped += 1
            return
        try:
            validate_scan(scan)
        except ScanError:
            self.skipped += 1
            return
        self.t.append(float(t))
        self.readings.append(self.read(scan))

    def read(self, scan: Scan) -> Reading:
        """The family's readings of one (valid) scan, and the distance to the first return in the swept path."""
        key = (float(scan.angle_min), float(scan.angle_increment), scan.num_beams)
        if key not in self._readers:
            if len(self._readers) > 256:  # an LDS-02 has a new layout every scan: keep the cache bounded
                self._readers.clear()
            angles = beam_angles(scan)
            self._readers[key] = (SectorReader(angles, self.family), np.cos(angles), np.sin(angles))
        reader, cos, sin = self._readers[key]
        r = usable_ranges(scan)
        with np.errstate(invalid="ignore"):
            along, across = r * cos + self.mount[0], np.abs(r * sin + self.mount[1])
        in_path = np.isfinite(r) & (along > 0.0) & (across <= self.half_width)
        return reader.read(r, float(along[in_path].min()) if in_path.any() else math.inf)

    def reading_at(self, t: float) -> Reading | None:
        """The latest scan's readings at or before ``t``; None before the first scan or after a gap of
        ``max_age``."""
        i = bisect.bisect_right(self.t, t + 1e-9) - 1
        if i < 0 or t - self.t[i] > self.max_age:
            return None
        return self.readings[i]


@dataclass(frozen=True)
class Gap:
    """A topic silent from ``start`` for ``length`` seconds (absolute times)."""

    topic: str
    start: float
    length: float

    @property
    def end(self) -> float:
        return self.start + self.length

    def text(self, t0: float) -> str:
        return f"no {self.topic} for {self.length:.1f} s from t={self.start - t0:.1f} s"


def gaps(topic: str, times: Sequence[float], floor: float = 1.0, periods: float = 5.0,
         within: tuple[float, float] | None = None) -> list[Gap]:
    """Where ``topic`` fell silent: consecutive messages further apart than ``floor`` s and ``periods`` times the
    topic's median period (a 5 Hz scan missing for 1 s is a gap; a 0.2 s hiccup is not). ``within``: also the
    silence from its start to the first message and from the last message to its end."""
    t = np.asarray(sorted(times), dtype=np.float64)
    if within is not None:
        a, b = within
        t = t[(t >= a) & (t <= b)]
        if t.size == 0:
            return [Gap(topic, a, b - a)] if b - a > floor else []
    if t.size < 2 and within is None:
        return []
    period = float(np.median(np.diff(t))) if t.size > 2 else 0.0
    limit = max(floor, periods * period)
    edges = np.concatenate(([within[0]], t, [within[1]])) if within is not None else t
    d = np.diff(edges)
    return [Gap(topic, float(edges[i]), float(d[i])) for i in np.flatnonzero(d > limit)]


@dataclass(frozen=True)
class Disobeyed:
    """An interval over which the yaw did not do what the commands asked (absolute times; rad/s and deg)."""

    start: float
    end: float
    commanded: float  # rad/s, the command in force
    turned_deg: float  # what the yaw did over the interval
    kind: str  # "turned the other way", "did not turn", "turned uncommanded"

    def text(self, t0: float) -> str:
        return (f"the robot did not follow its commands from t={self.start - t0:.1f} s to t={self.end - t0:.1f} s "
                f"(commanded {self.commanded:+.2f} rad/s, yaw {self.turned_deg:+.0f} deg: {self.kind}): "
                "handled or blocked")


def not_followed(pose_t: Sequence[float], uyaw: Sequence[float], commands: Sequence[tuple[float, float, float]],
                 *, settle: float = 0.5, hold: float = 1.0, min_rate: float = 0.2, stale: float = 1.0
                 ) -> list[Disobeyed]:
    """Intervals of at least ``hold`` s, ``settle`` s or more after a command changed, over which the yaw turned the
    other way than the command in force (|rate| >= ``min_rate``), turned less than a fifth of it while it asked for
    ``min_rate`` or more (stalled, held), or turned at ``min_rate`` or more with none commanded (a person turned it).
    ``uyaw`` is the unwrapped odometry yaw (rad) at ``pose_t``; ``commands`` (t, v, w) in time order. A command
    older than ``stale`` s is not taken as in force (the commands fell silent: a gap says so, not this)."""
    if len(pose_t) < 3 or not commands:
        return []
    t, yaw = np.asarray(pose_t, dtype=np.float64), np.asarray(uyaw, dtype=np.float64)
    times = [c[0] for c in commands]
    since = []  # when the command in force at each command began (a closed loop's varying rate is one command)
    for k, (tk, _, w) in enumerate(commands):
        since.append(since[-1] if k and _alike(w, commands[k - 1][2]) else tk)
    bad: list[tuple[float, float, float, str]] = []  # (t0, t1, w, kind) of sample pairs
    for i in range(1, t.size):
        a, b = t[i - 1], t[i]
        k = bisect.bisect_right(times, a) - 1
        if k < 0 or a - since[k] < settle or a - times[k] > stale or b - a <= 0 or b - a > 0.5:
            continue
        w = commands[k][2]
        nxt = times[k + 1] if k + 1 < len(times) else math.inf
        if nxt <= b and not _alike(commands[k + 1][2], w):  # the command changes within the pair
            continue
        rate = (yaw[i] - yaw[i - 1]) / (b - a)
        kind = _disobedience(w, rate, min_rate)
        if kind:
            bad.append((a, b, w, kind))
    return _runs(bad, t, yaw, hold)


def _alike(w1: float, w2: float) -> bool:
    """Two commanded rates that ask for the same thing: both (almost) zero, or the same direction within a factor of
    two (a node's P-controller varies its rate every message; the robot need not settle anew for each)."""
    if abs(w1) < 1e-3 or abs(w2) < 1e-3:
        return abs(w1) < 1e-3 and abs(w2) < 1e-3
    return w1 * w2 > 0 and 0.5 <= w1 / w2 <= 2.0


def _disobedience(w: float, rate: float, min_rate: float) -> str:
    """How a yaw rate disobeys a commanded one (empty: it does not)."""
    if abs(w) >= min_rate and rate * w < 0 and abs(rate) >= min_rate:
        return "turned the other way"
    if abs(w) >= min_rate and rate * w >= 0 and abs(rate) < 0.2 * abs(w):
        return "did not turn"
    if abs(w) < 1e-3 and abs(rate) >= min_rate:
        return "turned uncommanded"
    return ""


def _runs(bad: list[tuple[float, float, float, str]], t: np.ndarray, yaw: np.ndarray, hold: float) -> list[Disobeyed]:
    """Consecutive disobeying pairs of one kind and command joined into intervals; those of ``hold`` s or more."""
    out: list[Disobeyed] = []
    run: list[tuple[float, float, float, str]] = []
    for item in [*bad, None]:
        if run and (item is None or item[0] > run[-1][1] + 1e-9 or item[2:] != run[-1][2:]):
            start, end = run[0][0], run[-1][1]
            if end - start >= hold:
                turned = float(np.interp(end, t, yaw) - np.interp(start, t, yaw))
                out.append(Disobeyed(start, end, run[0][2], math.degrees(turned), run[0][3]))
            run = []
        if item is not None:
            run.append(item)
    return out
