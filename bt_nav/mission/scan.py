"""LaserScan geometry for the reactive controller, in pure numpy.

This module deliberately imports nothing from ROS: the behaviour tree, the 2D simulator and the unit tests
all need the same scan maths, and keeping it free of ``rclpy`` lets it run (and be property-tested) without
a ROS installation.  ``Scan.from_laserscan`` duck-types ``sensor_msgs/msg/LaserScan`` for the same reason.

Angle convention: radians in the robot frame, 0 = straight ahead (+x), positive = counter-clockwise = to
the robot's left.  Beam ``i`` points at ``angle_min + i * angle_increment``; nothing here assumes a
particular ``angle_min``, sweep direction or field of view, because the two robots we target disagree:
the TurtleBot3 LDS-01 publishes ``[0, 2pi)`` and the TurtleBot4 RPLIDAR ``[-pi, pi)``, and some drivers
sweep clockwise (negative increment).  Hence every lookup is done on wrapped angular differences instead
of hard-coded indices.

Range semantics follow REP 117: NaN carries no information, ``+inf`` means "nothing within range" (free),
``-inf`` means "something closer than ``range_min``", and finite values outside ``[range_min, range_max]``
(e.g. the LDS-01's ``0.0`` "no return") are discarded.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from bt_nav.mission.geometry import wrap_angle  # re-exported: the scan API speaks of it

__all__ = [
    "MAX_BEAMS",
    "Proximity",
    "Scan",
    "ScanError",
    "Sector",
    "SectorConfig",
    "SectorReading",
    "Sectors",
    "beam_angles",
    "beam_trig",
    "classify",
    "clean_ranges",
    "clean_validated",
    "clearer_side",
    "sector_indices",
    "sector_minima",
    "sectors_from_clean",
    "validate_scan",
    "wrap_angle",
]

#: Upper bound on beams per scan.  Real sensors publish at most a few thousand; anything near this limit is a
#: corrupt or hostile message and would make the per-layout caches allocate absurd amounts of memory.
MAX_BEAMS = 1_000_000

#: Slack for "is this beam inside the cone" so that a beam lying exactly on a cone edge (e.g. +30 deg with a
#: 1 deg increment) is not lost to floating-point rounding of ``angle_min + i * increment``.
_CONE_EPS = 1e-9


class ScanError(ValueError):
    """A LaserScan that cannot be interpreted geometrically.

    One exception type lets the ROS node catch every kind of malformed message in a single ``except`` and
    report it, instead of letting numpy errors (or, worse, silently wrong sector minima) leak into the tree.
    It subclasses ``ValueError`` so generic input-validation handlers also catch it.
    """


@dataclass(frozen=True, slots=True, eq=False)
class Scan:
    """An immutable snapshot of one LaserScan.

    Frozen so that a scan handed to several behaviours within one tick cannot be changed under them.
    ``eq=False`` (identity equality/hash) because the default field-wise ``__eq__`` would compare numpy arrays
    and raise "truth value of an array is ambiguous"; nothing needs value equality of whole scans.
    """

    angle_min: float
    angle_max: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray

    @classmethod
    def from_laserscan(cls, msg: Any) -> Scan:
        """Build a ``Scan`` from anything shaped like ``sensor_msgs/msg/LaserScan``.

        Duck-typed so this module never imports ROS.  ``ranges`` is copied because rclpy may hand us an
        ``array.array`` that a later message reuses; the dtype of an ``array('f')`` (float32) is kept to avoid
        a needless conversion.  Nothing is validated here beyond convertibility; call ``validate_scan``.

        Raises:
            ScanError: if a field is missing or not numeric.
        """
        names = ("angle_min", "angle_max", "angle_increment", "range_min", "range_max")
        try:
            scalars = {name: float(getattr(msg, name)) for name in names}
            raw = msg.ranges
        except AttributeError as exc:
            raise ScanError(f"message is not LaserScan-like: {exc}") from exc
        except (TypeError, ValueError) as exc:
            raise ScanError(f"LaserScan scalar field is not a number: {exc}") from exc
        try:
            ranges = np.array(raw, copy=True)
        except (TypeError, ValueError) as exc:
            raise ScanError(f"LaserScan ranges cannot be read as an array: {exc}") from exc
        if ranges.dtype.kind in "iu":
            ranges = ranges.astype(np.float64)
        return cls(ranges=ranges, **scalars)

    @property
    def num_beams(self) -> int:
        """Number of beams (length of ``ranges``); 0 for a 0-d array so validation can report it cleanly."""
        shape = np.shape(self.ranges)
        return int(shape[0]) if shape else 0


# ----------------------------------------------------------------------------------------------------
# Validation
# ----------------------------------------------------------------------------------------------------


def validate_scan(scan: Scan) -> None:
    """Reject scans whose geometry cannot be trusted.

    Every check is O(1) (no pass over the ranges) so this can run on every message at 20 Hz; the individual
    range values are *not* checked because REP 117 gives every value (NaN, +-inf, out of range) a meaning.

    Raises:
        ScanError: with a message naming the problem and the offending values.
    """
    ranges = np.asarray(scan.ranges)
    if ranges.ndim != 1:
        raise ScanError(f"ranges must be 1-D, got shape {ranges.shape}")
    n_beams = int(ranges.shape[0])
    if n_beams == 0:
        raise ScanError("ranges is empty (0 beams)")
    if n_beams > MAX_BEAMS:
        raise ScanError(f"too many beams: {n_beams} > {MAX_BEAMS}")
    if ranges.dtype.kind not in "fiu":
        raise ScanError(f"ranges must be real numbers, got dtype {ranges.dtype}")

    try:
        angle_min = float(scan.angle_min)
        angle_max = float(scan.angle_max)
        inc = float(scan.angle_increment)
        range_min = float(scan.range_min)
        range_max = float(scan.range_max)
    except (TypeError, ValueError) as exc:
        raise ScanError(f"scan scalar field is not a number: {exc}") from exc

    if inc == 0.0 or not math.isfinite(inc):
        raise ScanError(f"angle_increment must be finite and non-zero, got {inc!r}")
    for name, value in (
        ("angle_min", angle_min),
        ("angle_max", angle_max),
        ("range_min", range_min),
        ("range_max", range_max),
    ):
        if not math.isfinite(value):
            raise ScanError(f"{name} must be finite, got {value!r}")
    if range_min < 0.0:
        raise ScanError(f"range_min must be >= 0, got {range_min!r}")
    if range_max <= range_min:
        raise ScanError(
            f"range_max must be > range_min, got range_min={range_min!r}, range_max={range_max!r}"
        )

    span = angle_max - angle_min
    if span == 0.0:
        if n_beams != 1:
            raise ScanError(
                f"angle_max == angle_min ({angle_min!r}) describes a single beam, but ranges has {n_beams}"
            )
        return
    if (span > 0.0) != (inc > 0.0):
        raise ScanError(
            f"sweep direction mismatch: angle_max - angle_min = {span!r} but angle_increment = {inc!r}"
        )
    ratio = span / inc
    if not math.isfinite(ratio) or ratio > 2.0 * MAX_BEAMS:
        raise ScanError(
            f"angles imply an absurd beam count: (angle_max - angle_min) / angle_increment = {ratio!r}"
        )
    expected = round(ratio) + 1
    # Drivers disagree on whether angle_max is the last beam or one past it, so allow +-1.
    if abs(n_beams - expected) > 1:
        raise ScanError(
            f"len(ranges) = {n_beams} is inconsistent with the angles: angle_min={angle_min!r}, "
            f"angle_max={angle_max!r}, angle_increment={inc!r} imply {expected} beams (+-1 accepted)"
        )


# ----------------------------------------------------------------------------------------------------
# Beam angles
# ----------------------------------------------------------------------------------------------------


@lru_cache(maxsize=32)
def _cached_beam_angles(angle_min: float, inc: float, n_beams: int) -> np.ndarray:
    """Beam angles per layout, cached because the layout repeats on every message (10-20 Hz)."""
    angles = angle_min + np.arange(n_beams, dtype=np.float64) * inc
    angles.setflags(write=False)  # shared between callers: must not be mutated
    return angles


def _layout(scan: Scan) -> tuple[float, float, int]:
    """Hashable layout key; floats normalised so float32/np.float64 fields hit the same cache entry."""
    return float(scan.angle_min), float(scan.angle_increment), scan.num_beams


def beam_angles(scan: Scan) -> np.ndarray:
    """Angle of every beam, ``angle_min + i * angle_increment``, deliberately *not* wrapped.

    Unwrapped angles keep the array monotonic (useful for plotting and interpolation); use ``wrap_angle`` when
    comparing directions.  Returns a fresh writable copy so callers cannot corrupt the internal cache.

    Raises:
        ScanError: if the scan is malformed.
    """
    validate_scan(scan)
    return _cached_beam_angles(*_layout(scan)).copy()


@lru_cache(maxsize=8)
def _cached_beam_trig(angle_min: float, inc: float, n_beams: int) -> tuple[np.ndarray, np.ndarray]:
    angles = _cached_beam_angles(angle_min, inc, n_beams)
    cos, sin = np.cos(angles), np.sin(angles)
    cos.setflags(write=False)
    sin.setflags(write=False)
    return cos, sin


def beam_trig(scan: Scan) -> tuple[np.ndarray, np.ndarray]:
    """(cos, sin) of every beam angle, cached per layout and read-only, for a scan the caller has validated.

    The free paths need every beam's direction as a unit vector on every scan; the layout repeats,
    so the trigonometry is done once per layout instead of once per scan. ``np.cos`` is elementwise,
    so ``cos[mask]`` equals ``np.cos(angles[mask])`` bit for bit.
    """
    return _cached_beam_trig(*_layout(scan))


# ----------------------------------------------------------------------------------------------------
# Range cleaning (REP 117)
# ----------------------------------------------------------------------------------------------------


def _rep117(raw: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
    """Apply REP 117 to a float64 array in place and return it; dropped beams become NaN."""
    with np.errstate(invalid="ignore"):
        out_of_range = np.isfinite(raw) & ((raw < range_min) | (raw > range_max))
    raw[out_of_range] = np.nan
    raw[raw == -np.inf] = range_min
    return raw


def clean_ranges(scan: Scan) -> np.ndarray:
    """Float64 copy of the ranges with REP 117 applied, so consumers never special-case sensor quirks.

    NaN and finite out-of-``[range_min, range_max]`` readings (including the LDS-01's ``0.0`` "no return"
    whenever ``range_min > 0``) become NaN = no information; ``-inf`` becomes ``range_min`` (an obstacle too
    close to measure must be treated as being as close as possible); ``+inf`` stays ``+inf`` (free space).

    Raises:
        ScanError: if the scan is malformed.
    """
    validate_scan(scan)
    return clean_validated(scan)


def clean_validated(scan: Scan) -> np.ndarray:
    """:func:`clean_ranges` for a scan the caller has validated already (one validation per scan, not
    one per consumer)."""
    raw = np.array(scan.ranges, dtype=np.float64, copy=True)
    return _rep117(raw, float(scan.range_min), float(scan.range_max))


# ----------------------------------------------------------------------------------------------------
# Sectors
# ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Sector:
    """A cone of directions ``center +- half_width`` (radians), e.g. the front cone.

    Frozen and hashable so it can be part of the per-layout cache key.
    """

    center: float
    half_width: float

    def __post_init__(self) -> None:
        """Reject cones that would silently select nothing (or everything by NaN comparisons)."""
        if not math.isfinite(self.center):
            raise ValueError(f"Sector.center must be finite, got {self.center!r}")
        if not (math.isfinite(self.half_width) and self.half_width > 0.0):
            raise ValueError(f"Sector.half_width must be finite and > 0, got {self.half_width!r}")


@dataclass(frozen=True, slots=True)
class SectorConfig:
    """The three cones the reactive controller looks at, and how many valid beams make a cone trustworthy.

    The defaults are the homework's layout: a +-30 deg front cone split into its left half ``[0, +30]`` and
    right half ``[-30, 0]``, so "which side is clearer" compares the two halves of what is ahead.
    """

    front: Sector = Sector(0.0, math.radians(30))
    left: Sector = Sector(math.radians(15), math.radians(15))
    right: Sector = Sector(math.radians(-15), math.radians(15))
    min_valid_beams: int = 3

    def __post_init__(self) -> None:
        """A threshold below one beam would call a sector with no information "known"."""
        if isinstance(self.min_valid_beams, bool) or not isinstance(self.min_valid_beams, int | np.integer):
            raise ValueError(f"min_valid_beams must be an int, got {self.min_valid_beams!r}")
        if self.min_valid_beams < 1:
            raise ValueError(f"min_valid_beams must be >= 1, got {self.min_valid_beams!r}")

    @classmethod
    def from_degrees(
        cls,
        front_half_deg: float = 30.0,
        side_center_deg: float = 15.0,
        side_half_deg: float = 15.0,
        min_valid_beams: int = 3,
    ) -> SectorConfig:
        """Build a mirror-symmetric config from degree parameters (as written in YAML / ROS parameters).

        Left is centred at ``+side_center_deg`` and right at ``-side_center_deg`` so the two are always
        mirror images; asymmetric side cones would bias ``clearer_side``.

        Raises:
            ValueError: if a half width is not in ``(0, 180]``, the centre is not finite, or
                ``min_valid_beams < 1``.
        """
        for name, value in (("front_half_deg", front_half_deg), ("side_half_deg", side_half_deg)):
            if not (math.isfinite(value) and 0.0 < value <= 180.0):
                raise ValueError(f"{name} must be in (0, 180], got {value!r}")
        if not math.isfinite(side_center_deg):
            raise ValueError(f"side_center_deg must be finite, got {side_center_deg!r}")
        side_half = math.radians(side_half_deg)
        return cls(
            front=Sector(0.0, math.radians(front_half_deg)),
            left=Sector(math.radians(side_center_deg), side_half),
            right=Sector(-math.radians(side_center_deg), side_half),
            min_valid_beams=min_valid_beams,
        )


@dataclass(frozen=True, slots=True)
class SectorReading:
    """What one cone of the scan says.

    ``min_range`` is the nearest valid obstacle in metres, ``math.inf`` if every valid beam saw free space,
    and ``math.nan`` when the sector is unknown (too few beams carried information).  ``sector_minima``
    enforces the ``min_valid_beams`` threshold by writing NaN, so ``known`` can be derived from the
    reading itself without storing the threshold.
    """

    min_range: float
    valid_beams: int
    total_beams: int

    @property
    def known(self) -> bool:
        """Whether the reading may be acted on; unknown must never be mistaken for "clear".

        True iff the sector had beams, at least one (and, via ``sector_minima``, at least
        ``min(min_valid_beams, total_beams)``) of them was valid, and ``min_range`` is not NaN.
        """
        return self.total_beams > 0 and self.valid_beams > 0 and not math.isnan(self.min_range)


@dataclass(frozen=True, slots=True)
class Sectors:
    """The three sector readings of one scan, computed together so they are mutually consistent."""

    front: SectorReading
    left: SectorReading
    right: SectorReading


@lru_cache(maxsize=64)
def _cached_sector_indices(
    angle_min: float, inc: float, n_beams: int, center: float, half_width: float
) -> np.ndarray:
    """Indices of a cone for one layout; cached because the same layout arrives 10-20 times per second."""
    angles = _cached_beam_angles(angle_min, inc, n_beams)
    inside = np.abs(wrap_angle(angles - center)) <= half_width + _CONE_EPS
    indices = np.flatnonzero(inside)
    indices.setflags(write=False)  # shared between callers: must not be mutated
    return indices


def _sector_indices(scan: Scan, sector: Sector) -> np.ndarray:
    """``sector_indices`` without re-validating (the caller already did)."""
    angle_min, inc, n_beams = _layout(scan)
    return _cached_sector_indices(angle_min, inc, n_beams, float(sector.center), float(sector.half_width))


def sector_indices(scan: Scan, sector: Sector) -> np.ndarray:
    """Ascending indices of the beams whose direction lies within ``half_width`` of ``sector.center``.

    Membership uses the wrapped angular difference, so a cone straddling the 0/2pi seam (the LDS-01's front)
    or the +-pi seam (the RPLIDAR's rear) is contiguous in direction even though its indices are not.
    The edge is inclusive with a 1e-9 rad slack.  The returned array is cached and read-only.

    Raises:
        ScanError: if the scan is malformed.
    """
    validate_scan(scan)
    return _sector_indices(scan, sector)


def _reading(
    ranges: np.ndarray, indices: np.ndarray, range_min: float, range_max: float, min_valid: int
) -> SectorReading:
    """Reduce one cone of raw ranges to a ``SectorReading`` with REP 117 semantics, fully vectorised."""
    total = int(indices.size)
    if total == 0:
        return SectorReading(math.nan, 0, 0)
    # float64 so the range_min/range_max comparisons match clean_ranges exactly (NEP 50 would otherwise
    # compare float32 ranges against float32-rounded limits).
    raw = np.asarray(ranges[indices], dtype=np.float64)
    in_range = (raw >= range_min) & (raw <= range_max)  # False for NaN and +-inf
    pos_inf = raw == np.inf
    neg_inf = raw == -np.inf
    valid = int(np.count_nonzero(in_range | pos_inf | neg_inf))
    if valid < min(min_valid, total) or valid == 0:
        return SectorReading(math.nan, valid, total)
    if neg_inf.any():
        # -inf means "closer than range_min"; range_min is <= every in-range value, so it is the minimum.
        return SectorReading(range_min, valid, total)
    if in_range.any():
        return SectorReading(float(raw[in_range].min()), valid, total)
    return SectorReading(math.inf, valid, total)


def sector_minima(scan: Scan, config: SectorConfig = SectorConfig()) -> Sectors:
    """Nearest obstacle in the front, left and right cones: the reactive controller's whole view of the world.

    Validates first so a malformed message raises ``ScanError`` instead of producing plausible-looking but
    wrong distances.  A sector is known when it has beams and at least ``min(config.min_valid_beams,
    total_beams)`` of them are valid, so a 1-beam sector can still be known while a sector outside the
    field of view (0 beams) is always unknown.

    Raises:
        ScanError: if the scan is malformed.
    """
    validate_scan(scan)
    ranges = np.asarray(scan.ranges)
    range_min = float(scan.range_min)
    range_max = float(scan.range_max)
    min_valid = int(config.min_valid_beams)

    def read(sector: Sector) -> SectorReading:
        return _reading(ranges, _sector_indices(scan, sector), range_min, range_max, min_valid)

    return Sectors(front=read(config.front), left=read(config.left), right=read(config.right))


def _clean_reading(clean: np.ndarray, indices: np.ndarray, min_valid: int) -> SectorReading:
    """``_reading`` on REP 117-cleaned ranges: valid is not NaN, and the minimum of the valid values is
    ``range_min`` for a -inf beam, else the nearest in-range value, else +inf, as ``_reading`` says."""
    total = int(indices.size)
    if total == 0:
        return SectorReading(math.nan, 0, 0)
    cone = clean[indices]
    valid = total - int(np.count_nonzero(np.isnan(cone)))
    if valid < min(min_valid, total) or valid == 0:
        return SectorReading(math.nan, valid, total)
    return SectorReading(float(np.fmin.reduce(cone)), valid, total)  # fmin skips NaN


def sectors_from_clean(scan: Scan, clean: np.ndarray, config: SectorConfig = SectorConfig()) -> Sectors:
    """:func:`sector_minima` from ranges the caller has validated and cleaned (:func:`clean_validated`):
    the same readings, with the scan's single cleaning shared with the free paths."""
    min_valid = int(config.min_valid_beams)
    return Sectors(front=_clean_reading(clean, _sector_indices(scan, config.front), min_valid),
                   left=_clean_reading(clean, _sector_indices(scan, config.left), min_valid),
                   right=_clean_reading(clean, _sector_indices(scan, config.right), min_valid))


# ----------------------------------------------------------------------------------------------------
# Decisions
# ----------------------------------------------------------------------------------------------------


class Proximity(enum.Enum):
    """Coarse distance class of a sector, the vocabulary of the behaviour tree's conditions."""

    NONE = "none"
    FAR = "far"
    CLOSE = "close"
    UNKNOWN = "unknown"


def classify(reading: SectorReading, close_distance: float, far_distance: float) -> Proximity:
    """Map a reading to ``Proximity``; thresholds are strict (``min_range == close_distance`` is FAR).

    Unknown comes first so that missing data is never reported as NONE (which would let the robot drive on).

    Raises:
        ValueError: if a threshold is NaN or negative, or ``close_distance > far_distance`` (a
            misconfiguration that would make FAR unreachable).
    """
    if not (close_distance >= 0.0 and far_distance >= 0.0):
        raise ValueError(
            f"thresholds must be >= 0, got close_distance={close_distance!r}, far_distance={far_distance!r}"
        )
    if close_distance > far_distance:
        raise ValueError(
            f"close_distance ({close_distance!r}) must be <= far_distance ({far_distance!r})"
        )
    if not reading.known:
        return Proximity.UNKNOWN
    if reading.min_range < close_distance:
        return Proximity.CLOSE
    if reading.min_range < far_distance:
        return Proximity.FAR
    return Proximity.NONE


def clearer_side(sectors: Sectors) -> int:
    """+1 (turn left / CCW) if the left sector is clearer, -1 (turn right / CW) otherwise.

    An unknown side (too few beams with a return) counts as free space (+inf): a TurtleBot3's LDS-01 reads
    0.0 and its LDS-02 NaN where nothing is within range, so in a room wider than the LiDAR's range the open
    side is the unknown one, and the Smart Pivot must turn there, not towards the wall it does see. Ties -
    both unknown, both +inf - go left (+1): a fixed choice keeps the robot from oscillating between left
    and right on successive ticks.
    """
    left = sectors.left.min_range if sectors.left.known else math.inf
    right = sectors.right.min_range if sectors.right.known else math.inf
    return 1 if left >= right else -1

