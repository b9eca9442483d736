"""The recorder node of a mission over DDS: ground truth, commands and the tree's tip of one robot.

It lives in the process that runs the mission (``bt-nav demo``, the ROS benchmark), spinning in a thread
of its own (:class:`bt_nav.ros.rosutil.ThreadedNode`), one per robot. Times are sim time (the ground
truth's header stamps); ``wall`` keeps each sample's monotonic arrival time for real-time factors.

Each sample's tip and command are the ones *sent* last at or before its stamp, matched when the trajectory is
taken (:meth:`Recording.mission_trajectory`, :func:`held_at`), never the ones that had *arrived* when the sample
did. Why: the node's one executor takes one message per ready topic per round, so at 10-20x real time the
ground truth (30 a sim second) queues up behind the rare tree snapshots; labelled on arrival, a README demo drew
the last ~1.6 m before the deadline as Stopped (the tree's EvaluateMission had arrived ~8 s of sim time ahead of
the ground truth) and FullSpeed 2 s before arming. A snapshot says when it was taken (its ``t``, the executive's
tick, :func:`bt_nav.mission.snapshot.snapshot_time`); a command's time is its DDS source timestamp mapped to sim
time by the ground truth's own (source timestamp, stamp) pairs (:class:`bt_nav.ros.simclock.SimClock`).
"""

from __future__ import annotations

import bisect
import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from bt_nav.mission.snapshot import read_snapshot, snapshot_time
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
    wall: list[float] = field(default_factory=list)  # monotonic arrival time of each sample
    sent: list[int] = field(default_factory=list)  # DDS source timestamp (wall ns) of each sample, 0: unknown
    trees: list[tuple[float, str]] = field(default_factory=list)  # (sim time the snapshot was taken, its tip)
    cmds: list[tuple[int, float, float, float]] = field(default_factory=list)  # (sent wall ns, arrival sim, v, w)
    commands: int = 0
    tree_messages: int = 0
    current_tip: str = ""
    maneuvers: dict[str, int] = field(default_factory=dict)  # maneuver tip -> times it was entered
    foreign_truth: int = 0  # ground-truth messages from a second simulator (another run, same domain)
    truth_seq: int | None = None

    def arrival_sim(self) -> float:
        """Sim time of the newest ground truth read (-inf before the first): a message's time when it has none."""
        return self.t[-1] if self.t else -math.inf

    def command_times(self) -> list[float]:
        """Each command's sim time: its DDS source timestamp mapped by the ground truth's (source timestamp, stamp)
        pairs, else (no timestamp, or sent before the first sample) the newest ground truth when it arrived."""
        clock = SimClock(keep=len(self.t) + 1)
        for sent, t in zip(self.sent, self.t, strict=True):
            if sent:
                clock.add(sent, round(t * 1e9))
        times = []
        for sent, arrived, _, _ in self.cmds:
            sim = clock.sim_at(sent) if sent else None
            times.append(sim * 1e-9 if sim is not None else arrived)
        return times

    def labels(self, start: int, end: int) -> tuple[list[str], list[float], list[float]]:
        """The tip and the command (linear, angular) in force at each sample ``start:end`` (see the module
        docstring: by the times they were sent, not by arrival)."""
        times = self.t[start:end]
        tips = held_at(times, [t for t, _ in self.trees], [tip for _, tip in self.trees], "")
        sent = self.command_times()
        linear = held_at(times, sent, [v for _, _, v, _ in self.cmds], 0.0)
        angular = held_at(times, sent, [w for _, _, _, w in self.cmds], 0.0)
        return tips, linear, angular

    def mission_trajectory(self, verdict: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
        """The samples between the referee's t0 and its report as a :class:`bt_nav.media.plot.Trajectory`
        (each sample labelled with its branch), and as JSON with the commands and tips (sim time)."""
        from bt_nav.media.plot import Trajectory, branch_of_tip

        start, end = mission_slice(self, verdict)
        tips, linear, angular = self.labels(start, end)
        traj = Trajectory(self.t[start:end], self.x[start:end], self.y[start:end], self.yaw[start:end],
                          [branch_of_tip(tip) for tip in tips])
        data = {**traj.to_dict(), "tip": tips, "cmd_linear": linear, "cmd_angular": angular, "commands": self.commands,
                "tree_messages": self.tree_messages, "maneuvers": self.maneuvers,
                "foreign_truth": self.foreign_truth, "time_base": "sim time, s"}
        return traj, data


class Recorder:
    """A node of the demo's own, spinning in a thread: ground truth, commands and the tree tip.

    ``robot``: the namespace of the robot to record (one of several); empty: today's root topics. ``executive``: the
    robot is bt_nav's executive, and ground truth is subscribed only once its tree is heard (its latched snapshot
    comes as soon as the two match). Why: the demo's judge starts its t0 once this node reads ground truth
    (``truth_readers``), and a recorder that matched the executive after it (seen on a loaded machine: 16 s of sim
    time later) drew the path of the first leg without a branch and missed its commands. ``False`` for a node
    that publishes no tree (``bt-nav demo --exe``).
    """

    def __init__(self, robot: str = "", executive: bool = True) -> None:
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
        # Latched as the executive offers ``~/tree``, with room for the snapshots that arrive while this thread lags
        # (depth 1 kept only the newest of them: a short TurnAway between two took no colour).
        latched = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._truth: Any = None
        self._subscribe_truth = lambda: self.node.create_subscription(Odometry, f"{ns}ground_truth_odom",
                                                                      self._on_truth, reliable)
        self.node.create_subscription(Twist, f"{ns}cmd_vel", self._on_cmd, reliable)
        self.node.create_subscription(String, f"{ns or '/'}{EXECUTIVE_NAME}/tree", self._on_tree, latched)
        if not executive:
            self._truth = self._subscribe_truth()
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
            d.wall.append(time.monotonic())
            d.sent.append(int(info.get("source_timestamp") or 0) if isinstance(info, dict) else 0)

    def _on_cmd(self, msg: Any, info: Any) -> None:
        """A command with its MessageInfo: its DDS source timestamp times it (see the module docstring)."""
        sent = int(info.get("source_timestamp") or 0) if isinstance(info, dict) else 0
        with self.lock:
            d = self.data
            d.cmds.append((sent, d.arrival_sim(), float(msg.linear.x), float(msg.angular.z)))
            d.commands += 1

    def _on_tree(self, msg: Any) -> None:
        from bt_nav.media.plot import branch_of_tip

        snapshot = read_snapshot(msg.data)
        tip = str(snapshot.get("tip", "")) if snapshot is not None else ""
        taken = snapshot_time(snapshot) if snapshot is not None else None
        with self.lock:
            d = self.data
            if branch_of_tip(tip) == "Maneuver" and branch_of_tip(d.current_tip) != "Maneuver":
                d.maneuvers[tip] = d.maneuvers.get(tip, 0) + 1
            d.current_tip = tip
            d.trees.append((taken if taken is not None else d.arrival_sim(), tip))
            d.tree_messages += 1
        if self._truth is None:  # the executive is heard: now the judge may see this reader (see the class)
            self._truth = self._subscribe_truth()

    def sim_time(self) -> float | None:
        """Latest ground-truth stamp (sim time), None before the first."""
        with self.lock:
            return self.data.t[-1] if self.data.t else None

    def close(self) -> Recording:
        """Stop spinning, destroy the node, shut the context down; returns the recording."""
        self.ros.close()
        return self.data


def held_at(times: list[float], stamps: list[float], values: list[Any], before: Any) -> list[Any]:
    """The value in force at each of ``times``: the last of ``values`` whose stamp is at or before it (``before``
    ahead of the first). ``stamps`` in the order the values were sent; sorted here, stably (equal stamps keep it).
    """
    order = sorted(range(len(stamps)), key=stamps.__getitem__)
    keys = [stamps[i] for i in order]
    held = []
    for t in times:
        k = bisect.bisect_right(keys, t) - 1
        held.append(values[order[k]] if k >= 0 else before)
    return held


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
