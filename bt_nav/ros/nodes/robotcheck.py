"""``bt-nav checkoff --robot``: the lab's check-off judged live, beside a real robot, from what its topics carry.

A listener: it sends no command, and calls ``toggle_navigation`` only when told to (``--call-toggle``: true once it
has heard the robot for :data:`STATIC_BEFORE` s, false at the end, then it listens :data:`STATIC_AFTER` s more for the
static check; its own calls are then the check-off's schedule, timed as it made them). Otherwise the TA calls it, as
the sheet says. It runs on the user's own ROS_DOMAIN_ID and discovery range (the robot's: never bt_nav's localhost
lease), and ``--ros-args`` after the options are this node's (a launch file's remaps and name). While it listens, each
maneuver's line is printed the moment the judge can decide it (:data:`LINE_MARGIN` s after its turn settled: the
heard data judged again every :data:`REJUDGE_EVERY` s).

For ``--duration`` seconds, or until Ctrl-C, it keeps every /odom, /scan and /cmd_vel message (Twist or
TwistStamped, whichever the graph has), the ``toggle_navigation`` service events and ``/rosout`` (the node's lines:
the judge's announcements), with the time it heard each and the message's own stamp; then it hands them to the same
reading and judging as a bag of them (:func:`bt_nav.media.robotbag.recording_from`,
:func:`bt_nav.judge.recorded.judge_recording`). So the live verdict and the verdict on the bag of the same run follow
one rule; only the clock that times the arrivals is this process's (the wall clock).

QoS: best effort for the sensors and the commands (it hears a reliable publisher as well as a best-effort one, and
never slows the robot down), reliable for the service events (rosbag2 records them so too).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Log
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from std_srvs.srv import SetBool

from bt_nav.media.robotbag import ROSOUT, stamp_ns

NODE_NAME = "bt_nav_checkoff_listener"
#: s heard before calling toggle_navigation(true), and after calling it false (the static checks' spans).
STATIC_BEFORE, STATIC_AFTER = 3.0, 3.0
#: s between two live judgings of what was heard; s after a turn settled before its line is printed.
REJUDGE_EVERY, LINE_MARGIN = 1.0, 2.0
#: s to wait for toggle_navigation to be offered, and for each answer.
SERVICE_WAIT = 10.0
#: s after which a topic not heard yet is named, with the likely causes (the listener keeps listening).
NOTHING_HEARD_AFTER = 5.0
#: The RMW a TurtleBot3's Jazzy image runs (ROBOTIS' setup guide): the TA's computer must run the same.
ROBOT_RMW = "rmw_fastrtps_cpp"
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


def unheard(raw: dict[str, list[Any]], names: dict[str, str]) -> list[str]:
    """The robot's topics (odometry, scan, commands) not heard yet."""
    return [names[role] for role in ("odom", "scan", "cmd") if not raw.get(names[role])]


def rmw_name() -> str:
    """The RMW this process runs: ``RMW_IMPLEMENTATION``, else the one rclpy loaded (its default)."""
    chosen = os.environ.get("RMW_IMPLEMENTATION", "").strip()
    if chosen:
        return chosen
    try:
        return str(rclpy.get_rmw_implementation_identifier())
    except Exception:  # noqa: BLE001 - before rclpy.init on some versions: the default is Fast DDS
        return ROBOT_RMW


def unheard_words(missing: list[str], waited: float) -> str:
    """Which topics were not heard in ``waited`` s, the graph this listener is on, and why a robot may not be heard."""
    return (f"nothing heard on {', '.join(missing)} in {waited:.0f} s ({graph_words()}, RMW {rmw_name()}). Likely "
            "causes: the robot is on another ROS_DOMAIN_ID (on the robot: echo $ROS_DOMAIN_ID; export the same "
            "here); ROS_AUTOMATIC_DISCOVERY_RANGE is LOCALHOST on one side (SUBNET on both to hear another computer); "
            f"the robot runs another RMW_IMPLEMENTATION (a TurtleBot3's Jazzy image runs {ROBOT_RMW}: the same on "
            "both); the robot's bringup or the node is not running (ros2 topic list on the robot); a firewall or a "
            "Wi-Fi that drops multicast")


class HearingWatch:
    """Says once, :data:`NOTHING_HEARD_AFTER` s into listening, which of the robot's topics were not heard and the
    likely causes, then that they came if they do (the listener keeps listening all along)."""

    def __init__(self, names: dict[str, str], began: float) -> None:
        self.names, self.began = names, began
        self.warned: list[str] = []
        self.done = False

    def check(self, raw: dict[str, list[Any]], now: float) -> str | None:
        """A line to print now, or None."""
        if self.done or now < self.began + NOTHING_HEARD_AFTER:
            return None
        missing = unheard(raw, self.names)
        if not self.warned:
            self.warned = missing or ["-"]
            self.done = not missing
            return f"{unheard_words(missing, now - self.began)}; still listening" if missing else None
        if not missing:
            self.done = True
            return f"now hearing {', '.join(self.names[r] for r in ('odom', 'scan', 'cmd'))} " \
                   f"({now - self.began:.0f} s into listening)"
        return None


def graph_words() -> str:
    """The DDS graph this process joins, in words: the user's ROS_DOMAIN_ID and discovery range."""
    domain = os.environ.get("ROS_DOMAIN_ID", "").strip() or "0"
    reach = os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip() or "SUBNET"
    return f"ROS_DOMAIN_ID {domain}, discovery range {reach}"


class Toggler:
    """``toggle_navigation`` called by the listener itself (``--call-toggle``); :attr:`calls` as the check-off's
    schedule: (request ns, data, answer ns or None, success, message)."""

    def __init__(self, node: Node, service: str) -> None:
        self.node = node
        self.client = node.create_client(SetBool, service)
        self.service = service
        self.calls: list[tuple[int, bool, int | None, bool, str]] = []

    def call(self, data: bool) -> str:
        """Call and wait (spinning) for the answer; the outcome in words."""
        if not self.client.wait_for_service(timeout_sec=SERVICE_WAIT):
            self.calls.append((self.node.get_clock().now().nanoseconds, data, None, False, ""))
            return f"no {self.service} service within {SERVICE_WAIT:g} s ({graph_words()})"
        asked = self.node.get_clock().now().nanoseconds
        future = self.client.call_async(SetBool.Request(data=data))
        end = time.monotonic() + SERVICE_WAIT
        while not future.done() and time.monotonic() < end:
            rclpy.spin_once(self.node, timeout_sec=0.05)
        if not future.done():
            self.calls.append((asked, data, None, False, ""))
            return f"{self.service}({str(data).lower()}): no answer within {SERVICE_WAIT:g} s"
        answer = future.result()
        self.calls.append((asked, data, self.node.get_clock().now().nanoseconds, bool(answer.success),
                           str(answer.message)))
        return f"{self.service}({str(data).lower()}): success={answer.success} {answer.message!r}"


Raw = dict[str, list[tuple[int, int | None, Any]]]


def listen(names: dict[str, str], duration: float, call_toggle: bool = False,
           on_progress: Callable[[Raw, list[Any]], None] | None = None,
           ros_args: list[str] | None = None) -> tuple[Raw, list[str], list[Any] | None]:
    """Listen for ``duration`` seconds (0: until Ctrl-C), calling toggle_navigation if told to; what was heard,
    notes on it, and the listener's own calls (:class:`bt_nav.judge.recorded.ServiceCall`; None when it made
    none). ``on_progress(raw, calls)`` is called every :data:`REJUDGE_EVERY` s with what was heard so far."""
    from bt_nav.judge.recorded import ServiceCall

    rclpy.init(args=["bt_nav_checkoff", *(["--ros-args", *ros_args] if ros_args else [])])
    node = RobotListener(names)
    toggler = Toggler(node, names["service"].removesuffix("/_service_event")) if call_toggle else None
    notes: list[str] = []
    began = time.monotonic()
    end = began + duration if duration > 0 else float("inf")
    armed = False
    next_progress = began + REJUDGE_EVERY

    def own_calls() -> list[Any] | None:
        if toggler is None:
            return None
        return [ServiceCall(t * 1e-9, data, None if a is None else a * 1e-9, ok, msg)
                for t, data, a, ok, msg in toggler.calls]

    watch = HearingWatch(names, began)
    try:
        while time.monotonic() < end and rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
            said = watch.check(node.raw, time.monotonic())
            if said:
                print(f"bt-nav checkoff: {said}", flush=True)
            if toggler is not None and not armed and time.monotonic() >= began + STATIC_BEFORE:
                armed = True
                print(f"bt-nav checkoff: {toggler.call(True)}", flush=True)
            if on_progress is not None and time.monotonic() >= next_progress:
                next_progress = time.monotonic() + REJUDGE_EVERY
                on_progress(node.raw, own_calls() or [])
    except (KeyboardInterrupt, ExternalShutdownException):
        # Ctrl-C: as a KeyboardInterrupt, or (rclpy's own SIGINT handler shut the context down while the executor
        # waited) as ExternalShutdownException, which once ended the listener with a traceback and no verdict
        notes.append("stopped by Ctrl-C")
    finally:
        try:
            if toggler is not None and armed and rclpy.ok():
                print(f"bt-nav checkoff: {toggler.call(False)}", flush=True)
                after = time.monotonic() + STATIC_AFTER
                while time.monotonic() < after and rclpy.ok():
                    rclpy.spin_once(node, timeout_sec=0.1)
        except (KeyboardInterrupt, ExternalShutdownException):
            notes.append("the static check after deactivation was cut short by a second Ctrl-C")
        raw, command_type = node.raw, node.command_type
        node.destroy_node()
        rclpy.try_shutdown()
    if not command_type:
        notes.append(f"no {names['cmd']} publisher was seen (Twist or TwistStamped)")
    heard = ", ".join(f"{topic} {len(rows)}" for topic, rows in sorted(raw.items())) or "nothing"
    notes.append(f"heard live ({graph_words()}): {heard}")
    if toggler is not None:
        notes.append("toggle_navigation called by this listener: its own calls are the check-off's schedule")
    return raw, notes, own_calls()
