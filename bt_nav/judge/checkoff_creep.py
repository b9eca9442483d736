"""The lab check-off's creep check: armed, with nothing triggering, a node keeps moving (pure, no rclpy).

Why: the sheet's logic flow says that while navigation is enabled and the trigger does not hold, the node must
"maintain a slow forward velocity". A node that stops creeping after its first maneuver (its flag left on "turning
done", a creep published once and never again on a base whose command times out) passed every run before: the toggle
cycle's false came first, and nothing was checked after the true again.

The rule: a standstill while armed fails when it lasts ``creep_still`` s or more and, at every ground-truth sample of
it, no reasonable reading of the maneuver's trigger held (the judge's own :meth:`CheckoffJudge._trigger`: the widest
sectors, the loosest limit, the noise margin) and the front was clear beyond ``safety_distance`` plus that margin (the
widest front sector and the robot's swept path: a node braked by its AEB with its path blocked may be about to turn).
A standstill is the robot within ``move_on_distance`` of where it stopped (ground truth). Not counted: the first
``creep_start`` s after an arming was answered (the node's next scan), a turning command and the ``creep_settle`` s
after it (a maneuver and its settling), and everything from a disarm request to the next arming (the brake window).
"""

from __future__ import annotations

import bisect
import math
from typing import Any

#: The check's name, in the check-off's report order after "recovery turns".
CREEP_CHECK = "creep while armed"
#: What the check requires, in words.
CREEP_RULE = "moves while armed whenever nothing triggers"
#: The sheet's rule, ending every failure's sentence.
CREEP_SHEET = "the sheet says to maintain a slow forward velocity"


def armed_windows(judge: Any) -> list[tuple[float, float]]:
    """Where a standstill counts, as (from, to) times: from ``creep_start`` s after each arming answered (the first
    true, the toggle cycle's true again) to the next disarm request (``inf``: none yet)."""
    cfg = judge.config
    windows = []
    if judge.activated is not None:
        ends = [d for d in (judge.cycle_off_requested, judge.deactivation_requested) if d is not None]
        windows.append((judge.activated + cfg.creep_start, min(ends, default=math.inf)))
    if judge.cycle_on is not None:
        end = judge.deactivation_requested if judge.deactivation_requested is not None else math.inf
        windows.append((judge.cycle_on + cfg.creep_start, end))
    return windows


def _standstills(judge: Any, lo: float, hi: float, turns: list[float]) -> list[tuple[int, int]]:
    """The sample index runs (first, last) in [lo, hi] over which the robot stayed within ``move_on_distance`` of the
    run's first sample and no turning command (``turns``, sorted) was given in the ``creep_settle`` s before any of
    them; only runs of ``creep_still`` s or more (the rest cannot fail)."""
    cfg = judge.config
    ts, xs, ys = judge._t, judge._x, judge._y
    out: list[tuple[int, int]] = []
    first: int | None = None
    i0, i1 = bisect.bisect_left(ts, lo), bisect.bisect_right(ts, hi)
    for k in range(i0, i1):
        j = bisect.bisect_right(turns, ts[k])
        turned = j > 0 and turns[j - 1] >= ts[k] - cfg.creep_settle
        if first is not None and (turned or math.hypot(xs[k] - xs[first], ys[k] - ys[first]) > cfg.move_on_distance):
            if ts[k - 1] - ts[first] >= cfg.creep_still:
                out.append((first, k - 1))
            first = None
        if first is None and not turned:
            first = k
    if first is not None and ts[i1 - 1] - ts[first] >= cfg.creep_still:
        out.append((first, i1 - 1))
    return out


def _clear(judge: Any, k: int) -> Any:
    """Sample ``k``'s reading if nothing triggered there (no reading of the trigger held, the front and the swept
    path clear beyond ``safety_distance`` plus the margin), else None."""
    cfg = judge.config
    r = judge.readings.at(k)
    clear = cfg.safety_distance + cfg.trigger_margin
    if r is None or judge._trigger(r)[0] or r.front < clear or r.ahead < clear:
        return None
    return r


def longest_idle(judge: Any, now: float) -> tuple[float, float, Any]:
    """The longest standstill with nothing triggering while armed, up to ``now``: (seconds, its start, the reading
    at its start); (0, nan, None) when there is none of ``creep_still`` s."""
    cfg = judge.config
    turns = sorted(t for t, _, w in judge.commands if abs(w) >= cfg.rotation_min_rate)
    best: tuple[float, float, Any] = (0.0, math.nan, None)
    for lo, hi in armed_windows(judge):
        for a, b in _standstills(judge, lo, min(hi, now), turns):
            start: int | None = None
            first_reading = None
            for k in range(a, b + 2):  # one past the end closes the last run
                reading = _clear(judge, k) if k <= b else None
                if reading is not None and start is None:
                    start, first_reading = k, reading
                elif reading is None and start is not None:
                    length = judge._t[k - 1] - judge._t[start]
                    if length > best[0]:
                        best = (length, judge._t[start], first_reading)
                    start = None
    return best


def creep_check(judge: Any, now: float) -> dict[str, Any]:
    """The report line of the creep check (see the module docstring)."""
    cfg = judge.config
    length, start, r = longest_idle(judge, now)
    passed = length < cfg.creep_still
    required = f"no standstill of {cfg.creep_still:g} s while armed with nothing triggering"
    if passed:
        return {"name": CREEP_CHECK, "passed": True, "value": round(length, 2), "required": required,
                "detail": f"no standstill of {cfg.creep_still:g} s or more while armed with nothing triggering"}
    t0 = judge.t0 or 0.0
    front = f"front {r.front:.2f} m" if math.isfinite(r.front) else "nothing in front"
    what = (f"stood still for {length:.1f} s from t={start - t0:.1f} s while armed with nothing triggering ({front} "
            f"clear beyond safety_distance {cfg.safety_distance:.2f} m)")
    return {"name": CREEP_CHECK, "passed": False, "value": round(length, 2), "required": required,
            "detail": what, "reason": f"{what}: {CREEP_SHEET}"}
