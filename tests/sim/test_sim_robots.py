"""Several robots in one world (bt_nav_sim.multi, bt_nav.run.lockstep): one robot is the single-robot
core bit for bit, robots see each other in their LiDAR, a robot-robot contact is a collision for both,
and each robot's tree and referee are its own."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.core import SimConfig, SimCore
from bt_nav_sim.lidar import RayCaster
from bt_nav_sim.multi import MultiSimCore, auto_starts, parse_starts, robot_names
from bt_nav_sim.world import load_world

from bt_nav.run.lockstep import run_mission, run_robots

QUIET = SimConfig(world="empty_room", noise=False)


def test_one_robot_is_the_single_robot_core_bit_for_bit() -> None:
    config = SimConfig(world="stage_4", seed=3, spawn_jitter_m=0.05, spawn_jitter_deg=10.0)
    single, multi = SimCore(config), MultiSimCore(config, 1)
    commands = [(0.22, 0.0)] * 150 + [(0.1, 1.5)] * 80 + [(0.0, 0.0)] * 30 + [(0.22, -2.0)] * 100
    for v, w in commands:
        a = single.advance(v, w)
        (b,) = multi.advance([(v, w)])
        assert (a.t_ns, a.odom, a.collision) == (b.t_ns, b.odom, b.collision)
        assert (a.scan is None) == (b.scan is None)
        if a.scan is not None:
            assert np.array_equal(a.scan, b.scan)
    s, m = single.state, multi.cores[0].state
    assert (s.x, s.y, s.yaw, single.odom_x, single.odom_yaw) == (m.x, m.y, m.yaw, multi.cores[0].odom_x,
                                                                  multi.cores[0].odom_yaw)


def test_each_robot_sees_the_other_as_a_circle_of_its_radius() -> None:
    multi = MultiSimCore(QUIET, 2, starts=[(-0.5, 0.0, 0.0), (0.5, 0.0, math.pi)])
    scans = multi.outputs()
    front = [float(out.scan[0]) for out in scans]  # beam 0 points straight ahead
    assert front == pytest.approx([1.0 - 0.12, 1.0 - 0.12], abs=1e-6)
    alone = SimCore(QUIET, spawn=(-0.5, 0.0, 0.0)).scan()
    assert float(alone[0]) > 2.0, "without the other robot the beam reaches the wall"
    # the extra circles are cast exactly as the world's own cylinders
    world = load_world("empty_room")
    caster = RayCaster(world, QUIET.lidar_model())
    ranges = caster.cast(0.0, 0.0, 0.3, extra=np.array([[1.0, 0.2, 0.3], [-1.0, -1.0, 0.1]]))
    ux, uy = math.cos(0.3), math.sin(0.3)
    assert np.isfinite(ranges).all() and ranges.min() > 0.0
    assert float(ranges[0]) == pytest.approx(_ray_circle(ux, uy, 1.0, 0.2, 0.3), abs=1e-5)


def _ray_circle(ux: float, uy: float, cx: float, cy: float, r: float) -> float:
    b = ux * cx + uy * cy
    return b - math.sqrt(b * b - (cx * cx + cy * cy - r * r))


def test_head_on_robots_stop_at_contact_and_both_count_a_collision() -> None:
    multi = MultiSimCore(QUIET, 2, starts=[(-0.5, 0.0, 0.0), (0.5, 0.0, math.pi)])
    events = [[], []]
    for _ in range(600):
        for i, out in enumerate(multi.advance([(0.22, 0.0), (0.22, 0.0)])):
            if out.collision:
                events[i].append(out.t_ns)
    a, b = (c.state for c in multi.cores)
    assert math.hypot(a.x - b.x, a.y - b.y) >= 0.24 - 1e-6, "never overlapping"
    assert math.hypot(a.x - b.x, a.y - b.y) <= 0.24 + 1e-3, "stopped at contact"
    assert [len(e) for e in events] == [1, 1] and [c.collisions for c in multi.cores] == [1, 1]


def test_a_robot_standing_still_that_is_hit_counts_a_collision_too() -> None:
    multi = MultiSimCore(QUIET, 2, starts=[(-0.5, 0.0, 0.0), (0.5, 0.0, 0.0)])
    for _ in range(600):
        multi.advance([(0.22, 0.0), (0.0, 0.0)])
    assert [c.collisions for c in multi.cores] == [1, 1]
    assert multi.cores[1].state.x == 0.5, "a kinematic robot is not pushed"


def test_names_starts_and_placement() -> None:
    assert robot_names(2) == ["robot1", "robot2"]
    assert robot_names(1, ["/alpha", "beta "]) == ["alpha", "beta"]
    with pytest.raises(ValueError, match="differ"):
        robot_names(2, ["a", "a"])
    assert parse_starts("1,2,90; -1,0,0") == [(1.0, 2.0, math.pi / 2), (-1.0, 0.0, 0.0)]
    with pytest.raises(ValueError, match="x,y,yaw_deg"):
        parse_starts("1,2")
    with pytest.raises(ValueError, match="overlapping"):
        MultiSimCore(QUIET, 2, starts=[(0.0, 0.0, 0.0), (0.2, 0.0, 0.0)])
    world = load_world("stage_4")
    poses = auto_starts(world, world.spawn, 3, 0.12)
    assert poses[0] == world.spawn and len(poses) == 3
    for i, (x, y, _) in enumerate(poses):
        assert world.clearance(x, y) >= 0.3
        assert all(math.hypot(x - px, y - py) >= 0.6 for px, py, _ in poses[:i])


def test_lockstep_robots_have_their_own_trees_and_referees() -> None:
    """With the second robot parked out of the way, the first drives exactly its single-robot mission:
    the trees do not share a blackboard (each MissionCore owns one; py_trees' storage is process-wide)."""
    single = run_mission("stage_4", "C", 0, jitter=None)
    multi = run_robots("stage_4", "C", 0, robots=2, starts=((-0.7, 0.0, 0.0), (2.0, -1.5, 0.0)), jitter=None)
    first, second = multi.results
    assert first.travelled == pytest.approx(single.travelled, abs=0.05)
    assert first.passed and second.collisions == 0
    assert second.results["evaluation_calls"] == 1 and first.results["evaluation_calls"] == 1
    assert second.travelled > 1.0, "the parked robot was armed by its own referee and drove"
    lines = multi.report_lines()
    assert lines[0].startswith("robot1: ") and any(line.startswith("robot2: overall") for line in lines)
    assert lines[-1].startswith("summary: ") and "robot1" in lines[-1] and "robot2" in lines[-1]
