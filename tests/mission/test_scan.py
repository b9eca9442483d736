"""Tests for ``bt_nav.mission.scan``: hand-computed layouts of the real sensors plus brute-force property tests.

The property tests compare the vectorised, cached implementation with a deliberately naive reference that
loops over beams in pure Python and wraps angles a different way (``atan2(sin, cos)``), so a shared bug in
``wrap_angle`` or in the caching cannot make both sides agree by accident.
"""

from __future__ import annotations

import array
import math
import time
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bt_nav.mission.scan import (
    MAX_BEAMS,
    Proximity,
    Scan,
    ScanError,
    Sector,
    SectorConfig,
    SectorReading,
    Sectors,
    beam_angles,
    classify,
    clean_ranges,
    clearer_side,
    sector_indices,
    sector_minima,
    validate_scan,
    wrap_angle,
)

DEG = math.pi / 180.0
NAN = math.nan
INF = math.inf

# --------------------------------------------------------------------------------------------------------
# Layout helpers
# --------------------------------------------------------------------------------------------------------


def make_scan(
    angle_min: float,
    inc: float,
    ranges,
    range_min: float = 0.12,
    range_max: float = 3.5,
    angle_max: float | None = None,
) -> Scan:
    """Scan whose angle_max is the last beam unless given (the common driver convention)."""
    values = np.asarray(ranges, dtype=np.float64) if not isinstance(ranges, np.ndarray) else ranges
    if angle_max is None:
        angle_max = angle_min + (len(values) - 1) * inc
    return Scan(angle_min, angle_max, inc, range_min, range_max, values)


def lds01(ranges=None) -> Scan:
    """TurtleBot3 LDS-01: 360 beams, [0, 2pi), 1 degree apart."""
    values = np.ones(360) if ranges is None else ranges
    return make_scan(0.0, 2 * math.pi / 360, values)


def rplidar(ranges=None, angle_max: float = math.pi) -> Scan:
    """TurtleBot4 RPLIDAR: 640 beams over [-pi, pi); angle_max = pi is one past the last beam (n+1 case)."""
    values = np.ones(640) if ranges is None else ranges
    return make_scan(-math.pi, 2 * math.pi / 640, values, range_min=0.15, range_max=12.0, angle_max=angle_max)


def partial_fov(ranges=None) -> Scan:
    """A -135..+135 degree scanner with 0.5 degree spacing (541 beams), blind behind."""
    values = np.ones(541) if ranges is None else ranges
    return make_scan(-135 * DEG, 0.5 * DEG, values)


def clockwise(ranges=None) -> Scan:
    """360 beams sweeping clockwise from +pi (negative increment)."""
    values = np.ones(360) if ranges is None else ranges
    return make_scan(math.pi, -DEG, values)


# --------------------------------------------------------------------------------------------------------
# wrap_angle and beam_angles
# --------------------------------------------------------------------------------------------------------


def test_wrap_angle_scalars() -> None:
    assert wrap_angle(0.0) == 0.0
    assert wrap_angle(math.pi) == -math.pi  # half-open interval
    assert wrap_angle(-math.pi) == -math.pi
    assert wrap_angle(3 * math.pi) == pytest.approx(-math.pi)
    assert wrap_angle(1.5 * math.pi) == pytest.approx(-0.5 * math.pi)
    assert isinstance(wrap_angle(np.float32(1.0)), float)
    tiny = wrap_angle(-1e-20)
    assert -math.pi <= tiny < math.pi
    assert abs(tiny) < 1e-12


def test_wrap_angle_array() -> None:
    a = np.array([0.0, math.pi, -math.pi, 2 * math.pi, -2.5 * math.pi, -1e-20])
    w = wrap_angle(a)
    assert isinstance(w, np.ndarray)
    assert np.all(w >= -math.pi) and np.all(w < math.pi)
    np.testing.assert_allclose(w, [0.0, -math.pi, -math.pi, 0.0, -0.5 * math.pi, 0.0], atol=1e-12)
    assert a[1] == math.pi  # input untouched


@given(st.floats(min_value=-1e4, max_value=1e4, allow_nan=False))
@settings(max_examples=200, deadline=None)
def test_wrap_angle_property(x: float) -> None:
    w = wrap_angle(x)
    assert -math.pi <= w < math.pi
    assert math.isclose(math.cos(w), math.cos(x), abs_tol=1e-9)
    assert math.isclose(math.sin(w), math.sin(x), abs_tol=1e-9)
    wa = wrap_angle(np.array([x]))
    assert wa[0] == w


def test_beam_angles_not_wrapped_and_a_safe_copy() -> None:
    scan = lds01()
    angles = beam_angles(scan)
    assert angles.shape == (360,)
    assert angles[0] == 0.0
    assert angles[359] == pytest.approx(359 * DEG)  # 6.26 rad, not -1 deg
    angles[:] = 99.0  # must not corrupt the cache
    assert beam_angles(scan)[1] == pytest.approx(DEG)
    np.testing.assert_allclose(beam_angles(clockwise())[:3], [math.pi, math.pi - DEG, math.pi - 2 * DEG])


# --------------------------------------------------------------------------------------------------------
# sector_indices, hand-computed
# --------------------------------------------------------------------------------------------------------


def test_sector_indices_lds01_seam() -> None:
    scan = lds01()
    cfg = SectorConfig()
    front = sector_indices(scan, cfg.front)
    assert front.tolist() == list(range(0, 31)) + list(range(330, 360))  # ascending, wraps the 0/2pi seam
    assert sector_indices(scan, cfg.left).tolist() == list(range(0, 31))
    assert sector_indices(scan, cfg.right).tolist() == [0] + list(range(330, 360))


def test_sector_indices_rplidar_rear_straddles_pi() -> None:
    scan = rplidar()
    step = 360 / 640
    rear = sector_indices(scan, Sector(math.pi, 10 * DEG))
    expected = [
        i for i in range(640) if abs(wrap_angle(-math.pi + i * step * DEG - math.pi)) <= 10 * DEG + 1e-9
    ]
    assert rear.tolist() == expected
    assert rear[0] == 0 and rear[-1] == 639
    front = sector_indices(scan, SectorConfig().front)
    assert front[0] < 320 < front[-1]
    assert np.all(np.diff(front) == 1)


def test_sector_indices_edges_inclusive() -> None:
    # Beams exactly on +-30 deg are inside even though i*increment is not exactly 30 deg in binary.
    scan = lds01()
    idx = sector_indices(scan, Sector(0.0, 30 * DEG))
    assert 30 in idx and 330 in idx
    assert 31 not in idx and 329 not in idx


def test_sector_indices_outside_fov_is_empty() -> None:
    assert sector_indices(partial_fov(), Sector(math.pi, 20 * DEG)).size == 0


def test_sector_indices_cached_and_read_only() -> None:
    scan = lds01()
    first = sector_indices(scan, SectorConfig().front)
    second = sector_indices(lds01(np.zeros(360)), SectorConfig().front)
    assert first is second  # same layout -> same cached array
    with pytest.raises(ValueError):
        first[0] = 5


def test_sector_indices_negative_increment() -> None:
    scan = clockwise()
    left = sector_indices(scan, SectorConfig().left)  # [0, +30] deg -> indices 150..180
    assert left.tolist() == list(range(150, 181))


# --------------------------------------------------------------------------------------------------------
# REP 117
# --------------------------------------------------------------------------------------------------------


def test_clean_ranges_rep117() -> None:
    raw = np.array([NAN, INF, -INF, 0.0, 5.0, 1.0, 0.12, 3.5, 0.05, 3.50001])
    scan = make_scan(0.0, DEG, raw, range_min=0.12, range_max=3.5)
    cleaned = clean_ranges(scan)
    assert cleaned.dtype == np.float64
    expected = [NAN, INF, 0.12, NAN, NAN, 1.0, 0.12, 3.5, NAN, NAN]
    np.testing.assert_array_equal(cleaned, expected)  # NaN == NaN for assert_array_equal
    assert np.isneginf(raw[2]) and np.isnan(raw[0])  # source untouched
    assert cleaned is not scan.ranges


def test_clean_ranges_float32_message_limits() -> None:
    # A float32 message clamps readings to its float32 range_min; from_laserscan keeps that exact value,
    # so a reading equal to range_min stays valid despite float32 -> float64 conversion.
    msg = SimpleNamespace(
        angle_min=0.0,
        angle_max=2 * DEG,
        angle_increment=DEG,
        range_min=float(np.float32(0.12)),
        range_max=float(np.float32(3.5)),
        ranges=array.array("f", [0.12, 3.5, 0.0]),
    )
    cleaned = clean_ranges(Scan.from_laserscan(msg))
    assert cleaned[0] == pytest.approx(0.12) and cleaned[1] == 3.5 and math.isnan(cleaned[2])


def _cfg_single(sector: Sector, min_valid: int = 3) -> SectorConfig:
    return SectorConfig(front=sector, left=sector, right=sector, min_valid_beams=min_valid)


def test_sector_minima_defaults_lds01() -> None:
    ranges = np.full(360, INF)
    ranges[10] = 1.2  # left half of the front cone
    ranges[350] = 0.7  # right half
    ranges[90] = 0.2  # outside every sector
    s = sector_minima(lds01(ranges))
    assert s.front == SectorReading(0.7, 61, 61)
    assert s.left == SectorReading(1.2, 31, 31)
    assert s.right == SectorReading(0.7, 31, 31)
    assert clearer_side(s) == 1


def test_sector_minima_rep117_cases() -> None:
    n = 360
    base = np.full(n, INF)
    s = sector_minima(lds01(base))
    assert s.front.min_range == INF and s.front.known  # all free -> inf, known

    withneg = base.copy()
    withneg[5] = -INF
    withneg[6] = 0.5
    s = sector_minima(lds01(withneg))
    assert s.left.min_range == 0.12  # -inf -> obstacle at range_min
    assert s.right.min_range == INF

    allnan = np.full(n, NAN)
    s = sector_minima(lds01(allnan))
    assert not s.front.known and math.isnan(s.front.min_range)
    assert s.front.valid_beams == 0 and s.front.total_beams == 61

    zeros = np.zeros(n)  # LDS-01 "no return" everywhere
    s = sector_minima(lds01(zeros))
    assert not s.front.known and s.front.valid_beams == 0

    far = np.full(n, 9.0)  # > range_max: dropped, not free
    s = sector_minima(lds01(far))
    assert not s.front.known

    two_valid = np.full(n, NAN)
    two_valid[[1, 2]] = 1.0
    s = sector_minima(lds01(two_valid))  # min_valid_beams = 3
    assert s.left == SectorReading(NAN, 2, 31) or (math.isnan(s.left.min_range) and s.left.valid_beams == 2)
    assert not s.left.known
    s = sector_minima(lds01(two_valid), SectorConfig.from_degrees(min_valid_beams=2))
    assert s.left.known and s.left.min_range == 1.0


def test_sector_minima_unknown_outside_fov() -> None:
    s = sector_minima(partial_fov(), _cfg_single(Sector(math.pi, 20 * DEG)))
    assert s.front.total_beams == 0 and s.front.valid_beams == 0
    assert not s.front.known and math.isnan(s.front.min_range)
    assert classify(s.front, 0.3, 0.6) is Proximity.UNKNOWN


def test_sector_minima_one_beam_sector() -> None:
    narrow = Sector(90 * DEG, 0.2 * DEG)  # only beam 90 of an LDS-01
    ranges = np.full(360, NAN)
    ranges[90] = 2.0
    s = sector_minima(lds01(ranges), _cfg_single(narrow, min_valid=3))
    assert s.front == SectorReading(2.0, 1, 1) and s.front.known  # threshold capped at total_beams
    ranges[90] = NAN
    s = sector_minima(lds01(ranges), _cfg_single(narrow, min_valid=3))
    assert not s.front.known and s.front.total_beams == 1


def test_sector_minima_float32_and_rplidar() -> None:
    ranges = np.full(640, 5.0, dtype=np.float32)
    ranges[320] = 0.4
    ranges[330] = 0.3  # ~5.6 deg left
    s = sector_minima(rplidar(ranges))
    assert s.front.min_range == pytest.approx(0.3)
    assert s.left.min_range == pytest.approx(0.3)
    assert s.right.min_range == pytest.approx(0.4)  # index 320 (0 deg) belongs to both halves
    assert clearer_side(s) == -1


def test_sector_minima_validates() -> None:
    with pytest.raises(ScanError):
        sector_minima(Scan(0.0, 1.0, 0.0, 0.1, 3.5, np.ones(10)))


# --------------------------------------------------------------------------------------------------------
# classify, clearer_side
# --------------------------------------------------------------------------------------------------------


def reading(d: float) -> SectorReading:
    return SectorReading(d, 10, 10)


UNKNOWN = SectorReading(NAN, 0, 10)


@pytest.mark.parametrize(
    ("distance", "expected"),
    [
        (0.0, Proximity.CLOSE),
        (0.49, Proximity.CLOSE),
        (0.5, Proximity.FAR),  # equal to close_distance -> not CLOSE
        (0.99, Proximity.FAR),
        (1.0, Proximity.NONE),  # equal to far_distance -> not FAR
        (INF, Proximity.NONE),
    ],
)
def test_classify_thresholds(distance: float, expected: Proximity) -> None:
    assert classify(reading(distance), 0.5, 1.0) is expected


def test_classify_unknown_and_bad_thresholds() -> None:
    assert classify(UNKNOWN, 0.5, 1.0) is Proximity.UNKNOWN
    assert classify(SectorReading(NAN, 5, 5), 0.5, 1.0) is Proximity.UNKNOWN
    assert classify(reading(0.7), 0.5, 0.5) is Proximity.NONE  # equal thresholds: FAR is empty
    with pytest.raises(ValueError, match="close_distance"):
        classify(reading(1.0), 1.0, 0.5)
    with pytest.raises(ValueError):
        classify(reading(1.0), NAN, 0.5)
    with pytest.raises(ValueError):
        classify(reading(1.0), -0.1, 0.5)


@pytest.mark.parametrize(
    ("left", "right", "clearer"),
    [
        (reading(2.0), reading(1.0), 1),
        (reading(1.0), reading(2.0), -1),
        (reading(1.0), reading(1.0), 1),  # tie -> left
        (reading(INF), reading(INF), 1),
        (reading(INF), reading(3.0), 1),
        (reading(3.0), reading(INF), -1),
        (UNKNOWN, UNKNOWN, 1),
        (UNKNOWN, reading(0.5), 1),  # unknown is no return within range: free space, the clearer side
        (reading(0.5), UNKNOWN, -1),
        (UNKNOWN, reading(INF), 1),  # unknown counts as +inf: tie -> left
    ],
)
def test_clearer_side(left: SectorReading, right: SectorReading, clearer: int) -> None:
    s = Sectors(front=reading(1.0), left=left, right=right)
    assert clearer_side(s) == clearer


def test_reading_known() -> None:
    assert reading(1.0).known
    assert reading(INF).known
    assert not UNKNOWN.known
    assert not SectorReading(NAN, 0, 0).known
    assert not SectorReading(1.0, 0, 0).known


# --------------------------------------------------------------------------------------------------------
# SectorConfig
# --------------------------------------------------------------------------------------------------------


def test_sector_config_defaults_and_from_degrees() -> None:
    default = SectorConfig()
    assert default.front == Sector(0.0, math.radians(30))
    assert default.left == Sector(math.radians(15), math.radians(15))
    assert default.right == Sector(math.radians(-15), math.radians(15))
    assert default.min_valid_beams == 3
    assert SectorConfig.from_degrees() == default
    cfg = SectorConfig.from_degrees(
        front_half_deg=45, side_center_deg=60, side_half_deg=20, min_valid_beams=5
    )
    assert cfg.front.half_width == pytest.approx(math.radians(45))
    assert cfg.left.center == pytest.approx(math.radians(60))
    assert cfg.right.center == -cfg.left.center
    assert cfg.left.half_width == cfg.right.half_width == pytest.approx(math.radians(20))
    assert cfg.min_valid_beams == 5
    assert SectorConfig.from_degrees(front_half_deg=180).front.half_width == pytest.approx(math.pi)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"front_half_deg": 0.0},
        {"front_half_deg": -5.0},
        {"front_half_deg": 180.5},
        {"front_half_deg": NAN},
        {"side_half_deg": 0.0},
        {"side_half_deg": 200.0},
        {"side_center_deg": INF},
        {"min_valid_beams": 0},
        {"min_valid_beams": -1},
    ],
)
def test_sector_config_from_degrees_rejects(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        SectorConfig.from_degrees(**kwargs)


def test_sector_rejects_bad_half_width() -> None:
    with pytest.raises(ValueError, match="half_width"):
        Sector(0.0, 0.0)
    with pytest.raises(ValueError, match="center"):
        Sector(NAN, 0.1)


# --------------------------------------------------------------------------------------------------------
# Scan construction and validation
# --------------------------------------------------------------------------------------------------------


def test_from_laserscan_duck_typed() -> None:
    buf = array.array("f", [1.0, 2.0, float("nan")])
    msg = SimpleNamespace(
        angle_min=-0.1, angle_max=0.1, angle_increment=0.1, range_min=0.1, range_max=5.0, ranges=buf
    )
    scan = Scan.from_laserscan(msg)
    assert scan.num_beams == 3
    assert scan.ranges.dtype == np.float32
    buf[0] = 9.0  # message buffer reuse must not change the snapshot
    assert scan.ranges[0] == 1.0
    validate_scan(scan)

    msg.ranges = [1, 2, 3]
    assert Scan.from_laserscan(msg).ranges.dtype == np.float64
    msg.ranges = [1.0, 2.0, 3.0]
    assert Scan.from_laserscan(msg).ranges.dtype == np.float64


def test_from_laserscan_rejects_non_scan() -> None:
    with pytest.raises(ScanError, match="LaserScan"):
        Scan.from_laserscan(SimpleNamespace(angle_min=0.0))
    bad = SimpleNamespace(
        angle_min="x", angle_max=0.1, angle_increment=0.1, range_min=0.1, range_max=5.0, ranges=[1.0]
    )
    with pytest.raises(ScanError, match="not a number"):
        Scan.from_laserscan(bad)


def test_scan_is_frozen() -> None:
    scan = lds01()
    with pytest.raises(AttributeError):
        scan.angle_min = 1.0  # type: ignore[misc]
    assert scan != lds01()  # identity equality: no ambiguous array comparison
    assert scan == scan


@pytest.mark.parametrize(
    ("n", "ok"),
    [(359, True), (360, True), (361, True), (358, False), (362, False)],
)
def test_validate_length_tolerance(n: int, ok: bool) -> None:
    # angle_max = 359 deg implies 360 beams; drivers may be off by one either way.
    scan = Scan(0.0, 359 * DEG, DEG, 0.12, 3.5, np.ones(n))
    if ok:
        validate_scan(scan)
    else:
        with pytest.raises(ScanError, match="inconsistent"):
            validate_scan(scan)


def test_validate_accepts_real_layouts() -> None:
    rplidar_exclusive = rplidar(angle_max=math.pi - 2 * math.pi / 640)
    for scan in (lds01(), rplidar(), rplidar_exclusive, partial_fov(), clockwise()):
        validate_scan(scan)
    validate_scan(Scan(0.5, 0.5, 0.01, 0.1, 5.0, np.ones(1)))  # single beam, zero span
    # Real LDS-01 numbers (increment slightly larger than 1 deg, angle_max ~ 2pi).
    validate_scan(Scan(0.0, 6.28318977355957, 0.017501922324299812, 0.12, 3.5, np.ones(360, np.float32)))


def _ok(**overrides) -> Scan:
    fields = {
        "angle_min": 0.0,
        "angle_max": 9 * 0.1,
        "angle_increment": 0.1,
        "range_min": 0.1,
        "range_max": 5.0,
        "ranges": np.ones(10),
    }
    fields.update(overrides)
    return Scan(**fields)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"ranges": np.array([])}, "empty"),
        ({"ranges": np.ones((2, 5))}, "1-D"),
        ({"ranges": np.array(1.0)}, "1-D"),
        ({"ranges": np.array(["a"] * 10)}, "dtype"),
        ({"ranges": np.array([None] * 10)}, "dtype"),
        ({"angle_increment": 0.0}, "angle_increment"),
        ({"angle_increment": NAN}, "angle_increment"),
        ({"angle_increment": INF}, "angle_increment"),
        ({"angle_min": NAN}, "angle_min"),
        ({"angle_min": -INF}, "angle_min"),
        ({"angle_max": INF}, "angle_max"),
        ({"range_min": NAN}, "range_min"),
        ({"range_max": INF}, "range_max"),
        ({"range_min": -0.1}, "range_min must be >= 0"),
        ({"range_max": 0.1}, "range_max must be > range_min"),
        ({"range_max": 0.05}, "range_max must be > range_min"),
        ({"ranges": np.ones(12)}, "inconsistent"),
        ({"ranges": np.ones(7)}, "inconsistent"),
        ({"angle_increment": -0.1}, "sweep direction"),
        ({"angle_max": -0.9}, "sweep direction"),
        ({"angle_max": 0.0}, "single beam"),
        ({"angle_increment": 1e-300}, "absurd"),
    ],
)
def test_validate_scan_errors(overrides: dict, message: str) -> None:
    with pytest.raises(ScanError, match=message):
        validate_scan(_ok(**overrides))


def test_validate_scan_error_names_values() -> None:
    with pytest.raises(ScanError) as info:
        validate_scan(_ok(ranges=np.ones(13)))
    assert "13" in str(info.value) and "10" in str(info.value)
    with pytest.raises(ScanError) as info:
        validate_scan(_ok(range_min=-0.25))
    assert "-0.25" in str(info.value)


def test_validate_too_many_beams() -> None:
    n = MAX_BEAMS + 1
    scan = Scan(0.0, (n - 1) * 1e-6, 1e-6, 0.1, 5.0, np.ones(n, dtype=np.float32))
    with pytest.raises(ScanError, match="too many beams"):
        validate_scan(scan)
    ok = Scan(0.0, (MAX_BEAMS - 1) * 1e-6, 1e-6, 0.1, 5.0, np.ones(MAX_BEAMS, dtype=np.float32))
    validate_scan(ok)


def test_scan_error_is_value_error() -> None:
    assert issubclass(ScanError, ValueError)


@pytest.mark.parametrize("func", [sector_indices, clean_ranges, beam_angles, sector_minima])
def test_public_functions_validate(func) -> None:
    bad = _ok(angle_increment=0.0)
    args = {sector_indices: (Sector(0.0, 0.1),)}.get(func, ())
    with pytest.raises(ScanError):
        func(bad, *args)


# --------------------------------------------------------------------------------------------------------
# Brute-force reference (pure Python loops, independent angle wrapping)
# --------------------------------------------------------------------------------------------------------

BAND = 1e-7  # angular differences this close to a decision boundary are "borderline": either answer is OK


def ref_angdist(a: float, b: float) -> float:
    """|a - b| on the circle, via atan2 rather than the modulo used by the implementation."""
    d = a - b
    return abs(math.atan2(math.sin(d), math.cos(d)))


def ref_membership(angle_min: float, inc: float, n: int, sector: Sector) -> tuple[set[int], set[int]]:
    """(definitely inside, borderline) beam sets for a cone."""
    inside: set[int] = set()
    border: set[int] = set()
    edge = sector.half_width + 1e-9
    for i in range(n):
        d = ref_angdist(angle_min + i * inc, sector.center)
        if d <= edge - BAND:
            inside.add(i)
        elif d <= edge + BAND:
            border.add(i)
    return inside, border


def ref_reading(
    ranges: list[float], indices: list[int], range_min: float, range_max: float, min_valid: int
) -> tuple[float, int, int]:
    total = len(indices)
    valid = 0
    best = INF
    for i in indices:
        r = ranges[i]
        if math.isnan(r):
            continue
        if r == INF:
            d = INF
        elif r == -INF:
            d = range_min
        elif range_min <= r <= range_max:
            d = r
        else:
            continue
        valid += 1
        best = min(best, d)
    if total == 0 or valid == 0 or valid < min(min_valid, total):
        return NAN, valid, total
    return best, valid, total


SPECIALS = [NAN, INF, -INF, 0.0, 1e6, 0.01]


@st.composite
def layouts(draw) -> tuple[float, float, int, float]:
    angle_min = draw(st.floats(min_value=-math.pi, max_value=math.pi))
    step = draw(st.floats(min_value=1e-3, max_value=0.5))
    sign = draw(st.sampled_from([1.0, -1.0]))
    n = draw(st.integers(min_value=1, max_value=2000))
    # Driver conventions: angle_max is the last beam, or one past it.
    extra = draw(st.sampled_from([0, 1]))
    inc = sign * step
    angle_max = angle_min + (n - 1 + extra) * inc if n > 1 or extra else angle_min
    return angle_min, inc, n, angle_max


@st.composite
def scans(draw) -> Scan:
    angle_min, inc, n, angle_max = draw(layouts())
    range_min = draw(st.sampled_from([0.0, 0.05, 0.12]))
    range_max = draw(st.sampled_from([3.5, 12.0]))
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    specials = [*SPECIALS, range_min, range_max]  # exact limits are inclusive: probe them
    if n <= 40:
        finite = st.floats(min_value=0.0, max_value=15.0)
        values = draw(st.lists(st.one_of(finite, st.sampled_from(specials)), min_size=n, max_size=n))
    else:
        seed = draw(st.integers(min_value=0, max_value=2**32 - 1))
        special_frac = draw(st.sampled_from([0.0, 0.05, 0.5, 0.95, 1.0]))
        rng = np.random.default_rng(seed)
        values = rng.uniform(0.0, 15.0, n)
        mask = rng.random(n) < special_frac
        values[mask] = rng.choice(specials, size=int(mask.sum()))
    ranges = np.asarray(values, dtype=dtype)
    return Scan(angle_min, angle_max, inc, range_min, range_max, ranges)


sectors_st = st.builds(
    Sector,
    center=st.floats(min_value=-2 * math.pi, max_value=2 * math.pi),
    half_width=st.floats(min_value=1e-4, max_value=math.pi),
)

configs = st.one_of(
    st.just(SectorConfig()),
    st.builds(
        SectorConfig,
        front=sectors_st,
        left=sectors_st,
        right=sectors_st,
        min_valid_beams=st.integers(min_value=1, max_value=10),
    ),
)

PROPERTY = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@PROPERTY
@given(scan=scans(), config=configs)
def test_sector_minima_matches_reference(scan: Scan, config: SectorConfig) -> None:
    validate_scan(scan)
    result = sector_minima(scan, config)
    raw = [float(x) for x in scan.ranges]
    for name in ("front", "left", "right"):
        sector: Sector = getattr(config, name)
        got: SectorReading = getattr(result, name)
        indices = sector_indices(scan, sector)
        chosen = set(indices.tolist())
        inside, border = ref_membership(scan.angle_min, scan.angle_increment, scan.num_beams, sector)
        assert inside <= chosen <= inside | border, name
        assert indices.tolist() == sorted(chosen)
        # Membership agreed (up to borderline beams); the reduction must then match exactly.
        expected = ref_reading(raw, sorted(chosen), scan.range_min, scan.range_max, config.min_valid_beams)
        exp_min, exp_valid, exp_total = expected
        assert (got.valid_beams, got.total_beams) == (exp_valid, exp_total), name
        if math.isnan(exp_min):
            assert math.isnan(got.min_range) and not got.known, name
        else:
            assert got.min_range == exp_min and got.known, name
        assert got.known == (exp_total > 0 and exp_valid >= min(config.min_valid_beams, exp_total))


@PROPERTY
@given(scan=scans(), config=configs)
def test_clean_ranges_matches_reference(scan: Scan, config: SectorConfig) -> None:
    cleaned = clean_ranges(scan)
    n = scan.num_beams
    for i, r in enumerate(float(x) for x in scan.ranges):
        single = ref_reading([r], [0], scan.range_min, scan.range_max, 1)[0]
        c = float(cleaned[i])
        assert (math.isnan(c) and math.isnan(single)) or c == single, (i, r, c, single)
    assert cleaned.shape == (n,)


# --------------------------------------------------------------------------------------------------------
# Performance budget (best-of timing so a busy CI machine does not make it flaky)
# --------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("n", "budget_s"), [(360, 0.25e-3), (4096, 0.5e-3)])
def test_sector_minima_within_tick_budget(n: int, budget_s: float) -> None:
    rng = np.random.default_rng(0)
    ranges = rng.uniform(0.0, 4.0, n).astype(np.float32)
    scan = make_scan(-math.pi, 2 * math.pi / n, ranges)
    sector_minima(scan)  # warm the layout cache
    best = INF
    for _ in range(200):
        t0 = time.perf_counter()
        sector_minima(scan)
        best = min(best, time.perf_counter() - t0)
    assert best < budget_s
