"""Objects that appear (``appear_within``): hidden from the LiDAR and the contacts until a robot comes
near, then there for good; a deterministic function of the robot's path (merged steps included)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.core import SimConfig, SimCore
from bt_nav_sim.lidar import LDS01, RayCaster
from bt_nav_sim.multi import MultiSimCore
from bt_nav_sim.world import load_world, world_from_dict

from bt_nav.judge.checkoff_core import CheckoffConfig
from tests.judge.truthkit import truth_judge

ROOM = [[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]]


def _world(**obj):
    return world_from_dict({"name": "t", "segments": ROOM, "spawn": {"x": -1.0, "y": 0.0},
                            "boxes": [{"x": 0.0, "y": 0.0, "length": 0.3, "thickness": 0.3, **obj}]})


def test_a_hidden_box_is_invisible_until_a_robot_comes_near_then_stays() -> None:
    w = _world(appear_within=0.55)
    caster = RayCaster(w, LDS01)
    assert w.shown == (False,) and w.segments.shape == (4, 4) and w.boxes == ()
    assert w.clearance(-0.3, 0.0) == pytest.approx(1.7)  # the walls only
    assert caster.true_ranges(-1.0, 0.0, 0.0)[0] == pytest.approx(3.0)
    assert not w.update([(-1.0, 0.0), (-0.6, 0.0)])
    assert w.update([(-0.6, 0.0), (-0.5, 0.0)]) and w.shown == (True,) and w.version == 1
    assert w.clearance(-0.3, 0.0) == pytest.approx(0.15) and len(w.boxes) == 1
    assert caster.true_ranges(-1.0, 0.0, 0.0)[0] == pytest.approx(0.85)  # the caster re-read the world
    assert not w.update([(-1.9, 1.9)]) and w.shown == (True,)  # stays
    w.reset()
    assert w.shown == (False,) and caster.true_ranges(-1.0, 0.0, 0.0)[0] == pytest.approx(3.0)


def test_a_step_cannot_jump_past_the_threshold() -> None:
    """The swept check: a path piece passing within appear_within reveals, whatever its end points."""
    w = _world(appear_within=0.55)
    assert w.update([(-1.0, 0.5), (1.0, 0.5)])  # passes 0.5 m from the centre, ends 1.1 m away


def test_circles_appear_too_and_the_threshold_is_validated() -> None:
    w = world_from_dict({"name": "t", "segments": ROOM, "circles": [{"x": 1, "y": 0, "r": 0.1, "appear_within": 0.4}]})
    assert w.circles.shape == (0, 3) and w.update([(0.65, 0.0)]) and w.circles.shape == (1, 3)
    with pytest.raises(ValueError, match="appear_within must be >= 0.41"):
        _world(appear_within=0.4)  # 0.212 bounding radius + 0.2
    with pytest.raises(ValueError, match="checkoff_maneuvers"):
        world_from_dict({"name": "t", "checkoff_maneuvers": ["D"]})


def test_worlds_without_appearing_objects_carry_no_state() -> None:
    w = load_world("stage_4")
    segs = w.segments
    assert w.appearing == () and w.shown == () and not w.update([(0.0, 0.0)]) and w.version == 0
    w.reset()
    assert w.segments is segs


def test_the_simulation_reveals_it_at_the_threshold_and_never_inside_the_robot() -> None:
    """lab_appearing: creeping at 0.05 m/s the box appears with its face 0.40 m ahead, both single-stepped
    and merged up to the next output; the next scan sees it."""
    for merge in (False, True):
        core = SimCore(SimConfig(world="lab_appearing", noise=False, profile="lab"))
        core.outputs()
        while not core.world.shown[0]:
            out = core.advance(0.05, 0.0, core.steps_until(10**12) if merge else 1)
        x_at = core.state.x
        assert -0.55 <= x_at <= -0.55 + 0.05 * 0.2 + 1e-9  # at most one scan period late when merged
        assert core.world.clearance(core.state.x, core.state.y) > 0.12 + 0.2
        while (out := core.advance(0.05, 0.0)).scan is None:
            pass
        assert out.scan[0] == pytest.approx(-0.15 - core.state.x, abs=1e-4)


def test_appearance_is_reproduced_by_a_judge_with_a_world_of_its_own() -> None:
    core = SimCore(SimConfig(world="lab_appearing", noise=False, profile="lab"))
    own = load_world("lab_appearing")
    judge = truth_judge(CheckoffConfig(), own)  # update_world=True: reveals from observed poses
    shared = truth_judge(CheckoffConfig(), core.world, update_world=False)
    for judge_ in (judge, shared):
        judge_.start(0.0)
        judge_.activation_requested = 0.0  # armed: readings are cast
    reveal_sim = reveal_own = None
    for _ in range(500):
        core.advance(0.05, 0.0, 3)
        s = core.state
        judge.observe(core.t, s.x, s.y, s.yaw)
        shared.observe(core.t, s.x, s.y, s.yaw)
        reveal_sim = reveal_sim or (core.world.shown[0] and core.t)
        reveal_own = reveal_own or (own.shown[0] and core.t)
    assert reveal_sim and reveal_own and reveal_own - reveal_sim <= 0.03 + 1e-9
    last = len(judge._t) - 1
    assert judge.readings.at(last).front == pytest.approx(shared.readings.at(last).front)
    readings = [judge.readings.at(k) for k in range(len(judge._t))]
    first_seen = next(i for i, r in enumerate(readings) if r is not None and r.front < 1.0)
    assert readings[first_seen].front == pytest.approx(0.40, abs=0.002)


def test_several_robots_reveal_it_in_a_shared_world() -> None:
    multi = MultiSimCore(SimConfig(world="lab_appearing", noise=False), 2,
                         starts=[(-1.0, 0.0, 0.0), (0.0, 1.0, -math.pi / 2)])
    for _ in range(500):
        multi.advance([(0.0, 0.0), (0.1, 0.0)])
    assert multi.world.shown == (True,)  # robot 2 came near; robot 1 sees it too
    s = multi.cores[0].state
    assert float(np.min(multi.cores[0].caster.true_ranges(s.x, s.y, s.yaw))) < 1.0
    assert math.isfinite(multi.cores[0].scan()[0])
