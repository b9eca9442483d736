"""The lab's terminal: what a student's screen shows during a check-off, from the nodes' events.

The lab hands in a video of "the terminal output of starting the launch file and calling the service" and
of the robot reacting. ``bt-nav demo --profile lab`` runs the check-off over DDS; :class:`LabTerminal` shows,
stamped with sim time,

- the launch: the executive's start-up line, as the lab asks to verify it (node name, params file,
  maneuver, ``safety_distance``), once the executive's tree arrives (its first snapshot on ``~/tree``: the node
  is up and ticking), at the snapshot's sim time;
- each ``toggle_navigation`` call the judge makes and its reply, as ``ros2 service call`` prints them;
- the executive's maneuver and emergency-brake lines (``SmartPivot: ...``, ``AEB: ...``) as they happen;
  not tick statistics, not the scan checker's chatter.

Where each comes from: structured data, never the nodes' log lines. The judge publishes every call and reply on its
``~/events`` (:class:`bt_nav.ros.nodes.judging.JudgeNode`, :func:`bt_nav.mission.snapshot.call_event`: t, call,
data, success, message), the executive its leaves' announcements on ``~/events`` (each with its line, ``text``, and
``level``) and its tree on ``~/tree`` (:mod:`bt_nav.mission.snapshot`); this process's :class:`TerminalNode`
subscribes to them. Each line is stamped with the sim time its source gave it (the event's or snapshot's ``t``),
never the time this process read it, which at 22x real time lagged by seconds.

The nodes' raw output still goes to the run's log files (:class:`bt_nav.run.rundir.Logs`, the launcher's sink,
which also prints the judge's report lines): that is a terminal, not a data interface. The one exception is a
student's node (:class:`NodeTerminal`, ``bt-nav demo --exe``): a foreign node publishes no events, so its own lines
are shown from its log output (:data:`DEFAULT_LOG_LINE`: rcutils' default format, whose wall stamp gives the
sim time); the judge's calls come from the judge's events there too.

With a bag (``--bag``/``--video``) every shown line and every report line is also published on
``/bt_nav/events`` (:data:`bt_nav.media.bag.EVENTS`, latched) by :class:`TerminalNode`; ``bt-nav record``
records that topic instead of turning ``/rosout`` into events, so the bag's events, and the video's console
strip, are exactly the terminal's lines, stamped with the sim time at which this process published them.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from typing import Any

from bt_nav.media.bag import ANNOUNCEMENTS, EVENTS, TREE
from bt_nav.mission.snapshot import read_event, read_snapshot
from bt_nav.ros.bringup import EXECUTIVE_NAME, JUDGE_NODE_NAMES
from bt_nav.run.rundir import Logs, judge_line, split_stamp


def judge_event_topics() -> list[str]:
    """The judges' ``~/events`` at the root namespace (one robot): whichever judge the run has publishes on its own."""
    return [f"/{name}/events" for name in JUDGE_NODE_NAMES]


def service_call_lines(service: str, data: bool) -> list[str]:
    """What ``ros2 service call`` prints when it sends a SetBool request."""
    word = "true" if data else "false"
    return [f'$ ros2 service call {service} std_srvs/srv/SetBool "{{data: {word}}}"',
            f"requester: making request: std_srvs.srv.SetBool_Request(data={data})"]


def service_reply_lines(success: bool, message: str) -> list[str]:
    """What ``ros2 service call`` prints for a SetBool response."""
    return ["response:", f"std_srvs.srv.SetBool_Response(success={success}, message={message!r})"]


def call_lines(record: dict[str, Any]) -> list[str]:
    """The terminal lines of a judge's event (:func:`bt_nav.mission.snapshot.call_event`): a call or its reply as
    ``ros2 service call`` prints them; none for any other event (a request given up is in the judge's log)."""
    if record.get("event") == "call":
        return service_call_lines(f"/{record['call']}", bool(record["data"]))
    if record.get("event") == "reply":
        return service_reply_lines(bool(record.get("success")), str(record.get("message", "")))
    return []


def show_judge_event(show: Callable[[str, float], Any], text: str) -> None:
    """A judge's event on the wire (``~/events``): ``show`` each of its terminal lines (:func:`call_lines`) at the
    event's sim time."""
    record = read_event(text)
    for line in call_lines(record) if record is not None else ():
        show(line, float(record["t"]))


class TerminalNode:
    """This process's node of the terminal: it subscribes to the nodes' events and tree (std_msgs/String, JSON) and,
    with ``publish``, publishes the shown lines on ``/bt_nav/events`` (reliable, transient local: a recorder that
    subscribes late still gets the launch lines). Subscribe (:meth:`subscribe`), then :meth:`start`."""

    def __init__(self, publish: bool = True) -> None:
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        from bt_nav.ros.rosutil import ThreadedNode

        self.ros = ThreadedNode("bt_nav_demo_terminal")
        qos = QoSProfile(depth=500, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.publisher = self.ros.node.create_publisher(String, EVENTS, qos) if publish else None
        self._string = String

    def subscribe(self, topic: str, callback: Callable[[str], Any], latched: bool = False) -> None:
        """Hand each message's text on ``topic`` to ``callback`` (QoS as the publisher's: ``~/tree``'s latched depth
        1, an events topic's depth 100)."""
        from bt_nav.ros.rosutil import EVENTS_QOS, LATCHED

        self.ros.node.create_subscription(self._string, topic, lambda msg: callback(msg.data),
                                          LATCHED if latched else EVENTS_QOS)

    def start(self) -> None:
        """Start spinning (the subscriptions' callbacks run on this node's thread)."""
        self.ros.start()

    def publish(self, text: str) -> None:
        """One event line (nothing without ``publish``)."""
        if self.publisher is not None:
            self.publisher.publish(self._string(data=text))

    def wait_for_reader(self, timeout: float = 20.0) -> bool:
        """Wait (``timeout`` wall s at most) until a recorder subscribes; True if one did.

        Why: lines published before the recorder joins reach it only as transient-local history, which DDS may
        hand over after the first live line; a recorder that is there from the first line gets them in order.
        """
        deadline = time.monotonic() + timeout
        while self.publisher is not None and self.publisher.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.05)
        return True

    def close(self, wait: float = 1.0) -> None:
        """Wait (``wait`` wall s at most) until the recorder has every line, then go."""
        from rclpy.duration import Duration

        try:
            if self.publisher is not None:
                self.publisher.wait_for_all_acked(Duration(nanoseconds=int(wait * 1e9)))
        finally:
            self.ros.close()


class LabTerminal:
    """What the lab's terminal shows of a check-off over DDS (see the module docstring).

    Args:
        logs: the run's log files (and the judge's report lines on stdout).
        launch_line: the executive's start-up line as the terminal shows it (made by the command).
        node: this process's node: the terminal subscribes to the events and the tree on it and starts it; it
            publishes the shown lines when made with ``publish`` (a bag). None: no ROS (the sink alone).
        out: prints one terminal line (default ``print``).
    """

    def __init__(self, logs: Logs, launch_line: str, node: TerminalNode | None = None,
                 out: Callable[[str], Any] | None = None) -> None:
        self.logs = logs
        self.launch_line = launch_line
        self.node = node
        self.out = out or (lambda text: print(text, flush=True))
        self.lines: list[tuple[float | None, str]] = []  # everything shown, with its sim time
        self._up = False
        self._lock = threading.Lock()
        if node is not None:
            node.subscribe(TREE, self.on_tree, latched=True)
            node.subscribe(ANNOUNCEMENTS, self.on_announcement)
            for topic in judge_event_topics():
                node.subscribe(topic, self.on_judge_event)
            node.start()

    def show(self, text: str, t: float | None = None) -> None:
        """One terminal line at sim time ``t`` (default: the newest ground truth), published as an event."""
        t = self.logs.line_time() if t is None else t
        with self._lock:
            self.lines.append((t, text))
            self.out(f"[sim {t:6.2f} s] {text}" if t is not None else f"[sim      - s] {text}")
            if self.node is not None:
                self.node.publish(text)

    def event(self, text: str) -> None:
        """A line that is printed elsewhere (the report) but belongs in the bag's events."""
        if self.node is not None:
            with self._lock:
                self.node.publish(text)

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: the log files (which print the judge's report lines); a report line also goes to the bag."""
        self.logs.sink(name, line)
        line = split_stamp(line)[1]
        if judge_line(name, line) == "report":
            self.event(line)

    def on_tree(self, text: str) -> None:
        """The executive's tree: its first snapshot says the node is up (the launch line, at the snapshot's time)."""
        snapshot = read_snapshot(text)
        if snapshot is None or self._up:
            return
        self._up = True
        self.show(self.launch_line, float(snapshot["t"]))

    def on_announcement(self, text: str) -> None:
        """An executive's event: its line (``text``) as the executive logged it, at the event's time."""
        record = read_event(text)
        if record is not None and record.get("text"):
            self.show(f"[{record.get('level', 'INFO')}] [{EXECUTIVE_NAME}]: {record['text']}", float(record["t"]))

    def on_judge_event(self, text: str) -> None:
        """A judge's call or reply, as ``ros2 service call`` shows it, at the judge's sim time."""
        show_judge_event(self.show, text)


#: A line in rcutils' default console format, ``[INFO] [1712345678.123456789] [node]: text`` (a student's node
#: logs so unless it sets ``RCUTILS_CONSOLE_OUTPUT_FORMAT``): the wall time of the log call is in it.
DEFAULT_LOG_LINE = re.compile(r"^\[(?P<level>[A-Z]+)\] \[(?P<time>\d+\.\d+)\] \[(?P<node>[^\]]+)\]: (?P<msg>.*)$")


#: Lines of a Python traceback (a process stopped while it starts): not a report line.
PYTHON_ERROR = re.compile(r"^(?:Traceback |\s|\w+(?:Error|Interrupt|Exception)\b)")


class NodeTerminal:
    """The terminal of ``bt-nav demo --exe``: a student's own node in place of bt_nav's executive.

    Shows, stamped with the sim time each happened (:class:`bt_nav.ros.simclock.SimClock`): every line the node
    prints (its log lines at their log call; a plain ``print`` when it is read: a foreign node has only its text),
    the judge's service calls and replies as ``ros2 service call`` prints them (from the judge's events, at the
    judge's sim time: :meth:`listen`), and the judge's report lines as they are. Not the simulator's or the
    recorder's lines (they are in the run's log files).

    Args:
        clock: the map from wall to sim time (the demo's recorder node's).
        out: prints one terminal line (default ``print``).
    """

    def __init__(self, clock: Any, out: Callable[[str], Any] | None = None) -> None:
        self.clock = clock
        self.out = out or (lambda text: print(text, flush=True))
        self.lines: list[tuple[float | None, str]] = []
        self.node: TerminalNode | None = None  # the judge's events (:meth:`listen`)
        self._lock = threading.Lock()

    def show(self, text: str, t: float | None) -> None:
        """One terminal line at sim time ``t`` (None: not known yet)."""
        with self._lock:
            self.lines.append((t, text))
            self.out(f"[sim {t:6.2f} s] {text}" if t is not None else f"[sim      - s] {text}")

    def _sim(self, wall_s: float | None = None) -> float | None:
        import time

        sim = self.clock.sim_at(time.time_ns() if wall_s is None else round(wall_s * 1e9))
        return None if sim is None else sim * 1e-9

    def sink(self, name: str, line: str) -> None:
        """Launcher sink (after the run's log files)."""
        if name == "node":
            match = DEFAULT_LOG_LINE.match(line)
            if match is None:
                self.show(line, self._sim())
            else:
                self.show(f"[{match['level']}] [{match['node']}]: {match['msg']}", self._sim(float(match["time"])))
        elif judge_line(name, line) == "report" and not PYTHON_ERROR.match(line):
            # a judge's report line (of its own process or hosted by the simulator's): its times are the judge's own;
            # a judge stopped early says so in its log file, not here
            with self._lock:
                self.out(line)

    def listen(self) -> None:
        """Show the judge's calls and replies from its events (call once this process is on the run's domain; again
        for a run again on another domain)."""
        self.close()
        self.node = TerminalNode(publish=False)
        for topic in judge_event_topics():
            self.node.subscribe(topic, self.on_judge_event)
        self.node.start()

    def on_judge_event(self, text: str) -> None:
        """A judge's call or reply, as ``ros2 service call`` shows it, at the judge's sim time."""
        show_judge_event(self.show, text)

    def close(self) -> None:
        """Stop listening."""
        if self.node is not None:
            self.node.close(wait=0.0)
            self.node = None
