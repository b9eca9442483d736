"""The fault suite's toolkit on top of tests/ros/ros_harness.py: one executive under test as a :class:`Run`.

Why a layer: every fault case checks the same four things — the node is alive, the robot is stopped or
moving safely (seen by the harness node, a separate subscriber), the evaluation is called exactly once
when the deadline passes, and the log says what happened in one line. :class:`Run` keeps those checks in
one place, plus what the harness alone does not do: integrating the robot's heading for odometry,
counting log lines since a mark, a log barrier, and scripted ``evaluate_mission`` servers that refuse,
answer late, hang or die mid-call.
"""

from __future__ import annotations

import array
import math
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import rclpy
from rclpy.parameter import Parameter
from ros_harness import PERIOD, V_MAX, Harness, Sample

from bt_nav.mission.params import SPECS as _SPECS
from bt_nav.testing import front_scan, laserscan_msg, scan_from_ranges

FREE = laserscan_msg(front_scan())  # nothing within 3 m: full speed

W_TURN = float(_SPECS["angular_speed"].default)  # rotating in place and the Close branch
DUE_MARGIN = float(_SPECS["stop_margin"].default)  # the stop comes this long before mission_duration
#: A WARN/ERROR/FATAL line of rclpy's console output.
COMPLAINT = r"\[(WARN|ERROR|FATAL)\]"


def scan_msg(ranges: Sequence[float], *, stamp: tuple[int, int] | None = None, intensities: Sequence[float] = (),
             **fields: float | None) -> Any:
    """A LaserScan with exactly these fields (defaults: a TurtleBot3 LDS-01, 0..2pi CCW, one beam per ranges;
    ``fields``: those of :func:`bt_nav.testing.scan_from_ranges`)."""
    return laserscan_msg(scan_from_ranges(ranges, **fields), stamp=stamp, intensities=intensities)


def filled(value: float, beams: int = 360, **kwargs: Any) -> Any:
    """Every beam reads ``value``."""
    return scan_msg(array.array("f", [value]) * beams, **kwargs)


@dataclass
class ServedCall:
    """One request an :class:`EvaluationServer` received."""

    sim_time: float
    behaviour: str
    answered: bool | None = None  # the success sent; None: never answered


class EvaluationServer:
    """``evaluate_mission`` answering each call as scripted.

    Behaviours: ``ok``, ``refuse`` (success=false), ``slow:<s>`` (success after ``s`` seconds of
    simulated time), ``hang`` (never answers), ``die`` (the service is destroyed with the call
    pending, as when the server process dies; :meth:`start` brings a new one up). The last behaviour
    repeats.

    The service lives on a node of its own that no executor spins: :meth:`poll` takes the requests
    and sends the answers by hand, between ticks. Why: a late answer needs the request held open,
    and a coroutine callback awaiting a future makes rclpy's executor hand out that task on every
    ``spin_once`` without waiting on anything else, which starves the harness's subscriptions.
    """

    _instances = 0

    def __init__(self, h: Harness, script: Sequence[str] = ("ok",), name: str = "/evaluate_mission",
                 start: bool = True) -> None:
        EvaluationServer._instances += 1
        self.h = h
        self.node = rclpy.create_node(f"bt_nav_fault_evaluator_{EvaluationServer._instances}", context=h.context)
        self.script = list(script)
        self.name = name
        self.calls: list[ServedCall] = []
        self.service: Any = None
        self._pending: list[tuple[float, Any, ServedCall]] = []
        h.__dict__.setdefault("fault_servers", []).append(self)  # closed with the harness (tests/faults/conftest.py)
        if start:
            self.start()

    def start(self) -> None:
        """Create the service (again)."""
        from std_srvs.srv import Trigger

        if self.service is None:
            self.service = self.node.create_service(Trigger, self.name, lambda request, response: response)

    def stop(self) -> None:
        """Destroy the service (pending calls are never answered)."""
        if self.service is not None:
            self.node.destroy_service(self.service)
            self.service = None
            self._pending.clear()

    def close(self) -> None:
        """Destroy the node."""
        self.stop()
        self.node.destroy_node()

    @property
    def successes(self) -> int:
        """Calls answered with success=true."""
        return sum(1 for c in self.calls if c.answered)

    def count(self) -> int:
        """Calls so far (after taking what has arrived)."""
        self.poll()
        return len(self.calls)

    def _answer(self, header: Any, call: ServedCall, success: bool) -> None:
        from std_srvs.srv import Trigger

        response = Trigger.Response(success=success, message="scored" if success else "not ready, try again")
        self.service.send_response(response, header)
        call.answered = success

    def poll(self) -> None:
        """Take new requests, answer what is due, die when scripted (call between ticks)."""
        if self.service is None:
            return
        for entry in list(self._pending):
            due, header, call = entry
            if self.h.sim_time >= due - 1e-9:
                self._pending.remove(entry)
                self._answer(header, call, True)
        while self.service is not None:
            with self.service.handle:
                taken = self.service.handle.service_take_request(self.service.srv_type.Request)
            if taken is None or taken[1] is None:
                return
            header = taken[1]
            behaviour = self.script[min(len(self.calls), len(self.script) - 1)]
            call = ServedCall(self.h.sim_time, behaviour)
            self.calls.append(call)
            if behaviour in ("ok", "refuse"):
                self._answer(header, call, behaviour == "ok")
            elif behaviour.startswith("slow:"):
                self._pending.append((self.h.sim_time + float(behaviour.split(":", 1)[1]), header, call))
            elif behaviour == "die":
                self.stop()
            elif behaviour != "hang":
                raise ValueError(f"unknown behaviour {behaviour!r}")


class Run:
    """One executive under test (through its harness): the checks every fault case shares.

    ``odom``: ``"live"`` publishes the heading integrated from the commands before every tick,
    ``"frozen"`` keeps publishing the heading it had (a stuck robot), ``"off"`` publishes none.
    """

    def __init__(self, h: Harness, server: EvaluationServer | None = None) -> None:
        self.h = h
        self.server = server
        self.odom = "off"
        self.yaw = 0.0
        self.frozen_yaw = 0.0
        self.armed_at: float | None = None
        self._barrier_flip = False

    @property
    def process(self) -> Any:
        """The executive subprocess."""
        assert self.h.process is not None
        return self.h.process

    # ------------------------------------------------------------------ the log
    def mark(self) -> int:
        """Index of the next output line (lines from here on belong to the case that asked)."""
        return len(self.process.lines)

    def since(self, mark: int, pattern: str) -> list[str]:
        """Output lines after ``mark`` matching ``pattern``."""
        return [line for line in self.process.lines[mark:] if re.search(pattern, line)]

    def wait_line(self, pattern: str, since: int, what: str = "", timeout: float = 10.0, count: int = 1) -> None:
        """Wait until ``count`` lines after ``since`` match ``pattern``."""
        self.h.wait(lambda: len(self.since(since, pattern)) >= count, what or f"a log line /{pattern}/", timeout,
                    allow_exit=True)

    def expect_one(self, pattern: str, since: int, what: str = "") -> str:
        """Exactly one line after ``since`` matches ``pattern`` (after a barrier, so late lines count)."""
        self.wait_line(pattern, since, what)
        self.barrier()
        found = self.since(since, pattern)
        assert len(found) == 1, f"expected one line /{pattern}/, got {len(found)}: {found}"
        return found[0]

    def barrier(self) -> None:
        """Return once every line the executive logged before now has been read.

        A parameter change is a service call the executive handles in order with its ticks, and it logs
        ``parameters changed: ...``; once that line is read, everything logged before it has been too.
        """
        self._barrier_flip = not self._barrier_flip
        value = 10.5 if self._barrier_flip else 10.0
        mark = self.mark()
        (result,) = self.h.set_parameters(Parameter("stats_period", value=value))
        assert result.successful, result.reason
        self.wait_line(rf"parameters changed: stats_period={value}", mark, "the log barrier")

    def no_complaints(self, since: int) -> None:
        """No warning or error after ``since`` except the barrier's own lines."""
        self.barrier()
        complaints = self.since(since, COMPLAINT)
        assert not complaints, f"unexpected warnings/errors: {complaints}"

    def gap_line(self, pattern: str, since: int, note: Callable[[str], None], gap: str) -> None:
        """A line the executive should log but does not yet: a finding when absent, checked when present."""
        self.barrier()
        found = self.since(since, pattern)
        if not found:
            note(gap)
        else:
            assert len(found) == 1, f"expected one line /{pattern}/, got {found}"

    # ------------------------------------------------------------------ the robot
    def alive(self) -> None:
        """The executive still runs."""
        assert self.process.alive, f"the executive died\n{self.process.tail()}"

    def tick(self, scan: Any = None, to: float | None = None) -> Sample:
        """One tick (see Harness.tick), with odometry as configured and the evaluation server polled."""
        if self.odom == "live":
            self.h.publish_odom(self.yaw)
        elif self.odom == "frozen":
            self.h.publish_odom(self.frozen_yaw)
        before = len(self.h.samples)
        sample = self.h.tick(to, scan=scan)
        for s in self.h.samples[before:]:
            self.yaw = math.remainder(self.yaw + s.angular * PERIOD, 2 * math.pi)
        if self.server is not None:
            self.server.poll()
        return sample

    def jump_back(self, seconds: float) -> Sample:
        """``/clock`` jumps back by ``seconds`` (a simulator reset); returns the first tick after it.

        rcl restarts a timer's period on a backward jump (no tick at the jump itself, the next one a
        period later), so the first step goes 1 ms past that period: exactly at it, rounding of the
        nanosecond clock can leave the timer 1 ns short and no tick happens. The barrier makes sure the
        backward time has been taken in before the forward step is sent.
        """
        back = self.h.sim_time - seconds
        assert back > 0.0, "a /clock before 0 cannot be expressed"
        self.h.publish_clock(back)
        self.barrier()
        return self.tick(to=back + PERIOD + 1e-3)

    def ticks(self, n: int, scan: Any = None) -> list[Sample]:
        """``n`` ticks seeing ``scan``."""
        return [self.tick(scan) for _ in range(n)]

    def tick_until(self, condition: Callable[[], bool], what: str, *, scan: Any = FREE, timeout: float = 20.0,
                   pace: float = 0.01, stopped: bool = True) -> list[Sample]:
        """Tick seeing ``scan`` (``pace`` s of wall time apart, for discovery to progress) until ``condition``.

        Returns the ticks' samples. With ``stopped`` every tick must be a zero twist (the robot after the deadline).
        """
        samples: list[Sample] = []
        end = time.monotonic() + timeout
        while not condition():
            assert time.monotonic() < end, f"timed out after {timeout:.0f} s waiting for {what}\n{self.h.details()}"
            sample = self.tick(scan)
            samples.append(sample)
            assert not stopped or sample.is_zero, f"moved while {what}: {sample}"
            wait_wall(self.h, pace)
        return samples

    def arm(self) -> float:
        """Arm; returns the executive's own time of the first arming (from its answer)."""
        response = self.h.arm(True)
        assert response.success, response.message
        match = re.search(r"mission timer started at t=([\d.]+)", response.message)
        if match:
            self.armed_at = float(match.group(1))
        return self.h.sim_time if self.armed_at is None else self.armed_at

    def assert_full_speed(self, sample: Sample) -> None:
        """Straight ahead at max_linear_speed."""
        assert abs(sample.linear - V_MAX) < 1e-6 and sample.angular == 0.0, f"not full speed: {sample}"

    def assert_rotating(self, sample: Sample, rate: float = W_TURN) -> None:
        """In place (linear exactly 0) at ``rate``."""
        assert sample.linear == 0.0 and abs(abs(sample.angular) - rate) < 1e-6, f"not rotating in place: {sample}"

    def recover(self) -> Sample:
        """A good scan: the robot drives at full speed again (within three ticks)."""
        for _ in range(3):
            sample = self.tick(FREE)
            if sample.linear > 0.0:
                break
        self.assert_full_speed(sample)
        return sample

    # ------------------------------------------------------------------ the deadline
    def finish(self, duration: float = 50.0, margin: float = DUE_MARGIN, *, expect_calls: int = 1,
               scan: Any = FREE) -> None:
        """Run to the deadline: stop within a tick, exactly ``expect_calls`` evaluation call(s), one log line.

        Assumes the server answers at once (``ok``); other scripts check their own sequence.
        """
        assert self.armed_at is not None, "finish() needs the time of the first arming"
        assert self.server is not None, "finish() needs an evaluation server"
        due = self.armed_at + duration - margin
        mark = self.mark()
        before_calls = len(self.server.calls)
        target = max(self.h.sim_time + PERIOD, due - 2 * PERIOD)
        self.tick(scan, to=target)
        assert len(self.server.calls) == before_calls, "evaluation called before the deadline"
        for _ in range(4):
            if self.tick(scan).is_zero and self.h.sim_time >= due:
                break
        last = self.h.samples[-1]
        assert last.is_zero and self.h.sim_time <= due + 2 * PERIOD + 1e-6, f"no stop at the deadline: {last}"
        self.tick_until(lambda: self.server.count() >= before_calls + expect_calls, "the evaluation call", scan=scan)
        after = self.ticks(10, scan)
        assert all(s.is_zero for s in after), f"motion after the deadline: {after}"
        assert len(self.server.calls) == before_calls + expect_calls, (
            f"expected {expect_calls} evaluation call(s), the server saw {len(self.server.calls) - before_calls}")
        self.expect_one(r"deadline reached at t=", mark, "the deadline line")
        self.expect_one(r"EvaluateMission: evaluation accepted", mark, "the evaluation-accepted line")
        self.alive()


def connect(h: Harness, process: Any) -> Harness:
    """What tests/ros's ``executive`` fixture does after starting the process (for executives started with
    an environment of their own): wait for matching, the first command, and a scan taken in."""
    from ros_harness import STARTUP_TIMEOUT

    h.connect(process)
    h.first_contact()
    prime = laserscan_msg(front_scan())
    h.wait(lambda: h.tick(scan=prime).is_zero and process.has_line("scan usable again"),
           "the executive to receive scans", STARTUP_TIMEOUT)
    return h


def wait_wall(h: Harness, seconds: float) -> None:
    """Spin the harness for ``seconds`` of wall time (only where wall time itself is the subject)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        h.spin()


def default_sectors() -> Any:
    """The cones ProcessScan uses with the default parameters."""
    from bt_nav.mission.scan import SectorConfig

    d = {name: _SPECS[name].default for name in ("front_half_angle_deg", "side_center_deg", "side_half_angle_deg",
                                                 "min_valid_beams")}
    return SectorConfig.from_degrees(front_half_deg=d["front_half_angle_deg"], side_center_deg=d["side_center_deg"],
                                     side_half_deg=d["side_half_angle_deg"], min_valid_beams=d["min_valid_beams"])


def expected_proximity(scan: Any) -> str:
    """What the tree must do with a scan: 'stop' (malformed), or the class of the robot's path ahead as
    ProcessScan computes it with the default parameters (unknown when the front cone is unknown)."""
    from bt_nav.mission.behaviours.perception import ProcessScan
    from bt_nav.mission.paths import free_paths
    from bt_nav.mission.scan import Proximity, ScanError, sector_minima

    try:
        sectors = sector_minima(scan, default_sectors())
        far = float(_SPECS["far_distance"].default)
        ahead = free_paths(scan, float(_SPECS["path_half_width"].default), ProcessScan.HORIZON * far).ahead
    except ScanError:
        return "stop"
    if not sectors.front.known:
        return Proximity.UNKNOWN.value
    close = float(_SPECS["close_distance"].default)
    return (Proximity.CLOSE if ahead < close else Proximity.FAR if ahead < far else Proximity.NONE).value
