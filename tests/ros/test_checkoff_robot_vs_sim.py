"""The robot judge against the simulator's judge on one run over real DDS (localhost, this test's own domain).

``bt-nav sim-run --profile checkoff --rtf 1`` stands in for the robot: the simulator, bt_nav's executive in lab mode
and the simulator's own check-off judge (ground truth, ray casts; it calls toggle_navigation). Beside it
``bt-nav checkoff --robot`` hears only what a TurtleBot's graph carries: /scan, /odom (the simulator's wheel
odometry, stamped on sim time, with a real base's pivot over-read and drift; 0.12 s actuation latency), /cmd_vel,
/rosout. Both must give each maneuver the same PASSED/FAILED, their angles
within 3 deg and their forward motion within 0.02 m; the listener's overall verdict is the simulator's.
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

from simtools import Proc

from bt_nav.testing import wait_until

#: A real base's effects on the simulator's /odom and wheels (the robot judge sees them; ground truth does not).
EFFECTS = {"actuation_latency": 0.12, "odom_yaw_scale": 1.015, "odom_turn_drift": 0.008}


def test_the_robot_judge_agrees_with_the_simulators_judge_on_one_run(tmp_path: Path) -> None:
    live, truth = tmp_path / "live.json", tmp_path / "truth.json"
    listener = Proc("checkoff", "--robot", "--maneuver", "C", "--json", str(live))
    try:
        wait_until(lambda: any("listening to" in line for line in listener.stdout), 30.0, "the listener started")
        run = Proc("sim-run", "--profile", "checkoff", "--maneuver", "C", "--world", "lab_object", "--rtf", "1",
                   "--json", str(truth), *(a for name, value in EFFECTS.items() for a in ("--sim-param",
                                                                                       f"{name}={value}")))
        assert run.wait(180.0) == 0, run.output()
        listener.proc.send_signal(signal.SIGINT)  # the TA's Ctrl-C: the verdict of what was heard
        code = listener.wait(60.0)
    finally:
        listener.stop()
    assert live.is_file(), f"the listener (exit code {code}) wrote no verdict\n{listener.output()}"
    sim, robot = json.loads(truth.read_text()), json.loads(live.read_text())
    assert code == (0 if robot["passed"] else 1), listener.output()
    assert sim["passed"] and robot["passed"], (sim["report_lines"], robot["report_lines"], listener.output())
    assert len(robot["judged_maneuvers"]) == len(sim["maneuvers"]) >= 1, robot["report_lines"]
    for mine, theirs in zip(robot["judged_maneuvers"], sim["maneuvers"], strict=True):
        assert mine["passed"] == theirs["passed"]
        assert abs(mine["angle_deg"] - theirs["angle_deg"]) <= 3.0, (mine["angle_deg"], theirs["angle_deg"])
        assert abs(mine["forward_motion"] - theirs["forward_motion"]) <= 0.02
        print(f"maneuver: odometry {mine['angle_deg']:+.2f} deg {mine['forward_motion']:.4f} m, ground truth "
              f"{theirs['angle_deg']:+.2f} deg {theirs['forward_motion']:.4f} m")
    out = "\n".join(listener.stdout)
    assert "maneuver 1 (" in out.split("check-off of maneuver C from the live robot")[0], out  # printed live


def test_the_listener_calls_toggle_navigation_itself(tmp_path: Path) -> None:
    """``--call-toggle``: beside ``sim-run --profile lab`` (the simulator and bt_nav's executive, no judge) the
    listener arms the robot after 3 s and disarms it at the end; its own calls are the schedule, so the service
    checks are judged (not "not judged" as when the TA calls and no service event is recorded)."""
    verdict = tmp_path / "live.json"
    robot = Proc("sim-run", "--profile", "lab", "--maneuver", "C", "--world", "lab_object", "--rtf", "1")
    try:
        wait_until(lambda: any("ROS_DOMAIN_ID" in line for line in robot.stdout), 60.0, "the simulated robot runs")
        listener = Proc("checkoff", "--robot", "--call-toggle", "--duration", "32", "--maneuver", "C",
                        "--json", str(verdict))
        code = listener.wait(120.0)
    finally:
        robot.stop()
    res = json.loads(verdict.read_text())
    out = "\n".join(listener.stdout)
    assert "toggle_navigation(true): success=True" in out and "toggle_navigation(false): success=True" in out, out
    names = {c["name"]: c["passed"] for c in res["checks"]}
    assert names["toggle_navigation answered"] and names["static before activation"], res["report_lines"]
    assert not any(n["name"] == "toggle_navigation answered" for n in res["not_judged"])
    assert res["passed"] and code == 0 and len(res["judged_maneuvers"]) >= 1, res["report_lines"]
