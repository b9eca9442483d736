"""Timing faults through the real executive over DDS: sensor streams that stop, odometry that lies, a /clock
that jumps back (simulator reset) or stalls (simulator paused or dead).

Expected semantics: scans stop -> stop within scan_timeout (+ one tick), drive again when they return;
odometry stops mid-maneuver -> the maneuver finishes open loop (dead reckoning of the commanded rate);
odometry frozen (stuck robot) -> the time allowance ends the maneuver with a stop; /clock backwards -> the
last scan is "in the future" and unusable until a fresh one, the deadline latch never re-arms; /clock
stalls -> no ticks, so the tree cannot stop a moving robot: the executive's wall-clock watchdog
(``clock_watchdog``) publishes a stop.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from conftest import FaultCases
from faultkit import FREE, EvaluationServer, Run, wait_wall
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from ros_harness import PERIOD, Harness

from bt_nav.testing import front_scan, laserscan_msg

CLOSE = laserscan_msg(front_scan(front=0.25))  # nearer than pivot_distance (0.3): maneuver C starts
SCAN_TIMEOUT = 0.5
from bt_nav.mission.params import SPECS as _SPECS  # noqa: E402

# |rotation| / rate + 1 s + maneuver_time_margin
ALLOWANCE_C = 90.0 / math.degrees(float(_SPECS["maneuver_angular_speed"].default)) + 1.0 + 2.0


def odometry_faults(h: Harness, run: Run, faults: FaultCases) -> None:
    """The odometry cases of :func:`test_sensor_stream_faults` (one executive, maneuver C, armed)."""
    with faults.case("odometry stops mid-maneuver", "timing",
                     "maneuver C starts on live odometry, odometry stops after 3 ticks: the turn finishes open loop "
                     "(dead reckoning) within its allowance, linear exactly 0 throughout; one 'turning' and one "
                     "'done' line; then drives on") as case:
        mark = run.mark()
        first = run.tick(CLOSE)
        assert first.linear == 0.0 and first.angular != 0.0, first
        run.ticks(3, FREE)  # the maneuver holds its branch (InProgress?) although the trigger cleared
        run.odom = "off"
        started = h.sim_time - 4 * PERIOD
        turning = []
        while (sample := run.tick(FREE)).linear == 0.0 and h.sim_time - started < ALLOWANCE_C + 1.0:
            turning.append(sample)
        assert all(s.linear == 0.0 and s.angular != 0.0 for s in turning[:-1]), turning
        run.assert_full_speed(sample)
        run.expect_one(r"SmartPivot: front .*: turning (left|right) 90 deg", mark)
        run.expect_one(r"SmartPivot: done: turned [+-]\d", mark)
        assert h.sim_time - started < ALLOWANCE_C, "finished by the allowance, not by dead reckoning"
        run.gap_line(r"SmartPivot: .*open loop", mark, case.note,
                     "gap: no line says the turn went open loop (proposed: RotationManeuver logs it once per "
                     "maneuver)")
        run.odom = "live"

    with faults.case("odometry frozen mid-maneuver (stuck robot)", "timing",
                     f"odometry keeps coming with a constant heading: the maneuver gives up after its allowance "
                     f"({ALLOWANCE_C:.2f} s) with a stop and one 'out of time' line, linear exactly 0 throughout; "
                     "then drives on"):
        run.odom = "frozen"
        run.frozen_yaw = run.yaw
        mark = run.mark()
        start = run.tick(CLOSE)
        started = h.sim_time
        assert start.linear == 0.0 and start.angular != 0.0, start
        samples = []
        while (sample := run.tick(FREE)).linear == 0.0 and h.sim_time - started < ALLOWANCE_C + 2.0:
            samples.append(sample)
        assert all(s.linear == 0.0 for s in samples)
        gave_up = h.sim_time - started
        assert ALLOWANCE_C - PERIOD <= gave_up <= ALLOWANCE_C + 3 * PERIOD, f"gave up after {gave_up:.2f} s"
        run.assert_full_speed(sample)
        run.expect_one(r"SmartPivot: out of time after \d+\.\d s, [+-]\d+ deg short", mark)
        run.odom = "live"

    with faults.case("odometry with invalid orientations", "timing",
                     "NaN, all-zero and overflowing quaternions are dropped with one throttled line; the robot "
                     "keeps driving on the scans"):
        mark = run.mark()
        for q in ((math.nan, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 0.0), (1e300, 1e300, 1e300, 1e300)):
            msg = Odometry()
            msg.pose.pose.orientation.x, msg.pose.pose.orientation.y = q[0], q[1]
            msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = q[2], q[3]
            h.odom_pub.publish(msg)
            run.assert_full_speed(run.tick(FREE))
        run.expect_one(r"dropping odometry with an invalid orientation", mark)


def test_sensor_stream_faults(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive("-p", "maneuver:=C", "-p", "trigger_at_arming:=true", "-p", "trigger_clear_away:=0.0",
                  "-p", f"scan_timeout:={SCAN_TIMEOUT}", "-p", "odom_timeout:=0.5")
    run = Run(h, EvaluationServer(h))
    run.odom = "live"
    run.arm()
    run.assert_full_speed(run.tick(FREE))

    with faults.case("scans stop", "timing", f"moving until the last scan is {SCAN_TIMEOUT} s old, stopped within "
                     "scan_timeout + one tick (+ one tick of scan/clock race), stays stopped; one 'stale scan' line"):
        run.ticks(3, FREE)
        last_scan = h.sim_time  # the last scan arrived at this tick's time or the previous one's
        mark = run.mark()
        samples = run.ticks(16)
        first_stop = next(i for i, s in enumerate(samples) if s.is_zero)
        assert all(s.linear > 0.0 for s in samples[:first_stop]), samples[:first_stop]
        assert all(s.is_zero for s in samples[first_stop:]), samples[first_stop:]
        age = samples[first_stop].sim_time - last_scan
        assert age <= SCAN_TIMEOUT + 2 * PERIOD + 1e-6, f"stopped only {age:.2f} s after the last scan"
        run.expect_one(rf"ProcessScan: stale scan: none newer than {SCAN_TIMEOUT:.2f} s — stopping", mark)
    with faults.case("scans resume", "timing", "the first fresh scan drives again; one 'usable again' line"):
        mark = run.mark()
        run.recover()
        run.expect_one(r"ProcessScan: ok — scan usable again", mark)

    odometry_faults(h, run, faults)

    with faults.case("sensor group: deadline", "mission",
                     "stop at the deadline, exactly one evaluation call, one 'deadline reached' line, node alive"):
        run.finish()


WATCHDOG = 0.6  # s of wall time (default 1.0; shorter here to keep the suite fast)


def test_clock_faults(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive("-p", f"clock_watchdog:={WATCHDOG}")
    run = Run(h, EvaluationServer(h))
    run.arm()
    run.assert_full_speed(run.tick(FREE))

    with faults.case("/clock stalls while moving (watchdog on)", "timing",
                     f"no /clock for > 2x clock_watchdog ({WATCHDOG} s wall): exactly one zero twist, published "
                     "without a tick; one 'clock watchdog' line; ticks resume -> drives, one 'ticking again' line"):
        run.assert_full_speed(run.tick(FREE))
        mark, count = run.mark(), len(h.samples)
        h.wait(lambda: len(h.samples) > count, "the watchdog's stop", timeout=WATCHDOG + 2.0)
        wait_wall(h, WATCHDOG)  # and nothing more
        stops = h.samples[count:]
        assert len(stops) == 1 and stops[0].is_zero, f"expected one watchdog stop, got {stops}"
        waited = stops[0].wall_time - h.samples[count - 1].wall_time
        assert WATCHDOG - 0.05 <= waited <= WATCHDOG + 1.0, f"the watchdog stopped after {waited:.2f} s"
        run.expect_one(r"clock watchdog: no tick for \d+\.\d s of wall time while moving \(/clock stalled\?\)", mark)
        run.assert_full_speed(run.tick(laserscan_msg(front_scan())))
        run.expect_one(r"clock watchdog: ticking again after", mark)

    with faults.case("/clock stalls while stopped", "timing",
                     "disarmed (zero twist) and no /clock: nothing is published, no watchdog line (nothing to stop)"):
        assert h.arm(False).success
        assert run.tick(FREE).is_zero
        mark, count = run.mark(), len(h.samples)
        wait_wall(h, 2 * WATCHDOG)
        assert len(h.samples) == count, h.samples[count:]
        assert not run.since(mark, r"clock watchdog")
        assert h.arm(True).success
        run.assert_full_speed(run.tick(FREE))

    with faults.case("/clock stalls while moving, watchdog disabled", "timing",
                     "clock_watchdog:=0 at runtime: the executive publishes nothing while /clock stands still, i.e. "
                     "a base that holds its last cmd_vel keeps driving blind (why the watchdog exists)") as case:
        (result,) = h.set_parameters(Parameter("clock_watchdog", value=0.0))
        assert result.successful, result.reason
        run.assert_full_speed(run.tick(FREE))
        count = len(h.samples)
        wait_wall(h, 2 * WATCHDOG)
        assert len(h.samples) == count, h.samples[count:]
        case.note(f"hazard confirmed with the watchdog off: last command {h.samples[-1].linear:.2f} m/s held "
                  f"for {2 * WATCHDOG:.1f} s of wall time with no new command")
        (result,) = h.set_parameters(Parameter("clock_watchdog", value=WATCHDOG))
        assert result.successful, result.reason

    with faults.case("/clock jumps back 5 s (simulator reset)", "timing",
                     "the last scan is stamped in the future: stop with one 'scan stamped in the future' line; "
                     "no crash, no deadline; a fresh scan drives again with one 'usable again' line"):
        run.assert_full_speed(run.tick(FREE, to=h.sim_time + 10.0))  # well clear of t=0 before jumping back
        run.assert_full_speed(run.tick(FREE))
        mark = run.mark()
        stopped = [run.jump_back(5.0), *run.ticks(2)]
        assert all(s.is_zero for s in stopped), stopped
        run.expect_one(r"ProcessScan: scan stamped in the future \(clock jumped back\?\) — stopping", mark)
        run.assert_full_speed(run.ticks(2, laserscan_msg(front_scan()))[-1])
        run.expect_one(r"ProcessScan: ok — scan usable again", mark)
        assert not run.since(mark, r"deadline reached|clock watchdog")  # every stop above came from a tick
        run.alive()

    with faults.case("clock group: deadline after the reset", "mission",
                     "the deadline follows the clock (first arming + 50 s - stop_margin on the reset clock): "
                     "stop, exactly one evaluation call, one 'deadline reached' line"):
        run.finish()

    with faults.case("/clock jumps back 20 s after the deadline", "timing",
                     "the deadline latch does not re-arm: stays stopped, no second evaluation call, no second "
                     "'deadline reached' line; arming is still refused"):
        calls = len(run.server.calls)
        mark = run.mark()
        assert run.jump_back(20.0).is_zero
        assert all(s.is_zero for s in run.ticks(10, laserscan_msg(front_scan())))
        assert all(s.is_zero for s in run.ticks(5, FREE))
        refused = h.arm(True)
        assert not refused.success and "mission ended" in refused.message, refused.message
        assert all(s.is_zero for s in run.ticks(3, FREE))
        assert len(run.server.calls) == calls
        run.barrier()
        assert not run.since(mark, r"deadline reached|calling the evaluation service")
        run.alive()

