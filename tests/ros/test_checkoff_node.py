"""The lab's check-off judge node over real DDS: the real executive in lab mode passes; a robot that never
moves fails. Each run is the simulator as fast as its followers keep up (the homework demo's pacing)."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from simtools import Proc, StubRobot

from bt_nav.judge.checkoff_core import CheckoffConfig

LAB_ARM = "/toggle_navigation"


@pytest.mark.parametrize(("maneuver", "world"), [("C", "lab_object"), ("B", "lab_dead_end"), ("A", "lab_passerby")])
def test_the_executive_in_lab_mode_passes_its_checkoff(maneuver: str, world: str, tmp_path: Path) -> None:
    """``sim-run --profile checkoff``: simulator, executive (config/lab.yaml, toggle_navigation) and the judge
    node; the run's exit code is the judge's. Among people walking (lab_passerby) the judge reads where they
    were from the simulator's ``walkers``."""
    started = time.monotonic()
    results = tmp_path / "results.json"
    run = Proc("sim-run", "--profile", "checkoff", "--maneuver", maneuver, "--world", world, "--rtf", "0",
               "--json", str(results))
    code = run.wait(150.0)
    wall = time.monotonic() - started
    assert code == 0, run.output()
    verdict = json.loads(results.read_text())
    assert verdict["passed"] and verdict["done"] and not verdict["timed_out"], verdict["report_lines"]
    assert len(verdict["maneuvers"]) >= 1 and verdict["collisions"] == 0
    assert verdict["maneuver"] == maneuver and verdict["config"]["maneuver"] == maneuver
    arm = CheckoffConfig().activate_at  # the schedule's arming, sim s after t0
    assert verdict["t0_sim"] > 0.0 and verdict["times"]["activated"] == pytest.approx(arm, abs=0.2)
    out = "\n".join(run.stdout)
    assert "overall: PASSED" in out and f"check-off of maneuver {maneuver} in {world}" in out
    # log lines carry the sim clock and the schedule's time: "sim 3.85 s (t0 + 2.00 s): toggle_navigation(true)"
    assert f"(t0 + {arm:.1f}" in out and "toggle_navigation(true) -> success" in out, out
    print(f"check-off {maneuver} in {world}: {wall:.1f} s wall")


def test_a_robot_that_never_moves_fails(ros_context: Any, tmp_path: Path) -> None:
    """A stub that answers toggle_navigation and never moves: static checks pass, "maneuvers performed" fails."""
    sim = Proc("sim", "--world", "lab_object", "--profile", "lab", "--rtf", "0")
    robot = StubRobot(ros_context, LAB_ARM)
    try:
        judge = Proc("checkoff", "--maneuver", "A", "--world", "lab_object", "--json", str(tmp_path / "r.json"),
                     "--timeout", "60", "--ros-args", "-p", "activate_at:=1.0", "-p", "armed_for:=3.0",
                     "-p", "static_after:=2.0")
        assert judge.wait(90.0) == 1, judge.output() + sim.output()
        assert "maneuvers performed (0 performed, required >= 1): FAILED" in judge.stdout, judge.output()
        assert judge.stdout[-1] == "overall: FAILED"
        assert any(line.startswith("static before activation") and line.endswith(": PASSED")
                   for line in judge.stdout), judge.output()
        assert any(line.startswith("static after deactivation") and line.endswith(": PASSED")
                   for line in judge.stdout), judge.output()
        # true, then false (a call retried under load may repeat one; the order may not change)
        assert robot.requests[0] is True and robot.requests[-1] is False, robot.requests
        assert robot.requests == sorted(robot.requests, reverse=True), robot.requests
        results = json.loads((tmp_path / "r.json").read_text())
        assert results["passed"] is False and results["maneuvers"] == [] and results["commands"] == 0
        assert sim.alive(), sim.output()
    finally:
        sim.stop()
        robot.close()
