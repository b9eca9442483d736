"""Free paths of the robot's width along candidate headings (bt_nav.mission.paths), on ray-cast scans."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim import LDS01, RayCaster, world_from_dict
from hypothesis import given, settings
from hypothesis import strategies as st

from bt_nav.mission.paths import HEADINGS, free_paths, neighbour_min
from bt_nav.mission.scan import Scan

HALF = 0.2


def scan_of(world: dict, x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> Scan:
    """A noiseless LDS-01 scan from (x, y, yaw) in a world given as a dict."""
    caster = RayCaster(world_from_dict({"name": "t", **world}), LDS01)
    m = LDS01
    return Scan(m.angle_min, m.angle_max, m.angle_increment, m.range_min, m.range_max, caster.cast(x, y, yaw))


def test_nothing_around_means_the_horizon_everywhere() -> None:
    paths = free_paths(scan_of({}), HALF, horizon=2.0)
    assert np.all(paths.free == 2.0) and paths.ahead == 2.0
    assert paths.steer(1.0) == 0.0  # no turn needed


def test_wall_ahead_stops_the_front_of_the_disk() -> None:
    paths = free_paths(scan_of({"segments": [[1.0, -3.0, 1.0, 3.0]]}), HALF, horizon=3.0)
    assert paths.ahead == pytest.approx(1.0 - HALF, abs=0.02)
    # along heading phi the disk touches the wall when its centre is HALF from it: (1 - HALF) / cos(phi)
    i = int(np.argmin(np.abs(HEADINGS - math.radians(45))))
    assert paths.free[i] == pytest.approx((1.0 - HALF) * math.sqrt(2), abs=0.03)


def test_a_post_beside_the_path_does_not_block_it_but_one_in_it_does() -> None:
    beside = free_paths(scan_of({"circles": [{"x": 1.0, "y": 0.35, "r": 0.05}]}), HALF, horizon=2.0)
    assert beside.ahead == 2.0  # 0.30 m off the centre line: the 0.2 m half width passes it
    inside = free_paths(scan_of({"circles": [{"x": 0.6, "y": 0.1, "r": 0.05}]}), HALF, horizon=2.0)
    assert 0.3 < inside.ahead < 0.6
    assert inside.steer(1.5) < 0  # the post is on the left: the nearest clear heading is to the right


def test_shoulder_obstacle_blocks_the_path_although_no_cone_would_see_it() -> None:
    # a post at 40 deg, 0.28 m away: lateral 0.18 < 0.2, so driving straight would hit it
    px, py = 0.28 * math.cos(math.radians(40)), 0.28 * math.sin(math.radians(40))
    paths = free_paths(scan_of({"circles": [{"x": px, "y": py, "r": 0.02}]}), HALF, horizon=2.0)
    assert paths.ahead < 0.2


def test_steer_prefers_the_smallest_turn_and_the_fallback_respects_a_side() -> None:
    # a corridor bend: wall ahead, open to the left only
    world = {"segments": [[1.0, -1.0, 1.0, 0.5], [-1.0, -0.5, 1.0, -0.5]]}
    paths = free_paths(scan_of(world), HALF, horizon=2.0)
    left = paths.steer(1.5)
    assert left > math.radians(30)
    assert paths.roomiest(-1) <= 0.0  # forced right: the best there, not a left turn
    assert paths.side_room(1) > paths.side_room(-1)


@given(x=st.floats(0.3, 2.5), y=st.floats(-1.0, 1.0))
@settings(max_examples=60, deadline=None)
def test_free_path_never_overshoots_a_point_in_the_corridor(x: float, y: float) -> None:
    """Driving the free path along a heading never brings the disk's centre within HALF of the post."""
    paths = free_paths(scan_of({"circles": [{"x": x, "y": y, "r": 0.03}]}), HALF, horizon=3.0)
    for phi, free in zip(paths.headings, paths.free, strict=True):
        cx, cy = free * math.cos(phi), free * math.sin(phi)
        along = np.linspace(0.0, 1.0, 50)
        gap = np.hypot(along * cx - x, along * cy - y).min() - 0.03
        # a thin post is sampled by beams 1 deg apart: the miss can be up to one beam spacing at its range
        assert gap >= HALF - 0.01 - math.hypot(x, y) * math.radians(1.0)


def test_steer_centres_the_robot_in_a_corridor() -> None:
    corridor = {"segments": [[-1.0, 0.4, 4.0, 0.4], [-1.0, -0.4, 4.0, -0.4]]}
    centred = free_paths(scan_of(corridor), HALF, horizon=1.5)
    assert centred.steer(1.2) == pytest.approx(0.0, abs=math.radians(2.5))
    off_centre = free_paths(scan_of(corridor, y=0.1), HALF, horizon=1.5)  # nearer the left wall
    target = off_centre.steer(1.2)
    assert target is not None and target < 0.0, "steer back towards the middle"


def test_steer_turns_no_more_than_needed_past_an_obstacle() -> None:
    post = free_paths(scan_of({"circles": [{"x": 1.0, "y": 0.05, "r": 0.1}]}), HALF, horizon=1.5)
    target = post.steer(1.2)
    assert target is not None and 0.0 < abs(target) <= math.radians(45)
    assert post.steer(1.2, side=-1) < 0.0 < post.steer(1.2, side=1)


def test_steer_is_none_when_no_heading_is_clear() -> None:
    box = {"segments": [[0.8, -2.0, 0.8, 2.0], [-2.0, 1.0, 0.8, 1.0], [-2.0, -0.6, 0.8, -0.6]]}
    paths = free_paths(scan_of(box), HALF, horizon=1.5)
    assert paths.steer(1.2) is None
    assert paths.side_room(1) > paths.side_room(-1)  # what the leaves fall back on: the side with more room


@settings(max_examples=300, deadline=None)
@given(values=st.lists(st.floats(0.0, 3.0), min_size=1, max_size=40), edge=st.integers(0, 4))
def test_neighbour_min_is_the_edge_padded_window_minimum(values: list[float], edge: int) -> None:
    """The shifted-slice minimum equals the plain definition (pad with the end values, window minimum)."""
    v = np.asarray(values)
    window = np.lib.stride_tricks.sliding_window_view(np.pad(v, edge, mode="edge"), 2 * edge + 1).min(axis=1)
    assert np.array_equal(neighbour_min(v, edge), window)


@pytest.mark.parametrize("mount", [(0.08, 0.03), (-0.032, 0.0), (0.2, -0.1)])
def test_a_lidar_off_the_centre_gives_the_body_its_own_free_paths(mount: tuple[float, float]) -> None:
    """A scanner mounted off the robot's centre sees the same world from elsewhere: told its mount, the free paths
    are the body's, as from a scanner at the centre; not told, the body's corridor is misplaced by the offset."""
    from bt_nav.mission.paths import free_paths_from_clean
    from bt_nav.mission.scan import clean_ranges

    world = {"segments": [[1.0, -3.0, 1.0, 3.0]], "circles": [{"x": 0.5, "y": 0.45, "r": 0.05}]}
    centred = free_paths(scan_of(world), HALF, horizon=3.0)
    # the same robot pose, the sensor at the mount (heading 0: the mount adds straight to the position)
    mounted = scan_of(world, x=mount[0], y=mount[1])
    told = free_paths_from_clean(mounted, clean_ranges(mounted), HALF, 3.0, mount=mount)
    naive = free_paths_from_clean(mounted, clean_ranges(mounted), HALF, 3.0)
    assert np.allclose(told.free, centred.free, atol=0.02), np.abs(told.free - centred.free).max()
    assert told.ahead == pytest.approx(1.0 - HALF, abs=0.02)
    assert naive.ahead == pytest.approx(1.0 - HALF - mount[0], abs=0.02)  # what a mount left out costs


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.05, 1.3), min_size=1, max_size=360),
       st.lists(st.floats(-1.6, 1.6), min_size=70, max_size=70))
def test_free_paths_are_the_plain_formula_and_along_keeps_its_answers(ranges: list[float], asked: list[float]) -> None:
    """The in-place free paths equal the module docstring's formula written plainly, and along() answers what
    interpolation says however often and of however many headings it is asked (its answers are kept)."""
    step = 2 * math.pi / len(ranges)
    scan = Scan(-math.pi, -math.pi + (len(ranges) - 1) * step, step, 0.0, LDS01.range_max,
                np.asarray(ranges, dtype=np.float32))
    paths = free_paths(scan, HALF, horizon=1.0)
    r, beam = scan.ranges.astype(float), -math.pi + np.arange(len(ranges)) * step
    x, y = r * np.cos(beam), r * np.sin(beam)
    expected = []
    for phi in HEADINGS:
        ahead = x * math.cos(phi) + y * math.sin(phi)
        lateral = y * math.cos(phi) - x * math.sin(phi)
        inside = (np.abs(lateral) < HALF) & (ahead > 0.0)
        reach = ahead[inside] - np.sqrt(HALF * HALF - lateral[inside] ** 2)
        expected.append(min(1.0, max(0.0, float(reach.min()))) if inside.any() else 1.0)
    np.testing.assert_allclose(paths.free, expected, rtol=0, atol=1e-12)
    for heading in asked + asked[:5]:
        assert paths.along(heading) == float(np.interp(heading, HEADINGS, paths.free))
