"""People walking (bt_nav_sim.walkers): their walk, their giving way, their place in the world file, and what
the robots make of them (seen by the LiDAR, a contact is a collision, the check-off judge sees them too)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.core import SimConfig
from bt_nav_sim.multi import MultiSimCore
from bt_nav_sim.walkers import GIVE_WAY, Walkers, WalkerSpec
from bt_nav_sim.world import load_world, world_from_dict

from bt_nav.judge.checkoff_core import CheckoffConfig
from tests.judge.truthkit import truth_judge

NO_ROBOTS = np.zeros((0, 3))
ROOM = [{"x": 0, "y": -2.0, "length": 8, "thickness": 0.1}, {"x": 0, "y": 2.0, "length": 8, "thickness": 0.1},
        {"x": -4.0, "y": 0, "length": 4, "thickness": 0.1, "yaw_deg": 90},
        {"x": 4.0, "y": 0, "length": 4, "thickness": 0.1, "yaw_deg": 90}]


def _spec(**kw: float) -> WalkerSpec:
    values = {"radius": 0.2, "speed": 1.0, "pause": 1.0, "phase": 0.0, **kw}
    return WalkerSpec(path=np.array([[0.0, 0.0], [2.0, 0.0]]), **values)


def _walk(walkers: Walkers, seconds: float, robots: np.ndarray = NO_ROBOTS) -> None:
    for _ in range(round(seconds / 0.01)):
        walkers.step(0.01, robots)


def test_a_walker_paces_its_path_there_and_back_with_pauses() -> None:
    w = Walkers([_spec()], seed=0)
    assert tuple(w.xy[0]) == (0.0, 0.0) and _spec().cycle == pytest.approx(6.0)
    seen = []
    for _ in range(6):
        _walk(w, 1.0)
        seen.append(round(float(w.xy[0, 0]), 6))
    # 1 m/s out (2 s), 1 s at the end, back (2 s), 1 s at the start
    assert seen == [1.0, 2.0, 2.0, 1.0, 0.0, 0.0]


def test_the_start_is_drawn_from_the_seed_unless_fixed() -> None:
    free = WalkerSpec(path=np.array([[0.0, 0.0], [5.0, 0.0]]))
    starts = [float(Walkers([free], seed).xy[0, 0]) for seed in range(6)]
    assert starts == [float(Walkers([free], seed).xy[0, 0]) for seed in range(6)]  # deterministic per seed
    assert len(set(starts)) == 6
    # 4.5 s into the cycle: 1.5 s into the walk back from x = 2
    assert float(Walkers([_spec(phase=4.5)], seed=3).xy[0, 0]) == pytest.approx(0.5)


def test_a_walker_gives_way_to_a_robot_and_walks_on_once_it_is_gone() -> None:
    w = Walkers([_spec()], seed=0)
    robot = np.array([[1.5, 0.0, 0.12]])
    _walk(w, 2.0, robot)
    gap = 1.5 - float(w.xy[0, 0]) - 0.2 - 0.12
    assert GIVE_WAY - 1e-9 <= gap <= GIVE_WAY + 0.011, gap  # it stood at the give-way distance (one step)
    _walk(w, 1.5, np.array([[1.5, 1.0, 0.12]]))  # the robot moved aside: on to the end (0.93 s), standing
    assert float(w.xy[0, 0]) == pytest.approx(2.0)


def test_world_files_are_checked() -> None:
    base = {"name": "w", "boxes": ROOM, "spawn": {"x": -3.0, "y": 0.0}}
    world = world_from_dict({**base, "walkers": [{"path": [[0, -1.5], [0, 1.5]], "r": 0.25}]})
    assert len(world.walkers) == 1 and world.walkers[0].radius == 0.25 and world.walkers[0].phase is None
    for walkers, match in (([{"path": [[-3, -1.5], [-3, 1.5]]}], "from a robot at the spawn"),
                           ([{"path": [[0, 0], [0, 3]]}], "runs into an obstacle"),
                           ([{"path": [[0, 0]]}], "at least two"),
                           ([{"path": [[0, 0], [0, 1]], "speed": 0}], "speed must be > 0"),
                           ([{"path": [[0, 0], [0, 1]], "pause": "long"}], "pause must be a number")):
        with pytest.raises(ValueError, match=match):
            world_from_dict({**base, "walkers": walkers})


def _standing_person_ahead() -> MultiSimCore:
    """A robot facing +x and a person 1.0 m ahead who stands there (a pause far longer than the run)."""
    world = world_from_dict({"name": "w", "boxes": ROOM, "spawn": {"x": -2.0, "y": 0.0},
                             "walkers": [{"path": [[-1.0, 0.0], [-1.0, 1.0]], "pause": 1000, "phase": 0.0,
                                          "speed": 1.0}]})
    # phase 0 walks towards y = 1 at once: start it standing at the first point instead
    sim = MultiSimCore(SimConfig(world="w", noise=False), world=world)
    sim.walkers.standing[0] = 1000.0
    return sim


def test_the_lidar_sees_a_person_and_driving_into_one_is_a_collision() -> None:
    sim = _standing_person_ahead()
    ranges = sim.outputs()[0].scan
    assert ranges is not None and float(ranges[0]) == pytest.approx(1.0 - 0.2, abs=0.05)  # beam 0 points ahead
    for _ in range(800):  # 8 s at 0.22 m/s: far enough to reach the person
        sim.advance([(0.22, 0.0)])
    assert sim.collisions == 1
    assert sim.cores[0].state.x == pytest.approx(-1.0 - 0.2 - 0.12, abs=0.01)  # stopped at contact
    assert sim.steps_until(10**12) == 1  # people move between steps: no merged steps


def test_the_checkoff_judge_sees_people_where_the_simulator_said() -> None:
    judge = truth_judge(CheckoffConfig(), world_from_dict({"name": "w", "boxes": ROOM}))
    far = judge.readings.read(-2.0, 0.0, 0.0, None).front
    near = judge.readings.read(-2.0, 0.0, 0.0, np.array([[-1.5, 0.0, 0.2]])).front
    assert far > 3.0 and near == pytest.approx(0.3)
    judge.on_walkers(1.0, [[-1.5, 0.0, 0.2]])
    judge.on_walkers(0.5, [[9.0, 9.0, 0.2]])  # out of order: dropped
    assert judge.readings.walkers_at(1.2)[0, 0] == -1.5 and judge.readings.walkers_at(0.2)[0, 0] == -1.5


def test_the_bundled_worlds_with_people() -> None:
    for name in ("lobby", "lab_passerby"):
        world = load_world(name)
        assert len(world.walkers) == 3
        sim = MultiSimCore(SimConfig(world=name, profile="lab" if name.startswith("lab") else "homework",
                                     noise=False), world=world)
        start = sim.walkers.xy.copy()
        for _ in range(300):
            sim.advance([(0.0, 0.0)])
        assert not np.allclose(start, sim.walkers.xy)  # they walk
        assert sim.collisions == 0 and math.isfinite(float(sim.walkers.xy.sum()))


def _judge_a_turn_after_a_person_passed(walkers: bool, leaves: float = 6.0, turns: float = 6.2) -> dict:
    """Maneuver A's judge: armed at 5 s, a robot standing at (-2, 0) facing +x; a person 0.3 m ahead until
    ``leaves`` who is gone by ``turns``, when the robot starts a 120 deg turn in place for 1 s (it decided on
    the older scan). ``walkers``: whether the simulator reported the person (else the judge sees a static
    world)."""
    judge = truth_judge(CheckoffConfig(maneuver="A"), world_from_dict({"name": "w", "boxes": ROOM}))
    judge.start(0.0)
    for k in range(0, 161):  # ground truth at 20 Hz, 0..8 s
        t = k * 0.05
        for action in judge.step(t):
            judge.on_activate_result(t, action.data, True)
        if walkers:
            judge.on_walkers(t, [[-1.5, 0.0, 0.2]] if t <= leaves + 1e-9 else [[-1.5, 3.0, 0.2]])
        turned = math.radians(120.0) * min(1.0, max(0.0, (t - turns) / 1.0))
        judge.observe(t, -2.0, 0.0, turned)
        judge.on_command(t, 0.0, 2.0 if turns - 1e-9 <= t < turns + 1.0 else 0.0)
    (episode,) = judge.results()["maneuvers"]
    return episode


def test_a_turn_on_a_person_who_just_left_is_judged_on_the_scan_the_robot_had() -> None:
    seen = _judge_a_turn_after_a_person_passed(walkers=True)
    assert seen["trigger"] and seen["angle_ok"] and seen["readings"]["front"] == pytest.approx(0.3, abs=0.01)
    unseen = _judge_a_turn_after_a_person_passed(walkers=False)
    assert not unseen["trigger"], unseen  # the judge without the person: nothing ahead, the trigger failed
    # the turn that starts as the robot is armed, on the scan of a person who passed just before the arming
    at_arming = _judge_a_turn_after_a_person_passed(walkers=True, leaves=4.95, turns=5.05)
    assert at_arming["trigger"] and at_arming["readings"]["front"] == pytest.approx(0.3, abs=0.01), at_arming
