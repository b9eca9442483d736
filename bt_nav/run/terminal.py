"""The lab's terminal: what a student's screen shows during a check-off, picked from the nodes' output.

The lab hands in a video of "the terminal output of starting the launch file and calling the service" and
of the robot reacting. ``bt-nav demo --profile lab`` runs the check-off over DDS; :class:`LabTerminal` is its
line sink: every node line still goes to the run's log files (:class:`bt_nav.run.rundir.Logs`, which also
prints the judge's report lines), and the terminal shows, stamped with sim time,

- the launch: the executive's start-up line, as the lab asks to verify it (node name, params file,
  maneuver, ``safety_distance``);
- each ``toggle_navigation`` call the judge makes and its reply, as ``ros2 service call`` prints them;
- the executive's maneuver and emergency-brake lines (``Randomizer: ...``, ``AEB: ...``) as they happen;
  not tick statistics, not the scan checker's chatter.

Each line is stamped with the sim time it happened at its source: a node's line with the sim time of its log
call (the line's own wall stamp mapped by ``/clock``: :meth:`bt_nav.run.rundir.Logs.line_time`), a judge's call
with the sim time the judge wrote into it; never the time this process read it, which at 22x real time lagged
by seconds.

With a bag (``--bag``/``--video``) every shown line and every report line is also published on
``/bt_nav/events`` (:data:`bt_nav.media.bag.EVENTS`, latched) by :class:`EventPublisher`; ``bt-nav record``
records that topic instead of turning ``/rosout`` into events, so the bag's events, and the video's console
strip, are exactly the terminal's lines, stamped with the sim time at which this process published them.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from typing import Any

from bt_nav.media.bag import EVENTS
from bt_nav.mission.maneuver_spec import tips as maneuver_tips
from bt_nav.ros.bringup import EXECUTIVE_NAME
from bt_nav.run.rundir import Logs, judge_line, split_stamp

#: The executive's lines the terminal shows, by the label they start with: the maneuvers' (the maneuver spec's
#: tips, looked up on each line) and the brake's.
SHOWN_LABELS = frozenset({"AEB"})
#: An rcutils line in the run's format (:data:`bt_nav.run.rundir.LOG_FORMAT`).
LOG_LINE = re.compile(r"^\[(?P<level>[A-Z]+)\] \[(?P<node>[^\]]+)\]: (?P<msg>.*)$")
#: The judge's call and reply lines (:class:`bt_nav.ros.nodes.judging.JudgeNode`).
CALL_LINE = re.compile(r"^sim (?P<t>-?[\d.]+) s(?: \(t0 \+ [-\d.]+ s\))?: (?P<call>\w+)\((?P<data>true|false)\) "
                       r"(?:sent|-> (?P<ok>success|failure): (?P<message>.*))$")


def service_call_lines(service: str, data: bool) -> list[str]:
    """What ``ros2 service call`` prints when it sends a SetBool request."""
    word = "true" if data else "false"
    return [f'$ ros2 service call {service} std_srvs/srv/SetBool "{{data: {word}}}"',
            f"requester: making request: std_srvs.srv.SetBool_Request(data={data})"]


def service_reply_lines(success: bool, message: str) -> list[str]:
    """What ``ros2 service call`` prints for a SetBool response."""
    return ["response:", f"std_srvs.srv.SetBool_Response(success={success}, message={message!r})"]


class EventPublisher:
    """``/bt_nav/events`` (std_msgs/String, reliable, transient local: a recorder that subscribes late still
    gets the launch lines) from a node of this process's own."""

    def __init__(self) -> None:
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        from bt_nav.ros.rosutil import ThreadedNode

        self.ros = ThreadedNode("bt_nav_demo_terminal")
        qos = QoSProfile(depth=500, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.publisher = self.ros.node.create_publisher(String, EVENTS, qos)
        self._string = String
        self.ros.start()

    def publish(self, text: str) -> None:
        """One event line."""
        self.publisher.publish(self._string(data=text))

    def wait_for_reader(self, timeout: float = 20.0) -> bool:
        """Wait (``timeout`` wall s at most) until a recorder subscribes; True if one did.

        Why: lines published before the recorder joins reach it only as transient-local history, which DDS may
        hand over after the first live line; a recorder that is there from the first line gets them in order.
        """
        deadline = time.monotonic() + timeout
        while self.publisher.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.05)
        return True

    def close(self, wait: float = 1.0) -> None:
        """Wait (``wait`` wall s at most) until the recorder has every line, then go."""
        from rclpy.duration import Duration

        try:
            self.publisher.wait_for_all_acked(Duration(nanoseconds=int(wait * 1e9)))
        finally:
            self.ros.close()


class LabTerminal:
    """The line sink of a lab check-off over DDS (see the module docstring).

    Args:
        logs: the run's log files (and the judge's report lines on stdout).
        launch_line: the executive's start-up line as the terminal shows it (made by the command).
        events: where shown lines also go (None: no bag).
        out: prints one terminal line (default ``print``).
    """

    def __init__(self, logs: Logs, launch_line: str, events: EventPublisher | None = None,
                 out: Callable[[str], Any] | None = None) -> None:
        self.logs = logs
        self.launch_line = launch_line
        self.events = events
        self.out = out or (lambda text: print(text, flush=True))
        self.lines: list[tuple[float | None, str]] = []  # everything shown, with its sim time
        self._lock = threading.Lock()

    def show(self, text: str, t: float | None = None) -> None:
        """One terminal line at sim time ``t`` (default: the newest ground truth), published as an event."""
        t = self.logs.line_time() if t is None else t
        with self._lock:
            self.lines.append((t, text))
            self.out(f"[sim {t:6.2f} s] {text}" if t is not None else f"[sim      - s] {text}")
            if self.events is not None:
                self.events.publish(text)

    def event(self, text: str) -> None:
        """A line that is printed elsewhere (the report) but belongs in the bag's events."""
        if self.events is not None:
            with self._lock:
                self.events.publish(text)

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: the log files, then what the lab's terminal shows of ``line``."""
        self.logs.sink(name, line)
        wall_ns, line = split_stamp(line)
        when = self.logs.line_time(wall_ns) if wall_ns is not None else None
        match = LOG_LINE.match(line)
        judge = judge_line(name, line)
        if judge is not None:
            if judge == "report":
                self.event(line)  # a report line (Logs printed it)
            elif match is not None:
                self._judge_line(match["msg"])
        elif name.endswith("executive") and match is not None:
            message = match["msg"]
            if message.startswith(f"{EXECUTIVE_NAME} up:"):
                self.show(self.launch_line, when)
            elif message.split(":", 1)[0] in SHOWN_LABELS | maneuver_tips():
                self.show(f"[{match['level']}] [{match['node']}]: {message}", when)

    def _judge_line(self, message: str) -> None:
        """The judge's toggle_navigation calls and replies, as ``ros2 service call`` shows them."""
        call = judge_call(message)
        for text in call[1] if call else ():
            self.show(text, call[0])


def judge_call(message: str) -> tuple[float, list[str]] | None:
    """A judge's log message about its service call or the reply (:data:`CALL_LINE`): its sim time and the
    terminal lines ``ros2 service call`` prints for it; None for any other message."""
    call = CALL_LINE.match(message)
    if call is None:
        return None
    if call["ok"] is None:
        return float(call["t"]), service_call_lines(f"/{call['call']}", call["data"] == "true")
    return float(call["t"]), service_reply_lines(call["ok"] == "success", call["message"])


#: A line in rcutils' default console format, ``[INFO] [1712345678.123456789] [node]: text`` (a student's node
#: logs so unless it sets ``RCUTILS_CONSOLE_OUTPUT_FORMAT``): the wall time of the log call is in it.
DEFAULT_LOG_LINE = re.compile(r"^\[(?P<level>[A-Z]+)\] \[(?P<time>\d+\.\d+)\] \[(?P<node>[^\]]+)\]: (?P<msg>.*)$")


#: Lines of a Python traceback (a process stopped while it starts): not a report line.
PYTHON_ERROR = re.compile(r"^(?:Traceback |\s|\w+(?:Error|Interrupt|Exception)\b)")


class NodeTerminal:
    """The terminal of ``bt-nav demo --exe``: a student's own node in place of bt_nav's executive.

    Shows, stamped with the sim time each happened (:class:`bt_nav.ros.simclock.SimClock`): every line the node
    prints (its log lines at their log call; a plain ``print`` when it is read), the judge's service calls and
    replies as ``ros2 service call`` prints them, and the judge's report lines as they are. Not the simulator's
    or the recorder's lines (they are in the run's log files).

    Args:
        clock: the map from wall to sim time (the demo's recorder node's).
        out: prints one terminal line (default ``print``).
    """

    def __init__(self, clock: Any, out: Callable[[str], Any] | None = None) -> None:
        self.clock = clock
        self.out = out or (lambda text: print(text, flush=True))
        self.lines: list[tuple[float | None, str]] = []
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
        elif judge_line(name, line) is not None:  # a judge's, of its own process or hosted by the simulator's
            log = DEFAULT_LOG_LINE.match(line)
            if log is None:
                if not PYTHON_ERROR.match(line):  # a judge stopped early says so in its log file, not here
                    with self._lock:
                        self.out(line)  # a report line: its times are the judge's own
                return
            call = judge_call(log["msg"])
            for text in call[1] if call else ():
                self.show(text, call[0])
