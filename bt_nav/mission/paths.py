"""Free paths: how far the robot's whole width could drive along each candidate heading, from one scan.

A cone ("the nearest beam within +-20 deg") is a poor model of what lies ahead of a robot with a width:
far away the cone is much wider than the robot, so it turns away from obstacles it would pass; close by
it is narrower, so an obstacle at the robot's shoulder is not "ahead" until the disk touches it. The swept
corridor of the robot's width is what matters. For heading ``phi`` (robot frame, + is left) and a scan
point at (x, y), the point is in the corridor when its lateral offset ``l = -x sin(phi) + y cos(phi)`` is
smaller than the half width ``w``; the robot's front then touches it after travelling
``a - sqrt(w^2 - l^2)`` along the heading, where ``a = x cos(phi) + y sin(phi)``. The free path of a
heading is the smallest such distance (or ``horizon`` when nothing is in the way).

Beams without information (NaN after REP 117) are ignored: the cones' ``min_valid_beams`` rule is what
stops a blind robot, and a few dropped beams must not make a clear corridor look blocked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from bt_nav.mission.scan import Scan, beam_trig, clean_ranges

#: Candidate headings, robot frame: -90 .. +90 deg every 5 deg (0 is straight ahead, index 18).
HEADINGS = np.radians(np.arange(-90.0, 90.0 + 1e-9, 5.0))
#: m of free path a heading must gain per radian of turn to be preferred (turning costs time or speed).
TURN_COST = 0.25
#: Neighbouring headings on each side (5 deg apart) whose free path a heading is judged by: 1 = +-5 deg.
EDGE_HEADINGS = 1


def neighbour_min(values: np.ndarray, edge: int) -> np.ndarray:
    """The least of each value and its ``edge`` neighbours on either side; the array's own ends are not
    obstacles (a window running off an end sees only what is inside)."""
    out = values.copy()
    for k in range(1, min(edge, len(values) - 1) + 1):
        np.minimum(out[k:], values[:-k], out=out[k:])
        np.minimum(out[:-k], values[k:], out=out[:-k])
    return out


@dataclass(frozen=True, slots=True, eq=False)
class FreePaths:
    """Free travel (m) along each of ``headings`` (rad), capped at the horizon it was computed with.

    Its arrays are not changed after it is made (one per scan), so :meth:`steer` keeps its answers: the tree ticks
    twice or more per scan, and the motion leaves ask the same questions on every tick.
    """

    headings: np.ndarray
    free: np.ndarray
    _answers: dict[tuple[float, int, float, int], float | None] = field(default_factory=dict, repr=False)
    _along: dict[float, float] = field(default_factory=dict, repr=False)

    @property
    def ahead(self) -> float:
        """Free travel straight ahead."""
        return self.along(0.0)

    def along(self, heading: float) -> float:
        """Free travel along ``heading`` (rad; interpolated between the candidate headings). The guards ask
        it of the same few headings on every tick between two scans, so answers are kept."""
        answer = self._along.get(heading)
        if answer is None:
            if len(self._along) >= 64:  # a turning robot asks of ever new headings: keep it bounded
                self._along.clear()
            answer = self._along[heading] = float(np.interp(heading, self.headings, self.free))
        return answer

    def steer(self, need: float, side: int = 0, turn_cost: float = TURN_COST,
              edge: int = EDGE_HEADINGS) -> float | None:
        """The heading to steer for (rad): clear for ``need`` metres, little turning, not grazing anything.

        A heading is judged by the least free path within ``edge`` neighbouring headings on either side
        (so one that grazes an obstacle is judged by the obstacle, and in a corridor the middle is best).
        Of the headings judged clear for ``need``, the one with the most free path less ``turn_cost``
        metres per radian of turn wins; ties go to the smaller turn, then left. ``side`` +1 / -1 keeps
        to left / right turns (straight ahead included). None when no heading is clear for ``need``.
        """
        key = (need, side, turn_cost, edge)
        if key in self._answers:
            return self._answers[key]
        h = self.headings
        safe = neighbour_min(self.free, edge)
        usable = safe >= need
        if side:
            usable &= side * h >= 0.0
        answer = None
        if usable.any():
            score = np.where(usable, safe - turn_cost * np.abs(h) - 1e-9 * np.abs(h) + 1e-12 * h, -np.inf)
            answer = float(h[int(np.argmax(score))])
        if len(self._answers) >= 64:  # the needs are parameters: a few; a constant FreePaths must not grow forever
            self._answers.clear()
        self._answers[key] = answer
        return answer

    def roomiest(self, side: int) -> float:
        """The heading with the most free path on one side (+1 left, -1 right; never straight ahead: the
        caller wants to turn); of equal ones the widest turn."""
        h = self.headings
        score = np.where(side * h > 0.0, self.free + 1e-9 * np.abs(h), -np.inf)
        return float(h[int(np.argmax(score))])

    def side_room(self, side: int) -> float:
        """The most free path among the headings on one side (+1 left, -1 right, 0 excluded)."""
        mask = side * self.headings > 0
        return float(self.free[mask].max()) if mask.any() else 0.0


@lru_cache(maxsize=16)
def _trig(headings: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    h = np.asarray(headings)
    return np.cos(h)[:, None], np.sin(h)[:, None]


_HEADINGS_TRIG = _trig(tuple(float(h) for h in HEADINGS))


def free_paths(scan: Scan, half_width: float, horizon: float, headings: np.ndarray = HEADINGS) -> FreePaths:
    """The free path along every heading for a robot of ``half_width`` (see the module docstring).

    Raises:
        ScanError: if the scan is malformed.
    """
    return free_paths_from_clean(scan, clean_ranges(scan), half_width, horizon, headings)


def free_paths_from_clean(scan: Scan, ranges: np.ndarray, half_width: float, horizon: float,
                          headings: np.ndarray = HEADINGS, mount: tuple[float, float] = (0.0, 0.0)) -> FreePaths:
    """:func:`free_paths` from the scan's cleaned ranges (:func:`~bt_nav.mission.scan.clean_validated`; the
    caller has validated the scan), so one cleaning serves the cones and the paths.

    The same arithmetic in the same order as the plain formula (so the same bits), in place where it
    can be: per scan only the beams near enough count, and their directions come from the per-layout
    cache (:func:`~bt_nav.mission.scan.beam_trig`).

    ``mount`` is where the LiDAR sits in the robot's frame (forward, left; m): the corridor is the body's, so
    a scanner mounted ahead of the centre sees its points that much further forward of the body's centre.
    """
    cos_b, sin_b = beam_trig(scan)
    mount_x, mount_y = float(mount[0]), float(mount[1])
    if mount_x or mount_y:
        return _free_paths_mounted(ranges, cos_b, sin_b, mount_x, mount_y, half_width, horizon, headings)
    x_all = ranges * cos_b
    # Near enough (False for NaN and +inf; -inf is range_min after cleaning), and not behind the robot by
    # more than its half width: a point in a corridor of a heading within +-90 deg has x > -half_width,
    # so beams further behind never count (the slack keeps rounding on the safe side).
    near = (ranges < horizon + half_width) & (x_all > -half_width - 1e-9)
    if not near.any():
        return FreePaths(headings, np.full(headings.shape, float(horizon)))
    return _corridor_free(x_all[near], ranges[near] * sin_b[near], half_width, horizon, headings)


def _free_paths_mounted(ranges: np.ndarray, cos_b: np.ndarray, sin_b: np.ndarray, mount_x: float, mount_y: float,
                        half_width: float, horizon: float, headings: np.ndarray) -> FreePaths:
    """Free paths of a LiDAR mounted at (``mount_x``, ``mount_y``): its points moved into the body's frame."""
    with np.errstate(invalid="ignore"):  # inf * 0 for a no-return beam along an axis: NaN, never near
        x_all = ranges * cos_b + mount_x
        y_all = ranges * sin_b + mount_y
    near = (np.hypot(x_all, y_all) < horizon + half_width) & (x_all > -half_width - 1e-9)
    if not near.any():
        return FreePaths(headings, np.full(headings.shape, float(horizon)))
    return _corridor_free(x_all[near], y_all[near], half_width, horizon, headings)


def _corridor_free(x: np.ndarray, y: np.ndarray, half_width: float, horizon: float,
                   headings: np.ndarray) -> FreePaths:
    """The free path along each heading among the points (x, y) of the robot's frame (module docstring)."""
    cos_h, sin_h = _HEADINGS_TRIG if headings is HEADINGS else _trig(tuple(float(h) for h in headings))
    along = x * cos_h
    along += y * sin_h
    lateral = y * cos_h
    lateral -= x * sin_h
    outside = np.abs(lateral) >= half_width  # beside the corridor ...
    outside |= along <= 0.0  # ... or behind (x and y are finite: the near test dropped NaN and inf)
    np.multiply(lateral, lateral, out=lateral)
    np.subtract(half_width * half_width, lateral, out=lateral)  # >= 0 inside: |l| < w gives l * l <= w * w
    np.sqrt(lateral, out=lateral, where=~outside)  # outside stays negative: overwritten below
    along -= lateral  # the reach
    np.copyto(along, math.inf, where=outside)
    free = along.min(axis=1)
    return FreePaths(headings, np.clip(free, 0.0, float(horizon), out=free))
