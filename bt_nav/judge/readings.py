"""The lab's trigger readings as a *family*: every reasonable way a student may read "front", "left" and "right".

The lab sheet names its sectors ("Obstacle < 0.5m (Front)", "Left AND Right") but gives them no width, and its
C reads "< 0.3 m (front)" while its AEB brakes at ``safety_distance``. A right node may read its front over
+-5 deg or +-30 deg, its sides centred anywhere from 60 to 110 deg, and pivot at the sheet's 0.3 m or where its AEB
braked. A judge that picks one of these readings fails the nodes that picked another. So the check-off judges
against the whole family, and which way a rule leans depends on what it accuses the node of:

- **"its trigger did not hold"** only when *no* reading held: the nearest distance of the widest sectors
  (front +-30 deg; sides over 30..140 deg, the union of the side sectors), against the loosest limit (C: the
  larger of 0.3 m and ``safety_distance``), plus the noise margin;
- **"it turned late"** only when *every* reading held: the nearest distance of the narrowest front (+-5 deg)
  and, for each side, the largest over the sector centres of the narrow (+-5 deg) sector's nearest distance,
  against the tightest limit (C: the smaller of the two), with no margin;
- **C's side**: the sides as each (centre, half-width) pair of the family reads them, and their means; a side is
  required only where every pair agrees (see :class:`bt_nav.judge.checkoff_core.CheckoffJudge`). The pairs reach
  as close to the bow as :data:`SIDE_REACH_DEG` and as wide as :data:`WIDE_SIDE` (30-150 deg): right nodes read
  their sides centred at 70 deg, or spanning 30-150 deg, and such a sector may see the obstacle C pivots from (its
  corner, where the robot's yaw puts it) and call that side the closer one. Where they disagree with the sectors
  beside the robot either side passes, with a finding (:mod:`bt_nav.judge.findings`).

Pure (NumPy only): the judge casts noise-free ranges from the true pose and hands them here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: What a side's mean counts for a beam with nothing in range (the LDS-01's range).
MEAN_CAP = 3.5
#: Degrees between the side-sector centres the "every reading" rule tries.
CENTRE_STEP_DEG = 5.0
#: deg: how close to the bow C's side sectors may reach (a 30-150 deg "left" is a reasonable reading of the sheet).
SIDE_REACH_DEG = 30.0
#: (centre, half-width) deg of the widest side sector C's comparison tries: 30-150 deg.
WIDE_SIDE = (90.0, 60.0)
#: deg: further side-sector centres C's comparison tries beside the family's ends, 75 and 90 (70: measured, a right
#: node's "left" centred at 70 deg).
SIDE_CENTRES = (70.0, 75.0, 90.0)


@dataclass(frozen=True)
class SectorFamily:
    """The reasonable sector readings (degrees; + = left, CCW; 0 = straight ahead)."""

    front_min_half: float = 5.0  # the narrowest front a student reads: -5..+5 deg
    front_max_half: float = 30.0  # the widest: -30..+30 deg (the homework's own front)
    side_centre_min: float = 60.0  # a side sector is centred anywhere from here ...
    side_centre_max: float = 110.0  # ... to here
    side_min_half: float = 5.0  # with a half-width from here ...
    side_max_half: float = 30.0  # ... to here

    def __post_init__(self) -> None:
        if not (0 < self.front_min_half <= self.front_max_half <= 90 and 0 < self.side_min_half <= self.side_max_half
                and 0 <= self.side_centre_min <= self.side_centre_max <= 180):
            raise ValueError(f"an empty or inverted sector family: {self}")

    def describe(self) -> str:
        """The family in words (the judge's rule lines and the docs say which readings it used)."""
        return (f"front sectors from +-{self.front_min_half:g} to +-{self.front_max_half:g} deg, side sectors "
                f"centred {self.side_centre_min:g}-{self.side_centre_max:g} deg, +-{self.side_min_half:g} to "
                f"+-{self.side_max_half:g} deg wide")


@dataclass
class Reading:
    """Noise-free readings at one ground-truth sample (m; inf: nothing there)."""

    front: float  # nearest in the widest front: the reading that holds first
    left: float  # nearest over every left sector of the family (their union)
    right: float
    ahead: float  # distance to the first obstacle in the swept path (robot's width + margin)
    front_all: float = math.inf  # nearest in the narrowest front: below a limit, every front reading is
    left_all: float = math.inf  # the largest narrow-sector distance over the centres: below a limit, every left is
    right_all: float = math.inf
    left_abeam: float = math.inf  # nearest over 60..120 deg: beside the robot, what C's sides are shown as
    right_abeam: float = math.inf
    sides: tuple[tuple[float, float], ...] = ()  # (left, right) per (centre, half-width) of the family, and means


class SectorReader:
    """The family's masks over one LiDAR's beam angles, built once; :meth:`read` turns ranges into a
    :class:`Reading` with one masked minimum per row of a matrix (cheap enough for every ground-truth sample)."""

    def __init__(self, angles: np.ndarray, family: SectorFamily | None = None) -> None:
        self.family = family = family or SectorFamily()
        deg = np.degrees(np.remainder(np.asarray(angles, dtype=np.float64) + math.pi, 2 * math.pi) - math.pi)
        centres = np.arange(family.side_centre_min, family.side_centre_max + 1e-9, CENTRE_STEP_DEG)
        # C's comparison of the sides: every sector a right node may read, reaching no closer to the bow than
        # SIDE_REACH_DEG. One that reaches 30 deg off the bow may see the very obstacle C pivots away from on
        # whichever side the robot's yaw puts its corner: a node reading it so turns the other way, and is right by
        # its reading; so the side is required only where these agree too.
        pairs = [(c, h) for c in sorted({family.side_centre_min, *SIDE_CENTRES, family.side_centre_max})
                 for h in sorted({family.side_min_half, 15.0, family.side_max_half})
                 if family.side_min_half <= h <= family.side_max_half and c - h >= SIDE_REACH_DEG - 1e-9]
        pairs.append(WIDE_SIDE)
        lo, hi = family.side_centre_min - family.side_max_half, family.side_centre_max + family.side_max_half
        rows = [np.abs(deg) <= family.front_max_half + 1e-9, np.abs(deg) <= family.front_min_half + 1e-9]
        for sign in (1.0, -1.0):  # left, then right
            side = sign * deg
            rows.append((side >= lo - 1e-9) & (side <= hi + 1e-9))
            rows += [np.abs(side - c) <= family.side_min_half + 1e-9 for c in centres]
            rows += [np.abs(side - c) <= h + 1e-9 for c, h in pairs]
        self._masks = np.array(rows)
        self._centres, self._pairs = len(centres), len(pairs)
        self._mean_left = np.abs(deg - 90.0) <= 30.0 + 1e-9
        self._mean_right = np.abs(deg + 90.0) <= 30.0 + 1e-9
        self._masks = np.vstack([self._masks, self._mean_left, self._mean_right])
        self._has_means = bool(self._mean_left.any() and self._mean_right.any())  # beams beside the robot on both sides
        # Each row's beams gathered into one array, row after row (and an inf at the end), so one
        # np.minimum.reduceat takes every row's minimum without a (rows x beams) array per reading; a row without
        # beams reads inf.
        sizes = self._masks.sum(axis=1)
        self._gather = np.nonzero(self._masks)[1]
        self._starts = np.concatenate(([0], np.cumsum(sizes)[:-1])).astype(np.intp)
        self._empty = sizes == 0

    def read(self, ranges: np.ndarray, ahead: float) -> Reading:
        """The family's readings of ``ranges`` (one per beam, inf: nothing) and the swept path's ``ahead``."""
        nearest = np.minimum.reduceat(np.append(ranges[self._gather], np.inf), self._starts)
        nearest[self._empty] = np.inf
        n, p = self._centres, self._pairs
        per_side = 1 + n + p
        left, right = nearest[2:2 + per_side], nearest[2 + per_side:2 + 2 * per_side]
        sides = [(float(a), float(b)) for a, b in zip(left[1 + n:], right[1 + n:], strict=True)]
        capped = np.minimum(ranges, MEAN_CAP)
        if self._has_means:
            sides.append((float(capped[self._mean_left].mean()), float(capped[self._mean_right].mean())))
        return Reading(front=float(nearest[0]), left=float(left[0]), right=float(right[0]), ahead=float(ahead),
                       front_all=float(nearest[1]), left_all=float(left[1:1 + n].max()),
                       right_all=float(right[1:1 + n].max()), left_abeam=float(nearest[-2]),
                       right_abeam=float(nearest[-1]), sides=tuple(sides))
