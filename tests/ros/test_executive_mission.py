"""The mission deadline and the evaluation call, in simulated time.

``mission_duration`` 50 s and ``stop_margin`` (its default): the stop and the call are due 50 s less it, in
simulated time after the first arming. The harness moves ``/clock`` there in a few jumps, so each
test takes a second or two of wall time and proves the deadline follows ``/clock``, not the wall.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ros_harness import PERIOD, Harness

from bt_nav.mission.params import SPECS
from bt_nav.testing import front_scan, laserscan_msg

FREE = laserscan_msg(front_scan())
DUE = 50.0 - float(SPECS["stop_margin"].default)  # mission_duration - stop_margin (the defaults)


def arm_and_drive(h: Harness) -> float:
    """Arm at the current simulated time, check it drives; returns the time of the first arming."""
    armed_at = h.sim_time
    response = h.arm(True)
    assert response.success and "mission timer started" in response.message
    assert h.tick(scan=FREE).linear > 0.0
    return armed_at


def test_deadline_follows_sim_time_and_calls_exactly_once(executive: Callable[..., Harness]) -> None:
    h = executive("-p", "mission_duration:=50.0", "-p", f"stop_margin:={50.0 - DUE}")
    h.serve_evaluation()
    wall_start = time.monotonic()
    armed_at = arm_and_drive(h)

    # 0.1 s (two ticks) before the deadline: still driving, no call.
    assert h.tick(armed_at + DUE - 2 * PERIOD, scan=FREE).linear > 0.0
    assert h.tick(scan=FREE).linear > 0.0
    assert h.calls == []

    # The tick at the deadline (or the next one: float rounding of the due time) stops; the request goes out on the
    # tick after, once the zero twist is out ("stop its motion and send the request").
    latch = h.tick(scan=FREE)
    if not latch.is_zero:
        latch = h.tick(scan=FREE)
    assert latch.is_zero
    time.sleep(0.5)
    assert h.calls == [], "the request went out before the stop was published"
    assert h.tick(scan=FREE).is_zero
    h.wait(lambda: len(h.calls) == 1, "the evaluation call")  # simulated time stands still meanwhile
    assert armed_at + DUE + PERIOD - 1e-6 <= h.calls[0].sim_time <= armed_at + DUE + 2 * PERIOD + 1e-6
    assert h.tick(armed_at + DUE + 0.1, scan=FREE).is_zero  # /clock on past the deadline: still stopped
    assert time.monotonic() - wall_start < 20.0  # nowhere near 50 s of wall time

    # Long after: still stopped, still exactly one call; arming again is refused.
    assert all(s.is_zero for s in h.ticks(10, scan=FREE))
    assert h.tick(armed_at + 120.0 + PERIOD, scan=FREE).is_zero
    refused = h.arm(True)
    assert not refused.success and "mission ended" in refused.message
    assert all(s.is_zero for s in h.ticks(3, scan=FREE))
    assert len(h.calls) == 1
    h.wait(lambda: h.process.has_line(r"evaluation accepted"), "the evaluation-accepted log line")


def test_refused_evaluation_is_retried(executive: Callable[..., Harness]) -> None:
    h = executive("-p", "evaluation_retry_delay:=0.5")
    h.serve_evaluation(answers=[False, True])
    armed_at = arm_and_drive(h)
    assert h.tick(armed_at + DUE + PERIOD, scan=FREE).is_zero
    h.wait(lambda: len(h.calls) == 1, "the first evaluation call")
    assert not h.calls[0].answered_success

    # The refusal is seen on a later tick, then the retry waits 0.5 s of simulated time.
    for _ in range(int(0.5 / PERIOD) + 4):
        if len(h.calls) == 2:
            break
        assert h.tick().is_zero
    h.wait(lambda: len(h.calls) == 2, "the retried evaluation call")
    assert h.calls[1].answered_success
    assert h.calls[1].sim_time - h.calls[0].sim_time >= 0.5 - 1e-6
    h.ticks(20)
    assert len(h.calls) == 2
    assert h.process.has_line(r"attempt 1 failed \(success=false")


def test_evaluation_waits_for_a_late_server(executive: Callable[..., Harness]) -> None:
    # Plenty of retries: the executive must also *discover* the server, which takes wall time.
    h = executive("-p", "evaluation_timeout:=1.0", "-p", "evaluation_retries:=100", "-p",
                  "evaluation_retry_delay:=0.2")
    armed_at = arm_and_drive(h)
    assert h.tick(armed_at + DUE + PERIOD, scan=FREE).is_zero
    for _ in range(int(1.5 / PERIOD)):  # the first attempt times out: nobody serves the call
        assert h.tick().is_zero
    h.wait(lambda: h.process.has_line(r"evaluation attempt 1 failed \(the evaluation service is not available\)"),
           "the first attempt's failure")
    assert h.calls == []

    h.serve_evaluation()
    h.wait(lambda: h.tick().is_zero and len(h.calls) == 1, "the call to the late server", timeout=20.0)
    h.ticks(40)
    assert len(h.calls) == 1
    assert all(s.is_zero for s in h.samples[-40:])
