"""A short lock-step mission written into a bag once per session: the media tests read it."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_nav.media.bag import MissionBag
from bt_nav.run.lockstep import run_mission

MISSION = {"world": "stage_4", "maneuver": "C", "seed": 1, "profile": "homework"}
DURATION = 12.0  # sim s: past the first arming at 5 s, so every topic has messages


@pytest.fixture(scope="session")
def mission_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A rosbag2 directory of the first 12 s of stage_4, maneuver C, seed 1 (lock-step)."""
    path = tmp_path_factory.mktemp("bags") / "mission"
    with MissionBag(path, mission=MISSION) as bag:
        result = run_mission(MISSION["world"], MISSION["maneuver"], MISSION["seed"], duration=DURATION, sink=bag)
        bag.event(result.sim_time, "verdict: end of the test's window")
    return path
