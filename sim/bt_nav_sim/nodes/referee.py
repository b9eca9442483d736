"""``bt_nav_referee``: the homework referee (:mod:`bt_nav_sim.referee_core`) over real DDS, in sim time.

Run: ``bt-nav referee [--json PATH] [--timeout S] [--time-scale X] [--ros-args ...]`` or
``ros2 run bt_nav referee``.

Sequence:

1. wait until the robot's activate service (``/reactive_control/activate``, parameter
   ``activate_service``) exists, ``/clock`` runs and ground truth arrives (and the simulator listens
   on ``sim_sync``, for at most ``sync_wait`` wall seconds); that instant is t0 (sim time)
   (with ``wait_for_cmd_vel``, which the bringup's ``eval`` profile sets, also until the robot's first
   ``cmd_vel``: its executive is ticking on sim time, not merely starting up);
2. a timer on the node clock (sim time, ``use_sim_time`` is true by default) calls
   :meth:`Referee.step` at ``rate_hz``; each :class:`Activate` it returns becomes an asynchronous
   SetBool call whose answer goes back through :meth:`Referee.on_activate_result` (a request
   unanswered for ``call_timeout`` wall seconds is sent again, ``call_retries`` times, then counts as
   failed and the schedule retries on a later step; the same request is never out twice at once);
3. the Trigger server ``/reactive_control/evaluate_mission`` answers with :meth:`Referee.on_evaluate`;
   ``ground_truth_odom`` feeds :meth:`Referee.observe` (message stamps, from t0 on) and ``collisions``
   (the simulator's JSON events) :meth:`Referee.on_collision`;
4. when the referee is done: the final deactivation is sent (and briefly waited for), the report lines
   are printed on stdout exactly as the referee makes them, the results go to ``--json`` and the
   process exits 0 when every check passed, 1 when one failed.

Sim-time faithfulness (``sync``, on by default): the node tells the simulator (topic ``sim_sync``,
see :mod:`bt_nav_sim.nodes.simulator`) where its clock is, 20 times per sim second, and holds sim time while an
activate call is in flight. So neither a busy CPU nor a fast simulation can make the referee late
or turn a service round trip into seconds of sim time; at 1x this changes nothing measurable.

A wall-clock ``timeout`` bounds the whole run, so a broken simulation cannot hang a test or a CI job:
it prints a ``TIMEOUT`` line and the provisional report and exits 2.

Namespaces: every name but ``/clock`` is relative, so ``--ros-args -r __ns:=/robot1`` with relative
service names (``-p activate_service:=reactive_control/activate``, ``-p
evaluate_service:=reactive_control/evaluate_mission``, what :func:`bt_nav.ros.bringup.nodes` sets for a
namespace) judges that robot alone: its ground truth, collisions and services, on its own timeline; its
``sim_sync`` name is then its fully qualified node name, so one simulator can follow several referees.

Timings can be shortened for tests: ``time_scale`` multiplies every duration of the schedule
(``static_before`` ... ``settle_after_call``, not the sampling ``window``) after the individual
parameters are applied.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import time
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from std_msgs.msg import String
from std_srvs.srv import SetBool, Trigger

from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.ros.rosutil import coerce_int_overrides
from bt_nav.ros.supervise import StopRequest
from bt_nav_sim.nodes.simulator import param_args, split_ros_args
from bt_nav_sim.referee_core import Activate, Referee, RefereeConfig, scaled

NODE_NAME = "bt_nav_referee"
EXIT_PASSED, EXIT_FAILED, EXIT_TIMEOUT = 0, 1, 2

#: After the verdict, wait at most this long (wall) for the final deactivation to be answered.
FINAL_CALL_WAIT = 1.0


_DEFAULTS = RefereeConfig()


class RefereeNode(Node):
    """The referee node (see the module docstring); rclpy must be initialised.

    Args:
        wall_start: monotonic wall time the ``timeout`` counts from (default: now).
    """

    PARAMETERS: dict[str, tuple[Any, str]] = {
        "json": ("", "write the results here (JSON); empty: do not write"),
        "timeout": (300.0, "wall-clock seconds after which the run is abandoned (exit 2)"),
        "time_scale": (1.0, "multiplies every duration of the schedule (tests use < 1)"),
        "activate_service": ("/reactive_control/activate", "the robot's SetBool activate service"),
        "evaluate_service": ("/reactive_control/evaluate_mission", "the Trigger service served here"),
        "call_timeout": (1.0, "wall s after which an unanswered activate request is sent again"),
        "call_retries": (3, "resends of an unanswered activate request before it counts as failed"),
        "sync": (True, "send heartbeats and holds on sim_sync so the simulator never outruns the referee"),
        "sync_rate_hz": (20.0, "heartbeat rate on sim_sync, Hz of sim time"),
        "sync_wait": (5.0, "wall s to wait for the simulator to listen on sim_sync before starting anyway"),
        "service_wait": (0.0, "sim s to wait for the activate service before starting anyway (0: wait)"),
        "wait_for_cmd_vel": (False, "also wait for the robot's first cmd_vel before t0 (its executive ticks)"),
        "cmd_vel_stamped": (False, "cmd_vel is geometry_msgs/TwistStamped (for wait_for_cmd_vel)"),
        **{f.name: (float(getattr(_DEFAULTS, f.name)), f"RefereeConfig.{f.name}") for f in fields(_DEFAULTS)},
    }

    def __init__(self, wall_start: float | None = None) -> None:
        super().__init__(NODE_NAME)
        p = self._declare_parameters()
        config = RefereeConfig(**{f.name: float(p[f.name]) for f in fields(_DEFAULTS)})
        self.config = scaled(config, float(p["time_scale"]))
        self.referee = Referee(self.config)
        self.json_path = str(p["json"])
        self.timeout = float(p["timeout"])
        self.call_timeout = float(p["call_timeout"])
        self.call_retries = int(p["call_retries"])
        self.service_wait = float(p["service_wait"])
        self.activate_name = str(p["activate_service"])
        self._create_interfaces(p)
        self.sync_wait = float(p["sync_wait"])
        self.wall_start = time.monotonic() if wall_start is None else wall_start
        self._init_state()
        self.get_logger().info(
            f"waiting for {self.activate_name} and /clock; schedule: activate at {self.config.static_before:g} s, "
            f"deactivate at {self.config.deactivate_at:g} s, reactivate at {self.config.reactivate_at:g} s, "
            f"evaluation by {self.config.evaluation_deadline:g} s (sim time from t0)")

    # -------------------------------------------------------------- set-up
    def _declare_parameters(self) -> dict[str, Any]:
        """Declare every parameter of :attr:`PARAMETERS`; returns their values by name."""
        coerce_int_overrides(self, {name: default for name, (default, _) in self.PARAMETERS.items()})
        return {name: self.declare_parameter(name, default, ParameterDescriptor(description=text)).value
                for name, (default, text) in self.PARAMETERS.items()}

    def _create_interfaces(self, p: dict[str, Any]) -> None:
        """The activate client, the evaluate server, the inputs, and the sim_sync heartbeat if ``sync``."""
        self.activate_client = self.create_client(SetBool, self.activate_name)
        self.create_service(Trigger, str(p["evaluate_service"]), self._on_evaluate)
        self.create_subscription(Odometry, "ground_truth_odom", self._on_truth,  # (msg, info): see _own_truth
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.create_subscription(String, "collisions", self._on_collision, QoSProfile(depth=50))
        self._cmd_vel_seen = not bool(p["wait_for_cmd_vel"])
        self._cmd_sub = None
        if not self._cmd_vel_seen:
            self._cmd_sub = self.create_subscription(TwistStamped if p["cmd_vel_stamped"] else Twist, "cmd_vel",
                                                     self._on_first_cmd, 10)
        # Its name on sim_sync: several robots' referees (one per namespace) must not be one follower.
        self.who = NODE_NAME if self.get_namespace() == "/" else self.get_fully_qualified_name()
        self.sync = bool(p["sync"])
        self.sync_pub = self.create_publisher(String, "sim_sync", QoSProfile(depth=50)) if self.sync else None
        if self.sync_pub is not None:
            self.create_timer(1.0 / max(1e-3, float(p["sync_rate_hz"])), self._heartbeat)

    def _init_state(self) -> None:
        """Progress of the run: start, pending calls, verdict."""
        self._truth_seen = False
        self.started = False
        self._first_clock: float | None = None
        self._step_timer: Any = None
        self._pending: dict[bool, tuple[Any, float, int]] = {}  # data -> (future, sent at: wall s, attempt)
        self._finish_by: float | None = None  # wall deadline for the final call, once done
        self.finished = False
        self.exit_code = EXIT_FAILED
        self.timed_out = False
        self.calls = 0
        self._truth_seq: int | None = None  # publication sequence number of the last ground truth
        self.foreign: str | None = None  # why the judged messages cannot all be this run's

    # -------------------------------------------------------------- time
    def now(self) -> float:
        """Node clock seconds (sim time with use_sim_time)."""
        return self.get_clock().now().nanoseconds * 1e-9

    # -------------------------------------------------------------- main-loop duties
    def poll(self) -> None:
        """Called between executor spins: start, wall timeout, finishing."""
        if self.finished:
            return
        if time.monotonic() - self.wall_start > self.timeout or self.foreign is not None:
            self._give_up()
            return
        self._expire_calls()
        if not self.started:
            self._try_start()
        elif self._finish_by is not None and (not self._pending or time.monotonic() > self._finish_by):
            self._conclude()

    def _on_first_cmd(self, msg: Any) -> None:
        """The robot's executive is ticking on sim time: it may be judged from now on."""
        self._cmd_vel_seen = True

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
        return missing

    def _try_start(self) -> None:
        now = self.now()
        if now > 0.0 and self._first_clock is None:
            self._first_clock = now
        missing = self._missing(now)
        robot = {self.activate_name, "the first cmd_vel"}
        waited = now - self._first_clock if self._first_clock is not None else 0.0
        if missing and self.service_wait > 0.0 and waited >= self.service_wait and set(missing) <= robot:
            self.get_logger().warning(f"{' and '.join(missing)} did not appear within {self.service_wait:g} s: "
                                      "starting anyway")
            missing = []
        if missing:
            # Judging needs the ground truth from the start and a simulator that waits for this node;
            # discovery between processes can take seconds on a loaded machine.
            self.get_logger().info(f"waiting for {', '.join(missing)}", throttle_duration_sec=2.0)
            return
        self.started = True
        self.referee.start(now)
        if self._cmd_sub is not None:
            self.destroy_subscription(self._cmd_sub)
            self._cmd_sub = None
        self.get_logger().info(f"t0 = {now:.2f} s (sim): {self.activate_name} is available")
        self._step_timer = self.create_timer(1.0 / self.config.rate_hz, self._on_step)

    def _on_step(self) -> None:
        if self.finished or self._finish_by is not None:
            return
        now = self.now()
        for action in self.referee.step(now):
            self._call(action, now)
        if self.referee.done:
            self._finish_by = time.monotonic() + FINAL_CALL_WAIT
            if self._step_timer is not None:
                self._step_timer.cancel()

    # -------------------------------------------------------------- activate calls
    def _call(self, action: Activate, now: float) -> None:
        data = bool(action.data)
        if data in self._pending:
            return  # the previous request with the same data is still out
        if not self.activate_client.service_is_ready():
            self.get_logger().warning(f"{self.activate_name} unavailable: activate({data}) failed",
                                      throttle_duration_sec=5.0)
            self.referee.on_activate_result(now, data, False)
            return
        self.get_logger().info(f"t={now - (self.referee.t0 or 0.0):.2f} s: activate({str(data).lower()})")
        self._send(data, attempt=1)

    def _send(self, data: bool, attempt: int) -> None:
        """One request; sim time is held (heartbeat) before it leaves, so its latency costs no sim time."""
        self.calls += 1
        self._pending[data] = (None, time.monotonic(), attempt)
        self._heartbeat()
        future = self.activate_client.call_async(SetBool.Request(data=data))
        self._pending[data] = (future, time.monotonic(), attempt)
        future.add_done_callback(lambda f, d=data: self._on_activate_done(f, d))

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
            self.get_logger().warning(f"activate({data}) raised {exc!r}")
            response = None
        success = bool(response is not None and response.success)
        message = "" if response is None else str(response.message)
        self.get_logger().info(f"t={now - (self.referee.t0 or 0.0):.2f} s: activate({str(data).lower()}) -> "
                               f"{'success' if success else 'failure'}: {message}")
        self.referee.on_activate_result(now, data, success)

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
                self.get_logger().warning(f"activate({data}) unanswered for {self.call_timeout:g} s wall: "
                                          f"sending it again (attempt {attempt + 1})")
                self._send(data, attempt + 1)
                continue
            self._heartbeat()
            self.get_logger().warning(f"activate({data}) unanswered after {attempt} attempts")
            self.referee.on_activate_result(self.now(), data, False)

    def _heartbeat(self) -> None:
        """Tell the simulator where this node's clock is and whether a call is in flight."""
        if self.sync_pub is None or self.finished:
            return
        payload = {"who": self.who, "t": round(self.now(), 9), "hold": bool(self._pending)}
        self.sync_pub.publish(String(data=json.dumps(payload)))

    def leave(self) -> None:
        """Tell the simulator to stop waiting for this node (after the verdict, or when stopping)."""
        if self.sync_pub is None:
            return
        self.sync_pub.publish(String(data=json.dumps({"who": self.who, "leave": True})))
        try:  # the process exits right after this: make sure the simulator got it
            self.sync_pub.wait_for_all_acked(Duration(nanoseconds=300_000_000))
        except Exception as exc:  # informational only: the simulator times the follower out anyway
            self.get_logger().debug(f"sim_sync goodbye not acknowledged: {exc!r}")

    # -------------------------------------------------------------- inputs
    def _on_evaluate(self, request: Any, response: Any) -> Any:
        now = self.now()
        response.success, response.message = self.referee.on_evaluate(now)
        self.get_logger().info(f"evaluate_mission called at t={now - (self.referee.t0 or 0.0):.2f} s: "
                               f"{response.message}")
        return response

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

    def _on_truth(self, msg: Any, info: Any = None) -> None:
        if not self._own_truth(info):
            return
        if not self.started:
            self._truth_seen = True
            return
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if self.referee.t0 is not None and t < self.referee.t0:
            return
        pose = msg.pose.pose
        q = pose.orientation
        self.referee.observe(t, pose.position.x, pose.position.y, yaw_from_quaternion(q.x, q.y, q.z, q.w))

    def _on_collision(self, msg: Any) -> None:
        if not self.started:
            return
        try:
            event = json.loads(msg.data)
            t, x, y = float(event["t"]), float(event["x"]), float(event["y"])
        except (ValueError, KeyError, TypeError) as exc:
            self.get_logger().warning(f"unreadable collision event {msg.data!r}: {exc}")
            return
        self.referee.on_collision(t, x, y)

    # -------------------------------------------------------------- the end
    def _conclude(self) -> None:
        self.leave()
        self.finished = True
        self.exit_code = EXIT_PASSED if self.referee.passed else EXIT_FAILED
        lines = self.referee.report_lines()
        for line in lines:
            print(line)
        sys.stdout.flush()
        self._write_json(lines)

    def _give_up(self) -> None:
        self.leave()
        self.finished = True
        self.timed_out = self.foreign is None
        self.exit_code = EXIT_TIMEOUT
        state = "before t0 (the activate service or /clock never came)" if not self.started else \
            f"at t={self.now() - (self.referee.t0 or 0.0):.2f} s of the schedule"
        if self.foreign is not None:  # nothing measured can be trusted: no figures at all
            print(f"NO VERDICT: {self.foreign}; set a ROS_DOMAIN_ID of its own for each run")
            lines = []
        else:
            print(f"TIMEOUT: no verdict after {self.timeout:g} s wall, {state}; provisional report:")
            lines = self.referee.report_lines()
        for line in lines:
            print(line)
        sys.stdout.flush()
        self._write_json(lines)

    def _write_json(self, lines: list[str]) -> None:
        if not self.json_path:
            return
        results = dict(self.referee.results())
        results.update({
            "report_lines": lines,
            "timed_out": self.timed_out,
            "foreign": self.foreign,
            "config": asdict(self.config),
            "wall_time_s": round(time.monotonic() - self.wall_start, 3),
            "activate_calls": self.calls,
        })
        path = Path(self.json_path)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
        except OSError as exc:
            self.get_logger().error(f"could not write {path}: {exc}")


def make_node(wall_start: float | None = None) -> RefereeNode:
    """Create the referee node (rclpy must be initialised)."""
    return RefereeNode(wall_start)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav referee``: exit 0 when every check passed, 1 when one failed, 2 on timeout or bad set-up."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ours, ros = split_ros_args(argv)
    parser = argparse.ArgumentParser(prog="bt-nav referee", description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="results file (parameter json)")
    parser.add_argument("--timeout", type=float, help="wall-clock limit, s (parameter timeout)")
    parser.add_argument("--time-scale", type=float, help="scale of the schedule's durations (parameter time_scale)")
    opts = parser.parse_args(ours)
    extra = param_args({"json": opts.json, "timeout": opts.timeout, "time_scale": opts.time_scale})

    wall_start = time.monotonic()
    # use_sim_time defaults to true here; a later -p use_sim_time:=false (the user's) wins.
    rclpy.init(args=[NODE_NAME, "--ros-args", "-p", "use_sim_time:=true", "--", *ros, *extra],
               signal_handler_options=SignalHandlerOptions.NO)
    stop = StopRequest().install()
    node = None
    try:
        try:
            node = make_node(wall_start)
        except (ValueError, TypeError) as exc:
            print(f"bt-nav referee: {exc}", file=sys.stderr)
            return EXIT_TIMEOUT
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        try:
            while rclpy.ok() and not node.finished and not stop:
                executor.spin_once(timeout_sec=0.02)
                node.poll()
        except (KeyboardInterrupt, ExternalShutdownException):
            stop.signum = stop.signum or signal.SIGINT
        if not node.finished:
            node.leave()
            print("referee stopped before its verdict", file=sys.stderr)
            return EXIT_TIMEOUT
        return node.exit_code
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
