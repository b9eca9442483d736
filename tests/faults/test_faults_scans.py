"""Bad scans through the real executive over DDS: every REP 117 corner, malformed geometry, absurd sizes, stamps.

One executive takes the whole sequence (a fresh process per case would cost a second each): each bad
scan is followed by a good one, which shows the recovery, and the run ends at the mission deadline with
exactly one evaluation call. Expected semantics (bt_nav/scan.py, bt_nav/behaviours/perception.py):

- malformed geometry -> ProcessScan logs ``malformed scan: <why> — stopping`` once and the tree stops
  (StopBlind) until a good scan: ``ok — scan usable again``, once;
- NaN / out-of-range / no-return beams carry no information: an unknown front is treated as close
  (rotate in place, never forward); +inf is free space (full speed is correct); -inf is an obstacle at
  range_min (rotate in place);
- the executive stamps scans on receipt with its own clock, so the header stamp does not matter.
"""

from __future__ import annotations

import array
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from conftest import LONG, FaultCases
from faultkit import FREE, EvaluationServer, Run, default_sectors, expected_proximity, filled, scan_msg
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rclpy.serialization import deserialize_message, serialize_message
from ros_harness import V_MAX, Harness
from sensor_msgs.msg import LaserScan

from bt_nav.mission.params import SPECS as _SPECS
from bt_nav.mission.scan import Proximity, Scan, ScanError, sector_minima

_W_TURN = float(_SPECS["angular_speed"].default)
_W_MAX = max(_W_TURN, float(_SPECS["maneuver_angular_speed"].default))

NAN, INF = math.nan, math.inf
GAP_UNKNOWN_FRONT = ("gap: no log line says the front is unknown (it rotates in place without a word); proposed: "
                     "ProcessScan logs 'front sector unknown ...' once per change")


def malformed_case(run: Run, faults: FaultCases, name: str, msg: Any, why: str) -> None:
    """A scan the geometry rejects: stop, one ``malformed scan`` line, recovery with one ``usable again`` line."""
    with faults.case(name, "scan", f"stops (zero twist) while the scan is malformed; one line 'malformed scan: "
                     f"{why}'; a good scan restores full speed with one 'usable again' line; node alive"):
        mark = run.mark()
        stopped = [run.tick(msg) for _ in range(3)]
        assert all(s.is_zero for s in stopped), f"moved on a malformed scan: {stopped}"
        run.expect_one(rf"ProcessScan: malformed scan: .*{why}.* — stopping", mark)
        mark = run.mark()
        run.recover()
        run.expect_one(r"ProcessScan: ok — scan usable again", mark)
        run.alive()


def blind_case(run: Run, faults: FaultCases, name: str, msg: Any, checked: str) -> None:
    """A well-formed scan whose front carries no information: rotate in place, never forward."""
    with faults.case(name, "scan", f"{checked}: front unknown -> rotates in place (linear exactly 0, "
                     "|angular| = angular_speed) on every tick, never forward; full speed again after a good scan; "
                     "no 'malformed' complaint; node alive") as case:
        mark = run.mark()
        for sample in run.ticks(4, msg):
            run.assert_rotating(sample)
        assert not run.since(mark, r"malformed scan"), "a well-formed scan was reported as malformed"
        run.gap_line(r"front sector unknown", mark, case.note, GAP_UNKNOWN_FRONT)
        run.recover()
        run.alive()


def unusual_layouts(run: Run, faults: FaultCases) -> None:
    """The legal-but-unusual scans of :func:`test_bad_scans_one_executive` (one executive, armed)."""
    # Geometry that is legal but unusual.
    with faults.case("scan: clockwise sweep (negative increment, angle_max < angle_min)", "scan",
                     "a legal clockwise scan is no fault: free -> full speed; obstacle ahead -> rotates in place"):
        cw = scan_msg([3.0] * 360, angle_min=math.pi, angle_increment=-2 * math.pi / 360)
        run.assert_full_speed(run.ticks(2, cw)[-1])
        ahead = [0.2 if abs(math.remainder(math.pi - i * 2 * math.pi / 360, 2 * math.pi)) < math.radians(30) else 3.0
                 for i in range(360)]
        run.assert_rotating(run.ticks(2, scan_msg(ahead, angle_min=math.pi, angle_increment=-2 * math.pi / 360))[-1])
        run.recover()
    blind_case(run, faults, "scan: rear only (135..225 deg)",
               scan_msg([3.0] * 91, angle_min=math.radians(135), angle_increment=math.radians(1)),
               "91 beams covering the rear only, none in the front sector")
    with faults.case("scan: 1 beam", "scan", "a single beam straight ahead: at 0.2 m -> rotates in place; at 3 m -> "
                     "drives (a 1-beam sector counts as known: min(min_valid_beams, beams in the sector))") as case:
        one_close = scan_msg([0.2], angle_min=0.0, angle_increment=0.01, angle_max=0.0)
        run.assert_rotating(run.ticks(2, one_close)[-1])
        one_free = scan_msg([3.0], angle_min=0.0, angle_increment=0.01, angle_max=0.0)
        sample = run.ticks(2, one_free)[-1]
        assert sample.linear >= 0.0 and math.isfinite(sample.angular)
        if sample.linear > 0.0:
            case.note("finding: drives at full speed on ONE beam (min_valid_beams is waived for a sector with "
                      "fewer beams, scan.py _reading); design question")
        run.recover()
    with faults.case("scan: 100,000 beams", "scan", "100k-beam scans (400 KB) over DDS: free -> full speed, obstacle "
                     "ahead -> rotates in place; node alive"):
        n = 100_000
        big_free = filled(3.0, n)
        run.assert_full_speed(run.ticks(3, big_free)[-1])
        ahead = np.full(n, 3.0, dtype=np.float32)
        angles = np.arange(n) * (2 * math.pi / n)
        ahead[np.abs(np.remainder(angles + math.pi, 2 * math.pi) - math.pi) <= math.radians(30)] = 0.2
        run.assert_rotating(run.ticks(3, scan_msg(array.array("f", ahead.tobytes())))[-1])
        run.recover()
        run.alive()
    for label, stamp in (("far in the past (1970)", (0, 0)), ("far in the future (2038)", (2**31 - 1, 999_999_999))):
        with faults.case(f"scan: header stamp {label}", "scan",
                         "the executive stamps scans on receipt with its node clock: the header stamp is ignored, "
                         "a free scan drives at full speed, an obstacle ahead rotates; no complaint"):
            mark = run.mark()
            run.assert_full_speed(run.ticks(2, scan_msg([3.0] * 360, stamp=stamp))[-1])
            run.assert_rotating(run.ticks(2, filled(0.2, stamp=stamp))[-1])
            run.no_complaints(mark)
            run.recover()


def test_bad_scans_one_executive(executive: Callable[..., Harness], faults: FaultCases) -> None:
    h = executive()
    run = Run(h, EvaluationServer(h))
    run.arm()
    run.assert_full_speed(run.tick(FREE))

    # REP 117: values that carry no information, or mean "free" / "too close".
    blind_case(run, faults, "scan: NaN everywhere", filled(NAN), "all 360 ranges NaN")
    with faults.case("scan: +inf everywhere", "scan", "REP 117 +inf = nothing within range: full speed straight "
                     "ahead (correct), no complaint"):
        mark = run.mark()
        for sample in run.ticks(3, filled(INF)):
            run.assert_full_speed(sample)
        run.no_complaints(mark)
    with faults.case("scan: -inf everywhere", "scan", "REP 117 -inf = closer than range_min: obstacle at range_min "
                     "-> rotates in place, never forward, no complaint"):
        mark = run.mark()
        for sample in run.ticks(3, filled(-INF)):
            run.assert_rotating(sample)
        run.no_complaints(mark)
        run.recover()
    blind_case(run, faults, "scan: zeros (LDS-01 'no return')", filled(0.0), "all ranges 0.0 < range_min 0.12")
    blind_case(run, faults, "scan: ranges outside [range_min, range_max]",
               scan_msg([5.0 if i % 2 else 0.05 for i in range(360)]), "ranges alternate 5.0 (> 3.5) and 0.05 (< 0.12)")

    # Malformed geometry.
    malformed_case(run, faults, "scan: empty ranges", scan_msg([], angle_increment=0.01, angle_max=1.0),
                   r"ranges is empty")
    malformed_case(run, faults, "scan: angle_increment 0", scan_msg([3.0] * 360, angle_increment=0.0, angle_max=6.2),
                   r"angle_increment must be finite and non-zero")
    malformed_case(run, faults, "scan: angle_increment negative (sweep mismatch)",
                   scan_msg([3.0] * 360, angle_increment=-2 * math.pi / 360, angle_max=6.2657),
                   r"sweep direction mismatch")
    malformed_case(run, faults, "scan: angle_increment NaN", scan_msg([3.0] * 360, angle_increment=NAN, angle_max=6.2),
                   r"angle_increment must be finite and non-zero, got nan")
    malformed_case(run, faults, "scan: len(ranges) inconsistent with the angles",
                   scan_msg([3.0] * 100, angle_increment=2 * math.pi / 360, angle_max=2 * math.pi * 359 / 360),
                   r"len\(ranges\) = 100 is inconsistent")
    malformed_case(run, faults, "scan: range_min NaN",
                   scan_msg([3.0] * 360, range_min=NAN), r"range_min must be finite")
    malformed_case(run, faults, "scan: range_max below range_min", scan_msg([3.0] * 360, range_min=3.5, range_max=0.12),
                   r"range_max must be > range_min")
    malformed_case(run, faults, "scan: angle_min +inf", scan_msg([3.0] * 360, angle_min=INF, angle_max=INF),
                   r"angle_min must be finite")

    unusual_layouts(run, faults)

    with faults.case(f"scan group: deadline after {len(faults.records)} scan cases", "mission",
                     "stop at the deadline, exactly one evaluation call, one 'deadline reached' line, node alive"):
        run.finish()


# ---------------------------------------------------------------------------------------------- the fuzzer
F32 = st.floats(width=32)  # any float32, NaN and +-inf included
ODD = st.sampled_from([NAN, INF, -INF, 0.0, -0.0])


FIELDS = ("angle_min", "angle_max", "angle_increment", "range_min", "range_max", "beams")


@st.composite
def laser_scans(draw: st.DrawFn) -> Any:
    """Any LaserScan: a plausible layout (any beam count, either sweep direction) with REP 117 patches in the
    ranges, and zero to three fields replaced by anything a float32 can hold (NaN, +-inf, huge, negative)."""
    broken = draw(st.one_of(st.just(set()), st.sets(st.sampled_from(FIELDS), max_size=3)))  # half intact
    n = draw(st.one_of(st.integers(0, 4), st.integers(5, 400), st.sampled_from([360, 640, 1081])))
    angle_min = draw(st.floats(-7.0, 7.0, width=32))
    span = draw(st.floats(0.0625, 6.25, width=32)) * draw(st.sampled_from([1.0, -1.0]))
    increment = float(np.float32(span / max(n - 1, 1)))
    angle_max = float(np.float32(angle_min + increment * max(n - 1, 0)))
    range_min = draw(st.floats(0.0, 1.0, width=32))
    range_max = draw(st.floats(1.5, 40.0, width=32))
    anything = st.one_of(F32, ODD, st.floats(-0.125, 0.125, width=32))
    if "angle_min" in broken:
        angle_min = draw(anything)
    if "angle_max" in broken:
        angle_max = draw(anything)
    if "angle_increment" in broken:
        increment = draw(anything)
    if "range_min" in broken:
        range_min = draw(anything)
    if "range_max" in broken:
        range_max = draw(anything)
    if "beams" in broken:  # len(ranges) no longer matches the angles
        n = max(0, n + draw(st.sampled_from([-n, -2, 2, 50, 1000])))
    value = st.one_of(st.floats(0.0, 5.0, width=32), ODD, F32)
    ranges = np.full(n, draw(value), dtype=np.float32)
    for _ in range(draw(st.integers(0, 4))):
        if n:
            first = draw(st.integers(0, n - 1))
            ranges[first:first + draw(st.integers(1, max(1, n // 4)))] = draw(value)
    msg = scan_msg(array.array("f", ranges.tobytes()), angle_min=angle_min, angle_increment=increment,
                   angle_max=angle_max, range_min=range_min, range_max=range_max,
                   stamp=(draw(st.integers(-(2**31), 2**31 - 1)), draw(st.integers(0, 2**32 - 1))),
                   intensities=[1.0] * draw(st.integers(0, 3)))
    msg.header.frame_id = draw(st.text(max_size=8))
    msg.time_increment = draw(st.one_of(st.just(0.0), F32))  # unused by bt_nav: must not matter either
    msg.scan_time = draw(st.one_of(st.just(0.2), F32))
    return msg


def expected(msg: Any) -> tuple[str, Any]:
    """What the tree must do with this scan, from the bytes the executive receives (float32 on the wire)."""
    received = deserialize_message(serialize_message(msg), LaserScan)
    try:
        scan = Scan.from_laserscan(received)
        sectors = sector_minima(scan, default_sectors())
    except ScanError:
        return "stop", None
    return expected_proximity(scan), sectors


def check_command(kind: str, linear: float, angular: float) -> None:
    """The oracle: malformed -> stop; unknown/close front -> rotate in place; far -> slow and turn; none -> full."""
    assert math.isfinite(linear) and math.isfinite(angular)
    assert abs(linear) <= V_MAX + 1e-9 and abs(angular) <= _W_MAX + 1e-9
    if kind == "stop":
        assert linear == 0.0 and angular == 0.0, "moved on a malformed scan"
    elif kind in (Proximity.UNKNOWN.value, Proximity.CLOSE.value):
        assert linear == 0.0 and abs(abs(angular) - _W_TURN) < 1e-6, "not rotating in place, front blocked/unknown"
    elif kind == Proximity.FAR.value:
        slow = float(_SPECS["slow_linear_speed"].default)
        assert slow - 1e-6 <= linear <= V_MAX + 1e-6 and angular != 0.0, "far band: should slow down and turn away"
    else:
        assert abs(linear - V_MAX) < 1e-6 and abs(angular) <= _W_TURN + 1e-9, "free front: should drive at full speed"


FUZZ_CHECKED = ("hypothesis: any LaserScan (0-3 geometry fields replaced by any float32 incl. NaN/+-inf, "
                 "0..2081 beams, either sweep, REP 117 patches, any header stamp / frame_id / time_increment / "
                 "scan_time / intensities) through the real node; every tick's command "
                 "matches the oracle (malformed -> stop, unknown/close front -> rotate in place, far band -> slow "
                 "turn, free -> full speed); node alive; recovers; deadline -> exactly one evaluation call")


def test_fuzz_laserscan_through_the_node(executive: Callable[..., Harness], faults: FaultCases) -> None:
    examples = 1000 if LONG else 100
    with faults.case(f"scan fuzzer over DDS ({examples} examples)", "scan", FUZZ_CHECKED) as case:
        h = executive("-p", "mission_duration:=3600.0")
        run = Run(h, EvaluationServer(h))
        run.arm()
        seen: dict[str, int] = {}

        @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
        @given(msg=laser_scans())
        def one_scan(msg: Any) -> None:
            kind, sectors = expected(msg)
            seen[kind] = seen.get(kind, 0) + 1
            sample = run.tick(msg)
            try:
                check_command(kind, sample.linear, sample.angular)
            except AssertionError as exc:
                raise AssertionError(f"{exc}: command ({sample.linear}, {sample.angular}) for a '{kind}' scan, "
                                     f"sectors {sectors}") from None
            run.alive()

        one_scan()
        case.note("examples by expected reaction: " + ", ".join(f"{k} {v}" for k, v in sorted(seen.items())))
        assert seen.get("stop", 0) > 0 and sum(v for k, v in seen.items() if k != "stop") > 0, seen
        run.recover()
        run.finish(3600.0)
