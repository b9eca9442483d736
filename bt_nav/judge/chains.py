"""Maneuvers back to back: where one continuous rotation holds several of a node's maneuvers, and how a chain of
them is judged (the check-off judge's, :mod:`bt_nav.judge.checkoff_core`; pure, no rclpy).

Why: a node whose trigger still holds after its turn starts the next one at once (a Randomizer in a dead end whose
front stays blocked, a Retreat still squeezed after its spin). The commands then never pause, and a judge that
takes one continuous rotation as one maneuver sees a 397 deg Randomizer, or one 4329 deg Retreat instead of 24 of
them, and tells the student the wrong thing.

A rotation is split only where all three hold (:func:`split_run`), the earliest such point each time:

(a) the node marks a new maneuver there (:func:`marks`): a line it logged (``/rosout``, any words: the lab
    template logs one as each maneuver starts) within :data:`ANNOUNCE_WINDOW` s, a pause in its commands, or a step
    in its commanded rate (a rise, or a drop to a new steady rate; a closed loop's gradual slow-down is not one);
(b) the judge's own readings show the trigger held at that moment, for a pause or a rate step (an announced start
    splits whatever the readings say: each maneuver the node announced is judged as it made it, its trigger
    included; measured: three announced right Randomizers of 96, 142 and 103 deg read as one of 348 deg);
(c) the part before it is within the maneuver's angle range;

and the rest of the rotation turns at least half the smallest maneuver, unless the disarm cut it short: a line the
node logs as a maneuver ends (``done: turned 114 deg``) falls within the window of the turn's last commands, and must
not cut off its last few degrees as a maneuver of their own (measured: bt_nav's own executive on a lagging base).

A rotation with no such point stays one maneuver, judged as before; a too-large one is told how to make its
maneuvers visible (:data:`SPLIT_HINT`). Maneuvers the robot made without travelling between them form a chain
(:func:`chains`), judged by its maneuver's purpose (:class:`bt_nav.mission.maneuver_spec.Purpose`,
:func:`chain_verdict`): a search (the Randomizer, the Smart Pivot) that turns again on a still-blocked front is
searching on, and passes with a finding that counts the turns; an exit (the Retreat) that never leads out before the
disarm failed its purpose ("never moved on"): a finding too, as the sheet only implies driving out, unless the
course makes it strict (:mod:`bt_nav.judge.findings`).
"""

from __future__ import annotations

import bisect
import math
import statistics
from collections.abc import Sequence
from typing import Any

from bt_nav.judge.findings import BACK_TO_BACK, SEARCH_CHAIN, finding

#: s: an episode whose last turning command came this close to the disarm request (or after it) was
#: stopped by the disarm, as it must be: its angle is not judged. A node that publishes from its scan callback
#: sends its last turning command up to a scan period (the LDS-01's 0.2 s) before the disarm reaches it.
INTERRUPT_SLACK = 0.3
#: s: a line the node logged this close to a point of its rotation marks a new maneuver there.
ANNOUNCE_WINDOW = 0.3
#: A gap between two turning commands longer than this many times their usual period (and at least
#: :data:`PAUSE_MIN` s) is a pause: the node stopped sending for a moment, as between two maneuvers.
PAUSE_FACTOR = 2.5
#: s: the shortest silence that is a pause. The paced simulator may lead a graded node by its command period plus
#: 0.1 s, and up to a scan period more for a node answering its scans (bt_nav_sim.pacing.Followers): a node that a
#: busy machine delays leaves silences that long in sim time without pausing (measured: a right Randomizer's one
#: announced 176 deg turn read as 125 + 50 deg on a loaded machine).
PAUSE_MIN = 0.6
#: rad/s and fraction: a step in the commanded rate at least this large (both) marks a new maneuver.
RATE_STEP = 0.05
RATE_FRACTION = 0.2
#: What a too-large rotation's failure adds: how a node makes its maneuvers back to back visible.
SPLIT_HINT = ("if these were several maneuvers back to back, none was seen to begin: log a line as each one starts "
              "(as the template's execute_rotation_maneuver does), or pause or change the turn rate between them")


def _rate_step(commands: Sequence[tuple[float, float, float]], i: int, b: int, min_turn: float) -> bool:
    """Whether the commanded rate steps at command ``i`` (of a run ending at ``b``): a rise or a reversal, or a drop
    to a rate the node then keeps while turning at least ``min_turn`` rad (a new maneuver's steady rate, not a
    closed loop slowing down towards its target, nor its last few degrees at a minimum rate)."""
    w_before, w = commands[i - 1][2], commands[i][2]
    if abs(w - w_before) < max(RATE_STEP, RATE_FRACTION * max(abs(w), abs(w_before))):
        return False
    if w * w_before < 0 or abs(w) > abs(w_before):
        return True
    j = i
    while j < b and abs(commands[j + 1][2] - w) <= 0.02 * abs(w):
        j += 1
    return (commands[j][0] - commands[i][0]) * abs(w) >= min_turn


def marks(commands: Sequence[tuple[float, float, float]], a: int, b: int, announcements: Sequence[float],
          min_turn: float = 0.0) -> list[tuple[int, str]]:
    """The command indices in ``(a, b]`` at which the node marks a new maneuver, and how (``announcement``,
    ``pause``, ``rate change``), in order; ``min_turn`` (rad): how far a drop's new rate must turn to count
    (:func:`_rate_step`). An announcement marks the nearest pause or rate step within :data:`ANNOUNCE_WINDOW` of
    it, else the first command at or after it (its maneuver's first command follows the line), else the nearest
    command within the window. A node that announced the rotation's first maneuver announces its maneuvers: then
    only its announcements mark (a pause or a rate step inside an announced turn is the machine's or its control
    loop's, not a maneuver it did not announce)."""
    found: dict[int, str] = {}
    gaps = [commands[i][0] - commands[i - 1][0] for i in range(a + 1, b + 1)]
    usual = statistics.median([g for g in gaps if g > 0.0] or [0.0])
    for i in range(a + 1, b + 1):
        if commands[i][0] - commands[i - 1][0] > max(PAUSE_MIN, PAUSE_FACTOR * usual):
            found[i] = "pause"
        elif _rate_step(commands, i, b, min_turn):
            found[i] = "rate change"
    first_t, last_t = commands[a][0], commands[b][0]
    announced: dict[int, str] = {}
    for ta in announcements:
        if not first_t - ANNOUNCE_WINDOW <= ta <= last_t + ANNOUNCE_WINDOW:
            continue
        near = [i for i in range(a + 1, b + 1) if abs(commands[i][0] - ta) <= ANNOUNCE_WINDOW]
        if not near:
            continue
        marked = [i for i in near if i in found]
        after = [i for i in near if commands[i][0] >= ta - 1e-9]
        if marked or after:  # a line after the rotation's last command is no mark in it (a "done" line)
            announced[min(marked, key=lambda i: abs(commands[i][0] - ta)) if marked else after[0]] = "announcement"
    if any(abs(ta - first_t) <= ANNOUNCE_WINDOW for ta in announcements):
        return sorted(announced.items())  # a node that announces its maneuvers marks each one so, and only so
    return sorted({**found, **announced}.items())


def split_run(judge: Any, a: int, b: int) -> list[tuple[int, int, float | None, str]]:
    """Run ``a..b`` of ``judge``'s commands as back-to-back maneuvers: ``(first, last, cut, why)`` each, ``cut`` the
    time the next one began (None for the last piece), ``why`` what marked it. See the module docstring."""
    cfg, commands = judge.config, judge.commands
    if not judge._t:
        return [(a, b, None, "")]
    rule = cfg.spec.angle
    pieces: list[tuple[int, int, float | None, str]] = []
    first, since = a, commands[a][0]
    half = 0.5 * math.radians(rule.low_deg - cfg.angle_tolerance_deg)  # half the smallest maneuver
    last = commands[b][0]
    cut_short = last >= judge.next_disarm(commands[a][0]) - INTERRUPT_SLACK
    turning_next = next((t for t, _, w in commands[b + 1:] if abs(w) >= cfg.rotation_min_rate), math.inf)
    end_yaw = judge._interp(judge._uyaw, judge._settled_at(last, min(last + cfg.settle_timeout, turning_next)))
    for i, why in marks(commands, a, b, judge.announcement_times(), half):
        if i <= first:
            continue
        t = commands[i][0]
        at = judge._interp(judge._uyaw, t)
        turned = math.degrees(at - judge._interp(judge._uyaw, since))
        if not rule.holds(abs(turned), cfg.angle_tolerance_deg):
            continue
        if abs(end_yaw - at) < half and not cut_short:
            continue
        if why != "announcement" and not judge._trigger(judge._readings_at(t)[0])[0]:
            continue
        pieces.append((first, i - 1, t, why))
        first, since = i, t
    return [*pieces, (first, b, None, "")]


def chains(judge: Any, episodes: Sequence[dict[str, Any]]) -> list[list[dict[str, Any]]]:
    """The maneuvers made back to back, two or more in a row without the robot travelling ``move_on_distance``
    between one's settling and the next one's start (recovery turns break a chain)."""
    out: list[list[dict[str, Any]]] = []
    run: list[dict[str, Any]] = []
    for e in episodes:
        if e["kind"] != "maneuver":
            run = []
            continue
        if run:
            prev = run[-1]
            gap = judge._path_length(prev["settled"] + prev["t0"], e["t"] + e["t0"])
            if gap >= judge.config.move_on_distance:
                run = []
        run.append(e)
        if len(run) == 2:
            out.append(run)
    return out


def _start_readings(chain: Sequence[dict[str, Any]], reads: str) -> str:
    """The trigger's readings at each start of a chain, compactly (``front at each start, m: 0.42, 0.44``)."""
    def fmt(value: Any) -> str:
        return "-" if value is None else f"{value:.2f}"
    if reads == "sides":
        values = [f"{fmt((e['readings'] or {}).get('left'))}/{fmt((e['readings'] or {}).get('right'))}"
                  for e in chain]
        return "left/right at each start, m: " + ", ".join(values)
    return "front at each start, m: " + ", ".join(fmt((e["readings"] or {}).get("front")) for e in chain)


def chain_verdict(judge: Any, chain: Sequence[dict[str, Any]], now: float) -> tuple[bool, str]:
    """Whether a chain served its maneuver's purpose, and what it was in words. An exit chain whose robot never
    travelled ``move_on_distance`` after its last maneuver, before the next disarm (or the report), fails: it never
    moved on. A search chain passes (each turn began with its trigger holding: the search went on)."""
    cfg = judge.config
    spec = cfg.spec
    last = chain[-1]
    t0 = last["t0"]
    settle = last["settled"] + t0
    end = min(judge.next_disarm(last["t"] + t0), now)
    travelled = judge._path_length(settle, end) if end > settle else 0.0
    total = sum(abs(e["angle_deg"]) for e in chain)
    n, title, rule = len(chain), spec.title, spec.angle
    what = f"{n} {title}s back to back ({total:.0f} deg in place)"
    when = f"t={chain[0]['t']:.1f}-{last['settled']:.1f} s"
    loose = cfg.limits()[0]
    readings = _start_readings(chain, spec.trigger.reads)
    if spec.purpose.kind == "exit" and (last["interrupted"] or travelled < cfg.move_on_distance):
        size = f"{rule.low_deg:.0f}" if rule.low_deg == rule.high_deg else f"{rule.low_deg:.0f}-{rule.high_deg:.0f}"
        return False, (f"never moved on: {what}: after each {size} deg {title} the {spec.trigger.words} still read "
                       f"< {loose:g} m and it turned again; it never drove out {spec.purpose.words} ({when}; "
                       f"{readings})")
    return True, (f"{what}, {when}: each began with its trigger ({spec.trigger.words} < {loose:g} m) still "
                  f"holding, so it turned again {spec.purpose.words} ({readings})")


def chain_check(judge: Any, episodes: Sequence[dict[str, Any]], now: float) -> tuple[dict[str, Any] | None,
                                                                                      list[dict[str, Any]]]:
    """The "back-to-back maneuvers" check (None without a chain to judge) and its findings (records of
    :mod:`bt_nav.judge.findings`). A chain is a finding: a search's counts its turns (a student sees that the judge
    counted each), an exit's that never moved on says so, as the sheet only implies driving out (its Retreat is "a
    full 180 deg spin to exit"). Only a kind the course makes strict (``strict_findings``) fails the check. A chain
    holding a failed maneuver is judged only when it failed its purpose (that maneuver's own line says why)."""
    verdicts = []
    for chain in chains(judge, episodes):
        ok, text = chain_verdict(judge, chain, now)
        if not ok or all(e["passed"] for e in chain):
            verdicts.append((BACK_TO_BACK if not ok else SEARCH_CHAIN, text))
    if not verdicts:
        return None, []
    failed = [text for kind, text in verdicts if judge.config.strict(kind)]
    found = [finding(kind, text) for kind, text in verdicts if not judge.config.strict(kind)]
    check: dict[str, Any] = {"name": "back-to-back maneuvers", "passed": not failed, "value": len(verdicts),
                             "required": f"each chain {judge.config.spec.purpose.words}" + (
                                 " (strict)" if failed else " (else a finding)"),
                             "detail": "; ".join(text for _, text in verdicts)}
    if failed:
        check["reason"] = failed[0]
    return check, found


def turning_point(judge: Any, last: float, nxt: float, now: float, w_before: float, w_after: float) -> float:
    """Where one turn ends and the next, begun before the robot settled, starts: the yaw's extremum when the
    next turns the other way (the robot coasts on for up to a fifth of a second first); else where the node stopped
    turning, its first command between them that turns no more (a zero twist it sent and overrode with the next
    turn in one callback never slowed the robot: the node's own boundary is the only one); else the slowest
    moment of the rotation between them."""
    sign = 1.0 if w_before > 0 else -1.0
    ts, uy = judge._t, judge._uyaw
    i, j = bisect.bisect_left(ts, last), bisect.bisect_right(ts, min(nxt + 0.5, now))
    if j - i < 2:
        return nxt
    if w_before * w_after < 0:
        k = max(range(i, j), key=lambda n: sign * uy[n])
        return ts[k]
    stopped = next((t for t, _, w in judge.commands if last < t <= nxt and abs(w) < judge.config.rotation_min_rate),
                   None)
    if stopped is not None:
        return stopped
    k = min(range(i + 1, j), key=lambda n: sign * (uy[n] - uy[n - 1]) / max(ts[n] - ts[n - 1], 1e-9))
    return ts[k - 1]
