"""One simulation: a lock-step run predicts the DDS run of the same world, seed and settings.

Both paths step :class:`bt_nav_sim.core.SimCore` and tick :class:`bt_nav.mission.core.MissionCore`; over
DDS the executive's commands reach the simulator node through a real topic, and the simulator may lead a
tick by up to one tick period (50 ms) while it waits for them, where lock-step applies every command at the
next 10 ms step. With noise off, that latency is the only difference, so the two trajectories must stay
within a few centimetres of each other while the robot drives.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from simtools import Proc

from bt_nav.run.lockstep import run_mission

#: Largest ground-truth position gap allowed between the two runs while armed (m): 50 ms of command
#: latency at 0.22 m/s is 1.1 cm per command change, and headings that differ by that much drift apart
#: slowly over a turn.
TOLERANCE_M = 0.10
WORLD, SEED = "empty_room", 3


@pytest.mark.slow
@pytest.mark.parametrize("kinematics", ["ideal", "burger"])
def test_lockstep_and_ros_simulator_agree(tmp_path: Path, kinematics: str) -> None:
    demo = Proc("demo", "--world", WORLD, "--maneuver", "none", "--seed", str(SEED), "--out", str(tmp_path),
                "--name", "run", "--quiet", "--timeout", "50", "--sim-param", "noise=false",
                "--sim-param", f"kinematics={kinematics}")
    assert demo.wait(90.0) == 0, demo.output()
    ros = json.loads((tmp_path / "run" / "trajectory.json").read_text())
    ros_times = json.loads((tmp_path / "run" / "results.json").read_text())["times"]
    lock = run_mission(WORLD, "none", SEED, jitter=None, noise=False, kinematics=kinematics)

    # Both referees count from their own start (t0); the arming reply may land a tick apart.
    shift = ros_times["t0"] + ros_times["activated"] - lock.results["times"]["activated"]
    t_ros = np.asarray(ros["t"], dtype=float) - shift  # on the lock-step clock
    # armed at 5 s; the referee disarms at 20 s, and over DDS its request and the brake land up to a tick
    # and a service round trip later than in lock-step, so the comparison ends half a second before it
    window = (t_ros >= 5.0) & (t_ros <= 19.5)
    assert window.sum() > 300, "the DDS run recorded too few ground-truth samples"
    t = t_ros[window]
    x_lock = np.interp(t, lock.trajectory.t, lock.trajectory.x)
    y_lock = np.interp(t, lock.trajectory.t, lock.trajectory.y)
    x_ros, y_ros = np.asarray(ros["x"], dtype=float)[window], np.asarray(ros["y"], dtype=float)[window]
    gap = np.hypot(x_ros - x_lock, y_ros - y_lock)
    moved = np.hypot(np.diff(x_lock), np.diff(y_lock)).sum()
    assert moved > 2.5, f"the lock-step robot barely moved ({moved:.2f} m): nothing was compared"
    assert gap.max() < TOLERANCE_M, f"trajectories drift {gap.max():.3f} m apart (mean {gap.mean():.3f} m)"
