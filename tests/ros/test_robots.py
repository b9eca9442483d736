"""Two robots in one world over real DDS: one simulator hosting robot1 and robot2, two unchanged executives
and two referees, each pair in its robot's namespace (the graph of ``bringup.robot_nodes``).

What must hold: each referee arms its own robot on its own timeline (robot2's referee starts later, so
robot1 drives while robot2 is still disarmed and stopped), both are judged (one evaluation call each),
no message of one robot reaches the other (the graph: every robot topic and service has exactly its own
robot's nodes on it, nothing is left at the root; the traffic: robot2 commands nothing but zero while
robot1 drives), and each robot gets a zero twist on its own cmd_vel from its deadline on.

The mission is shortened (mission_duration 10 s, the referee's schedule x 0.2, 1 m to travel) so the
whole run takes about 15 s of sim time.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from simtools import Proc

from bt_nav.mission.params import SPECS
from bt_nav.ros.bringup import robot_nodes
from bt_nav.ros.rosutil import ThreadedNode
from bt_nav.testing import wait_until

ROBOTS = ["robot1", "robot2"]
SCALE = 0.2
MISSION = 10.0  # s, the executives' mission_duration
STOP_MARGIN = float(SPECS["stop_margin"].default)
#: Nodes that may touch a robot's topics besides its own executive, referee and the simulator.
OBSERVERS = {"/multi_probe"}


class Probe:
    """Records every robot's cmd_vel (with the sim time it arrived at) and ground truth.

    A :class:`~bt_nav.ros.rosutil.ThreadedNode` named ``multi_probe`` (one of :data:`OBSERVERS`)."""

    def __init__(self) -> None:
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock

        self.spinner = ThreadedNode("multi_probe")
        self.node = self.spinner.node
        self.lock = threading.Lock()
        self.now = 0.0
        self.cmds: dict[str, list[tuple[float, float, float]]] = {r: [] for r in ROBOTS}
        self.truth: dict[str, list[tuple[float, float, float]]] = {r: [] for r in ROBOTS}
        reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.node.create_subscription(Clock, "/clock", self._on_clock,
                                      QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
        for robot in ROBOTS:
            self.node.create_subscription(Twist, f"/{robot}/cmd_vel",
                                          lambda m, r=robot: self._add(self.cmds[r], m.linear.x, m.angular.z), 100)
            self.node.create_subscription(
                Odometry, f"/{robot}/ground_truth_odom",
                lambda m, r=robot: self._add(self.truth[r], m.pose.pose.position.x, m.pose.pose.position.y), reliable)
        self.spinner.start()

    def _on_clock(self, msg: Any) -> None:
        with self.lock:
            self.now = msg.clock.sec + msg.clock.nanosec * 1e-9

    def _add(self, sink: list, a: float, b: float) -> None:
        with self.lock:
            sink.append((self.now, float(a), float(b)))

    def moving(self, robot: str) -> bool:
        """The robot's latest command is motion."""
        with self.lock:
            return bool(self.cmds[robot]) and self.cmds[robot][-1][1:] != (0.0, 0.0)

    def close(self) -> None:
        self.spinner.close()


def _start(spec: Any) -> Proc:
    """A node of the bringup table as a ``bt-nav`` subprocess (its exact command line)."""
    return Proc(*spec.command()[3:])  # after "python -m bt_nav.cli"


@pytest.fixture
def world(tmp_path: Path) -> Iterator[dict[str, Any]]:
    """Simulator and both executives running, both referees built but not started; the probe."""
    results = {r: str(tmp_path / f"{r}.json") for r in ROBOTS}
    referee = {"time_scale": SCALE, "min_travelled": 1.0, "min_distance_from_start": 0.3, "timeout": 120.0}
    specs = robot_nodes("eval", ROBOTS, seed=0, rtf=0.0, results_json=results, referee=referee,
                        executive={"mission_duration": MISSION, "maneuver": "C"}, sim={"afap_max_rtf": 4.0})
    probe = Probe()
    procs: list[Proc] = []
    try:
        for spec in specs:
            if spec.executable != "referee":
                procs.append(_start(spec))
        yield {"specs": specs, "probe": probe, "procs": procs, "results": results}
    finally:
        for proc in reversed(procs):
            proc.stop()
        probe.close()


def _graph_is_separate(node: Any) -> None:
    """Every robot's topics and services carry only that robot's nodes (and the simulator, the probe)."""
    topics = {name for name, _ in node.get_topic_names_and_types()}
    for robot in ROBOTS:
        own = {f"/{robot}/bt_nav_executive", f"/{robot}/bt_nav_referee", "/bt_nav_sim", *OBSERVERS}
        for topic in ("cmd_vel", "scan", "odom", "ground_truth_odom", "collisions"):
            name = f"/{robot}/{topic}"
            assert name in topics, f"{name} missing: {sorted(topics)}"
            ends = node.get_publishers_info_by_topic(name) + node.get_subscriptions_info_by_topic(name)
            who = {f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in ends}
            assert who <= own, f"{name} reaches {who - own}"
    services = {name for name, _ in node.get_service_names_and_types()}
    for robot in ROBOTS:
        assert f"/{robot}/reactive_control/activate" in services
        assert f"/{robot}/reactive_control/evaluate_mission" in services
    root = {t for t in topics if t.count("/") == 1} - {"/clock", "/rosout", "/parameter_events", "/sim_sync"}
    assert not root, f"robot topics left at the root: {root}"
    assert not {s for s in services if s.startswith("/reactive_control")}, "a service escaped its namespace"


def test_two_namespaced_robots_are_armed_and_judged_independently(world: dict[str, Any]) -> None:
    probe: Probe = world["probe"]
    procs: list[Proc] = world["procs"]
    referees = [s for s in world["specs"] if s.executable == "referee"]
    details = lambda: "\n".join(p.output()[-3000:] for p in procs)  # noqa: E731

    wait_until(lambda: all(probe.cmds[r] for r in ROBOTS), 60.0, "both executives ticking", details)
    first = _start(referees[0])
    procs.append(first)
    wait_until(lambda: probe.moving("robot1"), 60.0, "robot1 armed by its referee", details)
    # robot1 drives while robot2 (whose referee is not even running) stays disarmed and still
    with probe.lock:
        robot2_before = list(probe.cmds["robot2"])
    assert robot2_before and all(c[1:] == (0.0, 0.0) for c in robot2_before), "robot2 moved without being armed"
    second = _start(referees[1])
    procs.append(second)
    codes = [first.wait(150.0), second.wait(150.0)]
    assert all(code in (0, 1) for code in codes), details()  # a verdict each (0 passed, 1 failed), no timeout
    _graph_is_separate(probe.node)

    verdicts = {r: json.loads(Path(world["results"][r]).read_text()) for r in ROBOTS}
    for robot, proc in zip(ROBOTS, (first, second), strict=True):
        result = verdicts[robot]
        assert result["done"] and result["evaluation_calls"] == 1 and result["activate_calls"] >= 3, proc.output()
        assert proc.stdout[-1].startswith("overall: "), proc.output()
        assert result["collisions"] == 0 and result["travelled"] > 1.0, proc.output()
        assert result["checks"][0]["name"] == "static at the end" and result["checks"][0]["passed"], proc.output()
    # own timelines: robot2's referee started after robot1 was already driving
    t0 = {r: verdicts[r]["times"]["t0"] for r in ROBOTS}
    armed = {r: t0[r] + verdicts[r]["times"]["activated"] for r in ROBOTS}
    assert t0["robot2"] > t0["robot1"] + 1.0 and armed["robot2"] > armed["robot1"] + 1.0

    # zero twist on each robot's own cmd_vel from its deadline on (first arming + duration - margin)
    for robot in ROBOTS:
        deadline = armed[robot] + MISSION - STOP_MARGIN
        with probe.lock:
            cmds = list(probe.cmds[robot])
        before = [c for c in cmds if armed[robot] + 0.5 < c[0] < deadline - 0.5]
        after = [c for c in cmds if c[0] > deadline + 0.1]
        assert any(c[1] > 0.0 for c in before), f"{robot} never drove before its deadline"
        assert after, f"no command on /{robot}/cmd_vel after its deadline {deadline:.2f} s"
        assert all(c[1:] == (0.0, 0.0) for c in after), f"{robot} moved after its deadline: {after[:5]}"
