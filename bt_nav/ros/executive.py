"""The mission executive node: ``bt_nav_executive``, the ROS edge around :class:`~bt_nav.mission.core.MissionCore`.

Run it with ``ros2 run bt_nav executive`` (colcon install) or ``bt-nav executive`` (pip install); both
accept the usual ROS arguments, e.g.::

    bt-nav executive --ros-args -r arm:=toggle_navigation -p safety_distance:=0.4 \\
        --params-file config/lab.yaml -p use_sim_time:=true

Interfaces (relative names, so ``-r`` remapping and namespaces work):

==============  ====================  =====================================  ===========================================
kind            name                  type                                   notes
==============  ====================  =====================================  ===========================================
service server  ``arm``               std_srvs/SetBool                       true arms (starts the mission timer), false
                                                                             stops; created by the ArmService leaf
service client  ``evaluate_mission``  std_srvs/Trigger                       called once at the deadline, with retries;
                                                                             created by the EvaluateMission leaf
subscription    ``scan``              sensor_msgs/LaserScan                  sensor-data QoS; stamped on receipt with
                                                                             the node clock
subscription    ``odom``              nav_msgs/Odometry                      optional: yaw closes the maneuvers' loop
publisher       ``cmd_vel``           geometry_msgs/Twist (TwistStamped      one command per tick
                                      with ``cmd_vel_stamped:=true``)
publisher       ``~/tree``            std_msgs/String                        the tree as text when a status or the tip
                                                                             changes (transient local, depth 1)
==============  ====================  =====================================  ===========================================

Parameters: every entry of :data:`bt_nav.mission.params.PARAMS`, declared with its description, unit and range
(``ros2 param describe``); the ones that shape the tree or the wiring (maneuver, random_seed,
tick_rate_hz, cmd_vel_stamped, frame_id) are read-only. A runtime change is checked by the same rules
as at start-up (one value, then cross rules such as close_distance < far_distance) and refused with the
reason, and the refusal is logged in one line (``parameter change refused: <reason>``) whether our
check or rclpy's own (range, type, read-only) refused it; an integer for a float parameter is
accepted, as on the command line. An invalid value at start-up (``-p``, params file) is not patched
over: the node logs ``refusing to start: <reason>`` and exits with status 2 — a robot must not drive
on a configuration nobody meant. One more parameter guards the ROS edge only: ``clock_watchdog``
(below).

Timing: the tree ticks on a timer of the node clock, so with ``use_sim_time`` the ticks, the mission
deadline, the scan timeout and the maneuvers all follow ``/clock``. Tick statistics (duration, overruns
against the period, exceptions, vetoed commands) are logged every ``stats_period`` and at exit.

Clock watchdog: with ``use_sim_time`` a stalled ``/clock`` (simulator paused or dead, bag player
stopped) means no ticks, and a robot base keeps executing the last ``cmd_vel`` it got — the tree,
frozen with the clock, cannot stop it. So a timer on the steady (wall) clock publishes one zero twist
when the last command was motion and no tick has happened for ``clock_watchdog`` wall seconds
(default 1.0; 0 disables; live), logged in one line, and another line when ticks resume.

Safety: no motion before the first arming, a stop on the first tick after a disarm and at the deadline
(the tree); every command is checked once more before it is published (finite, within the limits, zero
when disarmed or after the deadline). SIGINT and SIGTERM publish a zero twist before the ROS context
goes down (rclpy's own handlers are off, because they shut the context down first); the exit status is
0 then.

Testing hook (off unless the variable is set; tests/faults uses it): ``BT_NAV_FAULT_INJECT=<leaf>[@<n>]``
(comma-separated for several) makes the n-th ``update`` (default: the first) of each named tree node
raise :class:`InjectedFaultError` once, to prove that an exception inside the tree stops the robot for that
tick, is logged in one line and leaves the node running. The node warns at start-up when it is armed.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import threading
from collections import deque
from collections.abc import Iterable
from contextlib import suppress
from pathlib import Path
from time import monotonic, perf_counter
from types import FrameType
from typing import Any

import rclpy
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from bt_nav.mission import params as P
from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.resources import tree_file
from bt_nav.mission.scan import Scan, ScanError
from bt_nav.ros.rosutil import (
    LATCHED,
    CommandPublisher,
    ConfigError,
    EventLog,
    as_double,
    declare_parameters,
    route_py_trees_logging,
    unknown_overrides,
    yaw_from_quaternion,
)

NODE_NAME = "bt_nav_executive"
EXIT_OK, EXIT_ERROR, EXIT_CONFIG = 0, 1, 2
#: Longest wait inside the executor before the loop looks at the shutdown flag again.
SPIN_TIMEOUT = 0.05
#: Zero twists published at exit (cheap insurance against one lost sample) and how long to wait for acks.
FINAL_STOPS, FINAL_ACK_TIMEOUT = 3, 0.5
#: Slack when re-checking the limits (the core clamps exactly; this only absorbs float noise).
LIMIT_EPS = 1e-9
#: The ROS edge's own parameter (not in :data:`bt_nav.mission.params.PARAMS`: it is no mission setting). Why it
#: exists: see "Clock watchdog" above.
CLOCK_WATCHDOG = P.ParamSpec(
    "clock_watchdog", 1.0, "Wall-clock seconds without a tick, while the last command was motion, after which "
    "a zero twist is published (a stalled /clock under use_sim_time freezes the ticks); 0 disables.", "s",
    0.0, 60.0, in_tree=False)
#: Wall-clock seconds between two looks of the watchdog.
WATCHDOG_CHECK_PERIOD = 0.1
#: Environment variable of the test-only fault injection (see the module docstring).
FAULT_INJECT_ENV = "BT_NAV_FAULT_INJECT"


class InjectedFaultError(RuntimeError):
    """What an injected fault raises: its own type, so a log line can never pass for a real bug."""


def inject_faults(root: Any, spec: str) -> list[str]:
    """Arm the faults of a ``BT_NAV_FAULT_INJECT`` value on the tree under ``root``; returns ``name@n`` each.

    The behaviour's ``update`` is wrapped on the instance (the class stays untouched): the n-th call
    raises once, every other call runs the original.

    Raises:
        ConfigError: for an entry that names no node of the tree or has a bad count.
    """
    nodes = {node.name: node for node in root.iterate()}
    armed: list[str] = []
    for entry in filter(None, (part.strip() for part in spec.split(","))):
        name, _, count = entry.partition("@")
        node = nodes.get(name)
        if node is None:
            raise ConfigError(f"{FAULT_INJECT_ENV}: no tree node named {name!r} (nodes: {', '.join(sorted(nodes))})")
        try:
            nth = int(count) if count else 1
        except ValueError:
            nth = 0
        if nth < 1:
            raise ConfigError(f"{FAULT_INJECT_ENV}: {entry!r}: the count after @ must be an integer >= 1")
        _raise_on_update(node, nth)
        armed.append(f"{name}@{nth}")
    return armed


def _raise_on_update(node: Any, nth: int) -> None:
    """Make the ``nth`` call of ``node.update`` raise :class:`InjectedFaultError` (once)."""
    original = node.update
    calls = 0

    def update() -> Any:
        nonlocal calls
        calls += 1
        if calls == nth:
            raise InjectedFaultError(f"injected by {FAULT_INJECT_ENV} into update {nth} of {node.name}")
        return original()

    node.update = update


class TickStats:
    """Tick durations (wall clock, ``perf_counter``) and counters, summarised for the log.

    ``overruns`` counts ticks that took longer than the tick period: the timer cannot keep its rate
    then. The window (since the last periodic line) and a bounded history (for the exit line) are
    kept separately so a long run's exit line does not need every sample.
    """

    def __init__(self, period: float, history: int = 100_000) -> None:
        self.period = float(period)
        self.ticks = 0
        self.overruns = 0
        self.exceptions = 0
        self.vetoed = 0
        self.window: list[float] = []
        self.history: deque[float] = deque(maxlen=history)

    def record(self, duration: float) -> None:
        """One tick took ``duration`` seconds."""
        self.ticks += 1
        if duration > self.period:
            self.overruns += 1
        self.window.append(duration)
        self.history.append(duration)

    @staticmethod
    def describe(durations: Iterable[float]) -> str:
        """``min/mean/p99/max`` in milliseconds (``no ticks`` when empty)."""
        values = sorted(durations)
        if not values:
            return "no ticks"
        p99 = values[max(0, math.ceil(0.99 * len(values)) - 1)]
        mean = sum(values) / len(values)
        return (f"tick ms min/mean/p99/max {values[0] * 1e3:.2f}/{mean * 1e3:.2f}/{p99 * 1e3:.2f}/"
                f"{values[-1] * 1e3:.2f} over {len(values)}")

    def counters(self, faults: int) -> str:
        """The counters as one phrase (``faults``: exceptions the core caught inside the tree)."""
        return (f"ticks {self.ticks}, overruns {self.overruns} (period {self.period * 1e3:.1f} ms), "
                f"exceptions {faults + self.exceptions}, vetoed commands {self.vetoed}")

    def take_window(self) -> list[float]:
        """The durations since the last call, and start a new window."""
        window, self.window = self.window, []
        return window


class Executive:
    """The node's wiring: parameters, subscriptions, publishers, the tick timer and the stats.

    Args:
        node: the node to wire (named ``bt_nav_executive`` by :func:`main`).
        tree_path: another tree file (default: the installed ``trees/mission.xml``).

    Raises:
        ConfigError: when a start-up parameter is invalid or the tree cannot be built.
    """

    def __init__(self, node: Node, *, tree_path: str | None = None) -> None:
        self.node = node
        self.log = node.get_logger()
        self._clock = node.get_clock()
        self._closed = False
        for name in unknown_overrides(node, extra=(CLOCK_WATCHDOG.name,)):
            self.log.warning(f"ignoring parameter {name!r}: not a bt_nav parameter (typo?)")
        values = declare_parameters(node)
        self.watchdog = float(declare_parameters(node, (CLOCK_WATCHDOG,))[CLOCK_WATCHDOG.name])
        try:
            self.core = MissionCore(values, clock=self.now, node=node, events=EventLog(self.log), tree_path=tree_path)
        except (ValueError, OSError) as exc:
            raise ConfigError(str(exc)) from None
        faults = os.environ.get(FAULT_INJECT_ENV, "")
        if faults.strip():
            armed = inject_faults(self.core.root, faults)
            self.log.warning(f"test-only fault injection armed ({FAULT_INJECT_ENV}): {', '.join(armed)} "
                             "will raise once each")
        params = self.core.params
        self.period = 1.0 / float(params["tick_rate_hz"])
        self.stats = TickStats(self.period)
        self.scans = 0
        self.bad_scans = 0
        self.bad_odom = 0
        self._stats_since: float | None = None
        self._tree_key: tuple[Any, ...] | None = None
        self._refusal_logged: str | None = None  # set by the pre-set callback, so a refusal is logged once
        self._last_tick_wall: float | None = None  # monotonic() of the last tick (watchdog)
        self._moving = False  # the last command published was motion
        self._stalled = False  # the watchdog stopped the robot; cleared by the next tick
        self.watchdog_stops = 0

        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import LaserScan
        from std_msgs.msg import String

        self._string = String
        self.cmd = CommandPublisher(node, "cmd_vel", stamped=bool(params["cmd_vel_stamped"]),
                                    frame_id=str(params["frame_id"]))
        self.tree_publisher = node.create_publisher(String, "~/tree", LATCHED)
        self.scan_subscription = node.create_subscription(LaserScan, "scan", self._on_scan, qos_profile_sensor_data)
        self.odom_subscription = node.create_subscription(Odometry, "odom", self._on_odom, qos_profile_sensor_data)
        node.add_pre_set_parameters_callback(self._before_set_parameters)
        node.add_on_set_parameters_callback(self._on_set_parameters)
        node.add_post_set_parameters_callback(self._after_set_parameters)
        self.timer = node.create_timer(self.period, self._on_tick)
        self.watchdog_timer = node.create_timer(WATCHDOG_CHECK_PERIOD, self._on_watchdog,
                                                clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.log.info(self.describe(tree_path))

    # ------------------------------------------------------------------ info
    def now(self) -> float:
        """Mission-clock seconds: the node clock, so ``/clock`` under ``use_sim_time``."""
        return self._clock.now().nanoseconds * 1e-9

    def describe(self, tree_path: str | None) -> str:
        """The start-up line: what runs, where it came from, on which names."""
        params = self.core.params
        arm = getattr(self.core.arm_leaf, "service", None)
        evaluation = getattr(self.core.evaluate_leaf, "client", None)
        sim = self.node.get_parameter("use_sim_time").value
        return (f"{NODE_NAME} up: maneuver {P.MANEUVER_TITLES[str(params['maneuver'])]}, "
                f"tick {float(params['tick_rate_hz']):g} Hz on {'sim' if sim else 'system'} time, "
                f"arm server {getattr(arm, 'service_name', '-')}, evaluation client "
                f"{getattr(evaluation, 'service_name', '-')}, cmd_vel "
                f"{self.node.resolve_topic_name('cmd_vel')} as {'TwistStamped' if self.cmd.stamped else 'Twist'}; "
                f"tree {tree_path or tree_file()}; bt_nav from {Path(__file__).resolve().parents[1]}")

    # ------------------------------------------------------------------ inputs
    def _on_scan(self, msg: Any) -> None:
        """Convert and hand over; a message that cannot even be converted is dropped (and logged)."""
        try:
            scan = Scan.from_laserscan(msg)
        except (ScanError, ValueError, TypeError) as exc:
            self.bad_scans += 1
            self.log.warning(f"dropping a scan that cannot be converted ({self.bad_scans} so far): {exc}; "
                             "without fresh scans the robot stops", throttle_duration_sec=5.0)
            return
        self.scans += 1
        self.core.feed_scan(scan)  # stamped now: the tree's freshness rule is about arrival

    def _on_odom(self, msg: Any) -> None:
        """Heading from the pose's quaternion; a non-rotation is dropped (maneuvers go open loop)."""
        q = msg.pose.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        if not math.isfinite(yaw):
            self.bad_odom += 1
            self.log.warning(f"dropping odometry with an invalid orientation ({self.bad_odom} so far)",
                             throttle_duration_sec=5.0)
            return
        position = msg.pose.pose.position
        self.core.feed_odom(yaw, x=float(position.x), y=float(position.y))

    # ------------------------------------------------------------------ parameters
    def check_change(self, parameters: list[Parameter]) -> str | None:
        """Why this batch of changes is refused (our rules: table, cross rules, read-only), or None."""
        for p in parameters:
            if p.name == CLOCK_WATCHDOG.name:
                reason = CLOCK_WATCHDOG.check(P.coerce(CLOCK_WATCHDOG, p.value))
                if reason:
                    return reason
            elif p.name not in P.SPECS and not self.node.has_parameter(p.name):
                return f"unknown parameter {p.name!r}: not a bt_nav parameter (typo?)"
        values = {p.name: p.value for p in parameters if p.name in P.SPECS}
        return self.core.check_params(values) if values else None

    def _before_set_parameters(self, parameters: list[Parameter]) -> list[Parameter]:
        """Accept integers for float parameters, and log a refusal before rclpy makes it silently.

        rclpy checks the descriptors (range, type, read-only) before the on-set callback runs and
        refuses without a word in the node's log; our rules match the descriptors, so the reason
        is known here already and logged in the same one line as our own refusals.
        """
        specs = {**P.SPECS, CLOCK_WATCHDOG.name: CLOCK_WATCHDOG}
        parameters = [as_double(specs[p.name], p) if p.name in specs else p for p in parameters]
        self._refusal_logged = self.check_change(parameters)
        if self._refusal_logged:
            self.log.warning(f"parameter change refused: {self._refusal_logged}")
        return parameters

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate a change (the batch as a whole); applied only in the post-set callback."""
        reason = self.check_change(parameters)
        if reason and reason != self._refusal_logged:
            self.log.warning(f"parameter change refused: {reason}")
        self._refusal_logged = None
        return SetParametersResult(successful=reason is None, reason=reason or "")

    def _after_set_parameters(self, parameters: list[Parameter]) -> None:
        """Apply an accepted change; the tree sees it on the next tick."""
        values = {p.name: p.value for p in parameters if p.name in P.SPECS}
        watchdog = [p.value for p in parameters if p.name == CLOCK_WATCHDOG.name]
        if watchdog:
            self.watchdog = float(watchdog[-1])
            values[CLOCK_WATCHDOG.name] = self.watchdog
        if not values:
            return
        reason = self.core.set_params({k: v for k, v in values.items() if k in P.SPECS})
        if reason:  # cannot happen after a successful check; say so loudly if it ever does
            self.log.error(f"accepted parameter change could not be applied: {reason}")
            return
        changes = ", ".join(f"{name}={value!r}" for name, value in values.items())
        self.log.info(f"parameters changed: {changes}")

    # ------------------------------------------------------------------ ticking
    def _on_tick(self) -> None:
        """One tick: tree, last check, publish; then the tree snapshot and the stats."""
        started = perf_counter()
        self._note_tick()
        try:
            command = self.vet(self.core.tick())
            self.cmd.publish(command)
            self._moving = not command.is_zero
            self._publish_tree()
        except Exception as exc:  # the node must outlive any bug at its edge, and stop the robot
            self.stats.exceptions += 1
            self._moving = False
            self.log.error(f"tick {self.core.ticks} failed outside the tree: {exc!r}; publishing a stop")
            with suppress(Exception):
                self.cmd.publish(Command(0.0, 0.0, "executive error"))
        finally:
            self.stats.record(perf_counter() - started)
        self._log_stats_when_due()

    def _note_tick(self) -> None:
        """The watchdog's bookkeeping: when this tick happened, and a line if it ends a watchdog stop."""
        now = monotonic()
        if self._stalled and self._last_tick_wall is not None:
            self.log.info(f"clock watchdog: ticking again after {now - self._last_tick_wall:.1f} s of wall time "
                          "without a tick")
        self._stalled = False
        self._last_tick_wall = now

    def _on_watchdog(self) -> None:
        """Publish one stop when the robot was last told to move and the ticks stopped (wall clock)."""
        if self.watchdog <= 0.0 or not self._moving or self._last_tick_wall is None:
            return
        idle = monotonic() - self._last_tick_wall
        if idle < self.watchdog:
            return
        self._moving = False
        self._stalled = True
        self.watchdog_stops += 1
        self.cmd.publish(Command(0.0, 0.0, "clock watchdog"))
        clock = "/clock stalled?" if self.node.get_parameter("use_sim_time").value else "tick timer starved?"
        self.log.warning(f"clock watchdog: no tick for {idle:.1f} s of wall time while moving ({clock}): "
                         "published a stop; the next tick decides again")

    def vet(self, command: Command) -> Command:
        """The last look before the wire: finite, within limits, zero when the robot may not move.

        The core already guarantees the first two and the tree the last; this is a second,
        independent check. A failure is logged and counted, and a stop goes out instead.
        """
        params = self.core.params
        v_max = float(params["max_linear_speed"])
        w_max = max(float(params["angular_speed"]), float(params["maneuver_angular_speed"]))
        why = ""
        if not command.is_finite():
            why = "non-finite"
        elif abs(command.linear) > v_max + LIMIT_EPS or abs(command.angular) > w_max + LIMIT_EPS:
            why = f"beyond the limits ({v_max} m/s, {w_max} rad/s)"
        elif not command.is_zero and not self.core.value("armed", False):
            why = "motion while disarmed"
        elif not command.is_zero and self.core.mission_over:
            why = "motion after the deadline"
        if not why:
            return command
        self.stats.vetoed += 1
        self.log.error(f"vetoed command ({command.linear}, {command.angular}) from {command.source}: {why}; "
                       f"publishing a stop ({self.stats.vetoed} vetoed so far)", throttle_duration_sec=1.0)
        return Command(0.0, 0.0, f"vetoed: {why}")

    def _publish_tree(self) -> None:
        """``~/tree`` when a status or the tip changed (not every tick: the text is large)."""
        key = (tuple(self.core.statuses().items()), self.core.tip)
        if key != self._tree_key:
            self._tree_key = key
            self.tree_publisher.publish(self._string(data=self.core.snapshot()))

    def _log_stats_when_due(self) -> None:
        """The periodic stats line, every ``stats_period`` on the node clock (0: never)."""
        now = self.now()
        if self._stats_since is None or now < self._stats_since:  # first tick, or the clock jumped back
            self._stats_since = now
            return
        period = float(self.core.params["stats_period"])
        if period > 0.0 and now - self._stats_since >= period:
            self._stats_since = now
            self.log.info(f"stats: {TickStats.describe(self.stats.take_window())}; "
                          f"{self.stats.counters(self.core.faults)}")

    # ------------------------------------------------------------------ shutdown
    def close(self) -> None:
        """Stop ticking, stop the tree, publish zero twists and wait for them to be acknowledged; log stats.

        Idempotent; never raises (it runs in ``finally`` on the way out).
        """
        if self._closed:
            return
        self._closed = True
        with suppress(Exception):
            self.timer.cancel()
        with suppress(Exception):
            self.watchdog_timer.cancel()
        self.core.shutdown()
        try:
            for _ in range(FINAL_STOPS):
                self.cmd.publish(Command(0.0, 0.0, "shutdown"))
            if not self.cmd.wait_acked(FINAL_ACK_TIMEOUT):
                self.log.warning("the final zero twist was not acknowledged by every subscriber")
        except Exception as exc:  # context already gone: nothing more can be sent
            self.log.error(f"could not publish the final zero twist: {exc!r}")
        self.log.info(f"final stats: {TickStats.describe(self.stats.history)}; "
                      f"{self.stats.counters(self.core.faults)}; scans {self.scans} (dropped {self.bad_scans}), "
                      f"evaluation calls {self.core.evaluation_calls}, watchdog stops {self.watchdog_stops}")


class ShutdownRequest:
    """SIGINT/SIGTERM handling that leaves the ROS context up until the robot has been stopped.

    The first signal only sets a flag (the spin loop ends and ``finally`` publishes the stop); a
    second one while still spinning raises KeyboardInterrupt, for a callback that hangs; once
    closing, further signals are ignored so they cannot cut the stop short.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signum: int | None = None
        self.closing = False
        self._previous: dict[int, Any] = {}

    @property
    def requested(self) -> bool:
        """A signal arrived."""
        return self.signum is not None

    def handle(self, signum: int, frame: FrameType | None) -> None:
        """The signal handler."""
        if self.closing:
            return
        if self.signum is not None:
            raise KeyboardInterrupt
        self.signum = signum

    def install(self) -> bool:
        """Install the handlers (only possible in the main thread); returns whether they were."""
        if threading.current_thread() is not threading.main_thread():
            return False
        for signum in self.SIGNALS:
            self._previous[signum] = signal.signal(signum, self.handle)
        return True

    def restore(self) -> None:
        """Put the previous handlers back (``main`` may run inside another program)."""
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)
        self._previous.clear()


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Our own options (ROS arguments removed first)."""
    parser = argparse.ArgumentParser(
        prog="executive",
        description=f"The bt_nav mission executive node ({NODE_NAME}).",
        epilog="ROS arguments follow --ros-args, e.g. --ros-args -r arm:=toggle_navigation "
               "-p safety_distance:=0.4 --params-file config/lab.yaml -p use_sim_time:=true",
    )
    parser.add_argument("--tree", metavar="XML", help="another tree file (default: the installed trees/mission.xml)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the node until SIGINT/SIGTERM or an external shutdown.

    Returns:
        0 after a clean shutdown (signals included), 2 when the configuration is refused, 1 after an
        unexpected error (the robot is stopped in every case that still has a ROS context).
    """
    args = [NODE_NAME, *(sys.argv[1:] if argv is None else argv)]
    try:
        own = remove_ros_args(args=args)[1:]  # rcl parses (and refuses) --ros-args here, params files included
    except Exception as exc:
        print(f"{NODE_NAME}: refusing to start: bad ROS arguments: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_CONFIG
    try:
        options = parse_args(own)
    except SystemExit as exc:  # --help, or an unknown option
        return int(exc.code or 0) if not isinstance(exc.code, str) else EXIT_CONFIG
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:
        print(f"{NODE_NAME}: refusing to start: bad ROS arguments: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_CONFIG
    shutdown = ShutdownRequest()
    shutdown.install()
    node: Node | None = None
    executive: Executive | None = None
    executor: SingleThreadedExecutor | None = None
    undo_logging = None
    code = EXIT_OK
    try:
        try:
            node = Node(NODE_NAME)
            undo_logging = route_py_trees_logging(node.get_logger().get_child("py_trees"))
            executive = Executive(node, tree_path=options.tree)
        except (ConfigError, ValueError) as exc:
            message = f"refusing to start: {exc}".replace("\n", " ")
            if node is not None:
                node.get_logger().fatal(message)
            else:
                print(f"{NODE_NAME}: {message}", file=sys.stderr)
            return EXIT_CONFIG
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while not shutdown.requested and rclpy.ok():
            executor.spin_once(timeout_sec=SPIN_TIMEOUT)
        if shutdown.requested:
            name = signal.Signals(shutdown.signum).name if shutdown.signum is not None else "signal"
            node.get_logger().info(f"{name} received: stopping the robot and shutting down")
        else:
            node.get_logger().info("ROS shut down from outside: stopping the robot")
    except (KeyboardInterrupt, ExternalShutdownException):
        if node is not None:
            node.get_logger().warning("interrupted: stopping the robot and shutting down")
    except Exception as exc:
        code = EXIT_ERROR
        if node is not None:
            node.get_logger().fatal(f"unexpected error, shutting down: {exc!r}")
        else:
            print(f"{NODE_NAME}: unexpected error: {exc!r}", file=sys.stderr)
    finally:
        shutdown.closing = True
        if executive is not None:
            executive.close()
        if executor is not None:
            with suppress(Exception):
                executor.shutdown(timeout_sec=0.5)
        if node is not None:
            with suppress(Exception):
                node.destroy_node()
        if undo_logging is not None:
            undo_logging()
        rclpy.try_shutdown()
        shutdown.restore()
    return code


if __name__ == "__main__":
    raise SystemExit(main())
