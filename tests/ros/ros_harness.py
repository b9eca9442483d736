"""The test harness for the executive over real DDS: its subprocess, the harness node, scans and waits.

Isolation: this process (and every executive it starts) talks on localhost only
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) in a domain of its own: 215-232, claimed with a lock
file (:func:`bt_nav.ros.rosutil.claim_domain_id`), so pytest-xdist workers and concurrent ``make test``
runs on one machine never share one, and away from the 100-200 where ``bt-nav demo`` and
``sim-run`` pick random domains (a shared domain means foreign /clock and /cmd_vel in the test).
Both are set here, at import, before any ``rclpy.init``.

The executive under test always runs as a subprocess (the real ``main``, signals included) with
``use_sim_time``; the tests' :class:`Harness` node is the robot and the world: it publishes ``/clock``,
``/scan`` and ``/odom`` by hand, records every ``/cmd_vel``, calls ``arm`` and serves
``evaluate_mission``. Simulated time only moves when a test moves it, so a tick happens exactly when
the test asks for one, and a 50 s mission takes a few wall-clock seconds. Every wait is bounded and
polls a condition (no blind sleeps); a timeout fails with the executive's output attached.
"""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_nav.ros.rosutil import claim_domain_id, dds_env

# not 100-200: bt-nav demo/sim-run pick random domains there; with all 18 held by other test processes, wait for one
DOMAIN_ID = claim_domain_id(215, 232, wait=600.0)
os.environ.update(dds_env(DOMAIN_ID))
os.environ.update({"RCUTILS_COLORIZED_OUTPUT": "0", "RCUTILS_LOGGING_BUFFERED_STREAM": "0",
                   "PYTHONUNBUFFERED": "1"})
# Faster re-announcement of participants (why: see the file); Fast DDS 2.x and 3.x spellings.
_PROFILE = str(Path(__file__).with_name("fastdds_tests.xml"))
for _name in ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE"):
    os.environ.setdefault(_name, _PROFILE)

import rclpy  # noqa: E402  (after the DDS environment is set)
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter import Parameter, parameter_value_to_python  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
NODE = "/bt_nav_executive"
#: Tick period of the executive at its default rate; simulated time advances in these steps.
PERIOD = 0.05
#: Start of simulated time: half a period off the tick grid, so that every step (and every jump to
#: ``T0 + k * PERIOD``) triggers exactly one timer callback (rcl fires twice after a jump that lands
#: exactly on the grid).
T0 = 1.0 + PERIOD / 2
from bt_nav.mission.params import SPECS as _SPECS  # noqa: E402 - after the DDS environment is set
from bt_nav.mission.snapshot import read_event, read_snapshot  # noqa: E402
from bt_nav.testing import wait_until  # noqa: E402

# default limits: max_linear_speed, max(angular_speed, maneuver_angular_speed)
V_MAX = float(_SPECS["max_linear_speed"].default)
W_MAX = max(float(_SPECS["angular_speed"].default), float(_SPECS["maneuver_angular_speed"].default))
STARTUP_TIMEOUT = 20.0


# ---------------------------------------------------------------------------------------------- the executive
class ExecutiveProcess:
    """One ``bt-nav executive`` subprocess, its merged stdout/stderr collected by a reader thread."""

    def __init__(self, args: list[str], *, command: list[str] | None = None, env: dict[str, str] | None = None,
                 cwd: Path = REPO) -> None:
        base = command or [sys.executable, "-m", "bt_nav.cli", "executive"]
        self.argv = [*base, *args]
        self.started = time.monotonic()
        self.proc = subprocess.Popen(self.argv, cwd=cwd, env=env or dict(os.environ), stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, bufsize=1)
        self._lines: list[str] = []
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._lock:
                self._lines.append(line.rstrip("\n"))

    @property
    def lines(self) -> list[str]:
        """Output lines so far."""
        with self._lock:
            return list(self._lines)

    def has_line(self, pattern: str) -> bool:
        """Some output line matches the regular expression."""
        return any(re.search(pattern, line) for line in self.lines)

    def tail(self, n: int = 40) -> str:
        """The last output lines, for failure messages."""
        state = "running" if self.proc.poll() is None else f"exited with {self.proc.returncode}"
        return f"--- executive ({state}): {' '.join(self.argv)}\n" + "\n".join(self.lines[-n:])

    @property
    def alive(self) -> bool:
        """Still running."""
        return self.proc.poll() is None

    def wait_exit(self, timeout: float, step: Callable[[], None] | None = None) -> int:
        """Wait (spinning ``step`` meanwhile) for the process to end; its exit status."""
        wait_until(lambda: not self.alive, timeout, "the executive to exit", self.tail, step=step,
                   interval=0.01 if step is None else 0.0)
        self._reader.join(timeout=2.0)
        return int(self.proc.returncode)

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it does not go (teardown)."""
        if self.alive:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5.0)
        self._reader.join(timeout=2.0)


# ---------------------------------------------------------------------------------------------- the harness
@dataclass(frozen=True)
class Sample:
    """One received ``cmd_vel``, with the simulated time the harness had published when it arrived."""

    linear: float
    angular: float
    sim_time: float
    wall_time: float
    stamp: float | None = None
    frame_id: str | None = None

    @property
    def is_zero(self) -> bool:
        """An exact stop."""
        return self.linear == 0.0 and self.angular == 0.0


@dataclass
class EvaluationCall:
    """One request the harness's ``evaluate_mission`` server received."""

    sim_time: float
    wall_time: float
    answered_success: bool


class Harness:
    """The test's own node: clock, sensors, service ends and a recorder of every command.

    Single-threaded: the test spins it inside its waits, so callbacks never race the assertions.
    """

    def __init__(self, context: Any, *, stamped: bool = False, arm_service: str = "/arm",
                 name: str = "bt_nav_test_harness") -> None:
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan
        from std_msgs.msg import String
        from std_srvs.srv import SetBool

        self.context = context
        self.node = rclpy.create_node(name, context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.process: ExecutiveProcess | None = None
        self.sim_time = 0.0
        self.samples: list[Sample] = []
        self.trees: list[dict[str, Any]] = []  # ~/tree snapshots, read (bt_nav.mission.snapshot)
        self.events: list[dict[str, Any]] = []  # ~/events
        self.calls: list[EvaluationCall] = []
        self.answers: list[bool] = [True]
        self._scan: Any = None
        self._scan_at = -math.inf
        self.evaluation_server: Any = None
        self._clock_type, self._odom_type = Clock, Odometry
        self.clock_pub = self.node.create_publisher(Clock, "/clock", 10)
        self.scan_pub = self.node.create_publisher(LaserScan, "/scan", 10)
        self.odom_pub = self.node.create_publisher(Odometry, "/odom", 10)
        self.stamped = stamped
        self.cmd_sub = self.node.create_subscription(TwistStamped if stamped else Twist, "/cmd_vel", self._on_cmd, 100)
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.tree_sub = self.node.create_subscription(
            String, f"{NODE}/tree", lambda m: self.trees.append(read_snapshot(m.data)), latched)
        self.events_sub = self.node.create_subscription(
            String, f"{NODE}/events", lambda m: self.events.append(read_event(m.data)),
            QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self.arm_client = self.node.create_client(SetBool, arm_service)

    # ------------------------------------------------------------------ plumbing
    def close(self) -> None:
        """Destroy the node (the shared context stays)."""
        self.executor.remove_node(self.node)
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()

    def spin(self) -> None:
        """Handle what is ready (up to 10 ms of waiting)."""
        self.executor.spin_once(timeout_sec=0.01)

    def details(self) -> str:
        """Context for a failure message."""
        last = self.samples[-5:]
        text = (f"domain {DOMAIN_ID}, nodes {sorted(self.node.get_node_names())}, sim_time {self.sim_time:.3f}, "
                f"{len(self.samples)} cmd_vel, last {last}, calls {self.calls}")
        return text + ("\n" + self.process.tail() if self.process is not None else "")

    def wait(self, predicate: Callable[[], bool], what: str, timeout: float = 10.0, *,
             allow_exit: bool = False) -> None:
        """Spin until ``predicate``; fails early when the executive died (unless ``allow_exit``)."""

        def check() -> bool:
            if predicate():
                return True
            if not allow_exit and self.process is not None and not self.process.alive:
                raise AssertionError(f"the executive exited while waiting for {what}\n{self.details()}")
            return False

        wait_until(check, timeout, what, self.details, step=self.spin, interval=0.0)

    def connect(self, process: ExecutiveProcess, timeout: float = STARTUP_TIMEOUT) -> None:
        """Wait until the executive is up and matched with every endpoint the tests use."""
        self.process = process
        self.wait(lambda: (self.clock_pub.get_subscription_count() > 0 and self.scan_pub.get_subscription_count() > 0
                           and self.cmd_sub.get_publisher_count() > 0 and self.arm_client.service_is_ready()),
                  "the executive's endpoints to match", timeout)

    def first_contact(self, start: float = T0, timeout: float = STARTUP_TIMEOUT) -> Sample:
        """Step simulated time from ``start`` until a command arrives: both directions are matched then.

        Matching seen from the harness's side does not mean the executive has matched us yet. A tick
        whose command goes out before the executive's cmd_vel writer has matched our reader is lost
        for good, and resending the same ``/clock`` time triggers no new tick, so time must advance
        until a command gets through. After that one, nothing is lost any more (reliable, matched).
        """
        deadline = time.monotonic() + timeout
        target = start
        while True:
            try:
                return self._step(target, None, 1.0)
            except AssertionError:
                if time.monotonic() > deadline:
                    raise
                target += PERIOD

    def _on_cmd(self, msg: Any) -> None:
        twist = msg.twist if self.stamped else msg
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9 if self.stamped else None
        frame = msg.header.frame_id if self.stamped else None
        self.samples.append(Sample(twist.linear.x, twist.angular.z, self.sim_time, time.monotonic(), stamp, frame))

    # ------------------------------------------------------------------ the world
    def publish_clock(self, t: float) -> None:
        """Set simulated time (``/clock``)."""
        self.sim_time = t
        msg = self._clock_type()
        msg.clock.sec = int(t)
        msg.clock.nanosec = int(round((t - int(t)) * 1e9))
        self.clock_pub.publish(msg)

    def publish_odom(self, yaw: float) -> None:
        """Odometry with heading ``yaw``."""
        msg = self._odom_type()
        msg.pose.pose.orientation.z = math.sin(yaw / 2.0)
        msg.pose.pose.orientation.w = math.cos(yaw / 2.0)
        self.odom_pub.publish(msg)

    def tick(self, to: float | None = None, *, scan: Any = None, timeout: float = 5.0) -> Sample:
        """Move simulated time to ``to`` (default: one period on) and return the tick's command.

        With ``scan``, the returned tick is guaranteed to see that scan, fresh. The executive stamps a
        scan with its own clock on arrival, and the scan and ``/clock`` travel on different topics, so
        a scan sent just before the clock may still be in flight when the tick runs (the tick then
        sees the previous scan), and a scan sent before a jump is stamped with the old time. Hence a
        new scan (another object, or the same one not sent for a while) goes out one full round trip
        before the clock that counts: a jump first lands two periods short, then one period short
        with the scan; a single step becomes two (the result is one period later than asked).
        Repeating the same scan object on consecutive steps needs none of this: if the newest copy
        is late, the previous one (identical, at most two periods old) is used.
        """
        target = self.sim_time + PERIOD if to is None else to
        if scan is not None and not (scan is self._scan and target - self._scan_at <= 2.5 * PERIOD):
            gap = target - self.sim_time
            if gap > 2.5 * PERIOD:
                self._step(target - 2 * PERIOD, None, timeout)
            if gap > 1.5 * PERIOD:
                self._step(target - PERIOD, scan, timeout)
            else:
                self._step(target, scan, timeout)
                target += PERIOD
        return self._step(target, scan, timeout)

    def _step(self, target: float, scan: Any, timeout: float) -> Sample:
        """Publish ``scan`` (if any) and ``/clock`` ``target``; wait for the tick's command.

        ``/clock`` is best effort: it is sent again every 0.1 s while no command arrives (repeating
        a time is harmless, it triggers no tick).
        """
        count = len(self.samples)
        if scan is not None:
            self.scan_pub.publish(scan)
            self._scan, self._scan_at = scan, self.sim_time  # the executive's clock is at sim_time now
        self.publish_clock(target)
        resend = time.monotonic() + 0.1

        def arrived() -> bool:
            nonlocal resend
            if time.monotonic() > resend:
                self.publish_clock(target)
                resend = time.monotonic() + 0.1
            return len(self.samples) > count

        self.wait(arrived, f"a cmd_vel after /clock {target:.3f}", timeout)
        return self.samples[count]

    def ticks(self, n: int, *, scan: Any = None) -> list[Sample]:
        """``n`` ticks, one period each, each seeing ``scan`` (a new scan costs one lead-in tick, see :meth:`tick`)."""
        return [self.tick(scan=scan) for _ in range(n)]

    # ------------------------------------------------------------------ services
    def call(self, client: Any, request: Any, timeout: float = 10.0) -> Any:
        """Call a service and wait for the answer."""
        self.wait(client.service_is_ready, f"service {client.srv_name}", timeout)
        future = client.call_async(request)
        self.wait(future.done, f"the answer of {client.srv_name}", timeout)
        return future.result()

    def arm(self, data: bool = True) -> Any:
        """Call ``arm``; returns the SetBool response."""
        from std_srvs.srv import SetBool

        return self.call(self.arm_client, SetBool.Request(data=data))

    def serve_evaluation(self, name: str = "/evaluate_mission", answers: list[bool] | None = None) -> None:
        """Serve ``evaluate_mission``; answers in order (the last one repeats)."""
        from std_srvs.srv import Trigger

        self.answers = list(answers or [True])

        def handle(request: Any, response: Any) -> Any:
            index = min(len(self.calls), len(self.answers) - 1)
            response.success = self.answers[index]
            response.message = "scored" if response.success else "not ready, try again"
            self.calls.append(EvaluationCall(self.sim_time, time.monotonic(), response.success))
            return response

        self.evaluation_server = self.node.create_service(Trigger, name, handle)

    # ------------------------------------------------------------------ parameters
    def parameter_client(self, srv_type: Any, service: str) -> Any:
        """A client of one of the executive's parameter services (``list_parameters``...)."""
        return self.node.create_client(srv_type, f"{NODE}/{service}")

    def set_parameters(self, *parameters: Parameter, atomically: bool = False) -> list[Any]:
        """SetParameters(Atomically) on the executive; the SetParametersResult(s)."""
        from rcl_interfaces.srv import SetParameters, SetParametersAtomically

        if atomically:
            client = self.parameter_client(SetParametersAtomically, "set_parameters_atomically")
            request = SetParametersAtomically.Request(parameters=[p.to_parameter_msg() for p in parameters])
            return [self.call(client, request).result]
        client = self.parameter_client(SetParameters, "set_parameters")
        request = SetParameters.Request(parameters=[p.to_parameter_msg() for p in parameters])
        return list(self.call(client, request).results)

    def get_parameters(self, *names: str) -> dict[str, Any]:
        """GetParameters on the executive: name -> Python value."""
        from rcl_interfaces.srv import GetParameters

        client = self.parameter_client(GetParameters, "get_parameters")
        response = self.call(client, GetParameters.Request(names=list(names)))
        return {name: parameter_value_to_python(value) for name, value in zip(names, response.values, strict=True)}

    # ------------------------------------------------------------------ checks
    def assert_sane(self, v_max: float = V_MAX, w_max: float = W_MAX) -> None:
        """Every command received so far was finite and within the limits."""
        for sample in self.samples:
            assert math.isfinite(sample.linear) and math.isfinite(sample.angular), sample
            assert abs(sample.linear) <= v_max + 1e-9 and abs(sample.angular) <= w_max + 1e-9, sample


