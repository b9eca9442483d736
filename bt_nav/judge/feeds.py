"""The check-off judge's feed protocol (:class:`TriggerFeed`: a trigger reading per pose sample), and its feeds from a
recording: trigger readings from the robot's own LaserScans, and what the recording says about itself (gaps, commands
the robot did not follow). Pure: NumPy and the mission's scan module.

Why a second feed: in the simulator the readings are cast noise-free from ground truth in its world (the simulator's
truth feed, ``bt_nav_sim.truth``, built on :class:`TriggerFeed`). On a real TurtleBot3 there is no ground truth and no
world map; what there is, is the scans the robot recorded and its odometry. :class:`ScanReadings` turns each recorded
scan into the same :class:`bt_nav.judge.readings.Reading` (the whole reasonable-sector family, over *that scan's*
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

from bt_nav.judge.readings import Reading, SectorFamily, SectorReader
from bt_nav.mission.scan import Scan, ScanError, beam_angles, clean_validated, validate_scan

#: m: displacement allowed during a turn when the poses are odometry (a pivot's wheel slip drifts it by a few cm
#: on a real TurtleBot3); the ground-truth judge keeps its own ``forward_motion_max``.
ODOMETRY_FORWARD_MOTION_MAX = 0.03
#: s: a scan older than this at a pose's time is not that pose's reading (a Wi-Fi gap: nothing is known there).
SCAN_MAX_AGE = 1.0


class TriggerFeed(Protocol):
    """Where a check-off judge takes the trigger reading of each of its pose samples, by sample index: the simulator's
    truth feed (cast in its world from the true pose) or :class:`SourceReadings` (a robot's scans). The judge owns no
    world; its driver hands it a feed."""

    def add(self, x: float, y: float, yaw: float, t: float, armed: bool) -> None:
        """The next pose sample (in order), and whether the robot was armed then."""
        ...

    def at(self, k: int) -> Reading | None:
        """Sample ``k``'s reading while armed (None: not armed then, or no reading)."""
        ...

    def cast(self, k: int) -> Reading | None:
        """Sample ``k``'s reading though the robot was not armed then (an episode that starts at the arming may have
        been decided on a scan from just before it)."""
        ...

    def on_walkers(self, t: float, circles: object) -> None:
        """Where the people walking were at ``t`` (the simulator's; a robot's scans see people themselves)."""
        ...


class ReadingSource(Protocol):
    """Readings by time (a robot's scans): what :class:`SourceReadings` reads at each pose sample."""

    def reading_at(self, t: float) -> Reading | None:
        """The readings at time ``t`` (None: none known then)."""
        ...


class SourceReadings:
    """A :class:`TriggerFeed` over a :class:`ReadingSource`: an armed sample's reading is the source's at its time,
    read as the sample comes; a sample from before the arming is read only when an episode asks (:meth:`cast`)."""

    def __init__(self, source: ReadingSource) -> None:
        self.source = source
        self._t: list[float] = []
        self._armed: list[bool] = []
        self._readings: list[Reading | None] = []

    def add(self, x: float, y: float, yaw: float, t: float, armed: bool) -> None:
        self._t.append(t)
        self._armed.append(armed)
        self._readings.append(self.source.reading_at(t) if armed else None)

    def at(self, k: int) -> Reading | None:
        return self._readings[k]

    def cast(self, k: int) -> Reading | None:
        return self._readings[k] if self._armed[k] else self.source.reading_at(self._t[k])

    def on_walkers(self, t: float, circles: object) -> None:
        """Nothing: a robot's scans see the people walking themselves."""


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


#: rad/s: the fastest a TurtleBot3 base turns (the Burger's 2.84 rad/s): a yaw faster than it was not the motors'.
BASE_MAX_YAW_RATE = 2.84
#: s: the yaw rate is read over this span (the pose's jitter at 20 Hz would break a stall into pieces).
RATE_SPAN = 0.5
#: deg: a push turns the robot at least this much (a wobble of the odometry is not a hand).
PUSH_MIN_DEG = 5.0
#: m/s and m: a translation without a forward command at least this fast and this long is the robot carried.
CARRY_SPEED, CARRY_MIN = 0.05, 0.05

STUCK, HAND, CARRIED = "stuck", "moved by hand", "carried"


@dataclass(frozen=True)
class Disobeyed:
    """An interval over which the robot did not do what its commands asked (absolute times): ``kind`` is
    :data:`STUCK` (turned less than half the commanded rate), :data:`HAND` (turned the other way, faster than twice
    the command or than the base can, or with no turn commanded) or :data:`CARRIED` (moved with no forward command);
    ``how`` says which."""

    start: float
    end: float
    commanded: float  # rad/s (m/s for CARRIED), the command in force
    turned_deg: float  # what the yaw did over the interval
    kind: str
    how: str = ""
    moved_m: float = 0.0

    def what(self) -> str:
        """What the robot did instead, without when (``9 deg in 6.5 s while commanded -0.22 rad/s``)."""
        span = self.end - self.start
        if self.kind == STUCK:
            return f"{abs(self.turned_deg):.0f} deg in {span:.1f} s while commanded {self.commanded:+.2f} rad/s"
        if self.kind == CARRIED:
            return f"{self.moved_m:.2f} m in {span:.1f} s {self.how}"
        return f"{self.turned_deg:+.0f} deg in {span:.1f} s {self.how}"

    def text(self, t0: float) -> str:
        """The event and when (``stuck from t=20.2 s: 9 deg in 6.5 s while commanded -0.22 rad/s``)."""
        return f"{self.kind} from t={self.start - t0:.1f} s: {self.what()}"


def story(events: Sequence[Disobeyed], t0: float) -> str:
    """Several events in order, as one sentence: the first with when, each next with ``then`` (the turn the issue
    names: ``stuck from t=20.2 s: ...; then moved by hand at t=26.9 s: +48 deg in 0.6 s against the command``)."""
    parts = [events[0].text(t0)] if events else []
    parts += [f"then {d.kind} at t={d.start - t0:.1f} s: {d.what()}" for d in events[1:]]
    return "; ".join(parts)


def not_followed(pose_t: Sequence[float], uyaw: Sequence[float], commands: Sequence[tuple[float, float, float]],
                 *, xy: Sequence[tuple[float, float]] | None = None, settle: float = 0.5, hold: float = 1.0,
                 min_rate: float = 0.2, stale: float = 1.0) -> list[Disobeyed]:
    """Where the robot did not do what its commands asked, ``settle`` s or more after a command changed (the base
    takes that long to follow): stuck (turning less than half the commanded rate, for ``hold`` s or more, while
    asked for ``min_rate`` or more), moved by hand (turning the other way at ``min_rate`` or more, faster than twice
    the command or :data:`BASE_MAX_YAW_RATE`, or with no turn commanded; :data:`PUSH_MIN_DEG` or more), carried
    (``xy`` given: moving :data:`CARRY_SPEED` or faster with no forward command). ``uyaw`` is the unwrapped pose yaw
    (rad) at ``pose_t``; ``commands`` (t, v, w) in time order. A command older than ``stale`` s is not in force
    (the commands fell silent: a gap says so, not this). Read it on a whole recording: a window of it then sets the
    same intervals apart whatever its edges."""
    if len(pose_t) < 3 or not commands:
        return []
    t, yaw = np.asarray(pose_t, dtype=np.float64), np.asarray(uyaw, dtype=np.float64)
    pos = None if xy is None else np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    times = [c[0] for c in commands]
    blocks = _blocks(commands)
    bad: list[tuple[float, float, float, str, str]] = []  # (t0, t1, command, kind, how) of sample pairs
    for i in range(1, t.size):
        a, b = t[i - 1], t[i]
        k = bisect.bisect_right(times, a) - 1
        if k < 0 or a - times[k] > stale or b - a <= 0 or b - a > 0.5:
            continue
        if k + 1 < len(times) and times[k + 1] - a > stale or k + 1 == len(times) and b - times[k] > stale:
            continue  # the commands fall silent here: what the robot was sent is not known (a gap)
        since, until = blocks[k]
        if a - since < settle or until <= b + 0.5 * RATE_SPAN:  # the base still following, or about to change
            continue
        mid = 0.5 * (a + b)
        lo, hi = max(t[0], mid - 0.5 * RATE_SPAN), min(t[-1], mid + 0.5 * RATE_SPAN)
        rate = (np.interp(hi, t, yaw) - np.interp(lo, t, yaw)) / max(hi - lo, 1e-9)
        v, w = commands[k][1], commands[k][2]
        peak = max(abs(c[2]) for c in commands[min(k, bisect.bisect_left(times, a - settle)):k + 1])
        kind, how = _disobedience(w, peak, float(rate), min_rate)
        if not kind and pos is not None and abs(v) < 1e-3:
            speed = float(np.hypot(*(pos[i] - pos[i - 1]))) / (b - a)
            kind, how, w = (CARRIED, "with no forward command", v) if speed >= CARRY_SPEED else ("", "", w)
        if kind:
            bad.append((a, b, w, kind, how))
    return _runs(bad, t, yaw, pos, hold)


def _blocks(commands: Sequence[tuple[float, float, float]]) -> list[tuple[float, float]]:
    """For each command, when the command in force then began and when the next unlike one came (a closed loop's
    varying rate is one command: :func:`_alike`)."""
    since: list[float] = []
    for k, (tk, _, w) in enumerate(commands):
        since.append(since[-1] if k and _alike(w, commands[k - 1][2]) else tk)
    until = [math.inf] * len(commands)
    for k in range(len(commands) - 2, -1, -1):
        until[k] = until[k + 1] if since[k + 1] == since[k] else commands[k + 1][0]
    return list(zip(since, until, strict=True))


def _alike(w1: float, w2: float) -> bool:
    """Two commanded rates that ask for the same thing: both (almost) zero, or the same direction within a factor of
    two (a node's P-controller varies its rate every message; the robot need not settle anew for each)."""
    if abs(w1) < 1e-3 or abs(w2) < 1e-3:
        return abs(w1) < 1e-3 and abs(w2) < 1e-3
    return w1 * w2 > 0 and 0.5 <= w1 / w2 <= 2.0


def _disobedience(w: float, peak: float, rate: float, min_rate: float) -> tuple[str, str]:
    """How a yaw rate disobeys the command in force ``w`` (``peak``: the largest commanded in the last ``settle``
    s, which the base may still be turning at); empty when it does not."""
    if abs(w) >= min_rate and rate * w < 0 and abs(rate) >= min_rate:
        return HAND, "against the command"
    if abs(w) >= min_rate and rate * math.copysign(1.0, w) < 0.5 * abs(w):
        return STUCK, ""  # slower than half the command, or backing off too slowly to be a hand
    if abs(rate) > BASE_MAX_YAW_RATE:
        return HAND, f"faster than the base's {BASE_MAX_YAW_RATE:g} rad/s"
    if peak < 1e-3 and abs(rate) >= min_rate:
        return HAND, "with no turn commanded"
    if abs(w) >= 1e-3 and rate * w > 0 and abs(rate) > max(2.0 * peak, peak + min_rate):
        return HAND, f"faster than twice the command ({w:+.2f} rad/s)"
    return "", ""


def _runs(bad: list[tuple[float, float, float, str, str]], t: np.ndarray, yaw: np.ndarray, pos: np.ndarray | None,
          hold: float) -> list[Disobeyed]:
    """Consecutive disobeying pairs of one kind joined into intervals (a hiccup of up to a rate span between two of
    the same kind is one interval); those that last (a stall, ``hold`` s) or count (a push, a carry)."""
    out: list[Disobeyed] = []
    run: list[tuple[float, float, float, str, str]] = []
    for item in [*bad, None]:
        if run and (item is None or item[0] > run[-1][1] + RATE_SPAN or item[3:] != run[-1][3:]):
            start, end, (w, kind, how) = run[0][0], run[-1][1], run[0][2:]
            turned = math.degrees(float(np.interp(end, t, yaw) - np.interp(start, t, yaw)))
            moved = 0.0 if pos is None else float(np.hypot(*(np.interp(end, t, p) - np.interp(start, t, p)
                                                             for p in pos.T)))
            keep = {STUCK: end - start >= hold, HAND: abs(turned) >= PUSH_MIN_DEG, CARRIED: moved >= CARRY_MIN}[kind]
            if keep:
                out.append(Disobeyed(start, end, w, turned, kind, how, moved))
            run = []
        if item is not None:
            run.append(item)
    return out
