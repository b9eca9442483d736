"""World loading, box geometry, clearance and the cluttered generator of bt_nav_sim."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from bt_nav_sim import LidarModel, World, cast_rays, list_worlds, load_world
from bt_nav_sim.world import box_corners, box_segments, world_from_dict


def _corner_set(segs: np.ndarray) -> set[tuple[float, float]]:
    pts = np.vstack([segs[:, 0:2], segs[:, 2:4]])
    return {(round(float(a), 9), round(float(b), 9)) for a, b in pts}


def test_stage_4_layout() -> None:
    w = load_world("stage_4")
    assert w.name == "stage_4"
    assert w.segments.shape == (48, 4)  # (4 outer + 8 inner walls) x 4 sides
    assert w.circles.shape == (2, 3)
    assert len(w.boxes) == 12
    assert {tuple(c) for c in w.circles.tolist()} == {(2.0, 2.0, 0.12), (-2.0, -2.0, 0.12)}
    assert w.spawn == pytest.approx((-0.7, 0.0, 0.0))
    # Nearest obstacle to the spawn: inner wall at x = -1.502 (face at -1.427), spanning y in [-0.408, 0.592].
    assert w.clearance(-0.7, 0.0) == pytest.approx(0.727)
    # Outer wall centre lines at +-2.425 with 0.15 m thickness -> inner faces at +-2.35, outer at +-2.5.
    assert w.segments[:, [0, 2]].max() == pytest.approx(2.5)
    assert w.segments[:, [1, 3]].min() == pytest.approx(-2.5)
    # (2.0, 0) is 0.35 from the x = 2.35 face and 0.388 from the inner wall at (1.911, 0.463).
    assert w.clearance(2.0, 0.0) == pytest.approx(0.35)
    # 0.08 from the cylinder at (-2, -2) (0.2 - 0.12), nearer than the y = -2.35 wall face (0.15).
    assert w.clearance(-2.0, -2.2) == pytest.approx(0.08)


def test_bundled_worlds_listed() -> None:
    assert {"stage_4", "empty_room", "corridor", "cluttered"} <= set(list_worlds())


@pytest.mark.parametrize("name", list_worlds())
def test_every_world_loads_closed_with_clear_spawn(name: str) -> None:
    w = load_world(name)
    assert isinstance(w, World)
    assert w.segments.dtype == np.float64 and w.segments.flags.c_contiguous
    x, y, _ = w.spawn
    assert w.clearance(x, y) >= 0.3
    xmin, ymin, xmax, ymax = w.bounds
    assert xmin < x < xmax and ymin < y < ymax
    # Closed: a long-range scan from the spawn hits a wall in every direction.
    probe = LidarModel(num_beams=1440, angle_increment=2 * math.pi / 1440, range_min=0.0, range_max=1e3)
    ranges = cast_rays(w, x, y, 0.0, probe)
    assert np.all(np.isfinite(ranges))
    # ...and every wall hit lies within the plotting bounds.
    ang = np.arange(1440) * probe.angle_increment
    hx, hy = x + ranges * np.cos(ang), y + ranges * np.sin(ang)
    assert np.all((hx >= xmin) & (hx <= xmax) & (hy >= ymin) & (hy <= ymax))


def test_corridor_squeezes_robot() -> None:
    w = load_world("corridor")
    x, y, yaw = w.spawn
    assert yaw == pytest.approx(0.0)
    scan = cast_rays(w, x, y, yaw, LidarModel(range_max=10.0))
    left, right = scan[90], scan[270]
    assert left < 0.5 and right < 0.5  # squeezed at the spawn already
    assert scan[0] > 2.0  # it is a corridor along the heading


def test_box_corners_yaw_0_and_90() -> None:
    c0 = box_corners(1.0, 2.0, 1.0, 0.2, 0.0)
    np.testing.assert_allclose(c0, [[1.5, 2.1], [0.5, 2.1], [0.5, 1.9], [1.5, 1.9]], atol=1e-12)
    c90 = box_corners(1.0, 2.0, 1.0, 0.2, math.pi / 2)
    np.testing.assert_allclose(c90, [[0.9, 2.5], [0.9, 1.5], [1.1, 1.5], [1.1, 2.5]], atol=1e-12)
    segs = box_segments(1.0, 2.0, 1.0, 0.2, math.pi / 2)
    assert segs.shape == (4, 4)
    # Each segment joins consecutive corners and the ring closes.
    np.testing.assert_allclose(segs[:, 2:4], np.roll(segs[:, 0:2], -1, axis=0))
    lengths = sorted(np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]).round(12))
    assert lengths == pytest.approx([0.2, 0.2, 1.0, 1.0])


def test_boxes_in_yaml_become_four_segments() -> None:
    w = world_from_dict(
        {
            "name": "boxes",
            "boxes": [
                {"x": 0, "y": 0, "length": 2.0, "thickness": 0.5, "yaw_deg": 0},
                {"x": 5, "y": 0, "length": 2.0, "thickness": 0.5, "yaw_deg": 90},
            ],
        }
    )
    assert w.segments.shape == (8, 4)
    assert _corner_set(w.segments[:4]) == {(1.0, 0.25), (-1.0, 0.25), (-1.0, -0.25), (1.0, -0.25)}
    assert _corner_set(w.segments[4:]) == {(5.25, 1.0), (5.25, -1.0), (4.75, -1.0), (4.75, 1.0)}
    assert w.boxes[1] == pytest.approx((5.0, 0.0, 2.0, 0.5, math.pi / 2))


def test_clearance_hand_picked_points() -> None:
    w = world_from_dict({"name": "t", "segments": [[0, 0, 2, 0]], "circles": [{"x": 5, "y": 0, "r": 1}]})
    assert w.clearance(1.0, 1.0) == pytest.approx(1.0)  # perpendicular foot inside the segment
    assert w.clearance(-1.0, -1.0) == pytest.approx(math.sqrt(2))  # nearest is the endpoint
    assert w.clearance(3.5, 0.0) == pytest.approx(0.5)  # circle surface is nearer than the segment end
    assert w.clearance(5.0, 0.0) == pytest.approx(-1.0)  # inside the cylinder: negative
    assert w.clearance(1.0, 0.0) == pytest.approx(0.0)  # on the wall
    assert world_from_dict({"name": "void"}).clearance(0.0, 0.0) == math.inf


def test_world_is_immutable() -> None:
    w = load_world("empty_room")
    with pytest.raises(dataclasses.FrozenInstanceError):
        w.name = "other"  # type: ignore[misc]
    with pytest.raises(ValueError):
        w.segments[0, 0] = 99.0


def test_load_by_path_and_errors(tmp_path) -> None:
    p = tmp_path / "mine.yaml"
    p.write_text("spawn: {x: 0.5, y: 0, yaw_deg: 90}\nsegments: [[0, -1, 0, 1]]\n")
    w = load_world(str(p))
    assert w.name == "mine"  # defaults to the file stem
    assert w.spawn == pytest.approx((0.5, 0.0, math.pi / 2))
    assert w.segments.shape == (1, 4) and w.circles.shape == (0, 3)
    with pytest.raises(FileNotFoundError, match="stage_4"):
        load_world("no_such_world")
    with pytest.raises(ValueError):
        world_from_dict({"name": "bad", "boxes": [{"x": 0, "y": 0, "length": 1}]})
    with pytest.raises(ValueError):
        world_from_dict({"name": "bad", "segments": [[0, 0, 1]]})


def _generated(w: World) -> tuple[np.ndarray, list[tuple]]:
    """Obstacles added by the generator: all circles and every box after the 4 room walls."""
    return w.circles, list(w.boxes[4:])


def test_cluttered_deterministic_per_seed() -> None:
    a, b = load_world("cluttered", seed=3), load_world("cluttered", seed=3)
    np.testing.assert_array_equal(a.segments, b.segments)
    np.testing.assert_array_equal(a.circles, b.circles)
    c = load_world("cluttered", seed=4)
    assert not (np.array_equal(a.segments, c.segments) and np.array_equal(a.circles, c.circles))
    # No seed -> the seed written in the YAML (42).
    d, e = load_world("cluttered"), load_world("cluttered", seed=42)
    np.testing.assert_array_equal(d.circles, e.circles)
    np.testing.assert_array_equal(d.segments, e.segments)


@pytest.mark.parametrize("seed", range(20))
def test_cluttered_invariants(seed: int) -> None:
    w = load_world("cluttered", seed=seed)
    circles, boxes = _generated(w)
    assert len(circles) + len(boxes) == 12
    sx, sy, _ = w.spawn
    assert w.clearance(sx, sy) >= 0.6  # keep_clear
    bounding = [(cx, cy, r) for cx, cy, r in circles.tolist()]
    bounding += [(bx, by, 0.5 * math.hypot(length, th)) for bx, by, length, th, _ in boxes]
    for i, (xi, yi, ri) in enumerate(bounding):
        assert abs(xi) + ri + 0.35 <= 2.35 + 1e-9 and abs(yi) + ri + 0.35 <= 2.35 + 1e-9  # gap to walls
        for xj, yj, rj in bounding[i + 1 :]:
            assert math.hypot(xi - xj, yi - yj) >= ri + rj + 0.35 - 1e-9  # gap between obstacles
