"""Ray casting, range conventions, noise and dropouts of bt_nav_sim.lidar."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim import HOMEWORK_LIDAR, LDS01, LidarModel, RayCaster, cast_rays, load_world, world_from_dict
from bt_nav_sim.lidar import ScanLayout, closed_quads

NOISELESS = LidarModel(range_max=10.0, noise_sigma=0.0)


def test_profiles() -> None:
    assert LDS01.num_beams == 360 and LDS01.range_max == 3.5 and LDS01.rate_hz == 5.0
    assert LDS01.range_min == 0.12 and LDS01.noise_sigma == 0.01 and LDS01.dropout_prob == 0.0
    assert HOMEWORK_LIDAR.range_max == 10.0 and HOMEWORK_LIDAR.rate_hz == 10.0
    assert LDS01.angle_max == pytest.approx(math.radians(359))
    with pytest.raises(ValueError):
        LidarModel(num_beams=0)


def test_empty_room_cardinal_beams() -> None:
    """Room faces at x, y = +-2.0; robot at (0.5, -0.3) facing +x."""
    world = load_world("empty_room")
    r = cast_rays(world, 0.5, -0.3, 0.0, NOISELESS)
    assert r.dtype == np.float32 and r.shape == (360,)
    assert r[0] == pytest.approx(1.5, abs=1e-6)  # +x wall
    assert r[90] == pytest.approx(2.3, abs=1e-6)  # +y wall (CCW positive)
    assert r[180] == pytest.approx(2.5, abs=1e-6)  # -x wall
    assert r[270] == pytest.approx(1.7, abs=1e-6)  # -y wall
    assert r[45] == pytest.approx(1.5 * math.sqrt(2), abs=1e-6)  # hits +x wall at y = 1.2
    assert r[30] == pytest.approx(1.5 / math.cos(math.radians(30)), abs=1e-6)
    # Facing +y, beam 0 now reads the +y wall and beam 90 the -x wall.
    r = cast_rays(world, 0.5, -0.3, math.pi / 2, NOISELESS)
    assert r[0] == pytest.approx(2.3, abs=1e-6)
    assert r[90] == pytest.approx(2.5, abs=1e-6)


def test_circle_straight_ahead() -> None:
    world = world_from_dict({"name": "pole", "circles": [{"x": 1.5, "y": 0.0, "r": 0.2}]})
    r = cast_rays(world, 0.0, 0.0, 0.0, NOISELESS)
    assert r[0] == pytest.approx(1.3, abs=1e-6)
    # Off-axis beam at 5 deg: t = b - sqrt(b^2 - (|c|^2 - r^2)) with b = 1.5 cos(5 deg).
    b = 1.5 * math.cos(math.radians(5))
    assert r[5] == pytest.approx(b - math.sqrt(b * b - (1.5**2 - 0.2**2)), abs=1e-6)
    # Tangent half-angle asin(0.2 / 1.5) = 7.66 deg: beam 8 misses, and nothing is behind.
    assert math.isinf(r[8]) and math.isinf(r[180]) and math.isinf(r[352])
    assert np.isfinite(r[353])


def test_sensor_inside_cylinder_reads_too_close() -> None:
    world = world_from_dict({"name": "pole", "circles": [{"x": 0.05, "y": 0.0, "r": 0.2}]})
    assert np.all(cast_rays(world, 0.0, 0.0, 0.0, NOISELESS) == 0.0)


def test_beyond_range_max_is_inf() -> None:
    world = load_world("empty_room")
    r = cast_rays(world, 0.0, 0.0, 0.0, LidarModel(range_max=1.0))
    assert np.all(np.isposinf(r))


def test_below_range_min_is_zero() -> None:
    world = load_world("empty_room")
    r = cast_rays(world, 1.95, 0.0, 0.0, LDS01)  # +x wall face 0.05 m ahead
    assert r[0] == 0.0
    assert math.isinf(r[180])  # 3.95 m > 3.5 m
    assert r[90] == pytest.approx(2.0, abs=1e-6)
    # Too-close and out-of-range readings are not touched by noise.
    rn = cast_rays(world, 1.95, 0.0, 0.0, LDS01, rng=np.random.default_rng(1))
    assert rn[0] == 0.0 and math.isinf(rn[180])


def test_no_noise_without_rng_and_deterministic_noise_with_seed() -> None:
    world = load_world("stage_4")
    a = cast_rays(world, -0.7, 0.0, 0.3, LDS01)
    b = cast_rays(world, -0.7, 0.0, 0.3, LDS01)
    np.testing.assert_array_equal(a, b)
    n1 = cast_rays(world, -0.7, 0.0, 0.3, LDS01, rng=np.random.default_rng(7))
    n2 = cast_rays(world, -0.7, 0.0, 0.3, LDS01, rng=np.random.default_rng(7))
    n3 = cast_rays(world, -0.7, 0.0, 0.3, LDS01, rng=np.random.default_rng(8))
    np.testing.assert_array_equal(n1, n2)
    assert not np.array_equal(n1, n3)
    assert not np.array_equal(n1, a)


def test_noise_sigma() -> None:
    world = load_world("empty_room")  # every wall within 2.83 m < 3.5 m from the centre
    caster = RayCaster(world, LDS01)
    true = caster.true_ranges(0.0, 0.0, 0.0).copy()
    rng = np.random.default_rng(123)
    err = np.concatenate([caster.cast(0.0, 0.0, 0.0, rng) - true for _ in range(50)])
    assert abs(err.mean()) < 0.001
    assert err.std() == pytest.approx(0.01, rel=0.05)


def test_dropouts_are_nan_and_seeded() -> None:
    world = load_world("empty_room")
    model = LidarModel(dropout_prob=0.25)
    assert not np.isnan(cast_rays(world, 0.0, 0.0, 0.0, model)).any()  # no rng, no faults
    scans = [cast_rays(world, 0.0, 0.0, 0.0, model, rng=np.random.default_rng(s)) for s in range(40)]
    frac = np.mean([np.isnan(s).mean() for s in scans])
    assert frac == pytest.approx(0.25, abs=0.02)
    again = cast_rays(world, 0.0, 0.0, 0.0, model, rng=np.random.default_rng(0))
    np.testing.assert_array_equal(np.isnan(again), np.isnan(scans[0]))


def test_negative_increment_and_offset_angle_min() -> None:
    world = load_world("empty_room")
    quad = LidarModel(num_beams=4, angle_min=math.pi / 2, angle_increment=-math.pi / 2, range_max=10.0)
    assert quad.angle_max == pytest.approx(-math.pi)
    r = cast_rays(world, 0.5, -0.3, 0.0, quad)
    np.testing.assert_allclose(r, [2.3, 1.5, 1.7, 2.5], atol=1e-6)  # +90, 0, -90, -180 deg
    centred = LidarModel(angle_min=-math.pi, range_max=10.0)
    r = cast_rays(world, 0.5, -0.3, 0.0, centred)
    assert r[180] == pytest.approx(1.5, abs=1e-6)  # straight ahead
    assert r[0] == pytest.approx(2.5, abs=1e-6)  # behind
    assert r[270] == pytest.approx(2.3, abs=1e-6)  # left


def _reference_scan(world, x: float, y: float, yaw: float, model: LidarModel) -> np.ndarray:
    """Slow per-beam, per-obstacle ray casting to check the vectorised one."""
    out = np.full(model.num_beams, math.inf)
    for i in range(model.num_beams):
        a = yaw + model.angle_min + i * model.angle_increment
        ux, uy = math.cos(a), math.sin(a)
        for x1, y1, x2, y2 in world.segments.tolist():
            dx, dy = x2 - x1, y2 - y1
            den = ux * dy - uy * dx
            if abs(den) < 1e-15:
                continue
            wx, wy = x1 - x, y1 - y
            t = (wx * dy - wy * dx) / den
            s = (wx * uy - wy * ux) / den
            if t >= 0 and -1e-9 <= s <= 1 + 1e-9:
                out[i] = min(out[i], t)
        for cx, cy, r in world.circles.tolist():
            wx, wy = cx - x, cy - y
            b = ux * wx + uy * wy
            disc = b * b - (wx * wx + wy * wy - r * r)
            if disc >= 0 and b - math.sqrt(disc) >= 0:
                out[i] = min(out[i], b - math.sqrt(disc))
    return out


@pytest.mark.parametrize("name", ["stage_4", "cluttered", "corridor"])
def test_vectorised_matches_reference(name: str) -> None:
    world = load_world(name)
    caster = RayCaster(world, LidarModel(num_beams=90, angle_increment=2 * math.pi / 90, range_max=10.0))
    rng = np.random.default_rng(5)
    x0, y0, x1, y1 = world.bounds
    poses = 0
    while poses < 5:
        x, y, yaw = rng.uniform(x0, x1), rng.uniform(y0, y1), rng.uniform(-math.pi, math.pi)
        if world.clearance(x, y) < 0.12:
            continue
        poses += 1
        np.testing.assert_allclose(
            caster.true_ranges(x, y, yaw), _reference_scan(world, x, y, yaw, caster.model), rtol=1e-9
        )


def test_closed_world_rays_through_corners_do_not_leak() -> None:
    # The beam at 135 deg from the corridor spawn passes exactly through the (-0.4, 0.4) wall corner.
    world = load_world("corridor")
    r = cast_rays(world, 0.0, 0.0, 0.0, LidarModel(range_max=1e3, range_min=0.0))
    assert r[135] == pytest.approx(0.4 * math.sqrt(2), abs=1e-6)
    assert np.all(np.isfinite(r))


@pytest.mark.parametrize("name", ["stage_4", "maze", "office", "lab_dead_end"])
def test_the_far_faces_of_boxes_change_no_range(name: str) -> None:
    """Leaving out the box faces turned away from the sensor gives the very ranges of casting every face, from
    free poses and from inside a box (where every face is turned away and all four are kept)."""
    world = load_world(name)
    culled, every = RayCaster(world), RayCaster(world)
    every._quads = np.zeros((0, 4), dtype=np.intp)
    assert culled._quads.shape[0] == len(world.boxes) > 0
    rng = np.random.default_rng(11)
    x0, y0, x1, y1 = world.bounds
    cx, cy = world.boxes[0][:2]
    poses = [(cx, cy, 0.3)] + [(rng.uniform(x0, x1), rng.uniform(y0, y1), rng.uniform(-math.pi, math.pi))
                               for _ in range(300)]
    for x, y, yaw in poses:
        np.testing.assert_array_equal(culled.true_ranges(x, y, yaw), every.true_ranges(x, y, yaw).copy())
    assert np.isfinite(culled.true_ranges(cx, cy, 0.3)).all(), "inside a box every beam meets a wall"


def test_only_closed_counter_clockwise_quads_are_boxes() -> None:
    square = np.array([[0, 0, 1, 0], [1, 0, 1, 1], [1, 1, 0, 1], [0, 1, 0, 0]], dtype=float)
    assert closed_quads(square).tolist() == [[0, 1, 2, 3]]
    assert closed_quads(square[::-1, [2, 3, 0, 1]]).shape == (0, 4), "clockwise: the inside is on the right"
    assert closed_quads(square[:3]).shape == (0, 4), "open: three walls of a room"
    assert closed_quads(np.vstack([square[:1], square])).tolist() == [[1, 2, 3, 4]]


def test_a_still_sensor_reuses_its_geometry_and_nothing_else() -> None:
    """Scans from one pose reuse the geometry, not the noise: each equals a fresh caster's scan from the same
    stream state. An object that appears, or a new beam layout, ends the reuse."""
    world = world_from_dict({"name": "t", "segments": [[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]],
                             "boxes": [{"x": 0.5, "y": 0.0, "length": 0.3, "thickness": 0.3, "appear_within": 0.45}]})
    model = LidarModel(range_max=3.5, dropout_prob=0.05)
    still = RayCaster(world, model)
    ours, theirs = np.random.default_rng(5), np.random.default_rng(5)
    scans = [still.cast(-1.0, 0.0, 0.0, ours) for _ in range(3)]
    for scan in scans:
        np.testing.assert_array_equal(scan, RayCaster(world, model).cast(-1.0, 0.0, 0.0, theirs))
    assert not np.array_equal(scans[0], scans[1]), "fresh noise every scan"
    assert world.update([(0.3, 0.0)]) and world.version == 1
    seen = still.cast(-1.0, 0.0, 0.0)
    assert seen[0] == pytest.approx(1.35, abs=1e-6), "the appeared box is seen from the same pose"
    wider = ScanLayout(0.0, 2 * math.pi / 180, 180)
    still.use_layout(wider)
    fresh = RayCaster(world, model)
    fresh.use_layout(wider)
    np.testing.assert_array_equal(still.cast(-1.0, 0.0, 0.0), fresh.cast(-1.0, 0.0, 0.0))
