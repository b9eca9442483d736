"""The mission executive node: ``bt_nav_executive``, the ROS edge around :class:`~bt_nav.mission.core.MissionCore`.

Run it with ``ros2 run bt_nav executive`` (colcon install) or ``bt-nav executive`` (pip install); both
accept the usual ROS arguments, e.g.::

    bt-nav executive --ros-args -r arm:=toggle_navigation -p safety_distance:=0.4 \\
        --params-file config/lab.yaml -p use_sim_time:=true

Interfaces (relative names, so ``-r`` remapping and namespaces work):

==============  ====================  ==============================  ==================================================
kind            name                  type                            notes
==============  ====================  ==============================  ==================================================
service server  ``arm``               std_srvs/SetBool                true arms (starts the mission timer), false stops
service client  ``evaluate_mission``  std_srvs/Trigger                called once at the deadline, with retries
subscription    ``scan``              sensor_msgs/LaserScan           sensor-data QoS; stamped on receipt (node clock)
subscription    ``odom``              nav_msgs/Odometry               optional: closes the maneuvers' loop
publisher       ``cmd_vel``           geometry_msgs/Twist             one command per tick (TwistStamped with
                                                                      ``cmd_vel_stamped:=true``)
publisher       ``~/tree``            std_msgs/String                 the tree as a JSON document when a status
                                                                      or the tip changes (transient local, depth
                                                                      1; :mod:`bt_nav.mission.snapshot`)
publisher       ``~/events``          std_msgs/String                 the leaves' announcements as JSON, e.g. a
                                                                      maneuver's side and angle (reliable,
                                                                      transient local, depth 100)
==============  ====================  ==============================  ==================================================

Parameters: every entry of :data:`bt_nav.mission.params.PARAMS`, with its description, unit and range
(``ros2 param describe``); ``live=False`` ones are read-only. Start-up values and live changes pass one
gate, :func:`bt_nav.mission.params.check_changes` (:mod:`bt_nav.ros.param_gate` for live ones): a refused
change gets the reason in its SetParametersResult and one ``parameter change refused: <reason>`` line; an
invalid start-up value makes the node log ``refusing to start: <reason>`` and exit with status 2 — a
robot must not drive on a configuration nobody meant.

Timing: the tree ticks on a timer of the node clock, so with ``use_sim_time`` the ticks, the deadline,
the scan timeout and the maneuvers all follow ``/clock``. Tick statistics (:mod:`bt_nav.ros.tick_stats`)
are logged every ``stats_period`` and at exit; ``clock_watchdog`` (:mod:`bt_nav.ros.safety`) publishes
one zero twist when ``/clock`` stalls while the robot moves. With ``trace_path`` set, every tick is
written there as the lock-step runner writes it (:mod:`bt_nav.mission.trace`), for ``bt-nav replay``.
With ``stats_path`` set, the exit statistics are written there as JSON too (a benchmark reads them).

Safety: no motion before the first arming, a stop after a disarm and at the deadline (the tree); every
command is vetted once more before it is published; SIGINT/SIGTERM publish a zero twist before the ROS
context goes down and exit with status 0 (:mod:`bt_nav.ros.runner`).
"""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import suppress
from time import monotonic, perf_counter
from typing import Any

from rclpy.clock import Clock, ClockType
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data

from bt_nav.mission import params as P
from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.profiles import params_files_note
from bt_nav.mission.resources import tree_file, written_whole
from bt_nav.mission.scan import Scan, ScanError
from bt_nav.mission.snapshot import snapshot_json
from bt_nav.mission.trace import TraceRecorder
from bt_nav.ros.param_gate import ParameterGate
from bt_nav.ros.rosutil import (
    EVENTS_QOS,
    LATCHED,
    CommandPublisher,
    ConfigError,
    QuietNode,
    RclpyEventLog,
    declare_parameters,
    route_py_trees_logging,
    unknown_overrides,
)
from bt_nav.ros.runner import run_node
from bt_nav.ros.safety import ClockWatchdog, veto_reason
from bt_nav.ros.tick_stats import TickStats

NODE_NAME = "bt_nav_executive"
#: Zero twists published at exit (cheap insurance against one lost sample) and how long to wait for acks.
FINAL_STOPS, FINAL_ACK_TIMEOUT = 3, 0.5
#: Wall-clock seconds between two looks of the clock watchdog.
WATCHDOG_CHECK_PERIOD = 0.1


class Executive:
    """The node's wiring: parameters, subscriptions, publishers, the tick timer and the stats.

    Args:
        node: the node to wire (named ``bt_nav_executive`` by :func:`main`).
        tree_path: another tree file (default: the installed ``trees/mission.xml``).

    Raises:
        ConfigError: when a start-up parameter is invalid, the tree cannot be built or the trace file
            cannot be opened.
    """

    def __init__(self, node: Node, *, tree_path: str | None = None) -> None:
        self.node = node
        self.log = node.get_logger()
        self._clock = node.get_clock()
        self._closed = False
        for name in unknown_overrides(node):
            self.log.warning(f"ignoring parameter {name!r}: not a bt_nav parameter (typo?)")
        try:
            self.core = MissionCore(declare_parameters(node), clock=self.now, node=node, events=RclpyEventLog(self.log),
                                    tree_path=tree_path)
            trace_path = str(self.core.params["trace_path"])
            self.trace = TraceRecorder(self.core, trace_path) if trace_path else None
        except (ValueError, OSError) as exc:
            raise ConfigError(str(exc)) from None
        params = self.core.params
        self.period = 1.0 / float(params["tick_rate_hz"])
        self.stats = TickStats(self.period)
        self.watchdog = ClockWatchdog(float(params["clock_watchdog"]))
        self.scans = self.bad_scans = self.bad_odom = 0
        self._wire(node, params)
        self.log.info(self.describe(tree_path))

    def _wire(self, node: Node, params: dict[str, P.Value]) -> None:
        """Publishers, subscriptions, parameter callbacks and the two timers."""
        from nav_msgs.msg import Odometry
        from sensor_msgs.msg import LaserScan
        from std_msgs.msg import String

        self._string = String
        self.cmd = CommandPublisher(node, "cmd_vel", stamped=bool(params["cmd_vel_stamped"]),
                                    frame_id=str(params["frame_id"]))
        self.tree_publisher = node.create_publisher(String, "~/tree", LATCHED)
        self.events_publisher = node.create_publisher(String, "~/events", EVENTS_QOS)
        # rclpy's QoS warnings on the inputs a robot's driver may offer otherwise, on a QuietNode too (QuietQosEvents)
        self.scan_subscription = node.create_subscription(LaserScan, "scan", self._on_scan, qos_profile_sensor_data,
                                                          event_callbacks=SubscriptionEventCallbacks())
        self.odom_subscription = node.create_subscription(Odometry, "odom", self._on_odom, qos_profile_sensor_data,
                                                          event_callbacks=SubscriptionEventCallbacks())
        self.parameters = ParameterGate(node, self.core, self.log)
        self.timer = node.create_timer(self.period, self._on_tick)
        self.watchdog_timer = node.create_timer(WATCHDOG_CHECK_PERIOD, self._on_watchdog,
                                                clock=Clock(clock_type=ClockType.STEADY_TIME))

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
                f"tree {tree_path or tree_file()}; {params_files_note(sys.argv)}"
                + (f"; trace {params['trace_path']}" if self.trace is not None else ""))

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
        """The pose (heading from the quaternion); a non-rotation is dropped (maneuvers go open loop)."""
        q = msg.pose.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        if yaw != yaw:  # NaN: not a rotation
            self.bad_odom += 1
            self.log.warning(f"dropping odometry with an invalid orientation ({self.bad_odom} so far)",
                             throttle_duration_sec=5.0)
            return
        position = msg.pose.pose.position
        self.core.feed_odom(yaw, x=float(position.x), y=float(position.y))

    # ------------------------------------------------------------------ ticking
    def _on_tick(self) -> None:
        """One tick: tree, last check, publish; then the tree snapshot, the trace and the stats."""
        started = perf_counter()
        resumed = self.watchdog.ticked(monotonic())
        if resumed is not None:
            self.log.info(f"clock watchdog: ticking again after {resumed:.1f} s of wall time without a tick")
        try:
            command = self.vet(self.core.tick())
            self.cmd.publish(command)
            self.watchdog.moving = not command.is_zero
            self._publish_state()
        except Exception as exc:  # the node must outlive any bug at its edge, and stop the robot
            self.stats.exceptions += 1
            self.watchdog.moving = False
            self.log.error(f"tick {self.core.ticks} failed outside the tree: {exc!r}; publishing a stop")
            command = Command(0.0, 0.0, "executive error")
            with suppress(Exception):
                self.cmd.publish(command)
        finally:
            self.stats.record(perf_counter() - started)
        self._record_trace(command)
        line = self.stats.periodic_line(self.now(), float(self.core.params["stats_period"]), self.core.faults)
        if line:
            self.log.info(line)

    def _record_trace(self, command: Command) -> None:
        """The tick's trace line; a trace that cannot be written is closed (logged once), the node drives on."""
        if self.trace is None:
            return
        try:
            self.trace.record(command)
        except (OSError, ValueError) as exc:
            self.log.error(f"trace {self.core.params['trace_path']}: {exc!r}; no more trace lines")
            trace, self.trace = self.trace, None
            with suppress(Exception):
                trace.close()

    def _on_watchdog(self) -> None:
        """Publish one stop when the robot was last told to move and the ticks stopped (wall clock)."""
        self.watchdog.timeout = float(self.core.params["clock_watchdog"])  # live parameter
        idle = self.watchdog.due(monotonic())
        if idle is None:
            return
        self.cmd.publish(Command(0.0, 0.0, "clock watchdog"))
        clock = "/clock stalled?" if self.node.get_parameter("use_sim_time").value else "tick timer starved?"
        self.log.warning(f"clock watchdog: no tick for {idle:.1f} s of wall time while moving ({clock}): "
                         "published a stop; the next tick decides again")

    def vet(self, command: Command) -> Command:
        """The last look before the wire (:func:`bt_nav.ros.safety.veto_reason`): a refused command is
        logged and counted, and a stop goes out instead."""
        why = veto_reason(command, self.core.params, armed=bool(self.core.value("armed", False)),
                          mission_over=self.core.mission_over)
        if not why:
            return command
        self.stats.vetoed += 1
        self.log.error(f"vetoed command ({command.linear}, {command.angular}) from {command.source}: {why}; "
                       f"publishing a stop ({self.stats.vetoed} vetoed so far)", throttle_duration_sec=1.0)
        return Command(0.0, 0.0, f"vetoed: {why}")

    def _publish_state(self) -> None:
        """The tick's events on ``~/events``, then ``~/tree`` when a status or the tip changed (not every tick:
        the document is large); the lock-step engine takes the same two from the core."""
        for record in self.core.take_announcements():
            self.events_publisher.publish(self._string(data=snapshot_json(record)))
        snapshot = self.core.changed_snapshot()
        if snapshot is not None:
            self.tree_publisher.publish(self._string(data=snapshot_json(snapshot)))

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
        if self.trace is not None:
            with suppress(Exception):
                self.trace.close()
        self.log.info(f"{self.stats.final_line(self.core.faults)}; scans {self.scans} (dropped {self.bad_scans}), "
                      f"evaluation calls {self.core.evaluation_calls}, watchdog stops {self.watchdog.stops}")
        self._write_stats()

    def _write_stats(self) -> None:
        """The final stats line's figures as JSON into ``stats_path`` (a benchmark's source: the line is for
        people); a file that cannot be written is logged, never raised (this runs on the way out)."""
        path = str(self.core.params["stats_path"])
        if not path:
            return
        record = {**self.stats.final_record(self.core.faults), "scans": self.scans, "dropped_scans": self.bad_scans,
                  "evaluation_calls": self.core.evaluation_calls, "watchdog_stops": self.watchdog.stops}
        try:
            with written_whole(path) as stream:
                stream.write(json.dumps(record) + "\n")
        except OSError as exc:
            self.log.error(f"stats {path}: {exc!r}")


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
    """Run the node until SIGINT/SIGTERM or an external shutdown (see :func:`bt_nav.ros.runner.run_node`).

    Returns:
        0 after a clean shutdown (signals included), 2 when the configuration is refused, 1 after an
        unexpected error (the robot is stopped in every case that still has a ROS context).
    """
    return run_node(NODE_NAME, argv, parse_args, make_node=QuietNode,
                    build=lambda node, options: Executive(node, tree_path=options.tree),
                    prepare=lambda node: route_py_trees_logging(node.get_logger().get_child("py_trees")))


if __name__ == "__main__":
    raise SystemExit(main())
