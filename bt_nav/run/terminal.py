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

import heapq
import json
import re
import shlex
import threading
import time
from collections.abc import Callable
from typing import Any

from bt_nav.media.bag import ANNOUNCEMENTS, EVENTS, TREE
from bt_nav.media.console import sim_stamp
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
        self._subscriptions: list[Any] = []

    def subscribe(self, topic: str, callback: Callable[[str], Any], latched: bool = False) -> None:
        """Hand each message's text on ``topic`` to ``callback`` (QoS as the publisher's: ``~/tree``'s latched depth
        1, an events topic's depth 100)."""
        from bt_nav.ros.rosutil import EVENTS_QOS, LATCHED

        self._subscriptions.append(self.ros.node.create_subscription(
            self._string, topic, lambda msg: callback(msg.data), LATCHED if latched else EVENTS_QOS))

    def publishers(self) -> int:
        """How many publishers the subscriptions have found (0: none discovered yet)."""
        return sum(sub.get_publisher_count() for sub in self._subscriptions)

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
            self.out(sim_stamp(t, text))
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
    prints (its log lines at their log call; a plain ``print`` when it is read: a foreign node has only its text)
    and the judge's service calls and replies as ``ros2 service call`` prints them (from the judge's events, at the
    judge's sim time: :meth:`listen`). Not the simulator's, the judge's or the recorder's own lines (they are in the
    run's log files); the judge's report lines are kept (:attr:`report`) for the command to print after the run, on
    the sim clock (:func:`on_sim_clock`).

    Why ``hold``: the node's lines come through its pipe at once, the judge's calls over DDS, whose transient-local
    history can reach a reader seconds late (discovery on a loaded machine): printed as they came, a call at
    ``sim 5.50 s`` once followed a maneuver line at ``sim 15.90 s``. With ``hold`` > 0 a line is printed once the sim
    clock is ``hold`` s past it and this process has found the judge's events (or :data:`FIND_JUDGE` wall seconds
    went by), in time order; :meth:`close` prints what is left. 0: printed at once.

    Args:
        clock: the map from wall to sim time (the demo's recorder node's).
        out: prints one terminal line (default ``print``).
        hold: sim seconds a line waits for earlier ones (see above).
    """

    def __init__(self, clock: Any, out: Callable[[str], Any] | None = None, hold: float = 0.0) -> None:
        self.clock = clock
        self.out = out or (lambda text: print(text, flush=True))
        self.hold = hold
        self.lines: list[tuple[float | None, str, str]] = []  # (sim time, text, kind: node, call) as shown
        self.report: list[str] = []  # the judge's report lines as it printed them (its own time base)
        self.node: TerminalNode | None = None  # the judge's events (:meth:`listen`)
        self._pending: list[tuple[float, int, float | None, str]] = []  # heap: (t, order, t, text)
        self._listening_since = time.monotonic()
        self._lock = threading.Lock()
        self._ticker: threading.Thread | None = None

    def show(self, text: str, t: float | None, kind: str = "node") -> None:
        """One terminal line at sim time ``t`` (None: not known yet: printed at once, it comes before the clock)."""
        with self._lock:
            self.lines.append((t, text, kind))
            if self.hold <= 0 or t is None:
                self.out(sim_stamp(t, text))
                return
            heapq.heappush(self._pending, (t, len(self.lines), t, text))
        self.release()

    def release(self, everything: bool = False) -> None:
        """Print the held lines whose time has come (see the class docstring), or all of them."""
        now = None if everything else self._sim()
        with self._lock:
            ready = everything or self._found_judge()
            while self._pending and ready and (everything or (now is not None and self._pending[0][0] <= now -
                                                              self.hold)):
                _, _, t, text = heapq.heappop(self._pending)
                self.out(sim_stamp(t, text))

    def _found_judge(self) -> bool:
        if time.monotonic() - self._listening_since > FIND_JUDGE:
            return True
        return self.node is not None and self.node.publishers() > 0

    def _sim(self, wall_s: float | None = None) -> float | None:
        if self.clock is None:
            return None
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
            # a judge's report line (of its own process or hosted by the simulator's): kept for after the run; a
            # judge stopped early says so in its log file, not here
            with self._lock:
                self.report.append(line)

    def listen(self) -> None:
        """Show the judge's calls and replies from its events (call once this process is on the run's domain; again
        for a run again on another domain)."""
        self.close(flush=False)
        self.node = TerminalNode(publish=False)
        for topic in judge_event_topics():
            self.node.subscribe(topic, self.on_judge_event)
        self.node.start()
        self._listening_since = time.monotonic()
        if self.hold > 0 and self._ticker is None:
            self._ticker = threading.Thread(target=self._tick, name="terminal-release", daemon=True)
            self._ticker.start()

    def _tick(self) -> None:
        while self._ticker is not None:
            self.release()
            time.sleep(0.1)

    def on_judge_event(self, text: str) -> None:
        """A judge's call or reply, as ``ros2 service call`` shows it, at the judge's sim time."""
        show_judge_event(lambda line, t: self.show(line, t, "call"), text)

    def transcript(self) -> list[dict[str, Any]]:
        """Every line shown, in time order (the unknown times first): ``{"t", "text", "kind"}``."""
        with self._lock:
            lines = list(self.lines)
        ordered = sorted(enumerate(lines), key=lambda e: (e[1][0] is not None, e[1][0] or 0.0, e[0]))
        return [{"t": t, "text": text, "kind": kind} for _, (t, text, kind) in ordered]

    def close(self, flush: bool = True) -> None:
        """Stop listening; print what is still held (``flush``)."""
        if flush:
            self._ticker = None
            self.release(everything=True)
        if self.node is not None:
            self.node.close(wait=0.0)
            self.node = None


#: Wall seconds the terminal holds lines at most while it has not found the judge's events (:class:`NodeTerminal`).
FIND_JUDGE = 10.0
#: A time in a judge's report line, counted from its t0 (``t=5.10 s``, ``t=0.00-5.00 s``), with the sim clock's
#: reading it may add (`` (sim 5.86 s)``).
_REPORT_TIME = re.compile(r"\bt=(?P<a>-?\d+(?:\.\d+)?)(?:-(?P<b>-?\d+(?:\.\d+)?))? s(?: \(sim -?\d+(?:\.\d+)? s\))?")


def on_sim_clock(line: str, t0_sim: float) -> str:
    """A judge's report line with its times (seconds from its t0) said on the sim clock, as every other line of the
    demo (``true at t=5.10 s`` -> ``true at sim 5.86 s``, ``over t=0.00-5.00 s`` -> ``over sim 0.76-5.76 s``), in
    the figure's own precision. Why: one time base in what a student reads; the judge's JSON keeps its own."""
    def shift(text: str) -> str:
        digits = len(text.partition(".")[2])
        return f"{float(text) + t0_sim:.{digits}f}"

    def repl(m: re.Match[str]) -> str:
        return f"sim {shift(m['a'])}" + (f"-{shift(m['b'])}" if m["b"] else "") + " s"

    return _REPORT_TIME.sub(repl, line)


def shell_text(words: list[str] | tuple[str, ...]) -> str:
    """A command's words as one would type them in a shell: ``-p maneuver:="C"`` (the double quotes keep a string a
    string for rcl's YAML) as ``-p maneuver:=C`` where YAML reads the bare word as the same string, and a word
    shell-quoted only when it needs it."""
    return " ".join(shlex.quote(_bare(word)) for word in words)


#: Words YAML would not read as a string when bare (booleans, nulls, in YAML 1.1 and 1.2 spellings).
_YAML_WORDS = {"true", "false", "yes", "no", "on", "off", "y", "n", "null", "~"}


def _bare(word: str) -> str:
    name, sep, value = word.partition(":=")
    if not sep or not (value.startswith('"') and value.endswith('"')):
        return word
    try:
        text = json.loads(value)
    except ValueError:
        return word
    plain = isinstance(text, str) and re.fullmatch(r"[A-Za-z_][\w./-]*", text) and text.lower() not in _YAML_WORDS
    return f"{name}:={text}" if plain else word
