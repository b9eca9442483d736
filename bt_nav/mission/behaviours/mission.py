"""Mission leaves: the arm service, the deadline latch and the evaluation call.

These are the leaves that talk to the outside world through services. They create their server and
client in ``setup(node=...)``; off-ROS (tests, lock-step) the same leaves run with the request handled
by a direct call (:meth:`ArmService.handle`) and an injected client with rclpy's Client interface.
"""

from __future__ import annotations

import math
from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import Condition, Leaf, port
from bt_nav.mission.snapshot import DEADLINE, DEADLINE_LEFT

Status = py_trees.common.Status


class ArmService(Leaf):
    """Owns the ``arm`` SetBool server and writes ``armed`` and the time of the first arming.

    The service callback answers at once, saying what happened; the tree reacts on its next tick.
    Arming after the mission ended is refused: the mission is one-shot, its evaluation has been
    requested, and a robot that starts moving again would spoil the referee's "static at the end".
    Arming without a usable scan is accepted (the scan may come a moment later) but said, as a
    warning and in the reply, with the reason the robot will not move yet. Replies give mission
    time (seconds since the first arming) and the clock only when it is sim time: an epoch reading
    means nothing to the person arming.
    """

    INPUT_PORTS = {
        "mission_over": port(bool, "the deadline has passed", default=False),
        "scan_ok": port(bool, "the newest scan is fresh and usable (ProcessScan, last tick)", default=False),
        "scan_status": port(str, "why the scan is (not) usable", default="no scan yet"),
        "mission_duration": port(float, "0: no deadline (the reply says so instead of a mission timer)",
                                 default=50.0),
    }
    OUTPUT_PORTS = {
        "armed": port(bool, "the robot may move", default=False),
        "first_armed_at": port(float, "mission-clock time of the first arming (nan: never)", default=math.nan),
        "arm_count": port(int, "how often the robot was armed (a new count is a fresh start)", default=0),
    }

    def setup(self, **kwargs: Any) -> None:
        """Create the SetBool server on the node, when there is one, named by ``arm_service``."""
        super().setup(**kwargs)
        self.service = None
        if self.node is not None:
            from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
            from std_srvs.srv import SetBool  # ROS edge only: the core runs without it

            # keep every request: with the default keep-last-10 a burst of calls loses requests, and a
            # client waiting for its disarm confirmation would never hear back
            qos = QoSProfile(depth=1, history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
            name = str(kwargs.get("arm_service") or "arm")  # the arm_service parameter
            self.service = self.node.create_service(SetBool, name, self._on_request, qos_profile=qos)

    def _on_request(self, request: Any, response: Any) -> Any:
        response.success, response.message = self.handle(bool(request.data))
        return response

    def handle(self, data: bool) -> tuple[bool, str]:
        """Apply one arm/disarm request; returns (success, message) as the service answers."""
        now = self.clock()
        armed = self.blackboard_client.get("armed")
        first = self.blackboard_client.get("first_armed_at")
        if not data:
            self._set_output("armed", False)
            message = "disarmed: robot stopped" if armed else "already disarmed: robot stays stopped"
            self.events.info(f"{self.label}: {message}")
            return True, message
        if now <= 0.0:
            message = ("refused: the clock has not started yet (with use_sim_time, no /clock has arrived); "
                       "the mission timer cannot start at t=0")
            self.events.warning(f"{self.label}: {message}")
            return False, message
        if self.get_input("mission_over"):
            message = (f"refused: the mission ended (mission t={now - first:.2f} s); "
                       "the robot stays stopped — restart the executive for a new mission")
            self.events.warning(f"{self.label}: {message}")
            return False, message
        if armed:
            return True, "already armed"
        self._set_output("armed", True)
        self._set_output("arm_count", int(self.blackboard_client.get("arm_count") or 0) + 1)
        if math.isnan(first):
            self._set_output("first_armed_at", float(now))
            message = (f"armed: mission timer started at {clock_text(now)} (mission t=0.00 s)"
                       if self.get_input("mission_duration") > 0.0 else
                       f"armed at {clock_text(now)}: navigating until disarmed (no deadline)")
        else:
            message = f"armed again at mission t={now - first:.2f} s"
        if not self.get_input("scan_ok"):
            message += (f"; no usable scan yet ({self.get_input('scan_status')}): the robot will not move until "
                        "one arrives")
            self.events.warning(f"{self.label}: {message}")
        else:
            self.events.info(f"{self.label}: {message}")
        return True, message

    def update(self) -> Status:
        """Always SUCCESS: this leaf's work happens in the service callback."""
        self.feedback_message = "armed" if self.last_output("armed", False) else "disarmed"
        return Status.SUCCESS


#: Clock readings above this are wall-clock epoch seconds, not sim time (about three years).
EPOCH_THRESHOLD = 1e8


def clock_text(now: float) -> str:
    """``t=12.34 s`` for a sim-time clock (whose readings mean something to the user: the referee and
    the logs use them); ``wall clock`` for an epoch reading (1.7e9 s says nothing)."""
    return "wall clock" if now > EPOCH_THRESHOLD else f"t={now:.2f} s"


class IsArmed(Condition):
    """Is the robot allowed to move?"""

    INPUT_PORTS = {"armed": port(bool, default=False)}
    OUTPUT_PORTS = {}

    def answer(self) -> bool:
        """``armed`` as written by :class:`ArmService`."""
        return bool(self.get_input("armed"))


class MissionDeadline(Condition):
    """One-shot latch: SUCCESS from ``mission_duration - stop_margin`` after the first arming, forever.

    ``mission_duration`` 0 means no deadline (the lab runs until it is disarmed): never SUCCESS.

    The margin makes the stop and the evaluation call land inside the limit even with a tick of
    delay and the service round trip. Once latched it never unlatches, not even if the clock jumps
    back (a simulator reset): the mission's evaluation must not be asked for twice.
    """

    INPUT_PORTS = {
        "first_armed_at": port(float, default=math.nan),
        "mission_duration": port(float, default=50.0),
        "stop_margin": port(float, default=0.25),
    }
    OUTPUT_PORTS = {"mission_over": port(bool, "latched deadline", default=False)}

    def answer(self) -> bool:
        """Has the deadline passed (latched)?"""
        if self.last_output("mission_over", False):
            return True
        duration = self.get_input("mission_duration")
        if duration <= 0.0:
            self.feedback_message, self.snapshot_data = "no deadline", {DEADLINE: "none"}
            return False
        first = self.get_input("first_armed_at")
        if math.isnan(first):
            self.feedback_message, self.snapshot_data = "not armed yet", {DEADLINE: "unarmed"}
            return False
        limit = first + duration - self.get_input("stop_margin")
        now = self.clock()
        if now < limit:
            self.feedback_message = f"{limit - now:.1f} s left"
            self.snapshot_data = {DEADLINE: "counting", DEADLINE_LEFT: limit - now}
            return False
        self._set_output("mission_over", True)
        self.feedback_message, self.snapshot_data = "deadline reached", {DEADLINE: "reached"}
        self.events.info(f"{self.label}: deadline reached at t={now:.2f} s ({now - first:.2f} s after the "
                         "first arming): stopping and asking for evaluation")
        return True


class EvaluateMission(Leaf):
    """Calls the ``evaluate_mission`` Trigger service exactly once per mission, without blocking a tick.

    ``call_async`` in ``initialise()`` (or when the server appears), RUNNING while the future is
    pending; a refused answer (success=false), an exception, a missing server or a timeout is one failed
    attempt, retried after a delay up to ``evaluation_retries`` times. After a success the leaf stays
    SUCCESS without calling again; after the last failed attempt it stays FAILURE (the tree keeps the
    robot stopped either way).
    """

    INPUT_PORTS = {
        "timeout": port(float, "seconds one attempt may take", default=2.0),
        "retries": port(int, "further attempts after a failure", default=5),
        "retry_delay": port(float, "seconds between attempts", default=0.5),
    }
    OUTPUT_PORTS = {"result": port(str, "what the evaluation call gave", default="not called")}

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.client: Any = None
        self.future: Any = None
        self.attempts = 0
        self.successful_calls = 0
        self.final: Status | None = None
        self._in_attempt = False
        self._attempt_elapsed = 0.0  # seconds spent in the current attempt
        self._wait_left = 0.0  # seconds of retry delay still to wait
        self._last_time: float | None = None
        self._held = False  # the first request waits for the tick after the stop (initialise)

    def setup(self, **kwargs: Any) -> None:
        """Use the injected ``evaluation_client`` or create a Trigger client on the node."""
        super().setup(**kwargs)
        self.client = kwargs.get("evaluation_client")
        if self.client is None and self.node is not None:
            from std_srvs.srv import Trigger  # ROS edge only

            self.client = self.node.create_client(Trigger, "evaluate_mission")

    def initialise(self) -> None:
        """Hold the first request for one tick; later ticks send it (``call_async``) and poll.

        The sheet's order is "stop its motion and send the request": the Stop before this leaf
        commands a zero twist that the node publishes only at the end of this tick, so a request sent
        now would reach the evaluator while the last command it heard still drives the robot. On the
        next tick the stop is out. After a tree reset (an exception elsewhere) a request already in
        flight is kept and polled again: sending a second one would ask the referee twice.
        """
        if self.final is None and self.client is not None:
            if self.attempts == 0 and not self._in_attempt:
                self._held = True
                self._elapse(self.clock())
            else:
                self._advance(self.clock())

    def _elapse(self, now: float) -> float:
        """Seconds since the previous call, never negative: a clock jumping back (a simulator reset)
        must not stretch a timeout or a retry delay by the size of the jump."""
        dt = 0.0 if self._last_time is None else max(0.0, now - self._last_time)
        self._last_time = now
        return dt

    def _advance(self, now: float) -> None:
        """Open an attempt when one is due and send its request as soon as the server is there."""
        dt = self._elapse(now)
        if self._in_attempt:
            self._attempt_elapsed += dt
        else:
            self._wait_left -= dt
            if self._wait_left > 0.0:
                return
            self.attempts += 1
            self._in_attempt = True
            self._attempt_elapsed = 0.0
        if self.future is None and self.client.service_is_ready():
            self.future = self.client.call_async(self.client.srv_type.Request())
            self.feedback_message = f"attempt {self.attempts}: request sent"
            self.events.info(f"{self.label}: calling the evaluation service (attempt {self.attempts})")
        elif self.future is None:
            self.feedback_message = f"attempt {self.attempts}: waiting for the evaluation service"

    def update(self) -> Status:
        """Poll the pending call; never blocks."""
        if self.final is not None:
            return self.final
        if self.client is None:
            return self._give_up("no evaluation client (no node and none injected)")
        if self._held:  # the tick that initialised it: its stop is published at this tick's end
            self._held = False
            self.feedback_message = "stopping first: the request goes out on the next tick"
            return Status.RUNNING
        self._advance(self.clock())
        if not self._in_attempt:
            return Status.RUNNING  # waiting out the retry delay
        if self.future is not None and self.future.done():
            future, self.future = self.future, None
            try:
                response = future.result()
            except Exception as exc:  # a server that died mid-call surfaces here: one failed attempt
                return self._attempt_failed(f"the call raised {exc!r}")
            if response is not None and response.success:
                return self._succeeded(str(response.message))
            message = "no response" if response is None else f"success=false: {response.message}"
            return self._attempt_failed(message)
        if self._attempt_elapsed >= self.get_input("timeout"):
            if self.future is None:
                return self._attempt_failed("the evaluation service is not available")
            self.client.remove_pending_request(self.future)
            self.future = None
            return self._attempt_failed("no answer within the timeout")
        return Status.RUNNING

    def _succeeded(self, message: str) -> Status:
        self.successful_calls += 1
        self.final = Status.SUCCESS
        self._in_attempt = False
        self._set_output("result", f"succeeded: {message}")
        self.feedback_message = f"evaluated: {message}"
        self.events.info(f"{self.label}: evaluation accepted: {message}")
        return Status.SUCCESS

    def _attempt_failed(self, why: str) -> Status:
        self._in_attempt = False
        if self.attempts > self.get_input("retries"):
            return self._give_up(f"attempt {self.attempts}: {why}; no retries left")
        self.events.warning(f"{self.label}: evaluation attempt {self.attempts} failed ({why}); retrying")
        self._set_output("result", f"attempt {self.attempts} failed: {why}")
        self._wait_left = self.get_input("retry_delay")
        self.feedback_message = f"attempt {self.attempts} failed: {why}"
        return Status.RUNNING

    def _give_up(self, why: str) -> Status:
        self.final = Status.FAILURE
        self._set_output("result", f"failed: {why}")
        self.feedback_message = f"gave up: {why}"
        self.events.error(f"{self.label}: evaluation failed: {why}")
        return Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        """Keep a request in flight across a reset; :meth:`cancel` drops it at shutdown."""

    def cancel(self) -> None:
        """Drop a pending request (shutdown); idempotent."""
        if self.future is not None and self.client is not None:
            self.client.remove_pending_request(self.future)
        self.future = None
