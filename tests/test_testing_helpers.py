"""The helpers in bt_nav/testing.py that the DDS tests and the benchmarks share: the one LaserScan builder
(and the scans it is fed) and the one bounded wait."""

from __future__ import annotations

import array
import math

import numpy as np
import pytest

from bt_nav.mission.scan import Scan
from bt_nav.testing import (
    FRONT_270,
    LDS01,
    REVERSED,
    RPLIDAR,
    Layout,
    front_scan,
    laserscan_msg,
    scan_from_ranges,
    synthetic_scan,
    wait_until,
)

FIELDS = ("angle_min", "angle_max", "angle_increment", "range_min", "range_max")


@pytest.mark.parametrize("layout", [LDS01, RPLIDAR, REVERSED, FRONT_270], ids=["lds01", "rplidar", "cw", "270"])
def test_a_message_carries_the_scan_field_for_field(layout: Layout) -> None:
    scan = synthetic_scan([(0.0, 0.4), (90.0, math.nan), (200.0, -math.inf)], layout=layout)
    msg = laserscan_msg(scan, stamp=(12, 345), intensities=[1.0] * 3)
    assert all(getattr(msg, name) == getattr(scan, name) for name in FIELDS)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (12, 345, "base_scan")
    assert isinstance(msg.ranges, array.array) and msg.ranges.typecode == "f"
    assert np.asarray(msg.ranges).tobytes() == scan.ranges.astype(np.float32).tobytes()  # NaN and -inf kept
    assert list(msg.intensities) == [1.0] * 3
    back = Scan.from_laserscan(msg)
    assert np.array_equal(back.ranges, scan.ranges.astype(np.float32), equal_nan=True)


def test_scan_from_ranges_keeps_any_field_and_defaults_to_an_lds01() -> None:
    scan = scan_from_ranges([3.0] * 360)
    assert (scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max) == (0.0, 2 * math.pi / 360, 0.12, 3.5)
    assert scan.angle_max == 2 * math.pi / 360 * 359 and scan.ranges.dtype == np.float32
    odd = scan_from_ranges([], angle_increment=math.nan, angle_max=1.0, range_min=3.5, range_max=0.12)
    msg = laserscan_msg(odd)
    assert math.isnan(msg.angle_increment) and msg.angle_max == 1.0 and len(msg.ranges) == 0
    assert (msg.range_min, msg.range_max) == (3.5, 0.12)  # malformed on purpose: nothing is validated
    one = scan_from_ranges([0.2], angle_increment=0.01, angle_max=0.0)
    assert one.angle_max == 0.0 and one.num_beams == 1
    big = scan_from_ranges(array.array("f", [math.inf]) * 1000)
    assert big.num_beams == 1000 and list(laserscan_msg(big).ranges) == [math.inf] * 1000


def test_front_scan_is_the_front_cone_of_an_lds01() -> None:
    scan = front_scan(0.25)
    near = np.flatnonzero(scan.ranges == np.float32(0.25))
    assert list(near) == [*range(31), *range(331, 360)]  # 0..30 deg and -29..-1 deg (-30 rounds outside)
    assert np.all(np.delete(scan.ranges, near) == 3.0)
    assert front_scan(rest=1.0, beams=720).num_beams == 720 and front_scan(increment=0.0).angle_max == 0.0


def test_wait_until_polls_steps_and_names_what_it_waited_for() -> None:
    seen: list[int] = []
    wait_until(lambda: len(seen) >= 3, 5.0, "three steps", step=lambda: seen.append(1), interval=0.0)
    assert len(seen) == 3
    wait_until(lambda: True, 0.0, "nothing")  # true at once: no wait, even with no time left
    with pytest.raises(AssertionError, match=r"timed out after 0\.1 s waiting for never\nlast words"):
        wait_until(lambda: False, 0.1, "never", lambda: "last words")
