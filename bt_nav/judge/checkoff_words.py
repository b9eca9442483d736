"""The check-off's words: what is wrong with a judged maneuver and the report lines of the maneuver checks, in
sentences a student can act on (the pure judge :mod:`bt_nav.judge.checkoff_core` makes the figures; the docs' judge
page and the grader quote these).

Why apart from the judge: the judge's state machine and its words change for different reasons, and one module
holding both outgrew its size limit.
"""

from __future__ import annotations

from typing import Any

from bt_nav.judge.chains import SPLIT_HINT
from bt_nav.mission.maneuver_spec import LiveMap, judge_names, maneuver_spec

#: The lab's names of the maneuvers (``the Randomizer``), a live view of the maneuver spec.
MANEUVER_NAMES = LiveMap(judge_names)


def _forward_text(e: dict[str, Any]) -> str:
    """Why a turn failed the forward rule, in figures that agree with each other: a forward command during it, or
    (none commanded) the ground truth's motion alone."""
    rule = "the check-off allows no forward motion during a maneuver"
    if e["forward_command"] > 0.0:
        speed = f"{e['forward_command']:.2f}" if e["forward_command"] >= 0.01 else f"{e['forward_command']:.3f}"
        return f"drove forward during the turn (commanded up to {speed} m/s, moved {e['forward_motion']:.2f} m); {rule}"
    return (f"moved {e['forward_motion']:.3f} m during the turn (ground truth) though none of its commands asked for "
            f"forward speed: stop fully before turning; {rule}")


def _readings_text(e: dict[str, Any], maneuver: str = "") -> str:
    """The judge's readings at a turn's start, as the failing line shows them: the front and the nearest of any
    side sector (what the triggers read); for a maneuver that turns towards the clearer side the sides beside the
    robot (60-120 deg), as it compares them (a wide side sector also sees the obstacle ahead)."""
    r = e.get("readings") or {}
    clearer = bool(maneuver) and maneuver_spec(maneuver).angle.side == "clearer"
    keys = (("front", "front"), ("left", "left_abeam"), ("right", "right_abeam")) if clearer else \
        (("front", "front"), ("left", "left"), ("right", "right"))
    parts = [f"{name} {r[k]:.2f} m" if r.get(k) is not None else f"{name} nothing" for name, k in keys if k in r]
    return "readings at the start: " + ", ".join(parts) if parts else "no readings at the start"


#: The kinds of fault a judged maneuver may have, as its check's ``kinds`` names them (the grader keys its advice to
#: a student on them: a trigger that did not hold needs other words than a turn of the wrong angle).
TRIGGER, LATE, ANGLE, SIDE, STILL_TURNING, FORWARD, MOVED_ON = (
    "trigger", "late", "angle", "side", "still turning", "forward", "moved on")
#: The rule a fault of each kind broke, when it is not the episode's angle rule.
FORWARD_RULE = "no forward command or motion from the turn's start to its end"
MOVED_ON_RULE = "move on after the turn (strict_findings moved_on)"


def maneuver_faults(maneuver: str, e: dict[str, Any]) -> list[tuple[str, str]]:
    """What is wrong with one judged maneuver: ``(kind, sentence)`` each, in the check-off's words (empty:
    nothing). The kind says which rule broke (the angle's size, the side, a turn never ended are apart: each
    needs its own advice)."""
    name = MANEUVER_NAMES.get(maneuver, maneuver)
    out = []
    if not e["trigger"]:
        out.append((TRIGGER, f"turned although its trigger did not hold ({e['trigger_detail']} is not true)"))
    if e.get("late"):
        at = f"{e['late_at']}: " if e.get("late_at") else ""
        out.append((LATE, f"turned late: {at}it crept on {e['crept_with_trigger']:.2f} m over "
                          f"{e['trigger_held_for']:.1f} s after its trigger held (does it read its distance parameter, "
                          "and its sectors at their angles from angle_min and angle_increment?)"))
    if not e["angle_ok"]:
        kind = STILL_TURNING if "still turning at the disarm" in str(e["rule"]) else \
            SIDE if e.get("size_ok") else ANGLE
        out.append((kind, f"turned {abs(e['angle_deg']):.0f} deg {e['side']}{_swung_text(e)}; {name} needs {e['rule']}"
                          + (f" ({SPLIT_HINT})" if e.get("unsplit") else "")))
    if not e["forward_ok"]:
        out.append((FORWARD, _forward_text(e)))
    if not e["moved_on"]:
        out.append((MOVED_ON, f"did not move on after the turn ({e['moved_on_detail']})"))
    return out


def maneuver_problems(maneuver: str, e: dict[str, Any]) -> list[str]:
    """What is wrong with one judged maneuver, one sentence each, in the check-off's words (empty: nothing)."""
    return [text for _, text in maneuver_faults(maneuver, e)]


def fault_rule(kind: str, e: dict[str, Any]) -> str:
    """The rule a fault of ``kind`` broke, in the judge's words: the trigger's for a trigger that did not hold or
    fired late, the angle's for an angle or a side, the forward rule for forward motion."""
    if kind in (TRIGGER, LATE):
        return str(e.get("trigger_rule") or e["rule"])
    return FORWARD_RULE if kind == FORWARD else MOVED_ON_RULE if kind == MOVED_ON else str(e["rule"])


def performed_check(cfg: Any, maneuvers: list[dict[str, Any]],
                     recoveries: list[dict[str, Any]]) -> dict[str, Any]:
    """Enough maneuvers; when there are too few and some turns were counted as emergency-stop recoveries, the
    detail says why the first of them is not the maneuver (a student sees a turn and must learn why it did not
    count)."""
    passed = len(maneuvers) >= cfg.min_maneuvers
    detail = f"{len(maneuvers)} performed, required >= {cfg.min_maneuvers}"
    if not passed and recoveries:
        e = recoveries[0]
        n = len(recoveries)
        why = "; ".join(maneuver_problems(cfg.maneuver, e)) or "it is one"
        detail += (f"; {n} turn{'s' if n != 1 else ''} after a stop with the path blocked counted as "
                   f"emergency-stop recover{'ies' if n != 1 else 'y'}, not as {cfg.maneuver}: the one at "
                   f"t={e['t']:.1f} s {why} ({_readings_text(e, cfg.maneuver)})")
    return {"name": "maneuvers performed", "passed": passed, "value": len(maneuvers),
            "required": cfg.min_maneuvers, "detail": detail}


def _swung_text(e: dict[str, Any]) -> str:
    """A reversed turn's swing the old way after its first command, which its angle rule counted for it."""
    swung = e.get("swung_deg") or 0.0
    return f" (+{swung:.0f} deg swung on the old way after its first command: counted)" if swung >= 0.5 else ""


def maneuver_check(number: int, maneuver: str, e: dict[str, Any]) -> dict[str, Any]:
    """The report line of one maneuver episode: every rule it was held to, what is wrong with it in words."""
    sim = f" (sim {e['t'] + e['t0']:.2f} s)" if e.get("t0") else ""  # the terminal's and the video's clock
    faults = maneuver_faults(maneuver, e)
    problems = [text for _, text in faults]
    detail = (f"{maneuver} at t={e['t']:.2f} s{sim}: {e['trigger_detail']}"
              f"{'' if e['trigger'] else ' did not hold'}; turned {abs(e['angle_deg']):.0f} deg {e['side']}"
              f"{_swung_text(e)}, "
              f"rule {e['rule']}; forward command {e['forward_command']:.3f} m/s, motion {e['forward_motion']:.3f} m; "
              f"moved on: {e['moved_on_detail']}" + (f"; {_readings_text(e, maneuver)}; " + "; ".join(problems)
                                                     if problems else ""))
    # the rule said beside a failure is the rule of the fault (the trigger's for a trigger that did not hold)
    required = fault_rule(faults[0][0], e) if faults else e["rule"]
    check = {"name": f"maneuver {number}", "passed": e["passed"], "value": e["angle_deg"], "required": required,
             "detail": detail}
    if problems:
        check["reason"] = f"maneuver {number} " + "; ".join(problems) + f" ({_readings_text(e, maneuver)})"
        check["kinds"] = list(dict.fromkeys(kind for kind, _ in faults))
        check["rules"] = {kind: fault_rule(kind, e) for kind, _ in faults}
    return check
