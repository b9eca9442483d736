"""The lock-step runner: the real tree and the simulator stepped together, judged by the referee.

What must hold for any number of robots runs for one and for two (``robots``): the one loop drives a
list of robots, one robot is a list of one. Two robots run shorter where the check allows it."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest

from bt_nav.cli.lockstep import main
from bt_nav.media.plot import BRANCHES, Trajectory, plot_run
from bt_nav.mission.trace import read_trace
from bt_nav.run.lockstep import run_mission, run_robots
from bt_nav.run.result import MissionResult

ROBOTS = [pytest.param(1, id="1robot"), pytest.param(2, id="2robots")]


def each_robot(robots: int, *args: Any, **kwargs: Any) -> list[MissionResult]:
    """Every robot's result of one lock-step run of ``robots`` robots (:func:`run_robots`'s arguments)."""
    results = run_robots(*args, robots=robots, **kwargs).results
    assert len(results) == robots
    return results


@pytest.mark.parametrize(("robots", "duration"), [pytest.param(1, None, id="1robot"),
                                                  pytest.param(2, 20.0, id="2robots")])
def test_same_seed_same_run(robots: int, duration: float | None) -> None:
    runs = [each_robot(robots, "stage_4", "A", seed, duration=duration) for seed in (3, 3, 4)]
    for a, b, c in zip(*runs, strict=True):
        assert a.results == b.results
        assert a.branch_ticks == b.branch_ticks
        np.testing.assert_array_equal(a.trajectory.x, b.trajectory.x)
        np.testing.assert_array_equal(a.trajectory.yaw, b.trajectory.yaw)
        assert not np.array_equal(a.trajectory.x, c.trajectory.x), "the seed matters"


@pytest.mark.parametrize("robots", ROBOTS)
def test_stage_4_mission_passes(robots: int) -> None:
    for result in each_robot(robots, "stage_4", "none", seed=0):
        _passes_stage_4(result)


def _passes_stage_4(result: MissionResult) -> None:
    assert result.passed, result.report_lines
    assert result.collisions == 0
    assert result.report_lines[-1] == "overall: PASSED"
    margin = float(result.parameters["stop_margin"])
    assert 0.0 < margin < 1.0
    # armed 5-20 s and from 30 s until the stop, due 50 s - stop_margin after the first arming
    assert result.active_time == pytest.approx(15.0 + 25.0 - margin, abs=0.1)
    assert 0.0 < result.efficiency <= 1.0
    assert result.travelled >= 8.0
    assert set(result.branch_ticks) <= set(BRANCHES)
    times = result.results["times"]
    assert times["activated"] == 5.0 and times["deactivation_requested"] == 20.0
    assert times["evaluation_called"] == pytest.approx(55.0 - margin, abs=0.06)
    # the report comes 3 s after the call, at the referee's next 2 Hz step
    assert times["evaluation_called"] + 3.0 <= result.sim_time <= times["evaluation_called"] + 3.5 + 1e-9


@pytest.mark.parametrize("robots", ROBOTS)
def test_driving_into_a_wall_is_caught_by_the_referee(robots: int) -> None:
    """Thresholds so small the robot never reacts: it hits the wall, and the referee must fail it."""
    # a path narrower than the robot (radius 0.12 m) and tiny thresholds: it only sees what is dead ahead
    for result in each_robot(robots, "stage_4", "none", seed=0, overrides={"close_distance": 0.05,
                                                                           "far_distance": 0.06,
                                                                           "path_half_width": 0.05}, jitter=None):
        assert result.collisions >= 1
        assert not result.passed
        assert "no collision" in result.failed_checks
        assert result.report_lines[-1] == "overall: FAILED"
        event = result.results["collision_events"][0]
        assert 5.0 < event["t"] < 20.0


@pytest.mark.parametrize("robots", ROBOTS)
def test_kinematics_and_profiles_reach_the_simulator(robots: int) -> None:
    runs = [each_robot(robots, "stage_4", "none", seed=1, duration=20.0, **options)
            for options in ({}, {"kinematics": "burger"}, {"profile": "turtlebot3"})]
    for ideal, burger, real in zip(*runs, strict=True):
        assert (ideal.kinematics, burger.kinematics, real.kinematics) == ("ideal", "burger", "burger")
        assert ideal.summary()["kinematics"] == "ideal"
        assert not np.array_equal(burger.trajectory.x, ideal.trajectory.x)  # the wheel limits act
        if robots == 1:  # a measurement of this start and seed (two robots start elsewhere, with other seeds)
            # the homework tuning turns at 2.5 rad/s while driving: wheel limits cost it distance
            assert burger.travelled < ideal.travelled - 0.1
        assert real.profile == "turtlebot3"


@pytest.mark.parametrize("robots", ROBOTS)
def test_noise_off_is_deterministic_without_a_seed_effect_on_the_sensors(robots: int) -> None:
    a = each_robot(robots, "empty_room", "none", seed=1, duration=12.0, jitter=None, noise=False)
    b = each_robot(robots, "empty_room", "none", seed=2, duration=12.0, jitter=None, noise=False)
    c = each_robot(robots, "empty_room", "none", seed=2, duration=12.0, jitter=None)
    for ra, rb, rc in zip(a, b, c, strict=True):
        np.testing.assert_allclose(ra.trajectory.x, rb.trajectory.x)  # nothing random is left
        assert not np.array_equal(ra.trajectory.x, rc.trajectory.x)  # noise on: the seed matters


@pytest.mark.parametrize("robots", ROBOTS)
def test_lab_profile_and_bad_arguments(robots: int) -> None:
    for result in each_robot(robots, "empty_room", "C", seed=0, profile="lab", duration=12.0):  # the judge needs one
        assert 0.4 < result.travelled < 0.51  # lab mode: armed at 2 s (5 s before issue 52), it creeps at 0.05 m/s
    with pytest.raises(ValueError, match="profile"):
        run_mission(profile="gazebo")
    with pytest.raises(ValueError, match="unknown parameter"):
        run_mission(overrides={"no_such_parameter": 1})


@pytest.mark.parametrize(("robots", "duration", "at_least"), [pytest.param(1, None, 1000, id="1robot"),
                                                             pytest.param(2, 20.0, 350, id="2robots")])
def test_cli_writes_trace_plot_and_json(robots: int, duration: float | None, at_least: int, tmp_path,
                                        capsys) -> None:
    """One robot: the trace and the results as they are; several: a trace per robot, results per robot.
    ``at_least``: trace lines and trajectory samples (20 Hz ticks, 30 Hz odometry) the run must give."""
    trace, picture, results = tmp_path / "trace.jsonl", tmp_path / "run.png", tmp_path / "results.json"
    code = main(["--world", "stage_4", "--maneuver", "B", "--seed", "2", "--trace", str(trace),
                 "--plot", str(picture), "--json", str(results), "--robots", str(robots),
                 *(["--duration", str(duration)] if duration else [])])
    out = capsys.readouterr().out
    data = json.loads(results.read_text())
    assert code == (0 if data["passed"] else 1)
    assert "overall:" in out and "maneuver B, seed 2" in out
    assert picture.stat().st_size > 10_000
    names = ["robot1", "robot2"][:robots]
    traces = [trace] if robots == 1 else [tmp_path / f"trace_{name}.jsonl" for name in names]
    each = [data] if robots == 1 else [data["robots"][name] for name in names]
    for path, robot in zip(traces, each, strict=True):
        header, ticks = read_trace(path)
        assert header["maneuver"] == "B" and len(ticks) > at_least
        assert "pose" in ticks[0]
        assert len(robot["trajectory"]["x"]) == len(robot["trajectory"]["branch"]) > at_least


def test_plot_accepts_a_plain_dict_trajectory(tmp_path) -> None:
    """The ROS demo records topics into plain arrays; the same function draws them."""
    from bt_nav_sim import load_world

    t = np.linspace(0.0, 10.0, 50)
    trajectory = {"t": t, "x": np.cos(t / 3), "y": np.sin(t / 3), "yaw": t / 3 + np.pi / 2,
                  "branch": ["FullSpeed"] * 20 + ["Maneuver"] * 10 + ["TurnAway"] * 20}
    results = {"passed": False, "travelled": 3.3, "collisions": 1, "collision_events": [{"x": 1.0, "y": 0.0}],
               "checks": [{"name": "no collision", "passed": False}]}
    path = plot_run(load_world("empty_room"), trajectory, results, tmp_path / "sub" / "run.svg")
    assert path.exists() and "<svg" in path.read_text()[:500]
    assert Trajectory.from_dict(trajectory).segments_of("Maneuver") == [(20, 30)]


def test_merged_physics_steps_match_single_steps() -> None:
    """Merging the 10 ms steps between events (once the twist has settled at the command) is exact, so it
    changes neither the path nor the tree's decisions."""
    merged = run_mission("stage_4", "C", seed=1, duration=20.0)
    single = run_mission("stage_4", "C", seed=1, duration=20.0, merge_steps=False)
    gap = np.hypot(merged.trajectory.x - single.trajectory.x, merged.trajectory.y - single.trajectory.y)
    assert gap.max() < 1e-6
    assert merged.branch_ticks == single.branch_ticks


@pytest.mark.parametrize("lidar", sorted(__import__("bt_nav_sim.lidar", fromlist=["LIDARS"]).LIDARS))
def test_every_real_lidar_flies_the_homework_and_the_checkoff(lidar: str, capsys: pytest.CaptureFixture) -> None:
    """``bt-nav lockstep --sim-param lidar=X`` for each model: the homework passes, and the lab's Smart Pivot is
    checked off in lab_object, with the executive told where the LiDAR sits (as the runner does)."""
    assert main(["--world", "stage_4", "--maneuver", "none", "--sim-param", f"lidar={lidar}"]) == 0
    assert "PASSED" in capsys.readouterr().out
    lab = run_mission("lab_object", "C", 0, profile="lab", sim_params={"lidar": lidar})
    assert lab.passed and lab.maneuvers >= 1 and lab.collisions == 0, lab.report_lines


@pytest.mark.parametrize("seed", [1, 15])
def test_smart_pivot_in_a_pocket_keeps_its_side(seed: int) -> None:
    """cluttered, maneuver C: the robot meets a pocket by the wall, the Smart Pivot turns a quarter towards the
    clearer side and the front is still close. The rotation in place that follows keeps the pivot's side; it
    chose afresh and turned back into the pocket (before: 7.92 m and 7.95 m, short of the homework's 8 m)."""
    result = run_mission("cluttered", "C", seed=seed)
    assert result.maneuvers >= 1 and result.collisions == 0
    assert result.passed, result.report_lines
    assert result.travelled >= 8.1
