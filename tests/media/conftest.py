"""Short lock-step missions written into bags once per session: the media tests read them.

``mission_bag`` is the one-robot bag; ``robots_bag`` is the same mission with one robot and with two (each
robot's topics under its namespace), for what must hold for any number of robots.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest
from bt_nav_sim.multi import robot_names

from bt_nav.media.bag import ROBOT_TOPICS, MissionBag
from bt_nav.run.lockstep import run_robots

MISSION = {"world": "stage_4", "maneuver": "C", "seed": 1, "profile": "homework"}
DURATION = 12.0  # sim s: past the first arming at 5 s, so every topic has messages


@dataclass(frozen=True)
class RobotsBag:
    """A bag of ``robots`` robots: one robot's topics at the root, several robots' under ``/robot1``, ..."""

    path: Path
    robots: int

    @property
    def namespaces(self) -> list[str]:
        """"" for one robot, ``/robot1``, ``/robot2``, ... for several."""
        return [""] if self.robots == 1 else [f"/{name}" for name in robot_names(self.robots)]

    def topics(self, topic: str) -> list[str]:
        """Where ``topic`` is in this bag: under every robot's namespace for a robot topic, else at the root."""
        return [ns + topic for ns in self.namespaces] if topic in ROBOT_TOPICS else [topic]


def write_mission_bag(path: Path, robots: int = 1) -> Path:
    """:data:`MISSION`'s first :data:`DURATION` s in lock-step with ``robots`` robots, as ``bt-nav lockstep
    --bag`` writes it (each robot's last event a verdict line)."""
    names = robot_names(robots)
    with MissionBag(path, mission={**MISSION, **({"robots": names} if robots > 1 else {})}) as bag:
        run = run_robots(MISSION["world"], MISSION["maneuver"], MISSION["seed"], duration=DURATION, sink=bag,
                         robots=robots)
        for name, result in zip(run.names, run.results, strict=True):
            (bag if robots == 1 else bag.robot(name)).event(result.sim_time, "verdict: end of the test's window")
    return path


@pytest.fixture(scope="session")
def mission_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A rosbag2 directory of the first 12 s of stage_4, maneuver C, seed 1 (lock-step)."""
    return write_mission_bag(tmp_path_factory.mktemp("bags") / "mission")


@pytest.fixture(scope="session", params=[1, 2], ids=["1robot", "2robots"])
def robots_bag(request: pytest.FixtureRequest, mission_bag: Path,
               tmp_path_factory: pytest.TempPathFactory) -> RobotsBag:
    """The mission of :func:`mission_bag` with one robot (that very bag) and with two."""
    if request.param == 1:
        return RobotsBag(mission_bag, 1)
    return RobotsBag(write_mission_bag(tmp_path_factory.mktemp("bags") / "robots", request.param), request.param)
