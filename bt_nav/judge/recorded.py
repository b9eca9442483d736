"""The lab's check-off judged from a real robot's recording: the same judge, the same rules and words, fed from
odometry and recorded scans instead of ground truth and ray casts. Pure (no rclpy, no bag format): the bag reader
(:mod:`bt_nav.media.robotbag`) hands over a :class:`Recording` of plain series.

What a recording cannot say, the verdict does not guess (:func:`judge_recording`):

- a service call is not on a topic: unless the recording holds rosbag2's service events
  (``/toggle_navigation/_service_event``), the arming is taken as the first non-zero command (or ``armed_at``) and
  the checks that need the calls (static before and after, toggle_navigation answered) are *not judged*;
- a real robot has no collision sensor in its bag: "no collision" is not judged (the TA watches for contact);
- a maneuver during which /odom or /scan (or /cmd_vel) fell silent, or the robot did not follow its commands
  (handled, or stalled against something), is not judged, never passed; the data's contradictions are named.

PASS needs every judged check to pass and at least one complete, judged maneuver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from bt_nav.judge.checkoff_core import INTERRUPT_SLACK, CheckoffConfig, CheckoffJudge
from bt_nav.judge.checkoff_creep import CREEP_CHECK
from bt_nav.judge.checkoff_words import maneuver_check
from bt_nav.judge.feeds import (
    ODOMETRY_FORWARD_MOTION_MAX,
    SCAN_MAX_AGE,
    Disobeyed,
    Gap,
    ScanReadings,
    SourceReadings,
    gaps,
    not_followed,
    story,
)
from bt_nav.mission.scan import Scan

#: The report's one time zero, in the words the help, the terminal, the JSON and the film use (a window does not move
#: it: a turn keeps its time in every window that holds it).
TIME_ZERO = "the first /odom, /scan or /cmd_vel message"
PASSED, FAILED, INCOMPLETE = "PASSED", "FAILED", "INCOMPLETE"


#: The checks that need the toggle_navigation calls to be seen (the creep check: when the node was armed, and when a
#: disarm stopped it, which a first non-zero command does not say).
SERVICE_CHECKS = ("static before activation", "toggle_navigation answered", "static after deactivation",
                  CREEP_CHECK)
NO_COLLISION_SENSOR = "a robot's recording has no contact sensor: the TA watches for collisions"


@dataclass(frozen=True)
class ServiceCall:
    """One ``toggle_navigation`` call seen in the recording's service events (absolute seconds)."""

    t: float  # the request
    data: bool
    answered: float | None = None  # the response (None: never answered)
    success: bool = False
    message: str = ""


@dataclass
class Recording:
    """A real robot's run as plain series, every time on one clock (absolute seconds, sorted)."""

    odom: list[tuple[float, float, float, float]]  # t, x, y, yaw (the pose's yaw; the twist is never read)
    scans: list[tuple[float, Scan]]
    commands: list[tuple[float, float, float]]  # t, v, w
    calls: list[ServiceCall] | None = None  # None: no service events recorded (arming not visible)
    mount: tuple[float, float] = (0.0, 0.0)  # the LiDAR's (x, y) on the robot (from /tf when recorded)
    topics: dict[str, str] = field(default_factory=lambda: {"odom": "/odom", "scan": "/scan", "cmd": "/cmd_vel"})
    notes: list[str] = field(default_factory=list)  # what the reader did (clock offsets, skipped messages)
    announcements: list[tuple[float, str, str]] = field(default_factory=list)  # (t, logger, line) of /rosout
    #: the same lines with their severity (t, level, logger, line; rcl_interfaces/Log's 10 DEBUG ... 50 FATAL), for a
    #: film's console, which shows INFO and above; the judge reads only :attr:`announcements`' times
    log: list[tuple[float, int, str, str]] = field(default_factory=list)

    @property
    def start(self) -> float:
        firsts = [s[0][0] for s in (self.odom, self.scans, self.commands) if s]
        return min(firsts) if firsts else 0.0

    @property
    def end(self) -> float:
        lasts = [s[-1][0] for s in (self.odom, self.scans, self.commands) if s]
        return max(lasts) if lasts else 0.0


@dataclass(frozen=True)
class Window:
    """Which part of a recording is the check-off (seconds from its first message; None: from the start / to the
    end / the arming as the recording shows it)."""

    start: float | None = None
    end: float | None = None
    armed_at: float | None = None


def odometry_config(config: CheckoffConfig) -> CheckoffConfig:
    """The check-off's rules for odometry poses: the displacement allowance of a pivot's wheel slip."""
    return replace(config, forward_motion_max=max(config.forward_motion_max, ODOMETRY_FORWARD_MOTION_MAX))


def judge_recording(rec: Recording, config: CheckoffConfig, window: Window = Window()) -> dict[str, Any]:  # noqa: B008
    """The check-off verdict of a recording (the simulator's verdict JSON, plus ``not_judged``, ``flags`` (and the
    same as ``events``: kind, start, end and text of each) and ``feed``). ValueError: an empty window, or no /odom
    or /scan in it."""
    origin = rec.start
    a = origin + (window.start or 0.0)
    b = origin + window.end if window.end is not None else rec.end
    if not b > a:
        raise ValueError(f"the window t={a - origin:.1f}-{b - origin:.1f} s is empty")
    odom = [p for p in rec.odom if a <= p[0] <= b]
    if len(odom) < 2:
        raise ValueError(f"no {rec.topics['odom']} (nav_msgs/Odometry) in the window: the judge needs the pose")
    if not any(a - SCAN_MAX_AGE <= t <= b for t, _ in rec.scans):
        raise ValueError(f"no {rec.topics['scan']} (sensor_msgs/LaserScan) in the window: the judge needs the scans")
    cfg = odometry_config(config)
    source = ScanReadings(cfg.family(), cfg.half_width, rec.mount)
    for t, scan in rec.scans:
        if a - SCAN_MAX_AGE <= t <= b:
            source.add(t, scan)
    judge = CheckoffJudge(cfg, SourceReadings(source))
    judge.start(origin)  # one time zero for every window (TIME_ZERO)
    disobeyed = _disobeyed(rec, a, b)
    judge.apart = [(d.start, d.end) for d in disobeyed]  # never joined to a turn beside it (bt_nav.judge.segments)
    arming = _arm(judge, rec, window, a, b)
    for t, x, y, yaw in odom:
        judge.observe(t, x, y, yaw)
    for t, v, w in rec.commands:
        if a <= t <= b:
            judge.on_command(t, v, w)
    for t, logger, line in rec.announcements:  # the node's log lines: where it began a maneuver, as over DDS
        if a <= t <= b:
            judge.on_announcement(t, logger, line)
    judge._finish(b)  # noqa: SLF001 - the recording is the schedule: the report is at its end
    res = judge.results()
    armed = judge.activation_requested if judge.activation_requested is not None else a
    flags = _flags(rec, odom, a, b, armed, disobeyed)
    flags.gaps = [g for g in flags.gaps if g.topic != rec.topics["cmd"] or _armed_over(judge, g)]
    _restate(res, rec, cfg, flags, origin, (a, b))
    res["feed"] = {"poses": f"{rec.topics['odom']} (pose x, y and yaw; the twist is not read)",
                   "readings": f"{rec.topics['scan']} as recorded ({len(source.t)} scans, {source.skipped} skipped)",
                   "commands": rec.topics["cmd"], "arming": arming, "window": [a - origin, b - origin],
                   "t0": origin,  # the report's time zero on the recording's clock (s; epoch seconds on a robot)
                   "time_zero": TIME_ZERO,
                   "forward_motion_max": cfg.forward_motion_max, "lidar_mount": list(rec.mount), "notes": rec.notes}
    return res


def _arm(judge: CheckoffJudge, rec: Recording, window: Window, a: float, b: float) -> str:
    """Set the judge's schedule from what the recording shows; the arming in words."""
    if rec.calls is not None:
        _replay_calls(judge, [c for c in rec.calls if a <= c.t <= b])
        return "toggle_navigation service events"
    if window.armed_at is not None:
        judge.activation_requested = judge.activated = rec.start + window.armed_at
        return f"given: t={judge.activation_requested - a:.1f} s (--armed-at)"
    first = next((t for t, v, w in rec.commands if a <= t <= b and (v != 0.0 or w != 0.0)), None)
    if first is None:
        return "never: no non-zero command in the window"
    judge.activation_requested = judge.activated = first - 1e-3
    return f"the first non-zero command, t={first - a:.1f} s (service calls not visible)"


def _armed_over(judge: CheckoffJudge, gap: Gap) -> bool:
    """Whether the node was armed through ``gap`` (a disarmed node may fall silent: that is no gap in its commands),
    by the calls the recording shows."""
    off = [(judge.cycle_off_requested, judge.cycle_on_requested), (judge.deactivation_requested, None)]
    for start, end in off:
        if start is not None and gap.start >= start and (end is None or gap.end <= end + 1.0):
            return False
    return True


def _replay_calls(judge: CheckoffJudge, calls: list[ServiceCall]) -> None:
    """The recorded toggle_navigation calls as the judge's schedule, in order: the first true arms; a false then a
    true while armed are a toggle cycle (the judge knows one; the TA may make it); the last false disarms."""
    last_false = max((i for i, c in enumerate(calls) if not c.data), default=None)
    for i, call in enumerate(calls):
        if call.data and judge.activation_requested is None:
            judge.activation_requested = call.t
        elif not call.data and i == last_false and judge.activation_requested is not None:
            judge.deactivation_requested = call.t
        elif not call.data and judge.activation_requested is not None and judge.cycle_off_requested is None:
            judge.cycle_off_requested = call.t
        elif call.data and judge.cycle_off_requested is not None and judge.cycle_on_requested is None:
            judge.cycle_on_requested = call.t
        answer = "answered" if call.answered is not None else "no response"
        judge.on_activate_result(call.answered if call.answered is not None else call.t, call.data, call.success,
                                 answer, call.message)


@dataclass
class _Flags:
    gaps: list[Gap]
    disobeyed: list[Disobeyed]
    gap_turns: list[dict[str, str]] = field(default_factory=list)  # turns the robot made while a topic was silent
    last_move: float | None = None  # the last non-zero command, when the disarm is not visible (no service events)


def _disobeyed(rec: Recording, a: float, b: float) -> list[Disobeyed]:
    """Where the robot did not follow its commands, read over the whole recording (so a window's edges change
    nothing), those touching the window [a, b]."""
    if len(rec.odom) < 3:
        return []
    pose = np.asarray(rec.odom, dtype=np.float64)
    found = not_followed(pose[:, 0], np.unwrap(pose[:, 3]), rec.commands, xy=pose[:, 1:3])
    return [d for d in found if d.end >= a and d.start <= b]


def _flags(rec: Recording, odom: list[tuple[float, ...]], a: float, b: float, armed: float,
           disobeyed: list[Disobeyed]) -> _Flags:
    """Where the recording falls silent (from the arming on) or contradicts the commands."""
    found = gaps(rec.topics["odom"], [p[0] for p in odom], within=(max(a, armed), b))
    found += gaps(rec.topics["scan"], [t for t, _ in rec.scans if a <= t <= b], within=(max(a, armed), b))
    found += gaps(rec.topics["cmd"], [t for t, _, _ in rec.commands if max(a, armed) <= t <= b])
    t = np.asarray([p[0] for p in odom])
    uyaw = np.unwrap(np.asarray([p[3] for p in odom]))
    cmds = [c for c in rec.commands if a <= c[0] <= b]
    flags = _Flags(sorted(found, key=lambda g: g.start), disobeyed)
    if rec.calls is None:
        flags.last_move = max((c[0] for c in cmds if c[1] != 0.0 or c[2] != 0.0), default=None)
    for g in flags.gaps:  # a turn nobody saw commanded (or read its scans): not judged, and said
        turned = math.degrees(float(np.interp(g.end, t, uyaw) - np.interp(g.start, t, uyaw)))
        seen = any(g.start < float(turn["end"]) for turn in flags.gap_turns)  # one turn, several silent topics
        if abs(turned) >= 20.0 and g.topic != rec.topics["odom"] and not seen:
            flags.gap_turns.append({"name": "a turn", "end": str(g.end), "why": f"the robot turned {turned:+.0f} "
                                                                                 f"deg while there was {g.text(a)}"})
    return flags


def _episode_problem(e: dict[str, Any], flags: _Flags, cfg: CheckoffConfig, rec: Recording, t0: float,
                     window: tuple[float, float]) -> str:
    """Why an episode cannot be judged on this recording (empty: it can): the window cuts it, a topic fell silent in
    it, the robot did not follow its commands in it (what it did instead, and when), or its end is the run's."""
    start, end = t0 + e["t"] - cfg.scan_age, t0 + e["settled"]
    cut = _cut_by_window(e, rec, cfg, t0, window)
    if cut:
        return cut
    for g in flags.gaps:
        if g.start < end and g.end > start:
            return g.text(t0)
    events = _events_of(flags.disobeyed, start, end)
    if events:
        said = story(events, t0)
        last_command = max((c[0] for c in rec.commands if window[0] <= c[0] <= window[1]), default=window[1])
        if not any(c[0] > events[-1].end and (c[1] or c[2]) for c in rec.commands if c[0] <= window[1]) \
                and window[1] - max(events[-1].end, last_command) < 3.0:
            said += f"; then the {'recording' if window[1] >= rec.end else 'window'} ends (t={window[1] - t0:.1f} s)"
        return said
    if e.get("readings") is None:
        return "no scan at its start"
    last = flags.last_move
    only_angle = not e["angle_ok"] and e["forward_ok"] and e["trigger"] and e["moved_on"] and not e.get("late")
    if last is not None and t0 + e["settled"] >= last - INTERRUPT_SLACK and only_angle:
        return (f"its turn ended with the run's last command (t={last - t0:.1f} s), as a disarm ends it, and the "
                "recording shows no service calls: its angle is not judged")
    return ""


def _events_of(events: list[Disobeyed], start: float, end: float) -> list[Disobeyed]:
    """The intervals set apart that touch an episode (from its scan's age before its first command to its settling),
    in time order."""
    return sorted((d for d in events if d.start < end and d.end > start), key=lambda d: d.start)


def _cut_by_window(e: dict[str, Any], rec: Recording, cfg: CheckoffConfig, t0: float,
                   window: tuple[float, float]) -> str:
    """Whether the window begins or ends inside the episode's turn (one turn's commands on both sides of an edge:
    the last before it and the first after it, within half a second, both turning): then the window holds only a
    piece of it, which is not the maneuver."""
    a, b = window

    def across(edge: float) -> bool:
        before = [c for c in rec.commands if edge - 0.5 <= c[0] < edge]
        after = [c for c in rec.commands if edge <= c[0] <= edge + 0.5]
        turning = cfg.rotation_min_rate
        return bool(before and after) and abs(before[-1][2]) >= turning and abs(after[0][2]) >= turning

    if t0 + e["t"] - a < 1.0 and across(a):
        return f"its turn began before the window (t={a - t0:.1f} s): only its end is in it"
    if b - (t0 + e["settled"]) < 1.0 and across(b):
        return f"the window ends (t={b - t0:.1f} s) during its turn"
    return ""


def sheet_words(e: dict[str, Any], cfg: CheckoffConfig) -> str:
    """The trigger as the sheet states it and the reading accepted beside it (``front 0.40 m: the sheet's 0.3 m did
    not hold; accepted at safety_distance 0.5 m``): a maneuver line must not print an accepted reading as the rule."""
    trigger, margin = cfg.spec.trigger, f" (+{cfg.trigger_margin:.2f} m sensor-noise tolerance)"
    read = str(e["trigger_detail"]).split(" < ", 1)[0]
    r = e.get("readings") or {}
    keys = ("left", "right") if trigger.reads == "sides" else ("front",)
    values = [r.get(k) for k in keys]
    nearest = max((v if v is not None else math.inf) for v in values)
    sheet = cfg.distance(trigger.distance)
    if nearest < sheet + cfg.trigger_margin:
        return f"{read} < the sheet's {sheet:g} m{margin}"
    if not trigger.or_braked_at:
        return f"{read}: the sheet's {sheet:g} m{margin}"
    other = cfg.distance(trigger.or_braked_at)
    if e["trigger"]:
        return f"{read}: the sheet's {sheet:g} m did not hold; accepted at {trigger.or_braked_at} {other:g} m{margin}"
    return (f"{read}: neither the sheet's {sheet:g} m nor the accepted {trigger.or_braked_at} {other:g} m held"
            f"{margin}")


def _maneuver_line(number: int, e: dict[str, Any], cfg: CheckoffConfig) -> dict[str, Any]:
    """A judged maneuver's line in the sheet's words, on the report's clock (no simulator's ``(sim ... s)``)."""
    words = sheet_words(e, cfg)
    e2 = {**e, "t0": 0.0, "trigger_detail": words}
    check = maneuver_check(number, cfg.maneuver, e2)
    if not e["trigger"]:  # "... did not hold" is already said in the sheet's words
        for key in ("detail", "reason"):
            if key in check:
                check[key] = check[key].replace(f"{words} did not hold", words, 1).replace(
                    f"({words} is not true)", f"({words})")
    return check


def _restate(res: dict[str, Any], rec: Recording, cfg: CheckoffConfig, flags: _Flags, t0: float,
             window: tuple[float, float]) -> None:
    """The judge's verdict restated for what the recording supports: checks it cannot judge moved to
    ``not_judged``, maneuvers in a gap, a contradiction or cut by the window too, the verdict from the judged ones."""
    not_judged: list[dict[str, str]] = []
    keep: dict[str, dict[str, Any]] = {}
    for kind, key in (("maneuver", "maneuvers"), ("recovery", "recovery_turns")):
        judged = []
        for number, e in enumerate(res[key], 1):
            why = _episode_problem(e, flags, cfg, rec, t0, window)
            e["not_judged"] = why or None
            name = f"maneuver {number}" if kind == "maneuver" else "recovery turn"
            if why:
                turned = f"turned {e['angle_deg']:+.0f} deg"
                not_judged.append({"name": name, "why": f"at t={e['t']:.1f} s, {turned}: {why}"})
            else:
                judged.append(e)
                if kind == "maneuver":
                    keep[name] = e
        res[f"judged_{key}"] = judged
    checks = []
    for c in res["checks"]:
        name = c["name"]
        if name in SERVICE_CHECKS and rec.calls is None:
            events = rec.topics.get("service", "service event")
            not_judged.append({"name": name, "why": f"service calls not visible: no {events} in the recording"})
        elif name == "no collision":
            not_judged.append({"name": name, "why": NO_COLLISION_SENSOR})
        elif name.startswith("maneuver ") and name not in keep:
            continue
        elif name.startswith("maneuver "):
            checks.append(_maneuver_line(int(name.split()[1]), keep[name], cfg))
        elif name == "maneuvers performed":
            checks.append(_performed(res, cfg, len(flags.gap_turns)))
        elif name == "recovery turns":
            bad = [e for e in res["judged_recovery_turns"] if not e["passed"]]
            checks.append({**c, "passed": not bad, "value": len(res["judged_recovery_turns"])})
        else:
            checks.append(c)
    res["checks"] = checks
    res["not_judged"] = not_judged + [{"name": n["name"], "why": n["why"]} for n in flags.gap_turns]
    res["flags"] = [g.text(t0) for g in flags.gaps] + [d.text(t0) for d in flags.disobeyed]
    # the same intervals with their times (s on the report's clock), so a film marks each while it happens
    res["events"] = [{"kind": "gap", "start": g.start - t0, "end": g.end - t0, "text": g.text(t0)} for g in flags.gaps]
    res["events"] += [{"kind": d.kind, "start": d.start - t0, "end": d.end - t0, "text": d.text(t0)}
                      for d in flags.disobeyed]
    res["verdict"] = _verdict(res)
    res["passed"] = res["verdict"] == PASSED


def _verdict(res: dict[str, Any]) -> str:
    """PASSED: at least one judged maneuver passed and no judged check failed; FAILED: a judged check failed;
    INCOMPLETE: nothing failed, but no maneuver could be judged (never PASSED on what could not be seen)."""
    if not all(c["passed"] for c in res["checks"] if c.get("status") != INCOMPLETE):
        return FAILED
    if any(e["passed"] for e in res["judged_maneuvers"]):
        return PASSED
    return INCOMPLETE


def _performed(res: dict[str, Any], cfg: CheckoffConfig, unseen: int = 0) -> dict[str, Any]:
    """The count of maneuvers: seen, judged, passed and failed (``unseen``: turns made while a topic was silent).
    Its status is the maneuvers' own: FAILED when one judged failed, INCOMPLETE when none could be judged."""
    judged = res["judged_maneuvers"]
    passed = sum(1 for e in judged if e["passed"])
    failed = len(judged) - passed
    seen = len(res["maneuvers"]) + unseen
    need = max(1, cfg.min_maneuvers)
    detail = f"{seen} seen: {len(judged)} judged, {passed} passed, {failed} failed"
    if seen > len(judged):
        detail += f"; {seen - len(judged)} not judged"
    detail += f"; required: >= {need} judged and passed, none failed"
    ok = passed >= need and failed == 0
    status = PASSED if ok else FAILED if failed or judged else INCOMPLETE
    return {"name": "maneuvers", "passed": ok, "status": status, "value": len(judged), "judged": len(judged),
            "passed_count": passed, "failed": failed, "not_judged": seen - len(judged), "required": need,
            "detail": detail}


def report_lines(res: dict[str, Any]) -> list[str]:
    """The verdict as the simulator's judge prints it (``name (detail): PASSED|FAILED``), then what was not judged
    and what the data contradicts, then the overall verdict."""
    lines = [f"{c['name']} ({c['detail']}): {c.get('status') or (PASSED if c['passed'] else FAILED)}"
             for c in res["checks"]]
    lines += [f"{n['name']}: NOT JUDGED ({n['why']})" for n in res.get("not_judged", [])]
    lines += [f"data: {f}" for f in res.get("flags", [])]
    verdict = res.get("verdict") or (PASSED if res["passed"] else FAILED)
    if verdict == INCOMPLETE:
        why = "; ".join(f"{n['name']}: {n['why']}" for n in res.get("not_judged", []) if n["name"].startswith(
            ("maneuver", "a turn"))) or "no maneuver was seen"
        verdict += f" (no maneuver could be judged: {why})"
    lines.append(f"overall: {verdict}")
    return lines

