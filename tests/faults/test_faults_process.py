"""Process-level faults through the real executive: signals mid-maneuver and mid-evaluation, exceptions injected
into leaves (``BT_NAV_FAULT_INJECT``, see faultinject.py and faulty_executive.py), and invalid parameter values
set at runtime.

Expected semantics: SIGINT/SIGTERM -> zero twists acknowledged by the subscriber, exit status 0, one
``<SIGNAL> received`` line and the final stats; an exception in a leaf -> a stop on that tick, one
``exception in leaf '<name>'`` line, the tree reset, the node alive and the next tick normal; an invalid
runtime parameter -> refused with the reason, one ``parameter change refused`` line, behaviour unchanged.
"""

from __future__ import annotations

import math
import os
import signal
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from conftest import FaultCases
from faultinject import FAULT_INJECT_ENV
from faultkit import DUE_MARGIN, FREE, EvaluationServer, Run, connect
from rclpy.parameter import Parameter
from ros_harness import PERIOD, ExecutiveProcess, Harness

from bt_nav.testing import front_scan, laserscan_msg

SIGNALS = [signal.SIGINT, signal.SIGTERM]
#: The real executive with the test-only fault injection (product code has none).
FAULTY_EXECUTIVE = [sys.executable, str(Path(__file__).with_name("faulty_executive.py"))]


def shut_down(run: Run, signum: int) -> int:
    """Send ``signum``; wait for the exit and the final zero twists; the exit status."""
    h = run.h
    count = len(h.samples)
    run.process.proc.send_signal(signum)
    code = run.process.wait_exit(10.0, step=h.spin)
    h.wait(lambda: len(h.samples) >= count + 3, "the final zero twists", allow_exit=True)
    assert all(s.is_zero for s in h.samples[count:]), h.samples[count:]
    return code


@pytest.mark.fault("process", "signal mid-maneuver A (robot rotating): >= 3 zero twists reach the subscriber, exit "
                   "status 0, one '<SIGNAL> received: stopping the robot' line, final stats line")
@pytest.mark.parametrize("signum", SIGNALS, ids=[s.name for s in SIGNALS])
def test_signal_mid_maneuver(executive: Callable[..., Harness], signum: signal.Signals) -> None:
    h = executive("-p", "maneuver:=A", "-p", "trigger_at_arming:=true", "-p", "random_seed:=7")
    run = Run(h)
    run.arm()
    turning = run.ticks(3, laserscan_msg(front_scan(front=0.4)))
    assert all(s.linear == 0.0 and s.angular != 0.0 for s in turning), turning
    assert shut_down(run, signum) == 0
    assert len(run.since(0, rf"{signum.name} received: stopping the robot and shutting down")) == 1
    assert run.process.has_line(r"final stats: .*evaluation calls 0, watchdog stops 0")


@pytest.mark.fault("process", "signal while the evaluation call is pending (server never answers): zero twists, exit "
                   "status 0, one '<SIGNAL> received' line, final stats say 'evaluation calls 0'; the server saw "
                   "exactly one request")
@pytest.mark.parametrize("signum", SIGNALS, ids=[s.name for s in SIGNALS])
def test_signal_mid_evaluation(executive: Callable[..., Harness], signum: signal.Signals) -> None:
    h = executive("-p", "mission_duration:=5.0", "-p", "evaluation_timeout:=30.0")
    server = EvaluationServer(h, ["hang"])
    run = Run(h, server)
    armed_at = run.arm()
    run.assert_full_speed(run.tick(FREE))
    run.tick(FREE, to=armed_at + 5.0 - DUE_MARGIN + PERIOD + 1e-3)
    run.tick_until(lambda: server.count() == 1, "the evaluation request")
    assert all(s.is_zero for s in run.ticks(3, FREE))
    assert shut_down(run, signum) == 0
    assert len(run.since(0, rf"{signum.name} received: stopping the robot and shutting down")) == 1
    assert run.process.has_line(r"final stats: .*evaluation calls 0")
    assert server.count() == 1


# ---------------------------------------------------------------------------------------------- injected exceptions
def start_with_faults(start_executive: Callable[..., ExecutiveProcess], make_harness: Callable[..., Harness],
                      spec: str, *ros_args: str) -> Harness:
    """An executive whose leaves raise as ``BT_NAV_FAULT_INJECT=spec`` says, connected to a new harness."""
    h = make_harness()
    process = start_executive(*ros_args, command=FAULTY_EXECUTIVE, env={**os.environ, FAULT_INJECT_ENV: spec})
    return connect(h, process)


def exception_line(name: str) -> str:
    """The core's line for an exception in leaf ``name``."""
    return rf"exception in leaf '{name}': InjectedFaultError\(.*\); publishing a stop and resetting the tree"


def test_exceptions_in_leaves(start_executive: Callable[..., ExecutiveProcess],
                              make_harness: Callable[..., Harness], faults: FaultCases) -> None:
    spec = "FullSpeed@3,TurnAway@2,SmartPivot@3,StopAtDeadline@1"
    h = start_with_faults(start_executive, make_harness, spec, "-p", "maneuver:=C", "-p", "trigger_at_arming:=true",
                          "-p", "random_seed:=7")
    run = Run(h, EvaluationServer(h))
    run.odom = "live"
    assert run.process.has_line(rf"test-only fault injection armed \(BT_NAV_FAULT_INJECT\): {spec.replace(',', ', ')}")
    run.arm()

    with faults.case("exception in FullSpeed while driving", "process",
                     "the 3rd update of the driving leaf raises: that tick publishes a stop, one 'exception in leaf "
                     "'FullSpeed'' line, the tree is reset; the next tick drives at full speed; node alive"):
        mark = run.mark()
        samples = run.ticks(6, FREE)
        zeros = [s for s in samples if s.is_zero]
        assert len(zeros) == 1 and samples[-1].linear > 0.0, samples
        assert all(s.is_zero or (s.linear > 0.2 and s.angular == 0.0) for s in samples), samples
        run.expect_one(exception_line("FullSpeed"), mark)
        run.alive()
    with faults.case("exception in TurnAway in the far band", "process",
                     "the 2nd update raises: one stop, one line; slow turning resumes on the next tick"):
        mark = run.mark()
        samples = run.ticks(5, laserscan_msg(front_scan(front=0.5)))
        assert sum(1 for s in samples if s.is_zero) == 1 and samples[-1].angular != 0.0, samples
        assert all(s.is_zero or (0.0 < s.linear <= 0.22 and s.angular != 0.0) for s in samples), samples
        run.expect_one(exception_line("TurnAway"), mark)
        run.recover()
    with faults.case("exception in SmartPivot mid-maneuver", "process",
                     "the 3rd update of a running maneuver raises: one stop, one line, the maneuver is reset "
                     "('preempted, stopped') and starts afresh; linear exactly 0 until it completes; then drives"):
        mark = run.mark()
        close = laserscan_msg(front_scan(front=0.25))
        samples = run.ticks(5, close)
        assert all(s.linear == 0.0 for s in samples), samples
        assert sum(1 for s in samples if s.is_zero) >= 1, samples
        run.expect_one(exception_line("SmartPivot"), mark)
        run.expect_one(r"SmartPivot: preempted, stopped", mark)
        turning = run.tick_until(lambda: run.h.samples[-1].linear > 0.0, "the maneuver to complete", stopped=False)
        assert all(s.linear == 0.0 for s in turning[:-1]), turning
        run.recover()
    with faults.case("exception in StopAtDeadline at the deadline", "process",
                     "the deadline tick's stop leaf raises: that tick stops anyway (exception path), the latch "
                     "holds, the next tick calls the evaluation: exactly one call, one exception line"):
        mark = run.mark()
        run.finish()
        run.expect_one(exception_line("StopAtDeadline"), mark)
    with faults.case("exceptions counted at exit", "process",
                     "SIGTERM after 4 injected exceptions: exit 0, final stats 'exceptions 4'"):
        assert shut_down(run, signal.SIGTERM) == 0
        assert run.process.has_line(r"final stats: .*exceptions 4, vetoed commands 0"), run.process.tail()




@pytest.mark.parametrize(("spec", "answer", "bug"), [
    ("EvaluateMission@1", "ok", None),
    ("EvaluateMission@2", "slow:0.3", None),
    ("StopAtDeadline@2", "slow:0.3", None),
], ids=["EvaluateMission-raises-as-it-sends", "EvaluateMission-raises-while-pending",
        "StopAtDeadline-raises-while-pending"])
def test_exception_while_evaluating(start_executive: Callable[..., ExecutiveProcess],
                                    make_harness: Callable[..., Harness], faults: FaultCases, spec: str,
                                    answer: str, bug: str | None) -> None:
    leaf, nth = spec.split("@")
    when = "as it sends the request" if nth == "1" else "while the request is in flight"
    with faults.case(f"exception in {leaf} {when}", "process",
                     f"{spec} with a server answering {answer}: stop throughout, one exception line, the node "
                     "survives, the evaluation is requested exactly once", known_bug=bug) as case:
        h = start_with_faults(start_executive, make_harness, spec, "-p", "mission_duration:=5.0")
        server = EvaluationServer(h, [answer])
        run = Run(h, server)
        armed_at = run.arm()
        run.assert_full_speed(run.tick(FREE))
        mark = run.mark()
        run.tick(FREE, to=armed_at + 5.0 - DUE_MARGIN + PERIOD + 1e-3)
        run.tick_until(lambda: bool(run.since(mark, r"evaluation accepted")), "the evaluation to be accepted")
        assert all(s.is_zero for s in run.ticks(10, FREE))
        run.expect_one(exception_line(leaf), mark)
        run.alive()
        requests = server.count()
        if bug is None:
            assert requests == 1, f"the server received {requests} evaluation requests"
        else:
            case.bug_check(requests == 1, f"the server received {requests} evaluation requests")


# ---------------------------------------------------------------------------------------------- runtime parameters
INVALID: list[tuple[str, list[Any], str]] = [
    ("negative distance", [Parameter("safety_distance", value=-0.4)], r"safety_distance must be >= 0\.05 m, got -0\.4"),
    ("NaN speed", [Parameter("max_linear_speed", value=math.nan)], r"max_linear_speed must be finite, got nan"),
    ("infinite timeout", [Parameter("scan_timeout", value=math.inf)], r"scan_timeout must be finite, got inf"),
    ("unknown maneuver name", [Parameter("maneuver", value="zigzag")], r"unknown maneuver 'zigzag'"),
    ("maneuver change while running", [Parameter("maneuver", value="B")], r"maneuver cannot change while"),
    ("wrong type (string for a distance)", [Parameter("safety_distance", value="far")],
     r"safety_distance must be a number, got 'far'"),
    ("cross rule (close_distance >= far_distance)", [Parameter("close_distance", value=0.8)],
     r"close_distance \(0\.8\) must be smaller than far_distance \(0\.7\)"),
    ("atomic batch with one bad value", [Parameter("far_distance", value=1.0), Parameter("close_distance", value=-1.0)],
     r"close_distance must be >= 0\.05 m"),
    ("unknown parameter (typo)", [Parameter("safty_distance", value=0.4)], r"unknown parameter 'safty_distance'"),
    ("negative clock_watchdog", [Parameter("clock_watchdog", value=-1.0)], r"clock_watchdog must be >= 0\.0 s"),
    ("read-only tick rate", [Parameter("tick_rate_hz", value=50.0)], r"tick_rate_hz cannot change while"),
]


def test_invalid_runtime_parameters(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive()
    run = Run(h, EvaluationServer(h))
    run.arm()
    run.assert_full_speed(run.tick(FREE))
    for label, parameters, reason in INVALID:
        with faults.case(f"runtime parameter: {label}", "parameters",
                         "set while driving: refused with the reason, one 'parameter change refused' line, the value "
                         "unchanged, full speed on the next ticks"):
            names = [p.name for p in parameters if p.name != "safty_distance"]
            before = h.get_parameters(*names) if names else {}
            mark = run.mark()
            results = h.set_parameters(*parameters, atomically=len(parameters) > 1)
            assert not any(r.successful for r in results), results
            run.expect_one(rf"parameter change refused: .*{reason}", mark)
            assert (h.get_parameters(*names) if names else {}) == before
            for sample in run.ticks(2, FREE):
                run.assert_full_speed(sample)
    with faults.case("runtime parameter: integer for a float", "parameters",
                     "safety_distance:=1 (an INTEGER, as `ros2 param set` sends it) is accepted as 1.0 like on the "
                     "command line: one 'parameters changed' line"):
        mark = run.mark()
        (result,) = h.set_parameters(Parameter("safety_distance", value=1))
        assert result.successful, result.reason
        assert h.get_parameters("safety_distance") == {"safety_distance": 1.0}
        run.expect_one(r"parameters changed: safety_distance=1\.0", mark)
        (result,) = h.set_parameters(Parameter("safety_distance", value=0.5))
        assert result.successful, result.reason
    with faults.case("runtime parameter: valid change takes effect at once", "parameters",
                     "max_linear_speed 0.1 with slow_linear_speed 0.05 (atomically): the next tick drives at 0.1 m/s; "
                     "restored to 0.22"):
        (result,) = h.set_parameters(Parameter("slow_linear_speed", value=0.05),
                                     Parameter("max_linear_speed", value=0.1), atomically=True)
        assert result.successful, result.reason
        assert abs(run.tick(FREE).linear - 0.1) < 1e-9
        (result,) = h.set_parameters(Parameter("max_linear_speed", value=0.22),
                                     Parameter("slow_linear_speed", value=0.12), atomically=True)
        assert result.successful, result.reason
        run.assert_full_speed(run.tick(FREE))
    with faults.case("parameter group: deadline", "mission",
                     f"after {len(faults.records)} runtime-change cases: stop at the deadline, exactly one evaluation "
                     "call, one 'deadline reached' line"):
        run.finish()
