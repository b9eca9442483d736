"""What every judge node shares: the referee's driver protocol over real DDS, in sim time.

The homework's referee (:mod:`bt_nav.ros.nodes.referee`) and the lab's check-off judge
(:mod:`bt_nav.ros.nodes.checkoff`) drive pure judges with one protocol (``start``, ``step`` -> activate
calls, ``on_activate_result``, ``observe``, ``on_collision``, ``results``, ``report_lines``, ``done``,
``passed``). Everything between that protocol and the wire lives here, once:

1. t0: wait until the robot's SetBool service (parameter ``activate_service``) exists, ``/clock`` runs and
   ground truth arrives (and the simulator listens on ``sim_sync``, for at most ``sync_wait`` wall
   seconds); with ``wait_for_cmd_vel`` also until the robot's first ``cmd_vel`` (its executive ticks on sim
   time, not merely starts up); with ``robot_clock_wait`` also until a node of the robot's has subscribed
   ``/clock`` for ``robot_clock_settle`` wall seconds (its sim clock runs before the first request);
2. a timer on the node clock (sim time) calls ``step`` at the judge's ``rate_hz``; each activate action
   becomes an asynchronous SetBool call, answered through ``on_activate_result`` (a request unanswered for
   ``call_timeout`` wall seconds is sent again, ``call_retries`` times, then counts as failed and the
   schedule retries on a later step; the same request is never out twice at once);
3. ``ground_truth_odom`` feeds ``observe`` (message stamps, from t0 on) and ``collisions`` (the simulator's
   JSON events) ``on_collision``; a judge that wants the commands (``on_command``) gets every ``cmd_vel``;
   its type is Twist or TwistStamped as the robot publishes it on the graph (``cmd_vel_type`` auto), or
   as ``cmd_vel_type``/``cmd_vel_stamped`` say;
4. when the judge is done: the report lines are printed on stdout exactly as the judge makes them, the
   results (with the run's facts) go to ``json`` and the process exits 0 when every check passed, 1 when
   one failed, 2 on timeout or when stopped first.

Events (``~/events``, std_msgs/String, reliable, transient local): each activate call, its reply and a request given
up, as JSON with fields (:func:`bt_nav.mission.snapshot.call_event`: t, call, data, answered, success, message), beside
their log lines. The lab's terminal (:mod:`bt_nav.run.terminal`) shows the calls from these, never from the log.

What the robot node did wrong that no check can see (``audit``, on by default): a
:class:`bt_nav.ros.nodes.audit.GraphAudit` samples the ROS graph about once per wall second and reads
``cmd_vel`` (no subscription to ``scan`` or ``/clock``, no publisher on ``cmd_vel``, the arm service never
offered, a message type or QoS that cannot match ours, NaN/inf commands, a command flood). Its findings are
logged as ``finding: ...`` warnings (stderr, not the report on stdout) and listed under ``findings`` in the
JSON, in every ending: verdict, timeout, or no start; ``finding_kinds`` gives each as data, in the same order
(:mod:`bt_nav.ros.nodes.findings`: its kind, topic and first clause).

No start (``start_wait`` > 0, what ``bt-nav grade --exe`` sets): when only the robot's part of t0 (its
service, its first ``cmd_vel``) is still missing after ``start_wait`` wall seconds, the judge does not wait
out its ``timeout``: it prints ``NOT JUDGED: <what> never appeared within <s> s wall``, writes that as
``not_started`` in the JSON (``passed`` false) and exits 1, a failed verdict in seconds instead of a timeout.

Sim-time faithfulness (``sync``): the node tells the simulator where its clock is on ``sim_sync`` and holds
sim time while a call is in flight (see :mod:`bt_nav.ros.nodes.simulator`), so a busy CPU never makes the
judge late. Without ``sync`` (``bt-nav grade --exe``: the simulator waits for nobody) a busy judge may fall
behind the ground truth queued for it; its report is then judged again once the poses stamped before it are
in (``catch_up``), never on missing poses. A wall-clock ``timeout`` bounds the whole run (``TIMEOUT`` line,
provisional report, exit 2).

Time base: every log line says the node clock's sim time and the schedule's time since t0, ``sim 58.50 s
(t0 + 54.50 s)``: the executive logs sim time too, so the two read side by side. The report lines count
from t0, as the judges make them; the JSON says so (``time_base``) and gives t0's sim time (``t0_sim``)
and wall time (``t0_wall``, epoch s).

Another run in the same ROS domain (a second simulator publishing ground truth) ends the run without a
verdict: a judgement over two robots' poses would report distances nobody drove.

Hosted (``fed``, what ``bt-nav grade --exe`` runs: :mod:`bt_nav.ros.nodes.hosting`): the judge lives in the
simulator's process and the simulator's loop feeds it what it would read over DDS, at the instant it happens: its
clock (each physics step), ground truth, collisions and the people walking, and the schedule's steps on the same
grid as the timer's (t0 + k / ``rate_hz``). No ``/clock``, ``ground_truth_odom`` or ``sim_sync`` subscription, no
process of its own to start, no judge starved of CPU behind a queue of poses; the heartbeats and holds go straight
to the simulator's follower table. What concerns the robot (the arm service, ``cmd_vel``, the graph audit) stays
on DDS, as the robot sees it. Two threads then call the judge (the loop, the executor): one lock serialises them.
"""

from __future__ import annotations

import functools
import json
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from bt_nav_sim.walkers import read_walkers_message
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import String
from std_srvs.srv import SetBool

from bt_nav.judge.referee_core import ANSWERED, UNANSWERED, UNAVAILABLE
from bt_nav.judge.unjudged import FreeMotion
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.resources import written_whole
from bt_nav.mission.snapshot import call_event, snapshot_json
from bt_nav.ros.nodes.audit import GraphAudit, is_ours
from bt_nav.ros.rosutil import EVENTS_QOS, QuietQosEvents, declare_node_parameters

EXIT_PASSED, EXIT_FAILED, EXIT_TIMEOUT = 0, 1, 2
#: After the verdict, wait at most this long (wall) for the final deactivation to be answered.
FINAL_CALL_WAIT = 1.0
#: The report waits until ground truth is taken up to this many sim s before its time, for at most TRUTH_WAIT
#: wall s more (see JudgeNode._caught_up).
TRUTH_LAG, TRUTH_WAIT = 0.1, 5.0
#: ``finding_kinds``' kind of a finding the judge made itself (its results' ``findings``), not the graph audit.
JUDGE_FINDING = "judge"
#: ``cmd_vel_type`` values: the message class of each (auto: whatever the robot publishes).
CMD_TYPES = {"Twist": Twist, "TwistStamped": TwistStamped}

#: The driver's own parameters, shared by every judge node (name -> (default, description)).
DRIVER_PARAMETERS: dict[str, tuple[Any, str]] = {
    "json": ("", "write the results here (JSON); empty: do not write"),
    "timeout": (300.0, "wall-clock seconds after which the run is abandoned (exit 2)"),
    "call_timeout": (1.0, "wall s after which an unanswered activate request is sent again"),
    "call_retries": (3, "resends of an unanswered activate request before it counts as failed"),
    "sync": (True, "send heartbeats and holds on sim_sync so the simulator never outruns the judge"),
    "sync_rate_hz": (20.0, "heartbeat rate on sim_sync, Hz of sim time"),
    "sync_wait": (5.0, "wall s to wait for the simulator to listen on sim_sync before starting anyway"),
    "service_wait": (0.0, "sim s to wait for the activate service before starting anyway (0: wait)"),
    "start_wait": (0.0, "wall s to wait for the robot's service (and first cmd_vel, if waited for) before a "
                        "failed verdict without a start (0: wait until the timeout)"),
    "audit": (True, "watch the graph and cmd_vel for what the robot did wrong that no check sees (findings)"),
    "domain_guard": (False, "end the run without a verdict when a program that is not the run's is on its domain "
                            "(bt-nav grade's runs own theirs; a sim-run or demo welcomes bt-nav arm, view, record)"),
    "audit_message_info": (True, "the audit counts the commands sent (DDS sequence numbers), not those that arrived; "
                                 "off: a hosting simulator may spin rclpy's EventsExecutor, which cannot pass them"),
    "wait_for_cmd_vel": (False, "also wait for the robot's first cmd_vel before t0 (its executive ticks)"),
    "robot_clock_wait": (0.0, "wall s to wait before t0 for a node of the robot's to subscribe /clock and keep it "
                              "robot_clock_settle s (0: do not wait); after that t0 comes anyway"),
    "robot_clock_settle": (0.5, "wall s a robot's /clock subscription must exist before t0 (see robot_clock_wait)"),
    "truth_readers": (0, "t0 also waits until ground_truth_odom has this many subscriptions besides this node's own "
                         "(a recorder that must hold the whole schedule: bt-nav demo's, with a hosted judge)"),
    "cmd_vel_type": ("auto", "cmd_vel message type: auto (as the robot publishes it), Twist or TwistStamped"),
    "cmd_vel_stamped": (False, "cmd_vel is geometry_msgs/TwistStamped (same as cmd_vel_type TwistStamped)"),
}


#: A hosted judge's line to the simulator's follower table: (who, its clock in ns, hold, leave).
SyncSink = Callable[[str, int, bool, bool], None]


def locked(method: Callable[..., Any]) -> Callable[..., Any]:
    """Run ``method`` under the node's lock (a hosted judge is called from the simulator's loop and the executor)."""
    @functools.wraps(method)
    def wrapper(self: JudgeNode, *args: Any, **kwargs: Any) -> Any:
        with self.lock:
            return method(self, *args, **kwargs)

    return wrapper


class JudgeNode(QuietQosEvents, Node):
    """A judge over DDS (see the module docstring); subclasses make the judge and add their interfaces.

    Subclass duties: ``PARAMETERS`` (``DRIVER_PARAMETERS`` plus their own), :meth:`make_judge` (returns the
    judge and its config dataclass) and :meth:`schedule_text`; ``wants_commands`` True to get every
    ``cmd_vel`` through the judge's ``on_command``.

    Args:
        name: the node name. ``wall_start``: monotonic wall time the ``timeout`` counts from (default: now).
        fed: hosted in the simulator's process, which feeds it (see the module docstring; :meth:`feed`).
        cli_args: the node's own ROS arguments (a hosted judge: the process's belong to the simulator).
        context: the rclpy context (None: the default one).
    """

    PARAMETERS: dict[str, tuple[Any, str]] = DRIVER_PARAMETERS
    wants_commands = False
    #: Parameters the assignment asks the judged node to declare (a finding when none does).
    required_parameters: tuple[str, ...] = ()

    def __init__(self, name: str, wall_start: float | None = None, *, fed: bool = False,
                 cli_args: list[str] | None = None, context: Any = None) -> None:
        super().__init__(name, context=context, cli_args=cli_args, use_global_arguments=cli_args is None)
        self.lock = threading.RLock()
        self.fed = fed
        self._fed_ns = 0  # a hosted judge's clock: the simulator's, at its latest step
        self.sync_sink: SyncSink | None = None  # a hosted judge's heartbeats (set by the host)
        self.arm_sink: Callable[[bool], None] | None = None  # a hosted judge's arm answers that said success (host)
        self.start_gate: Callable[[], str | None] | None = None  # what t0 waits for in a hosting simulator (or None)
        # a hosting simulator: whether its /clock publisher has matched every /clock subscription on the graph
        self.clock_matched: Callable[[], bool] | None = None
        p = declare_node_parameters(self, self.PARAMETERS)
        self.judge, self.config = self.make_judge(p)
        self.json_path = str(p["json"])
        self.timeout = float(p["timeout"])
        self.call_timeout = float(p["call_timeout"])
        self.call_retries = int(p["call_retries"])
        self.service_wait = float(p["service_wait"])
        self.start_wait = float(p["start_wait"])
        self.domain_guard = bool(p["domain_guard"])
        self.sync_wait = float(p["sync_wait"])
        self.robot_clock_wait = float(p["robot_clock_wait"])
        self.robot_clock_settle = float(p["robot_clock_settle"])
        self.truth_readers = int(p["truth_readers"])
        self._robot_clock_since: float | None = None  # wall time a robot's /clock subscription was first seen
        self.activate_name = str(p["activate_service"])
        self.call_name = self.activate_name.rstrip("/").rsplit("/", 1)[-1]  # activate, toggle_navigation
        self.wall_start = time.monotonic() if wall_start is None else wall_start
        self._init_state()
        self._create_interfaces(p)
        self.audit = GraphAudit(self, self.activate_name, parameters=self.required_parameters, now=self.now,
                                message_info=bool(p["audit_message_info"])) if bool(p["audit"]) else None
        self.get_logger().info(f"waiting for {self.activate_name} and /clock; {self.schedule_text()}")

    @property
    def needs_message_info(self) -> bool:
        """Whether a callback of this node takes rclpy's MessageInfo (ground truth, the audit's command reader): the
        node's executor must then not be Jazzy's EventsExecutor."""
        return not self.fed or (self.audit is not None and self.audit.message_info)

    # -------------------------------------------------------------- subclass hooks
    def make_judge(self, p: dict[str, Any]) -> tuple[Any, Any]:
        """(the judge, its config dataclass) from the declared parameter values ``p``."""
        raise NotImplementedError

    def schedule_text(self) -> str:
        """The start-up log line's account of the schedule."""
        raise NotImplementedError

    # -------------------------------------------------------------- set-up
    def _init_state(self) -> None:
        """Progress of the run: start, pending calls, verdict."""
        self._truth_seen = False
        self.started = False
        self.t0_wall: float | None = None  # the wall clock (epoch s) at t0: a benchmark splits a run's wall time there
        self._first_clock: float | None = None
        self._clock_wall: float | None = None  # wall time of the first /clock (the simulator may start last)
        self._waiting_line_at = 0.0  # wall time the next "waiting for" line may be logged
        self._step_timer: Any = None
        self._next_step_ns: int | None = None  # a hosted judge's next step (the timer's grid)
        self._pending: dict[bool, tuple[Any, float, int]] = {}  # data -> (future, sent at: wall s, attempt)
        self._finish_by: float | None = None  # wall deadline for the final call, once done
        self.finished = False
        self.exit_code = EXIT_TIMEOUT  # until a verdict: stopped or timed out
        self.timed_out = False
        self.calls = 0
        self._truth_seq: int | None = None  # publication sequence number of the last ground truth
        self._truth_t: float | None = None  # stamp of the last ground truth taken (sim s)
        self.foreign: str | None = None  # why the judged messages cannot all be this run's
        self.not_started: str | None = None  # why the robot was never judged (start_wait)
        self.free = FreeMotion()  # what the robot did before t0: the account of a run never judged
        self.findings: list[str] = []  # the audit's, at the end
        self.finding_kinds: list[dict[str, Any]] = []  # the same findings as data (bt_nav.ros.nodes.findings)
        self._cmd_sub: Any = None

    def _create_interfaces(self, p: dict[str, Any]) -> None:
        """The activate client, the inputs, and the sim_sync heartbeat if ``sync`` (hosted: the world's inputs and
        the heartbeat come from the host)."""
        self.activate_client = self.create_client(SetBool, self.activate_name)
        self.events_pub = self.create_publisher(String, "~/events", EVENTS_QOS)
        self.wait_for_cmd_vel = bool(p["wait_for_cmd_vel"])
        self._cmd_vel_seen = not self.wait_for_cmd_vel
        self._cmd_type = "TwistStamped" if bool(p["cmd_vel_stamped"]) else str(p["cmd_vel_type"])
        if self._cmd_type not in (*CMD_TYPES, "auto"):
            raise ValueError(f"cmd_vel_type must be auto, Twist or TwistStamped, got {self._cmd_type!r}")
        self._subscribe_cmd_vel()
        # Its name on sim_sync: several robots' judges (one per namespace) must not be one follower.
        self.who = self.get_name() if self.get_namespace() == "/" else self.get_fully_qualified_name()
        self.synced = bool(p["sync"])
        self.sync_pub = None
        if self.fed:
            return
        self.create_subscription(Odometry, "ground_truth_odom", self._on_truth,  # (msg, info): see _own_truth
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.create_subscription(String, "collisions", self._on_collision, QoSProfile(depth=50))
        if hasattr(self.judge, "on_walkers"):  # the people walking, for a judge that casts the robot's view
            self.create_subscription(String, "walkers", self._on_walkers,
                                     QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.sync_pub = self.create_publisher(String, "sim_sync", QoSProfile(depth=50)) if self.synced else None
        if self.sync_pub is not None:
            self.create_timer(1.0 / max(1e-3, float(p["sync_rate_hz"])), self._heartbeat)

    def _subscribe_cmd_vel(self) -> None:
        """Subscribe ``cmd_vel`` once its type is known (auto: from the robot's publisher on the graph)."""
        if self._cmd_sub is not None or (self._cmd_vel_seen and not self.wants_commands) or self._cmd_type == "none":
            return
        kind = self._cmd_type
        if kind == "auto":
            types = {i.topic_type.rsplit("/", 1)[-1]
                     for i in self.get_publishers_info_by_topic(self.resolve_topic_name("cmd_vel"))}
            kind = next((k for k in CMD_TYPES if k in types), "")
            if not kind:
                return  # no publisher yet: asked again at the next poll
        stamped = kind == "TwistStamped"
        try:
            self._cmd_sub = self.create_subscription(CMD_TYPES[kind], "cmd_vel",
                                                     lambda m: self._on_cmd(m.twist if stamped else m), 10)
        except Exception as exc:  # hosted: the simulator reads cmd_vel as the other type, and DDS refuses a second
            self._cmd_type = "none"  # the robot hears none of these commands either; the audit names the type
            self._cmd_vel_seen = True
            self.get_logger().warning(f"cannot read cmd_vel as {kind} beside the simulator's reader ({exc}): "
                                      "judging without the robot's commands, which its base does not hear either")

    @locked
    def _on_cmd(self, twist: Any) -> None:
        self._cmd_vel_seen = True
        if self.wants_commands and self.started:
            self.judge.on_command(self.now(), twist.linear.x, twist.angular.z)

    # -------------------------------------------------------------- time
    def now(self) -> float:
        """Node clock seconds (sim time with use_sim_time); a hosted judge's: the simulator's latest step."""
        if self.fed:
            return self._fed_ns * 1e-9
        return self.get_clock().now().nanoseconds * 1e-9

    def stamp(self, now: float | None = None) -> str:
        """``sim 58.50 s (t0 + 54.50 s)``: both time bases of a log line (sim clock, schedule)."""
        now = self.now() if now is None else now
        t0 = self.judge.t0
        return f"sim {now:.2f} s" + (f" (t0 + {now - t0:.2f} s)" if t0 is not None else "")

    # -------------------------------------------------------------- main-loop duties (runner: Finishing)
    @locked
    def poll(self) -> bool:
        """Called between executor spins: start, wall timeout, finishing; True once finished."""
        if self.finished:
            return True
        if time.monotonic() - self.wall_start > self.timeout or self.foreign is not None:
            self._give_up()
            return True
        if self.audit is not None:
            self.audit.sample()
            shared = self.audit.guard.finding(os.environ.get("ROS_DOMAIN_ID", "0")) if self.domain_guard else None
            if shared is not None and self.foreign is None:
                self.foreign = shared  # ends the run without a verdict (next poll): its launcher moves it
        self._subscribe_cmd_vel()
        self._expire_calls()
        if not self.started:
            self._try_start()
        elif self._finish_by is not None and (not self._pending or time.monotonic() > self._finish_by) \
                and self._caught_up():
            self._conclude()
        return self.finished

    def _caught_up(self) -> bool:
        """Ground truth up to the report time has been taken (or ``TRUTH_WAIT`` more wall seconds passed).

        Without ``sync`` (``bt-nav grade --exe``: the simulator waits for nobody) a busy judge falls behind the
        poses queued for it, while its clock (latest /clock only) does not: the report is made on time, and
        judged again (:meth:`catch_up`) on the poses stamped before it, once they are in. Otherwise a window
        at the end could hold none of them and a robot standing still fails "static".
        """
        report = self.judge.report_time
        return (report is None or self._truth_t is None or self._truth_t >= report - TRUTH_LAG
                or time.monotonic() > self._finish_by + TRUTH_WAIT)

    def close(self) -> None:
        """Stopped before the verdict (a signal, a shutdown): say so and let the simulator go on."""
        if self.finished:
            return
        self.finished = True
        self.leave()
        print(f"{self.get_name()} stopped before its verdict", file=sys.stderr)

    def _missing(self, now: float) -> list[str]:
        """What t0 still waits for (empty: start now)."""
        missing = []
        if now <= 0.0:
            missing.append("/clock")
        if not self.activate_client.service_is_ready():
            missing.append(self.activate_name)
        if not self._cmd_vel_seen:
            missing.append("the first cmd_vel")
        if not self._truth_seen:
            missing.append("ground_truth_odom")
        if self.sync_pub is not None and self.sync_pub.get_subscription_count() == 0 \
                and time.monotonic() - self.wall_start < self.sync_wait:
            missing.append("a simulator listening on sim_sync")
        if not self._robot_clock_ready():
            missing.append("the robot's /clock subscription")
        gate = self.start_gate() if self.start_gate is not None else None
        if gate:
            missing.append(gate)
        if self.truth_readers > 0 and \
                self.count_subscribers("ground_truth_odom") - (0 if self.fed else 1) < self.truth_readers:
            missing.append("a recorder of ground_truth_odom")
        return missing

    def _robot_clock_ready(self) -> bool:
        """With ``robot_clock_wait``: a node that is not ours has subscribed /clock at least
        ``robot_clock_settle`` wall s ago, or the wait is over.

        The settling counts from the later of the subscription and the first ``/clock`` (a node started before the
        simulator has subscribed before there was anything to match). Half a wall second: every process bt_nav starts
        announces itself every 0.25 s (:data:`bt_nav.ros.supervise.DISCOVERY_PROFILE`), so the simulator has matched
        the subscription by then, and the first request (5 sim s after t0: one wall second at 5x) comes 1.5 s after
        it. Why wait at all: a node on sim time refuses or mistimes what happens before its first /clock message (an
        arm request at sim 5 s reached a node whose clock had not started: measured under load at 5x real time,
        where discovery takes a wall second, i.e. 5 sim s). A node on wall time never subscribes; it is started
        anyway after the wait (and the graph audit says so)."""
        if self.robot_clock_wait <= 0.0:
            return True
        now = time.monotonic()
        if self._robot_clock_since is None:
            if any(not is_ours(info.node_name) for info in self.get_subscriptions_info_by_topic("/clock")):
                self._robot_clock_since = now
        if self._robot_clock_since is not None and self._clock_wall is not None:
            if now - max(self._robot_clock_since, self._clock_wall) >= self.robot_clock_settle:
                return True
            if self.clock_matched is not None and self.clock_matched():
                return True  # hosted: the simulator's own publisher says it reaches the subscription, no need to settle
        return now - self.wall_start >= self.robot_clock_wait

    def _try_start(self) -> None:
        now = self.now()
        if now > 0.0 and self._first_clock is None:
            self._first_clock, self._clock_wall = now, time.monotonic()
        missing = self._missing(now)
        robot = {self.activate_name, "the first cmd_vel"}
        waited = now - self._first_clock if self._first_clock is not None else 0.0
        if missing and self.service_wait > 0.0 and waited >= self.service_wait and set(missing) <= robot:
            self.get_logger().warning(f"{' and '.join(missing)} did not appear within {self.service_wait:g} s: "
                                      "starting anyway")
            missing = []
        if missing and 0.0 < self.start_wait <= time.monotonic() - self.wall_start and set(missing) <= robot:
            self._give_no_start(missing)
            return
        if missing:
            # Judging needs the ground truth from the start and a simulator that waits for this node;
            # discovery between processes can take seconds on a loaded machine.
            if time.monotonic() >= self._waiting_line_at:  # rclpy's own throttle inspects the stack at every call
                self._waiting_line_at = time.monotonic() + 2.0
                self.get_logger().info(f"waiting for {', '.join(missing)}")
            return
        self.started = True
        self.t0_wall = time.time()
        self.judge.start(now)
        if self._cmd_sub is not None and not self.wants_commands:
            self.destroy_subscription(self._cmd_sub)
            self._cmd_sub = None
        self.get_logger().info(f"t0 = sim {now:.2f} s: {self.activate_name} is available")
        if self.fed:  # the timer's grid, stepped by the host (feed)
            self._next_step_ns = self._fed_ns + self._step_period_ns()
        else:
            self._step_timer = self.create_timer(1.0 / self.config.rate_hz, self._on_step)

    def _step_period_ns(self) -> int:
        return int(round(1e9 / self.config.rate_hz))

    @locked
    def _on_step(self) -> None:
        if self.finished or self._finish_by is not None:
            return
        now = self.now()
        for action in self.judge.step(now):
            self._call(bool(action.data), now)
        if self.judge.done:
            self._finish_by = time.monotonic() + FINAL_CALL_WAIT
            if self._step_timer is not None:
                self._step_timer.cancel()

    # -------------------------------------------------------------- activate calls
    def _call(self, data: bool, now: float) -> None:
        if data in self._pending:
            return  # the previous request with the same data is still out
        if not self.activate_client.service_is_ready():
            self.get_logger().warning(f"{self.activate_name} unavailable: {self.call_name}({data}) failed",
                                      throttle_duration_sec=5.0)
            self.judge.on_activate_result(now, data, False, UNAVAILABLE)
            return
        self.get_logger().info(f"{self.stamp(now)}: {self.call_name}({str(data).lower()}) sent")
        self._tell("call", now, data)
        self._send(data, attempt=1)

    def _tell(self, kind: str, now: float, data: bool, **fields: Any) -> None:
        """One event about an activate call on ``~/events`` (:func:`bt_nav.mission.snapshot.call_event`): what
        the lab's terminal shows as ``ros2 service call`` prints it, without reading this node's log."""
        self.events_pub.publish(String(data=snapshot_json(call_event(kind, now, self.call_name, data, **fields))))

    def _send(self, data: bool, attempt: int) -> None:
        """One request; sim time is held (heartbeat) before it leaves, so its latency costs no sim time."""
        self.calls += 1
        self._pending[data] = (None, time.monotonic(), attempt)
        self._heartbeat()
        future = self.activate_client.call_async(SetBool.Request(data=data))
        self._pending[data] = (future, time.monotonic(), attempt)
        future.add_done_callback(lambda f, d=data: self._on_activate_done(f, d))

    @locked
    def _on_activate_done(self, future: Any, data: bool) -> None:
        entry = self._pending.get(data)
        if entry is None or entry[0] is not future:
            return  # expired earlier
        del self._pending[data]
        self._heartbeat()
        now = self.now()
        try:
            response = future.result()
        except Exception as exc:
            self.get_logger().warning(f"{self.call_name}({data}) raised {exc!r}")
            response = None
        success = bool(response is not None and response.success)
        message = "" if response is None else str(response.message)
        self.get_logger().info(f"{self.stamp(now)}: {self.call_name}({str(data).lower()}) -> "
                               f"{'success' if success else 'failure'}: {message}")
        self._tell("reply", now, data, answered=response is not None, success=success, message=message)
        if success and self.arm_sink is not None:
            self.arm_sink(data)
        self.judge.on_activate_result(now, data, success, ANSWERED if response is not None else UNANSWERED, message)

    def _expire_calls(self) -> None:
        """Resend a request unanswered for ``call_timeout`` wall seconds (sim time stays held), up to
        ``call_retries`` times; then report the failure (the schedule retries on a later step).

        A lost request is real on DDS: ``service_is_ready`` only says the client sees the server, not
        that the server already sees the client, so the very first request can vanish.
        """
        for data, (future, sent, attempt) in list(self._pending.items()):
            if time.monotonic() - sent <= self.call_timeout:
                continue
            del self._pending[data]
            if future is not None:
                self.activate_client.remove_pending_request(future)
            if attempt <= self.call_retries:
                self.get_logger().warning(f"{self.call_name}({data}) unanswered for {self.call_timeout:g} s wall: "
                                          f"sending it again (attempt {attempt + 1})")
                self._send(data, attempt + 1)
                continue
            self._heartbeat()
            self.get_logger().warning(f"{self.call_name}({data}) unanswered after {attempt} attempts")
            self._tell("unanswered", self.now(), data, attempts=attempt)
            self.judge.on_activate_result(self.now(), data, False, UNANSWERED)

    def _heartbeat(self) -> None:
        """Tell the simulator where this node's clock is and whether a call is in flight."""
        if self.finished:
            return
        if self.fed:
            if self.synced and self.sync_sink is not None:
                self.sync_sink(self.who, self._fed_ns, bool(self._pending), False)
            return
        if self.sync_pub is None:
            return
        payload = {"who": self.who, "t": round(self.now(), 9), "hold": bool(self._pending)}
        self.sync_pub.publish(String(data=json.dumps(payload)))

    def leave(self) -> None:
        """Tell the simulator to stop waiting for this node (after the verdict, or when stopping)."""
        if self.fed and self.synced and self.sync_sink is not None:
            self.sync_sink(self.who, self._fed_ns, False, True)
        if self.sync_pub is None:
            return
        self.sync_pub.publish(String(data=json.dumps({"who": self.who, "leave": True})))
        try:  # the process exits right after this: make sure the simulator got it
            self.sync_pub.wait_for_all_acked(Duration(nanoseconds=300_000_000))
        except Exception as exc:  # informational only: the simulator times the follower out anyway
            self.get_logger().debug(f"sim_sync goodbye not acknowledged: {exc!r}")

    # -------------------------------------------------------------- inputs
    def _own_truth(self, info: Any) -> bool:
        """Ground truth must come from one simulator: a second publisher in this ROS domain (another
        run sharing ROS_DOMAIN_ID) interleaves its robot's poses, and summing two robots' poses reports
        distances nobody drove. One publisher's sequence numbers only grow; a step back is someone else."""
        seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
        if seq is None or self.foreign is not None:
            return self.foreign is None
        if self._truth_seq is not None and seq <= self._truth_seq:
            names = sorted(f"{i.node_namespace.rstrip('/')}/{i.node_name}"
                           for i in self.get_publishers_info_by_topic("ground_truth_odom"))
            self.foreign = (f"ground_truth_odom comes from more than one simulator ({', '.join(names) or 'unknown'}):"
                            " another run shares this ROS_DOMAIN_ID")
            return False
        self._truth_seq = seq
        return True

    @locked
    def _on_truth(self, msg: Any, info: Any = None) -> None:
        if not self._own_truth(info):
            return
        pose = msg.pose.pose
        q = pose.orientation
        self._take_truth(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, pose.position.x, pose.position.y,
                         yaw_from_quaternion(q.x, q.y, q.z, q.w))

    def _take_truth(self, t: float, x: float, y: float, yaw: float) -> None:
        """One ground-truth pose (before t0: ground truth runs, and what the robot does goes to ``free``)."""
        if not self.started:
            self._truth_seen = True
            self.free.observe(t, x, y, yaw)
            return
        self._truth_t = t
        if self.judge.t0 is not None and t < self.judge.t0:
            return
        self.judge.observe(t, x, y, yaw)

    @locked
    def _on_collision(self, msg: Any) -> None:
        try:
            event = json.loads(msg.data)
            t, x, y = float(event["t"]), float(event["x"]), float(event["y"])
        except (ValueError, KeyError, TypeError) as exc:
            self.get_logger().warning(f"unreadable collision event {msg.data!r}: {exc}")
            return
        (self.judge if self.started else self.free).on_collision(t, x, y)

    @locked
    def _on_walkers(self, msg: Any) -> None:
        try:
            t, circles = read_walkers_message(msg.data)
        except ValueError as exc:
            self.get_logger().warning(f"unreadable walkers sample: {exc}")
            return
        self.judge.on_walkers(t, circles)

    # -------------------------------------------------------------- hosted: fed by the simulator's loop
    @locked
    def feed(self, t_ns: int, truth: tuple[float, float, float] | None = None,
             collision: tuple[float, float] | None = None, walkers: Any = None) -> None:
        """One physics step of the host at sim time ``t_ns``: what it published then, in the order it publishes it
        (a collision, the people walking, the ground-truth pose ``(x, y, yaw)``), then the schedule's step when the
        timer's grid is due. Called from the simulator's loop thread."""
        self._fed_ns = t_ns
        t = t_ns * 1e-9
        if collision is not None:
            (self.judge if self.started else self.free).on_collision(t, *collision)
        if walkers is not None and hasattr(self.judge, "on_walkers"):
            self.judge.on_walkers(t, walkers)
        if truth is not None:
            self._take_truth(t, *truth)
        if self._next_step_ns is not None and t_ns >= self._next_step_ns:
            self._next_step_ns += self._step_period_ns()
            self._on_step()
            if self._finish_by is not None:
                self._next_step_ns = None
        if self.synced and self.started:  # its clock is the host's: it never lags, it only holds for its calls
            self._heartbeat()

    # -------------------------------------------------------------- the end
    def _conclude(self) -> None:
        self.judge.catch_up()
        self.leave()
        self.finished = True
        self.exit_code = EXIT_PASSED if self.judge.passed else EXIT_FAILED
        lines = self.judge.report_lines()
        for line in lines:
            print(line)
        sys.stdout.flush()
        self._write_json(lines)

    def _give_no_start(self, missing: list[str]) -> None:
        """The robot's part of t0 never came within ``start_wait``: a failed verdict now, not a timeout later."""
        self.leave()
        self.finished = True
        self.exit_code = EXIT_FAILED
        what = [f"the service {self.resolve_service_name(m)}" if m == self.activate_name else m for m in missing]
        hint = self.audit.service_hint() if self.audit is not None and self.activate_name in missing else ""
        self.not_started = f"{' and '.join(what)} never appeared within {self.start_wait:g} s wall{hint}"
        print(f"NOT JUDGED: {self.not_started}")
        lines = self._unjudged_lines()
        for line in lines:
            print(line)
        sys.stdout.flush()
        self._write_json(lines, exclude=("service",) if self.activate_name in missing else ())

    def _unjudged_checks(self) -> list[dict[str, Any]]:
        """The checks of a run whose schedule never began: the service's absence and what the robot did meanwhile
        (from ground truth), never the schedule's checks over no data (they would pass vacuously)."""
        why = self.not_started or "the run ended before t0"
        return self.free.checks(self.resolve_service_name(self.activate_name), why)

    def _unjudged_lines(self) -> list[str]:
        return [*(f"{c['name']} ({c['detail']}): FAILED" for c in self._unjudged_checks()), "overall: FAILED"]

    def _give_up(self) -> None:
        self.leave()
        self.finished = True
        self.timed_out = self.foreign is None
        self.exit_code = EXIT_TIMEOUT
        state = "before t0 (the activate service or /clock never came)" if not self.started else \
            f"at {self.stamp()} of the schedule"
        if self.foreign is not None:  # nothing measured can be trusted: no figures at all
            print(f"NO VERDICT: {self.foreign}; set a ROS_DOMAIN_ID of its own for each run")
            lines = []
        else:
            print(f"TIMEOUT: no verdict after {self.timeout:g} s wall, {state}; provisional report:")
            lines = self.judge.report_lines() if self.started else self._unjudged_lines()
        for line in lines:
            print(line)
        sys.stdout.flush()
        self._write_json(lines)

    def _write_json(self, lines: list[str], exclude: tuple[str, ...] = ()) -> None:
        """The results, the run's facts and the audit's findings (logged here too); ``exclude``: findings the
        ending already states."""
        records = self.audit.finding_records(exclude) if self.audit is not None else []
        # the judge's own first (the check-off's maneuvers back to back), then the audit's
        judged = [str(f) for f in self.judge.results().get("findings") or []] if self.started else []
        self.findings = [*judged, *(found.text for found in records)]
        # each with its kind where the judge gives one (the check-off's: bt_nav.judge.findings), else the judge's
        kinds = (self.judge.results().get("finding_kinds") or []) if self.started else []
        self.finding_kinds = [*(kinds if len(kinds) == len(judged) else
                                ({"kind": JUDGE_FINDING, "topic": None, "clause": f} for f in judged)),
                              *(found.record() for found in records)]
        for finding in self.findings:
            self.get_logger().warning(f"finding: {finding}")
        if not self.json_path:
            return
        results = dict(self.judge.results())
        if not self.started:  # no schedule ran: the figures are the robot's own, from ground truth
            results.update(self.free.results(), checks=self._unjudged_checks(), passed=False,
                           unjudged=self.free.summary())
        missing = self.audit.parameter_findings() if self.audit is not None else []
        if self.audit is not None and self.required_parameters:  # `ros2 param list` and the values read back
            results["parameters"] = self.audit.parameter_report()
        if missing:  # the check-off's `ros2 param list` step failed
            results["checks"] = [*results["checks"], {
                "name": "parameters declared", "passed": False, "value": None,
                "required": ", ".join(self.required_parameters), "detail": "; ".join(missing), "reason": missing[0]}]
            results["passed"] = False
            for line in missing:
                print(f"parameters declared ({line}): FAILED")
        if not results["passed"] and self.exit_code == EXIT_PASSED:
            self.exit_code = EXIT_FAILED  # the process's status says what the file says
        results.update({
            "exit_code": self.exit_code,
            "findings": self.findings,
            "finding_kinds": self.finding_kinds,
            "not_started": self.not_started,
            "report_lines": lines,
            "timed_out": self.timed_out,
            "foreign": self.foreign,
            "config": asdict(self.config),
            "wall_time_s": round(time.monotonic() - self.wall_start, 3),
            "activate_calls": self.calls,
            "t0_sim": self.judge.t0,
            "t0_wall": self.t0_wall,
            "time_base": "times and report lines: seconds from t0 (t0_sim: t0 on the sim clock, t0_wall: on the "
                         "wall clock, epoch s); log lines: sim clock and t0 + seconds",
        })
        path = Path(self.json_path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with written_whole(path) as stream:  # whole or absent: a host's reader polls for it
                stream.write(json.dumps(results, indent=2) + "\n")
        except OSError as exc:
            self.get_logger().error(f"could not write {path}: {exc}")
