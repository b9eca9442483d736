"""``bt-nav checkoff --robot``: the check-off judged live from a robot's topics over real DDS (localhost, this test's
own domain). The "robot" is SIMULATED (tests/media/robotsynth.py: bt_nav_sim's physics and LDS-02 model, a scripted
template node), its messages published in real time by this test, stamped 0.3 s ahead of the wall clock as a real
TurtleBot's clock may be; the listener's verdict must match the run's ground truth."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from sensor_msgs.msg import LaserScan
from simtools import Proc

from bt_nav.ros.nodes.fakerobot import messages
from bt_nav.testing import wait_until
from tests.media.robotsynth import simulate


def test_the_live_listener_judges_a_robot_as_its_bag_would_be(ros_context: Any, tmp_path: Path) -> None:
    run = simulate(creep=0.15, rate=1.2, arm_at=1.0, disarm_at=9.0, end=10.0)
    assert run.turn_starts, "the simulated robot must meet the object"
    verdict = tmp_path / "live.json"
    judge = Proc("checkoff", "--robot", "--duration", "16", "--maneuver", "A", "--json", str(verdict))
    node = Node("fake_turtlebot", context=ros_context)
    pubs = {"odom": node.create_publisher(Odometry, "odom", 50), "scan": node.create_publisher(LaserScan, "scan", 10),
            "cmd_vel": node.create_publisher(Twist, "cmd_vel", 10)}
    try:
        wait_until(lambda: any("listening to" in line for line in judge.stdout), 30.0, "the listener started")
        wait_until(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()), 10.0, "it subscribed")
        start = time.time()
        for t, kind, msg in messages(run, start):  # what `bt-nav rehearse` publishes
            time.sleep(max(0.0, start + t - time.time()))
            pubs[kind].publish(msg)
        assert judge.wait(30.0) == 0, judge.output()
    finally:
        judge.stop()
        node.destroy_node()
    res = json.loads(verdict.read_text())
    assert res["passed"] and len(res["judged_maneuvers"]) == 1, res["report_lines"]
    m = res["maneuvers"][0]
    t0 = res["feed"]["t0"]  # wall seconds of the report's time zero; the run's is ``start``
    truth = run.true_turn(t0 - start + m["t"], t0 - start + m["settled"])
    assert abs(m["angle_deg"] - truth) < 3.0, (m["angle_deg"], truth)
    assert m["side"] == "right" and "service calls not visible" in res["feed"]["arming"]
    assert any("ahead of their receive times" in note for note in res["feed"]["notes"]), res["feed"]["notes"]
