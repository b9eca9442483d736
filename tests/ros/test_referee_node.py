"""The referee node over real DDS, with a robot that never moves (a stub activate server), shortened timings."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from simtools import Proc, StubRobot, wait_until

from bt_nav.judge.referee_core import RefereeConfig, scaled

ACTIVATE = "/reactive_control/activate"
EVALUATE = "/reactive_control/evaluate_mission"
SCALE = 0.1  # the whole schedule in ~6 s of sim time


@pytest.fixture
def world(ros_context: Any) -> Iterator[tuple[Proc, StubRobot]]:
    """A simulator (as fast as its followers allow) and the stub robot."""
    sim = Proc("sim")
    robot = StubRobot(ros_context, ACTIVATE, EVALUATE)
    yield sim, robot
    sim.stop()
    robot.close()


def _referee(tmp_path: Path, *extra: str) -> Proc:
    return Proc("referee", "--time-scale", str(SCALE), "--json", str(tmp_path / "results.json"), "--timeout", "40",
                *extra)


def test_a_robot_that_never_moves_fails(world: tuple[Proc, StubRobot], tmp_path: Path) -> None:
    sim, robot = world
    referee = _referee(tmp_path)
    code = referee.wait(60.0)
    assert code == 1, referee.output() + sim.output()
    assert referee.stdout == [
        "static at the end: PASSED",
        "static before activation: PASSED",
        "static after deactivation: PASSED",
        "minimum distance from start (reached 0.00 m, required 1.5 m): FAILED",
        "minimum travelled distance (travelled 0.00 m, required 8.0 m): FAILED",
        "evaluation service called: FAILED",
        "no collision (0 collisions): PASSED",
        "overall: FAILED",
    ], referee.output()
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["passed"] is False and results["done"] is True and results["timed_out"] is False
    assert results["report_lines"] == referee.stdout
    assert results["config"]["evaluation_deadline"] == pytest.approx(56.0 * SCALE)
    assert results["samples"] > 100  # ground truth arrived throughout
    # activate(true), deactivate, reactivate, and the final deactivation after the verdict
    assert robot.requests == [True, False, True, False]
    times = results["times"]
    assert times["activated"] - times["activation_requested"] < 0.2  # sim time is held during calls
    assert sim.alive(), sim.output()


def test_evaluation_is_served_and_judged(world: tuple[Proc, StubRobot], tmp_path: Path) -> None:
    sim, robot = world
    referee = _referee(tmp_path)
    wait_until(lambda: robot.requests[:3] == [True, False, True], 40.0, "the reactivation", referee.output)
    future = robot.evaluate.call_async(robot._trigger())
    wait_until(future.done, 20.0, "the evaluate_mission answer", referee.output)
    assert future.result().success, future.result().message
    assert "evaluation requested" in future.result().message
    assert referee.wait(60.0) == 1  # still no motion
    lines = dict(line.rsplit(": ", 1) for line in referee.stdout)
    assert lines["evaluation service called"] == "PASSED"
    assert lines["static at the end"] == "PASSED", referee.output()
    assert lines["minimum travelled distance (travelled 0.00 m, required 8.0 m)"] == "FAILED"
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["evaluation_calls"] == 1


def test_no_robot_means_timeout(ros_context: Any, tmp_path: Path) -> None:
    sim = Proc("sim")
    try:
        referee = Proc("referee", "--json", str(tmp_path / "results.json"), "--timeout", "3")
        assert referee.wait(30.0) == 2, referee.output()
        assert referee.stdout[0].startswith("TIMEOUT: no verdict after 3 s wall, before t0")
        assert referee.stdout[-1] == "overall: FAILED"
        assert json.loads((tmp_path / "results.json").read_text())["timed_out"] is True
    finally:
        sim.stop()


def test_time_scale_scales_durations_only() -> None:
    config = scaled(RefereeConfig(), 0.5)
    assert (config.static_before, config.deactivate_at, config.grace, config.reactivate_at) == (2.5, 10.0, 1.5, 15.0)
    assert (config.evaluation_deadline, config.settle_after_call, config.window) == (28.0, 1.5, 0.5)
    assert (config.min_travelled, config.min_distance_from_start, config.rate_hz) == (8.0, 1.5, 2.0)
    assert scaled(RefereeConfig(), 1.0) == RefereeConfig()
