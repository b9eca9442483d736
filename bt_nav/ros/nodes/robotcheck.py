"""``bt-nav checkoff --robot``: the lab's check-off judged live, beside a real robot, from what its topics carry.

A listener, nothing more: it sends no command and never calls ``toggle_navigation`` (the TA does, as the sheet
says). For ``--duration`` seconds, or until Ctrl-C, it keeps every /odom, /scan and /cmd_vel message (Twist or
TwistStamped, whichever the graph has), the ``toggle_navigation`` service events and ``/rosout`` (the node's lines:
the judge's announcements), with the time it heard each and the message's own stamp; then it hands them to the same
reading and judging as a bag of them (:func:`bt_nav.media.robotbag.recording_from`,
:func:`bt_nav_sim.recorded.judge_recording`). So the live verdict and the verdict on the bag of the same run follow
one rule; only the clock that times the arrivals is this process's (the wall clock).

QoS: best effort for the sensors and the commands (it hears a reliable publisher as well as a best-effort one, and
never slows the robot down), reliable for the service events (rosbag2 records them so too).
"""

from __future__ import annotations

import time
from functools import partial
from typing import Any

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Log
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from std_srvs.srv import SetBool

from bt_nav.media.robotbag import ROSOUT, stamp_ns

NODE_NAME = "bt_nav_checkoff_listener"
#: The command types a lab node may publish, by their graph names.
COMMAND_TYPES = {"geometry_msgs/msg/Twist": Twist, "geometry_msgs/msg/TwistStamped": TwistStamped}


class RobotListener(Node):
    """Keeps (receive ns, own stamp ns or None, message) per topic in :attr:`raw` (see the module docstring)."""

    def __init__(self, names: dict[str, str], context: Any = None) -> None:
        super().__init__(NODE_NAME, context=context)
        self.names = names
        self.raw: dict[str, list[tuple[int, int | None, Any]]] = {}
        self.command_type = ""
        sensors = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Odometry, names["odom"], partial(self._keep, names["odom"]), sensors)
        self.create_subscription(LaserScan, names["scan"], partial(self._keep, names["scan"]), sensors)
        self.create_subscription(SetBool.Event, names["service"], partial(self._keep, names["service"], stamped=False),
                                 QoSProfile(depth=50))
        self._listen_tf()
        self.create_subscription(Log, ROSOUT, partial(self._keep, ROSOUT), QoSProfile(depth=200))
        self._finder = self.create_timer(0.2, self._find_commands)
        self._find_commands()

    def _listen_tf(self) -> None:
        """/tf_static (latched) for the LiDAR's mount, where tf2_msgs is installed (a ROS install has it; the
        pip wheels this project runs on may not: then the LiDAR is taken at the robot's centre, and a note says so)."""
        try:
            from tf2_msgs.msg import TFMessage
        except ImportError:
            return
        latched = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(TFMessage, "/tf_static", partial(self._keep, "/tf_static"), latched)

    def _keep(self, topic: str, msg: Any, stamped: bool = True) -> None:
        now = self.get_clock().now().nanoseconds
        self.raw.setdefault(topic, []).append((now, stamp_ns(msg, getattr(msg, "stamp", None)) if stamped else None,
                                               msg))

    def _find_commands(self) -> None:
        """Subscribe to the command topic once the graph says its type (a node may publish either)."""
        if self.command_type:
            return
        for name, types in self.get_topic_names_and_types():
            if name == self.names["cmd"]:
                known = [t for t in types if t in COMMAND_TYPES]
                if known:
                    self.command_type = known[0]
                    self.create_subscription(COMMAND_TYPES[known[0]], name, partial(self._keep, name),
                                             QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT))
                    self.destroy_timer(self._finder)
                return


def listen(names: dict[str, str], duration: float) -> tuple[dict[str, list[tuple[int, int | None, Any]]], list[str]]:
    """Listen for ``duration`` seconds (0: until Ctrl-C); what was heard, and notes on it."""
    rclpy.init()
    node = RobotListener(names)
    notes: list[str] = []
    end = time.monotonic() + duration if duration > 0 else float("inf")
    try:
        while time.monotonic() < end and rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        notes.append("stopped by Ctrl-C")
    finally:
        raw, command_type = node.raw, node.command_type
        node.destroy_node()
        rclpy.try_shutdown()
    if not command_type:
        notes.append(f"no {names['cmd']} publisher was seen (Twist or TwistStamped)")
    heard = ", ".join(f"{topic} {len(rows)}" for topic, rows in sorted(raw.items())) or "nothing"
    notes.append(f"heard live: {heard}")
    return raw, notes
