"""The sector family's readings: every row's minimum is the minimum over its beams, whatever the beam layout (one
beam per degree, a finer one, an uneven count, so few beams that some sectors hold none), with misses (inf) and
invalid beams (nan) among the ranges."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_nav.judge.readings import Reading, SectorReader

LAYOUTS = {
    "lds01 0..2pi, 360": np.arange(360) * (2 * math.pi / 360),
    "rplidar -pi..pi, 1147": -math.pi + np.arange(1147) * (2 * math.pi / 1147),
    "lds02, 229": np.arange(229) * (2 * math.pi / 229),
    "8 beams": np.arange(8) * (2 * math.pi / 8),
}


def _reference(reader: SectorReader, ranges: np.ndarray) -> np.ndarray:
    """Each row's minimum by its definition: the masked beams' minimum, inf for a row without beams."""
    return np.array([ranges[row].min() if row.any() else np.inf for row in reader._masks])


@pytest.mark.parametrize("layout", LAYOUTS)
def test_every_row_reads_the_minimum_of_its_beams(layout: str) -> None:
    angles = LAYOUTS[layout]
    reader = SectorReader(angles)
    rng = np.random.default_rng(7)
    for trial in range(40):
        ranges = rng.uniform(0.1, 4.0, angles.size)
        ranges[rng.random(angles.size) < 0.2] = np.inf
        if trial % 4 == 0:
            ranges[rng.integers(angles.size)] = np.nan  # one invalid beam: its rows read nan, as min() does
        expected = _reference(reader, ranges)
        reading = reader.read(ranges, 1.25)
        n, p = reader._centres, reader._pairs
        per_side = 1 + n + p
        left, right = expected[2:2 + per_side], expected[2 + per_side:2 + 2 * per_side]
        got = [reading.front, reading.front_all, reading.left, reading.right, reading.left_abeam, reading.right_abeam]
        want = [expected[0], expected[1], left[0], right[0], expected[-2], expected[-1]]
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal([reading.left_all, reading.right_all],
                                      [left[1:1 + n].max(), right[1:1 + n].max()])
        pairs = [(float(a), float(b)) for a, b in zip(left[1 + n:], right[1 + n:], strict=True)]
        np.testing.assert_array_equal(reading.sides[:len(pairs)], pairs)
        assert isinstance(reading, Reading) and reading.ahead == 1.25


def test_a_sector_without_beams_reads_inf_not_its_neighbours_beam() -> None:
    reader = SectorReader(LAYOUTS["8 beams"])  # beams every 45 deg: the narrow side sector at 60 +- 5 deg has none
    reading = reader.read(np.full(8, 2.0), math.inf)
    assert reading.front_all == 2.0  # the beam straight ahead
    assert reading.left_all == math.inf and reading.right_all == math.inf  # the largest over centres, one of them empty
