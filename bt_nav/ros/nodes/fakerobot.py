"""A SIMULATED TurtleBot3 on DDS for the check-off's rehearsal (``bt-nav rehearse``): it publishes only what a real
robot's graph carries for the judge, ``/odom`` (nav_msgs/Odometry), ``/scan`` (sensor_msgs/LaserScan, an LDS-02's
varying beam count and NaN) and ``/cmd_vel`` (geometry_msgs/Twist: the commands of the lab sheet's template node
that drives it), in real time, its header stamps :data:`LEAD` s ahead of this computer's clock as a robot's own
clock may be. The run is :func:`bt_nav_sim.synthrobot.simulate`'s, computed before the first message; no ground
truth, no /clock, no simulator topic: ``bt-nav checkoff --robot`` beside it hears what it would hear from a robot.

It waits (up to :data:`LISTENER_WAIT` s) until something subscribes to /odom and /scan, so a listener started at
the same time misses nothing; its last message, on every way out, is a zero twist on /cmd_vel.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

#: s the robot's header stamps run ahead of this computer's clock.
LEAD = 0.3
#: s it waits for a subscriber to /odom and /scan before it drives anyway.
LISTENER_WAIT = 30.0


def _stamp(msg: Any, t: float) -> None:
    ns = round(t * 1e9)
    msg.header.stamp.sec, msg.header.stamp.nanosec = ns // 1_000_000_000, ns % 1_000_000_000


def messages(run: Any, start: float) -> list[tuple[float, str, Any]]:
    """(run time, topic, message) in time order, header stamps on the wall clock from ``start`` plus :data:`LEAD`."""
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import LaserScan

    out: list[tuple[float, str, Any]] = []
    for t, x, y, yaw, v, w in run.odom:
        m = Odometry()
        _stamp(m, start + t + LEAD)
        m.header.frame_id, m.child_frame_id = "odom", "base_footprint"
        m.pose.pose.position.x, m.pose.pose.position.y = x, y
        m.pose.pose.orientation.z, m.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        m.twist.twist.linear.x, m.twist.twist.angular.z = v, w
        out.append((t, "odom", m))
    for t, a0, da, n, ranges in run.scans:
        m = LaserScan()
        _stamp(m, start + t + LEAD)
        m.header.frame_id = "base_scan"
        m.angle_min, m.angle_increment, m.angle_max = a0, da, a0 + (n - 1) * da
        m.range_min, m.range_max = 0.0, 100.0
        m.ranges = np.asarray(ranges, dtype=np.float32).tolist()
        out.append((t, "scan", m))
    for t, v, w in run.cmds:
        m = Twist()
        m.linear.x, m.angular.z = v, w
        out.append((t, "cmd_vel", m))
    return sorted(out, key=lambda item: item[0])


def drive(run: Any, say: Any = print) -> None:
    """Publish ``run`` (a :class:`bt_nav_sim.synthrobot.Synth`) in real time (module docstring); ``say``: its lines."""
    import rclpy
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rclpy.node import Node
    from sensor_msgs.msg import LaserScan

    rclpy.init(args=["bt_nav_simulated_robot"])
    node = Node("simulated_turtlebot3")
    pubs = {"odom": node.create_publisher(Odometry, "odom", 50), "scan": node.create_publisher(LaserScan, "scan", 10),
            "cmd_vel": node.create_publisher(Twist, "cmd_vel", 10)}
    try:
        waited = time.monotonic() + LISTENER_WAIT
        while time.monotonic() < waited and not (pubs["odom"].get_subscription_count()
                                                 and pubs["scan"].get_subscription_count()):
            rclpy.spin_once(node, timeout_sec=0.1)
        say(f"driving: {len(run.odom)} poses, {len(run.scans)} scans, {len(run.cmds)} commands over "
            f"{run.odom[-1][0]:.1f} s, stamps {LEAD:g} s ahead")
        start = time.time()
        for t, topic, msg in messages(run, start):
            time.sleep(max(0.0, start + t - time.time()))
            pubs[topic].publish(msg)
        say("done")
    except KeyboardInterrupt:
        say("stopped")
    finally:
        pubs["cmd_vel"].publish(Twist())  # every way out: a zero twist
        node.destroy_node()
        rclpy.try_shutdown()
