"""Helpers for the simulator, referee and demo tests: ``bt-nav`` subprocesses and a probe node.

DDS isolation comes from ``conftest.py`` (its ``ros_harness`` import puts this process on localhost
in a domain of its own, before any ``rclpy.init``); :func:`ensure_local_dds` repeats that for a file
run on its own, so no test here can ever talk to the network. Subprocesses inherit the environment.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

from bt_nav.ros.rosutil import dds_env, domain_id_for
from bt_nav.testing import wait_until

REPO = Path(__file__).resolve().parents[2]


def ensure_local_dds() -> None:
    """Localhost-only discovery and a per-process domain, unless the conftest already set them."""
    if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE") != "LOCALHOST" or not os.environ.get("ROS_DOMAIN_ID"):
        os.environ.update(dds_env(domain_id_for(os.getpid())))
    os.environ.setdefault("RCUTILS_COLORIZED_OUTPUT", "0")
    os.environ["PYTHONUNBUFFERED"] = "1"


ensure_local_dds()

#: A line of Fast DDS's own log ("2026-11-25 18:12:30.981 [RTPS_TRANSPORT_SHM Error] ..."), colours removed.
FASTDDS_LOG = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d+ \[[A-Z_]+ (Error|Warning|Info)\]")
ANSI = re.compile(r"\x1b\[[0-9;]*m")


class Proc:
    """A ``bt-nav <command>`` subprocess with its output collected (stdout and stderr separately)."""

    def __init__(self, *args: str) -> None:
        self.argv = [sys.executable, "-m", "bt_nav.cli", *args]
        self.proc = subprocess.Popen(self.argv, cwd=REPO, env=dict(os.environ), stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1, start_new_session=True)
        self.stdout: list[str] = []
        self.stderr: list[str] = []
        self.dds_log: list[str] = []
        self._threads = [threading.Thread(target=self._pump, args=(self.proc.stdout, self.stdout), daemon=True),
                         threading.Thread(target=self._pump, args=(self.proc.stderr, self.stderr), daemon=True)]
        for thread in self._threads:
            thread.start()

    def _pump(self, stream: Any, sink: list[str]) -> None:
        for line in stream:
            line = line.rstrip("\n")
            # Fast DDS's own log (e.g. a shared-memory port another process holds) goes to stdout too; it is
            # the transport's, not the command's output the tests read.
            (self.dds_log if FASTDDS_LOG.match(ANSI.sub("", line)) else sink).append(line)

    def output(self) -> str:
        """Everything it printed so far (for failure messages)."""
        return ("--- stdout\n" + "\n".join(self.stdout) + "\n--- stderr\n" + "\n".join(self.stderr)
                + ("\n--- Fast DDS\n" + "\n".join(self.dds_log) if self.dds_log else ""))

    def alive(self) -> bool:
        """Still running?"""
        return self.proc.poll() is None

    def wait(self, timeout: float) -> int:
        """Exit code; fails the test (after killing the process) if it does not exit in time."""
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.stop()
            raise AssertionError(f"{' '.join(self.argv)} did not exit within {timeout} s\n{self.output()}") from None
        for thread in self._threads:
            thread.join(timeout=2.0)
        return code

    def stop(self) -> int | None:
        """SIGINT, then SIGKILL if it does not go within 5 s; returns the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5.0)
        for thread in self._threads:
            thread.join(timeout=2.0)
        return self.proc.returncode


def stamp_of(msg: Any) -> float:
    """A header stamp (or a Clock message's clock) in seconds."""
    stamp = msg.clock if hasattr(msg, "clock") else msg.header.stamp
    return stamp.sec + stamp.nanosec * 1e-9


def yaw_of(pose: Any) -> float:
    """Heading of a pose's quaternion."""
    q = pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


class Probe:
    """The test's side of the wire: records what the simulator publishes, sends commands and syncs.

    Spins its own executor in a thread; every list is appended under ``lock``. Commands are sent
    at 20 Hz (wall) from a timer while ``command`` is set, like a controller would, so the simulator
    follows them.
    """

    def __init__(self, context: Any, *, stamped: bool = False, name: str = "sim_probe") -> None:
        import rclpy
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan
        from std_msgs.msg import String

        self.rclpy = rclpy
        self.node = rclpy.create_node(name, context=context)
        self.lock = threading.Lock()
        self.clock: list[float] = []
        self.scans: list[Any] = []
        self.odom: list[Any] = []
        self.truth: list[Any] = []
        self.collisions: list[dict[str, Any]] = []
        best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        self.node.create_subscription(Clock, "/clock", lambda m: self._add(self.clock, stamp_of(m)), best_effort)
        self.node.create_subscription(LaserScan, "scan", lambda m: self._add(self.scans, m), qos_profile_sensor_data)
        self.node.create_subscription(Odometry, "odom", lambda m: self._add(self.odom, m), reliable)
        self.node.create_subscription(Odometry, "ground_truth_odom", lambda m: self._add(self.truth, m), reliable)
        self.node.create_subscription(String, "collisions", lambda m: self._add(self.collisions, json.loads(m.data)),
                                      QoSProfile(depth=50))
        self._stamped = stamped
        self._twist_type = TwistStamped if stamped else Twist
        self.cmd_pub = self.node.create_publisher(self._twist_type, "cmd_vel", 10)
        self.sync_pub = self.node.create_publisher(String, "sim_sync", QoSProfile(depth=50))
        self._string = String
        self.command: tuple[float, float] | None = None
        self.node.create_timer(0.05, self._send_command)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def _add(self, sink: list[Any], item: Any) -> None:
        with self.lock:
            sink.append(item)

    def _send_command(self) -> None:
        if self.command is None:
            return
        msg = self._twist_type()
        twist = msg.twist if self._stamped else msg
        twist.linear.x, twist.angular.z = float(self.command[0]), float(self.command[1])
        self.cmd_pub.publish(msg)

    def sync(self, **payload: Any) -> None:
        """Publish one ``sim_sync`` message (JSON of ``payload``)."""
        self.sync_pub.publish(self._string(data=json.dumps(payload)))

    def now(self) -> float:
        """Latest /clock seen (0 before the first)."""
        with self.lock:
            return self.clock[-1] if self.clock else 0.0

    def last_truth(self) -> Any:
        """Latest ground-truth message (None before the first)."""
        with self.lock:
            return self.truth[-1] if self.truth else None

    def wait_sim_time(self, t: float, timeout: float = 20.0) -> None:
        """Wait until /clock reaches ``t``."""
        wait_until(lambda: self.now() >= t, timeout, f"sim time {t:.2f} s (at {self.now():.2f} s)")

    def close(self) -> None:
        """Stop spinning and destroy the node."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.executor.remove_node(self.node)
        self.node.destroy_node()


class StubRobot:
    """Serves an activate service (always succeeds) and never moves; can call evaluate_mission (the referee's
    tests) or serve the lab's toggle_navigation (the check-off judge's)."""

    def __init__(self, context: Any, activate: str, evaluate: str = "/reactive_control/evaluate_mission") -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from std_srvs.srv import SetBool, Trigger

        self.node = rclpy.create_node("stub_robot", context=context)
        self.requests: list[bool] = []
        self.node.create_service(SetBool, activate, self._on_activate)
        self.evaluate = self.node.create_client(Trigger, evaluate)
        self._trigger = Trigger.Request
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def _on_activate(self, request: Any, response: Any) -> Any:
        self.requests.append(bool(request.data))
        response.success, response.message = True, f"stub: data={request.data}"
        return response

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.executor.remove_node(self.node)
        self.node.destroy_node()
