"""Service faults through the real executive over DDS: the evaluation server misbehaving in every way, and the
arm service abused (bursts, concurrent clients, arming mid-maneuver and after the end).

Expected semantics (bt_nav/behaviours/mission.py): an evaluation attempt fails when the server is absent,
refuses (success=false), raises or does not answer within evaluation_timeout; it is retried after
evaluation_retry_delay up to evaluation_retries times, then given up with one error line; the robot stays
stopped from the deadline on whatever happens; exactly one successful call. The arm service answers at
once, never restarts the mission timer, and refuses to arm after the deadline.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import rclpy
from conftest import LONG, FaultCases
from faultkit import DUE_MARGIN, FREE, EvaluationServer, Run
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from ros_harness import PERIOD, Harness
from std_srvs.srv import SetBool

from bt_nav.testing import front_scan, laserscan_msg

SHORT_MISSION = 5.0  # s: mission_duration of these runs (the deadline stop_margin before it)


def to_deadline(run: Run) -> None:
    """Drive, then jump to the deadline: the robot stops and the first attempt opens."""
    run.assert_full_speed(run.tick(FREE))
    assert run.armed_at is not None
    run.tick(FREE, to=run.armed_at + SHORT_MISSION - DUE_MARGIN + PERIOD + 1e-3)
    assert run.h.samples[-1].is_zero, run.h.samples[-1]


def test_evaluation_server_absent(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive("-p", f"mission_duration:={SHORT_MISSION}", "-p", "evaluation_timeout:=0.5", "-p",
                  "evaluation_retries:=2", "-p", "evaluation_retry_delay:=0.2")
    run = Run(h)
    run.arm()
    with faults.case("evaluation server absent at the deadline", "services",
                     "3 attempts (1 + evaluation_retries 2), each 'not available' after 0.5 s: two 'retrying' lines, "
                     "then one 'evaluation failed ... no retries left' line; stopped from the deadline on; node alive"):
        mark = run.mark()
        to_deadline(run)
        run.tick_until(lambda: bool(run.since(mark, r"evaluation failed")), "the evaluation to be given up")
        assert all(s.is_zero for s in run.ticks(10, FREE))
        assert len(run.since(mark, r"evaluation attempt \d failed \(the evaluation service is not available\); "
                                   r"retrying")) == 2
        run.expect_one(r"EvaluateMission: evaluation failed: attempt 3: the evaluation service is not available; "
                       r"no retries left", mark)
        run.alive()
    with faults.case("arm after the mission ended (evaluation given up)", "services",
                     "arm(true) after the deadline is refused with the reason, one warning line; the robot stays "
                     "stopped"):
        mark = run.mark()
        refused = h.arm(True)
        assert not refused.success and "the mission ended" in refused.message, refused.message
        assert all(s.is_zero for s in run.ticks(5, FREE))
        run.expect_one(r"ArmService: refused: the mission ended", mark)


def test_evaluation_server_misbehaves(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive("-p", f"mission_duration:={SHORT_MISSION}", "-p", "evaluation_timeout:=1.0", "-p",
                  "evaluation_retries:=50", "-p", "evaluation_retry_delay:=0.2")
    server = EvaluationServer(h, ["die", "refuse", "slow:0.5"], start=False)
    run = Run(h, server)
    run.arm()
    start = run.mark()

    with faults.case("evaluation server appears late", "services",
                     "no server at the deadline: attempts fail 'not available' (stopped, retrying); the server "
                     "comes up and receives the next attempt"):
        to_deadline(run)
        run.tick_until(lambda: bool(run.since(start, r"attempt 1 failed \(the evaluation service is not available\)")),
                       "the first attempt to fail")
        assert server.calls == []
        server.start()
        run.tick_until(lambda: server.count() >= 1, "the late server to be called")
    with faults.case("evaluation server dies mid-call", "services",
                     "the service is destroyed with the request pending (as when its process dies): the attempt "
                     "times out after evaluation_timeout with one 'no answer within the timeout' line; stopped"):
        mark = run.mark()
        run.tick_until(lambda: server.service is None, "the server to die")
        run.tick_until(lambda: bool(run.since(mark, r"failed \(no answer within the timeout\); retrying")),
                       "the attempt to time out")
        run.expect_one(r"failed \(no answer within the timeout\); retrying", mark)
        server.start()
    with faults.case("evaluation server answers success=false", "services",
                     "a refusal is a failed attempt: one 'success=false' line, retried after the delay; stopped"):
        mark = run.mark()
        run.tick_until(lambda: server.count() >= 2, "the call after the restart")
        run.tick_until(lambda: bool(run.since(mark, r"failed \(success=false: not ready, try again\); retrying")),
                       "the refusal")
        run.expect_one(r"failed \(success=false", mark)
    with faults.case("evaluation server answers slowly", "services",
                     "an answer 0.5 s (simulated) after the request, within evaluation_timeout 1.0 s, is accepted: "
                     "one 'evaluation accepted' line; stopped"):
        mark = run.mark()
        run.tick_until(lambda: server.count() >= 3, "the third call")
        asked = server.calls[2].sim_time
        run.tick_until(lambda: bool(run.since(mark, r"evaluation accepted")), "the slow answer to be accepted")
        assert h.sim_time - asked >= 0.5 - 1e-6, f"accepted {h.sim_time - asked:.2f} s after the request"
        run.expect_one(r"EvaluateMission: evaluation accepted: scored", mark)
    with faults.case("evaluation: exactly one successful call", "services",
                     "after absent, dead, refusing and slow servers: the server saw 3 requests, exactly 1 answered "
                     "success, no call after it; stopped all along from the deadline; one 'deadline reached' line"):
        assert all(s.is_zero for s in run.ticks(20, FREE))
        assert len(server.calls) == 3 and server.successes == 1, server.calls
        run.expect_one(r"deadline reached", start)
        run.alive()


def call_many(h: Harness, client: Any, requests: list[bool], window: int, timeout: float = 30.0) -> list[Any]:
    """Call ``client`` with each value, at most ``window`` requests in flight; the responses in order."""
    futures: list[Any] = []
    pending: list[Any] = []
    for data in requests:
        h.wait(lambda: sum(1 for f in pending if not f.done()) < window, "a free slot in the window", timeout)
        future = client.call_async(SetBool.Request(data=data))
        futures.append(future)
        pending.append(future)
    h.wait(lambda: all(f.done() for f in futures), "every answer", timeout)
    return [f.result() for f in futures]


def arm_bursts(h: Harness, run: Run, faults: FaultCases) -> None:
    """The burst cases of :func:`test_arm_service_abuse`: many arm/disarm calls, paced and all at once."""
    bursts = 5 if LONG else 1
    with faults.case(f"arm/disarm burst ({bursts} x 1,000 calls)", "services",
                     "1,000 alternating disarm/arm calls, 8 in flight, a tick every 50: every call answered "
                     "with success, one log line per call that changed something, every tick a stop or full "
                     "speed, the mission timer never restarted; stopped after a final disarm, drives after arm"):
        mark = run.mark()
        changed = 0
        for _ in range(bursts):
            for chunk in range(20):
                responses = call_many(h, h.arm_client, [i % 2 == 1 for i in range(50)], window=8)
                assert all(r.success for r in responses), [r.message for r in responses if not r.success]
                assert not any("timer started" in r.message for r in responses)
                changed += sum(1 for r in responses if r.message != "already armed")
                sample = run.tick(FREE)
                assert sample.is_zero or (sample.linear > 0.0 and sample.angular == 0.0), (chunk, sample)
        run.barrier()
        logged = len(run.since(mark, r"ArmService: "))
        assert logged == changed, f"{changed} calls changed something, {logged} ArmService lines"
        assert h.arm(False).success
        assert run.tick(FREE).is_zero
        assert h.arm(True).success
        run.assert_full_speed(run.tick(FREE))
        run.alive()
    with faults.case("arm burst: 200 calls in flight at once", "services",
                     "200 requests (arm/disarm alternating, the LAST a disarm) sent without waiting, from a "
                     "KEEP_ALL client: every request answered; the last request wins (robot stopped on the next "
                     "tick); node alive") as case:
        all_qos = QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=1, reliability=ReliabilityPolicy.RELIABLE)
        eager = h.node.create_client(SetBool, "/arm", qos_profile=all_qos)
        h.wait(eager.service_is_ready, "the KEEP_ALL client to see the arm service")
        futures = [eager.call_async(SetBool.Request(data=i % 2 == 1)) for i in range(199)]
        futures.append(eager.call_async(SetBool.Request(data=False)))
        answered, steady_since = -1, time.monotonic()
        while time.monotonic() - steady_since < 1.0:  # until no answer came for 1 s
            h.spin()
            done = sum(1 for f in futures if f.done())
            if done != answered:
                answered, steady_since = done, time.monotonic()
        stopped = run.tick(FREE)
        run.alive()
        for future in futures:
            if not future.done():
                eager.remove_pending_request(future)
        h.node.destroy_client(eager)
        assert h.arm(True).success
        run.assert_full_speed(run.tick(FREE))
        case.bug_check(answered == len(futures),
                       f"{answered} of {len(futures)} answered; the last (a disarm) "
                       f"{'took effect' if stopped.is_zero else 'was LOST: the robot kept driving'}")
        assert stopped.is_zero, "every request answered, yet the final disarm did not stop the robot"


def test_arm_service_abuse(executive: Callable[..., Harness], make_harness: Callable[..., Harness],
                           faults: FaultCases) -> None:
    h = executive("-p", "maneuver:=C", "-p", "trigger_at_arming:=true", "-p", "random_seed:=7")
    run = Run(h, EvaluationServer(h))
    run.odom = "live"
    other = rclpy.create_node("bt_nav_fault_second_client", context=h.context)
    h.executor.add_node(other)
    try:
        second = other.create_client(SetBool, "/arm")
        h.wait(second.service_is_ready, "the second client to see the arm service")
        with faults.case("two clients arm concurrently", "services",
                         "two nodes call arm(true) at once: both succeed, exactly one 'mission timer started' (line "
                         "and answer), the other answers 'already armed'; the robot drives"):
            mark = run.mark()
            futures = [h.arm_client.call_async(SetBool.Request(data=True)),
                       second.call_async(SetBool.Request(data=True))]
            h.wait(lambda: all(f.done() for f in futures), "both answers")
            messages = sorted(f.result().message for f in futures)
            assert all(f.result().success for f in futures), messages
            assert messages[0] == "already armed" and messages[1].startswith("armed: mission timer started"), messages
            run.armed_at = float(messages[1].split("t=")[1].split(" ")[0])
            run.expect_one(r"mission timer started", mark)
            run.assert_full_speed(run.tick(FREE))
        with faults.case("arm(true) during a maneuver", "services",
                         "maneuver C running: arm(true) answers 'already armed' without a log line; the maneuver "
                         "carries on (linear exactly 0, same turn direction) and completes; then drives"):
            first = run.tick(laserscan_msg(front_scan(front=0.25)))
            assert first.linear == 0.0 and first.angular != 0.0, first
            mark = run.mark()
            response = h.arm(True)
            assert response.success and response.message == "already armed", response.message
            turning = [run.tick(FREE) for _ in range(3)]
            assert all(s.linear == 0.0 and s.angular * first.angular > 0.0 for s in turning), turning
            run.tick_until(lambda: h.samples[-1].linear > 0.0, "the maneuver to complete", stopped=False)
            run.no_complaints(mark)
            assert not run.since(mark, r"ArmService")
        arm_bursts(h, run, faults)
        with faults.case("arm group: deadline after the burst", "mission",
                         "the deadline is 50 s - stop_margin after the FIRST arming (no burst restarted the timer): "
                         "stop, exactly one evaluation call, one 'deadline reached' line"):
            run.finish()
        with faults.case("arm after the mission ended (evaluated)", "services",
                         "arm(true) from both clients after the deadline: refused with the reason, one warning line "
                         "each; the robot stays stopped; no second evaluation call"):
            mark = run.mark()
            for client in (h.arm_client, second):
                response = h.call(client, SetBool.Request(data=True))
                assert not response.success and "the mission ended" in response.message, response.message
            assert all(s.is_zero for s in run.ticks(5, FREE))
            run.barrier()
            assert len(run.since(mark, r"ArmService: refused: the mission ended")) == 2
            assert len(run.server.calls) == 1
    finally:
        h.executor.remove_node(other)
        other.destroy_node()
