"""Start-up and shutdown of the executive: signals mid-maneuver, refused configurations, ``--help``."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from collections.abc import Callable

import pytest
from ros_harness import REPO, ExecutiveProcess, Harness

from bt_nav.testing import TickHarness, front_scan, laserscan_msg, wait_until


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_mid_maneuver_publishes_zero_and_exits_0(executive: Callable[..., Harness],
                                                         signum: signal.Signals) -> None:
    h = executive("-p", "maneuver:=A", "-p", "trigger_at_arming:=true",
                  "-p", "random_seed:=7", "-p", "safety_distance:=0.5")
    assert h.arm(True).success
    turning = h.ticks(3, scan=laserscan_msg(front_scan(front=0.4)))  # within safety_distance: maneuver A rotates
    assert all(s.linear == 0.0 and s.angular != 0.0 for s in turning), turning
    h.wait(lambda: bool(h.trees) and h.trees[-1]["tip"] == "Randomizer", "the tree showing the maneuver running")
    assert h.trees[-1]["nodes"][h.trees[-1]["path"][-1]]["status"] == "RUNNING"
    h.wait(lambda: any(e["event"] == "maneuver" for e in h.events), "the maneuver's event on ~/events")
    # The lock-step path runs the same tree code: its event for the same maneuver and seed has the same fields.
    lockstep = TickHarness("A", {"trigger_at_arming": True, "random_seed": 7, "safety_distance": 0.5})
    lockstep.tick()
    assert lockstep.arm()[0]
    lockstep.see((0.0, 0.4))
    lockstep.tick(3)
    (mine,) = [e for e in lockstep.core.take_announcements() if e["event"] == "maneuver"]
    (theirs,) = [e for e in h.events if e["event"] == "maneuver"]
    assert {k: theirs[k] for k in ("leaf", "maneuver", "side", "angle_deg")} == \
        {k: mine[k] for k in ("leaf", "maneuver", "side", "angle_deg")}
    assert theirs["readings"]["front"] == pytest.approx(0.4, abs=0.02)

    count = len(h.samples)
    h.process.proc.send_signal(signum)
    assert h.process.wait_exit(10.0, step=h.spin) == 0
    # The executive waits for our acknowledgement of its final zeros before it exits: they are here.
    h.wait(lambda: len(h.samples) >= count + 3, "the final zero twists", allow_exit=True)
    assert all(s.is_zero for s in h.samples[count:]), h.samples[count:]
    assert h.process.has_line(f"{signum.name} received: stopping the robot")
    assert h.process.has_line(r"final stats: tick ms min/mean/p99/max .*; ticks \d+, overruns \d+")


@pytest.mark.parametrize(("args", "reason"), [
    (["-p", "safety_distance:=-0.4"], r"safety_distance must be >= 0\.05 m, got -0\.4"),
    (["-p", "maneuver:=zigzag"], r"unknown maneuver 'zigzag'"),
    (["-p", "close_distance:=0.8"], r"close_distance \(0\.8\) must be smaller than far_distance \(0\.7\)"),
    (["-p", "evaluation_retries:=many"], r"evaluation_retries must be a number"),
], ids=["negative-distance", "unknown-maneuver", "close-not-below-far", "wrong-type"])
def test_invalid_startup_parameters_refuse_to_start(start_executive: Callable[..., ExecutiveProcess],
                                                    args: list[str], reason: str) -> None:
    process = start_executive(*args, sim_time=False)
    assert process.wait_exit(20.0) == 2
    refusals = [line for line in process.lines if "refusing to start" in line]
    assert len(refusals) == 1, process.tail()
    assert re.search(reason, refusals[0]), process.tail()


def test_integer_for_a_float_parameter_is_accepted(executive: Callable[..., Harness]) -> None:
    h = executive("-p", "safety_distance:=1", "-p", "mission_duration:=40")
    assert h.get_parameters("safety_distance", "mission_duration") == {"safety_distance": 1.0,
                                                                        "mission_duration": 40.0}


def test_params_file_and_typo_warning(executive: Callable[..., Harness]) -> None:
    h = executive("--params-file", str(REPO / "config" / "homework.yaml"), "-p", "safty_distance:=0.4")
    values = h.get_parameters("mission_duration", "maneuver", "slow_linear_speed")
    assert values == {"mission_duration": 50.0, "maneuver": "C", "slow_linear_speed": 0.2}
    h.wait(lambda: h.process.has_line(r"ignoring parameter 'safty_distance'"), "the typo warning")
    assert h.process.has_line(r"maneuver C Smart Pivot")


def test_help_needs_no_ros() -> None:
    result = subprocess.run([sys.executable, "-m", "bt_nav.cli", "executive", "--help"], cwd=REPO,
                            capture_output=True, text=True, timeout=30)
    assert result.returncode == 0
    assert "--ros-args" in result.stdout and "bt_nav_executive" in result.stdout


def test_unreadable_params_file_refuses_to_start(start_executive: Callable[..., ExecutiveProcess]) -> None:
    """A bad params file is refused as well (rcl's parser), with the reason in one line."""
    process = start_executive("--params-file", str(REPO / "config" / "does-not-exist.yaml"), sim_time=False)
    wait_until(lambda: not process.alive, 20.0, "the executive to refuse", details=process.tail)
    assert process.proc.returncode == 2
    assert any("refusing to start" in line for line in process.lines), process.tail()


def test_arming_before_the_first_clock_is_refused(start_executive: Callable[..., ExecutiveProcess],
                                                  make_harness: Callable[..., Harness]) -> None:
    h = make_harness()
    h.connect(start_executive())
    refused = h.arm(True)  # use_sim_time and no /clock yet: the mission timer would start at t=0
    assert not refused.success and "clock" in refused.message
    assert h.first_contact().is_zero
    assert h.arm(True).success
