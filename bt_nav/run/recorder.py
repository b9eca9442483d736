"""The recorder node of a mission over DDS: ground truth, commands and the tree's tip of one robot.

It lives in the process that runs the mission (``bt-nav demo``, the ROS benchmark), spinning in a thread
of its own (:class:`bt_nav.ros.rosutil.ThreadedNode`), one per robot. Times are sim time (the ground
truth's header stamps); ``wall`` keeps each sample's monotonic arrival time for real-time factors.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from bt_nav.mission.snapshot import read_snapshot
from bt_nav.ros.bringup import EXECUTIVE_NAME
from bt_nav.ros.simclock import SimClock


def rec_ready(recorder: Recorder) -> bool:
    """The recorder receives ground truth and the executive's commands."""
    with recorder.lock:
        return bool(recorder.data.t) and recorder.data.commands > 0


@dataclass
class Recording:
    """What the demo's recorder node saw (appended from its executor thread)."""

    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    yaw: list[float] = field(default_factory=list)
    tip: list[str] = field(default_factory=list)
    wall: list[float] = field(default_factory=list)  # monotonic arrival time of each sample
    cmd_linear: list[float] = field(default_factory=list)  # latest command at each sample
    cmd_angular: list[float] = field(default_factory=list)
    commands: int = 0
    tree_messages: int = 0
    current_tip: str = ""
    current_cmd: tuple[float, float] = (0.0, 0.0)
    maneuvers: dict[str, int] = field(default_factory=dict)  # maneuver tip -> times it was entered
    foreign_truth: int = 0  # ground-truth messages from a second simulator (another run, same domain)
    truth_seq: int | None = None

    def mission_trajectory(self, verdict: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
        """The samples between the referee's t0 and its report as a :class:`bt_nav.media.plot.Trajectory`
        (each sample labelled with its branch), and as JSON with the commands and tips (sim time)."""
        from bt_nav.media.plot import Trajectory, branch_of_tip

        start, end = mission_slice(self, verdict)
        traj = Trajectory(self.t[start:end], self.x[start:end], self.y[start:end], self.yaw[start:end],
                          [branch_of_tip(tip) for tip in self.tip[start:end]])
        data = {**traj.to_dict(), "tip": self.tip[start:end], "cmd_linear": self.cmd_linear[start:end],
                "cmd_angular": self.cmd_angular[start:end], "commands": self.commands,
                "tree_messages": self.tree_messages, "maneuvers": self.maneuvers,
                "foreign_truth": self.foreign_truth, "time_base": "sim time, s"}
        return traj, data


class Recorder:
    """A node of the demo's own, spinning in a thread: ground truth, commands and the tree tip.

    ``robot``: the namespace of the robot to record (one of several); empty: today's root topics.
    """

    def __init__(self, robot: str = "") -> None:
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        from bt_nav.ros.rosutil import ThreadedNode

        self.ros = ThreadedNode(f"bt_nav_demo_recorder{'_' + robot if robot else ''}")
        ns = f"/{robot}/" if robot else ""
        self.node = self.ros.node
        self.data = Recording()
        self.lock = threading.Lock()
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Odometry, f"{ns}ground_truth_odom", self._on_truth, reliable)
        self.node.create_subscription(Twist, f"{ns}cmd_vel", self._on_cmd, reliable)
        self.node.create_subscription(String, f"{ns or '/'}{EXECUTIVE_NAME}/tree", self._on_tree, latched)
        # Sim time at a wall instant (the times of the nodes' log lines, rundir.Logs), from each ground-truth sample's
        # source timestamp and stamp: 30 per sim second, a sample within 33 ms of sim time of any line. Not /clock: at
        # every follower's deadline it is twice as many messages, the CPU of a third of this node's work (measured:
        # 0.64-0.74 CPU s of a 1.6 s demo mission), taken from the simulator and the executive on a 2-core machine.
        self.clock = SimClock()
        self.ros.start()

    def _on_truth(self, msg: Any, info: Any) -> None:
        """Ground truth with its MessageInfo (no default: rclpy passes the info only to a callback that cannot be
        called with the message alone, and the publisher sequence number is what tells a second simulator)."""
        from bt_nav.ros.rosutil import yaw_from_quaternion

        q = msg.pose.pose.orientation
        d = self.data
        seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
        with self.lock:
            if seq is not None and d.truth_seq is not None and seq <= d.truth_seq:
                d.foreign_truth += 1  # one publisher's numbers only grow: this is another simulator
                return
            d.truth_seq = seq if seq is not None else d.truth_seq
            stamp = msg.header.stamp
            if isinstance(info, dict) and info.get("source_timestamp"):
                self.clock.add(info["source_timestamp"], stamp.sec * 1_000_000_000 + stamp.nanosec)
            d.t.append(stamp.sec + stamp.nanosec * 1e-9)
            d.x.append(msg.pose.pose.position.x)
            d.y.append(msg.pose.pose.position.y)
            d.yaw.append(yaw_from_quaternion(q.x, q.y, q.z, q.w))
            d.tip.append(d.current_tip)
            d.wall.append(time.monotonic())
            d.cmd_linear.append(d.current_cmd[0])
            d.cmd_angular.append(d.current_cmd[1])

    def _on_cmd(self, msg: Any) -> None:
        with self.lock:
            self.data.current_cmd = (float(msg.linear.x), float(msg.angular.z))
            self.data.commands += 1

    def _on_tree(self, msg: Any) -> None:
        from bt_nav.media.plot import branch_of_tip

        snapshot = read_snapshot(msg.data)
        tip = str(snapshot.get("tip", "")) if snapshot is not None else ""
        with self.lock:
            d = self.data
            if branch_of_tip(tip) == "Maneuver" and branch_of_tip(d.current_tip) != "Maneuver":
                d.maneuvers[tip] = d.maneuvers.get(tip, 0) + 1
            d.current_tip = tip
            d.tree_messages += 1

    def sim_time(self) -> float | None:
        """Latest ground-truth stamp (sim time), None before the first."""
        with self.lock:
            return self.data.t[-1] if self.data.t else None

    def close(self) -> Recording:
        """Stop spinning, destroy the node, shut the context down; returns the recording."""
        self.ros.close()
        return self.data


def mission_slice(rec: Recording, results: dict[str, Any]) -> tuple[int, int]:
    """Index range of the samples between the referee's t0 and its report (all samples if unknown)."""
    times = results.get("times") or {}
    t0 = times.get("t0")
    report = times.get("report")
    if t0 is None:
        return 0, len(rec.t)
    end_t = t0 + report if report is not None else math.inf
    start = next((i for i, t in enumerate(rec.t) if t >= t0), len(rec.t))
    end = next((i for i, t in enumerate(rec.t) if t > end_t), len(rec.t))
    return start, end


def speed_line(rec: Recording, verdict: dict[str, Any], wall: float) -> str:
    """``demo wall time 14.4 s; mission 50.0 s sim in 4.5 s wall (11.2x real time, ...)``."""
    start, end = mission_slice(rec, verdict)
    text = f"demo wall time {wall:.1f} s"
    if end - start > 1 and rec.wall[end - 1] > rec.wall[start]:
        sim_span, wall_span = rec.t[end - 1] - rec.t[start], rec.wall[end - 1] - rec.wall[start]
        text += (f"; mission {sim_span:.1f} s sim in {wall_span:.1f} s wall ({sim_span / wall_span:.1f}x real time, "
                 "varies with the machine)")
    return text
