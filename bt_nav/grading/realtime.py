"""A failed run at more than real time is run again before it stands: once more at the grade's speed, and (where a
speed can matter) at 1x; the grade says what each showed, and a failure stands unless the failed run's own evidence
excuses it.

Why: ``--exe`` runs the node's world faster than real time (``--rtf``: by default 0, as fast as the node keeps up,
often 8-12x; or a fixed factor) and gives the node sim time (``use_sim_time``). A node that times its turn or its
50 s with ``time.sleep`` or ``time.time`` is right on a robot at 1x and wrong in any faster simulation: at 5x its
90 deg pivot turns 450 deg. And a machine busy enough can starve
a right node for a wall second, long enough for the simulator's pace to stop waiting for it (its turn then runs on).
Neither is the node's mistake. But a node whose decisions change from run to run (an angle drawn, a side chosen)
can fail one run and pass the next for its own reasons: a passing re-run of it proves nothing.

The rule (:func:`decide`), for a failed run at ``rtf`` > 1 or 0 that a speed can change (:func:`speed_cannot_matter`;
at ``rtf`` 0 each run's speed is the factor it achieved, :func:`bt_nav.grading.exe.pace.achieved`, and the words
say it: "failed at 9.3x"):

- **load**: the failed run's own evidence shows its timing slipped (:func:`slipped_timing`: the simulator stopped
  waiting for the node's commands inside a failed maneuver, or while it was armed for any other failure) and a
  re-run passed: graded by the re-run, with a finding that names the load;
- **load** too: both re-runs passed, turning alike (a node that decides the same each time), the one at the
  grade's speed made the failed run's decisions, and the failed maneuver lasted
  longer (or shorter) in sim time than its twin and turned more (or less) for it (:func:`stretched_turn`): the
  node's timing slipped behind sim time, which a busy machine moves within the pace's bound;
- **wall clock**: its turns lasted about ``rtf`` times longer in sim time than at 1x, or its evaluation call came at
  1x only (:func:`wall_clock_evidence`), and the 1x run passed: graded at 1x, with a finding that names the wall
  clock;
- otherwise the failure stands, and the words say whether the runs differed (:func:`decisions_differ`: the
  maneuvers' sides or angles), whether a re-run passed, and how each ended.

Only failures a speed can have caused are run again: not a node that crashed while starting, whose arm service never
appeared, that only failed to declare a parameter, or whose scans or commands no message could carry (a wrong
topic, type or QoS). Those are fixed before the simulation moves. A run not graded (another program on its domain,
:mod:`bt_nav.grading.exe.run`) is no failure and is never run again here.

Cost: the grid's first such failure goes first (the probe); when both its re-runs fail, the other failures stand
without running again (a mistake fails at any speed); otherwise every one is run again. The re-runs at the grade's
speed live in ``<out>/rerun/``, those at 1x in ``<out>/realtime/``; resuming reuses the re-runs that finished.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from bt_nav_sim.pacing import CMD_VEL, PACE_FILE, read_pace_stops

from bt_nav.grading.exe.grid import ERROR, STOPPED, Workers, finished_runs, run_pool
from bt_nav.grading.exe.pace import achieved
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job, run_label
from bt_nav.ros.nodes.findings import CUT_OFF
from bt_nav.ros.supervise import StopRequest

Row = dict[str, Any]
#: Where a grid's re-runs go, below its ``--out``: at the grade's own speed, and at 1x.
RERUN_DIR, REALTIME_DIR = "rerun", "realtime"
#: Wall seconds a 1x run may take at least (a lab mission is ~75 sim s, start-up and shutdown besides).
REALTIME_LIMIT = 240.0


def failed_at_speed(row: Row | None) -> bool:
    """A run the node failed (not bt_nav's error, not stopped, not graded, not already decided on its re-runs)."""
    return bool(row) and not row["passed"] and row["outcome"] not in (ERROR, STOPPED) and "realtime" not in row \
        and "rerun" not in row and not row.get("not_graded")


#: Failed checks no speed can change: what the node declares at start-up (the lab's ``ros2 param list``), not what
#: it does in time. Every other check can (maneuvers, stops, lateness, collisions, distances, the evaluation call).
TIMELESS_CHECKS = frozenset({"parameters declared"})
#: The topic whose cut-off audit finding (:data:`bt_nav.ros.nodes.findings.CUT_OFF`: the node hears no scan or moves
#: no robot at any speed, a wrong topic, type or QoS) does not count: a node off sim time keeps the wall clock,
#: which is right at 1x.
WALL_CLOCK_TOPIC = "/clock"


def speed_cannot_matter(row: Row) -> str | None:
    """Why no speed of the simulation can change this failed run's verdict (a clause), or None when one can (the
    run then goes again at 1x). Only what is settled before the simulation moves: a crash while starting
    (:func:`bt_nav.grading.exe.log.node_crash`: importing or in an ``__init__``), the arm service never offered,
    ``parameters declared`` the only failed check, or scans or commands that no message could carry. A crash in a
    callback, a timeout and every other check may depend on time (a callback racing the first scan, a turn timed by
    the wall clock), so they do not count here."""
    if row["outcome"] == "node exited":
        crash = row.get("crash") or {}
        kind = str(crash.get("exception", "")).split(":")[0].rsplit(".", 1)[-1]  # ParameterNotDeclaredException
        return f"the node crashed while starting ({kind})" if crash.get("starting") else None
    verdict = row.get("verdict")
    if row["outcome"] != "verdict" or not verdict or verdict.get("timed_out"):
        return None
    if verdict.get("not_started"):
        return f"not judged: {verdict['not_started']}"
    failed = [check["name"] for check in verdict.get("checks", []) if not check.get("passed")]
    if failed and set(failed) <= TIMELESS_CHECKS:
        return f"only {', '.join(failed)} failed"
    cut = [found["clause"] for found in verdict.get("finding_kinds") or []
           if found.get("kind") in CUT_OFF and found.get("topic") != WALL_CLOCK_TOPIC]
    return cut[0] if cut else None


def checked(settings: ExeSettings) -> bool:
    """Whether a grid's failures are checked at 1x: the check on, and its runs faster than real time (``rtf`` > 1,
    or 0: as fast as the node keeps up, which is faster unless the node is too slow for the robot)."""
    return settings.realtime_check and not 0.0 < settings.rtf <= 1.0


def failed_jobs(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row]) -> list[Job]:
    """The jobs whose failure the grid checks at 1x: the failed runs a speed can have failed
    (:func:`speed_cannot_matter`); none at ``0 < rtf <= 1`` or with the check off (:func:`checked`)."""
    if not checked(settings):
        return []
    return [job for job in jobs if failed_at_speed(rows.get(job.key)) and speed_cannot_matter(rows[job.key]) is None]


def check_plan(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row]) -> list[str]:
    """What the terminal says before the 1x check: the failed run that goes first at 1x (and that the others follow
    if it passes there), then the failed runs not run again, grouped by why; nothing at ``0 < rtf <= 1``, with the check
    off, or without a failure."""
    if not checked(settings):
        return []
    again = failed_jobs(jobs, settings, rows)
    kept: dict[str, list[str]] = {}
    for job in jobs:
        row = rows.get(job.key)
        why = speed_cannot_matter(row) if row is not None and failed_at_speed(row) else None
        if why is not None:
            kept.setdefault(why, []).append(run_label(row))
    lines = []
    if again:
        others = len(again) - 1
        then = f", then the {others} other failed run{'s' if others > 1 else ''} that may depend on speed unless it " \
            "fails at both" if others else ""
        lines.append(f"bt-nav grade: {run_label(rows[again[0].key])} again {_at_speed(settings.rtf)} and at 1x real "
                     f"time before the failures stand{then} (--realtime-check off skips it): into "
                     f"{settings.out / RERUN_DIR}/ and {settings.out / REALTIME_DIR}/")
    if kept:
        head = "not re-run at 1x, no speed changes their verdict" if again else \
            "no failed run depends on speed, so none is re-run at 1x"
        groups = "; ".join(f"{_labels(labels)} ({why})" for why, labels in kept.items())
        lines.append(f"bt-nav grade: {head}: {groups}")
    return lines


def _labels(labels: list[str], shown: int = 3) -> str:
    """The first ``shown`` run labels, and how many more."""
    more = f" and {len(labels) - shown} more" if len(labels) > shown else ""
    return ", ".join(labels[:shown]) + more


def wall_clock_finding(evidence: str) -> str:
    """Why a run graded at 1x for its wall clock is not failed, on its evidence (:func:`wall_clock_evidence`)."""
    return (f"{evidence}: the node keeps time by the wall clock (time.sleep, time.time) where ROS time "
            "(self.get_clock(), sim time under use_sim_time) would keep it right in a simulation at any speed")


def _median(values: list[float]) -> float | None:
    values = sorted(values)
    return values[len(values) // 2] if values else None


#: The least ratio of two runs' turn durations (or evaluation calls) that counts as a wall clock: a busy machine
#: stretches a ROS-time turn by a few tenths of a second (measured: 0.1-0.3 s of a 2.6 s turn), never by 40 %.
WALL_CLOCK_MIN_RATIO = 1.4


def wall_clock_evidence(slow: dict[str, Any] | None, fast: dict[str, Any] | None, rtf: float) -> str | None:
    """What the two verdicts (at 1x and at ``rtf``) show of a node timing itself by the wall clock, in words; None
    where they show nothing of it. A wall-clock node's timed acts last the same *wall* time at every speed, so
    ``rtf`` times longer in sim time: its turns (the lab), or its 50 s (the homework: called at 1x, never or
    late at ``rtf``). A ROS-time node that overshot a turn under load took about as long in sim time."""
    if not slow or not fast:
        return None
    # the geometric midpoint of 1 (sim time) and rtf (wall time); at a factor near 1 (a slow node at --rtf 0) no
    # less than WALL_CLOCK_MIN_RATIO, beyond what a load's stretch of a ROS-time turn reaches
    threshold = max(rtf ** 0.5, WALL_CLOCK_MIN_RATIO)
    durations = [_median([m["settled"] - m["t"] for m in v.get("maneuvers") or [] if "settled" in m])
                 for v in (slow, fast)]
    if durations[0] and durations[1] is not None and durations[1] / durations[0] >= threshold:
        return (f"its turns lasted {durations[1]:.1f} sim s at {_factor(rtf)} and {durations[0]:.1f} sim s at 1x: "
                "the same wall time")
    called_slow, called_fast = slow.get("evaluation_called"), fast.get("evaluation_called")
    if called_slow and (called_fast is None or called_fast / called_slow >= threshold):
        at = "never" if called_fast is None else f"at t={called_fast:.1f} s"
        return f"its evaluation call came at t={called_slow:.1f} s at 1x and {at} at {_factor(rtf)}"
    return None



#: Degrees two runs' turns may differ and still be the same decision: twice the check-off's tolerance (each run's
#: turn may be off by that much from what the node meant).
SAME_ANGLE_DEG = 20.0
#: sim s: a failed turn that lasted this much longer or shorter than the same decision when run again was timed by
#: a node behind sim time (a 1 rad/s turn at 0.1 s is 6 deg; the jitter of a run's settling is a few hundredths)
STRETCH_MIN_S = 0.1
#: Degrees two re-runs' turns may differ to be a node that decides the same each time (half the check-off's tolerance)
CONSISTENT_DEG = 5.0


def _turns(verdict: dict[str, Any] | None) -> list[tuple[str, float]]:
    """A verdict's maneuvers as (side, degrees turned), in order."""
    return [(str(m.get("side")), abs(float(m.get("angle_deg", 0.0)))) for m in (verdict or {}).get("maneuvers") or []]


def _turn_words(turns: list[tuple[str, float]]) -> str:
    return ", ".join(f"{angle:.0f} deg {side}" for side, angle in turns) or "no maneuver"


def decisions_differ(failed: dict[str, Any] | None, again: dict[str, Any] | None) -> str | None:
    """How two runs' decisions differed, in words (None: they made the same ones, or there is nothing to compare):
    a maneuver turned to the other side, or by more than :data:`SAME_ANGLE_DEG` more or less, in the same place of
    the run's sequence. A node that draws its angle or its side (the lab's Randomizer, a coin for the side of a
    tie) differs from run to run for its own reasons, and one of its runs passing says nothing of another. The
    number of maneuvers alone is not compared (a turn that overshoots changes where the robot goes next)."""
    first, second = _turns(failed), _turns(again)
    for number, ((side1, angle1), (side2, angle2)) in enumerate(zip(first, second, strict=False), start=1):
        if side1 != side2 or abs(angle1 - angle2) > SAME_ANGLE_DEG:
            return f"maneuver {number} turned {angle1:.0f} deg {side1} in the failed run, {angle2:.0f} deg {side2} " \
                   f"when run again (turns: {_turn_words(first)}; again: {_turn_words(second)})"
    return None


def stretched_turn(failed: dict[str, Any] | None, again: dict[str, Any] | None,
                   slow: dict[str, Any] | None) -> str | None:
    """The failed run's first failed maneuver set beside the same maneuver of a passing re-run at the same speed
    that made the same decisions (:func:`decisions_differ` found none), in words (None: no such evidence): it lasted
    :data:`STRETCH_MIN_S` or more longer (or shorter) in sim time, and turned more (or less) for it. A node's turn
    lasts its own clock's or its odometry's time plus the change of its lag behind sim time, which the paced
    simulator bounds but a busy machine moves (measured: a 1 rad/s Retreat timed on the ROS clock turned 195 deg
    beside a test suite, 180 when run again); the same decision turned another way by its length alone is the
    machine's timing, not the node's choice. A node that draws its angles would look the same, so the two re-runs
    (``again`` and ``slow``, at 1x) must have turned alike up to that maneuver, within :data:`CONSISTENT_DEG`: a
    node that decides the same each time."""
    mine = next(((n, m) for n, m in enumerate((failed or {}).get("maneuvers") or [], start=1)
                 if not m.get("passed")), None)
    theirs = (again or {}).get("maneuvers") or []
    if mine is None or len(theirs) < mine[0] or "settled" not in mine[1] or "settled" not in theirs[mine[0] - 1]:
        return None
    first, second = _turns(again)[:mine[0]], _turns(slow)[:mine[0]]
    if len(second) < mine[0] or any(s1 != s2 or abs(a1 - a2) > CONSISTENT_DEG
                                    for (s1, a1), (s2, a2) in zip(first, second, strict=True)):
        return None
    number, m = mine
    other = theirs[number - 1]
    longer = (float(m["settled"]) - float(m["t"])) - (float(other["settled"]) - float(other["t"]))
    more = abs(float(m.get("angle_deg", 0.0))) - abs(float(other.get("angle_deg", 0.0)))
    if abs(longer) < STRETCH_MIN_S or longer * more <= 0.0:
        return None
    return (f"maneuver {number} lasted {float(m['settled']) - float(m['t']):.2f} sim s and turned "
            f"{abs(float(m['angle_deg'])):.0f} deg, the same turn {float(other['settled']) - float(other['t']):.2f} "
            f"s and {abs(float(other['angle_deg'])):.0f} deg when run again at the same speed: the node's timing "
            "slipped behind sim time")


def slipped_timing(verdict: dict[str, Any] | None, drops: list[float]) -> str | None:
    """The failed run's own evidence that its timing slipped, in words (None: none): the simulator stopped waiting
    for the node's commands (``drops``, sim times: :func:`run_drops`) while the node was
    armed, before its first failed maneuver settled (a slip after it cannot have caused it), or at any time armed
    when no maneuver failed. Sim time waits for the node's commands (:data:`bt_nav.grading.exe.run.FOLLOW_NODE`)
    unless the node says nothing for a wall second; a node that keeps commanding on its sim-time timer or its scans
    never meets that unless the machine starves it, and its turn then runs on without it (measured: a right pivot
    not scheduled for 1.5 s wall mid-turn at 5x, its one turn judged as 89 deg and then 2 deg). A drop while
    disarmed (the node has nothing to say) is no slip."""
    if not verdict or not drops:
        return None
    t0 = float(verdict.get("t0_sim") or 0.0)
    times = verdict.get("times") or {}
    armed, disarmed = times.get("activated"), times.get("deactivation_requested")
    if armed is None:
        return None
    failed = next(((n, m) for n, m in enumerate(verdict.get("maneuvers") or [], start=1) if not m.get("passed")), None)
    end = float("inf") if disarmed is None else float(disarmed)
    if failed is not None:
        end = min(end, float(failed[1].get("settled", failed[1]["t"])))
    inside = [t - t0 for t in drops if armed <= t - t0 <= end]
    if not inside:
        return None
    said = f"the simulator stopped waiting for the node's commands at t={inside[0]:.1f} s"
    if failed is not None:
        number, m = failed
        where = "inside" if inside[0] >= m["t"] - 0.05 else "before"
        said += f", {where} maneuver {number}, which failed (t={m['t']:.1f}-{m.get('settled', m['t']):.1f} s)"
    else:
        said += " while it was armed"
    return f"{said}: the node sent nothing for a wall second"


def run_drops(run_dir: str | Path) -> list[float]:
    """The sim times (s, the simulator's clock) at which a run's simulator stopped waiting for the node's
    ``cmd_vel``: the stops it wrote into the run directory's :data:`bt_nav_sim.pacing.PACE_FILE` at exit
    (:class:`bt_nav_sim.pacing.PaceStops`); none when it wrote none."""
    stops = read_pace_stops(Path(run_dir) / PACE_FILE) or []
    return [stop.t for stop in stops if stop.who == CMD_VEL]


def run_slipped(row: Row) -> str | None:
    """:func:`slipped_timing` of a run, read from its directory (the simulator's pace stops: :func:`run_drops`) and
    its verdict."""
    if not row.get("run_dir"):
        return None
    return slipped_timing(row.get("verdict"), run_drops(str(row["run_dir"])))


def _judged(row: Row) -> bool:
    """A re-run that says something of the node: not bt_nav's error, not stopped, not left without a grade."""
    return row["outcome"] not in (ERROR, STOPPED) and not row.get("not_graded")


def _failed_both(again: Row | None, slow: Row | None) -> bool:
    """Both re-runs of a failure ran, judged, and failed."""
    return all(r is not None and _judged(r) and not r["passed"] for r in (again, slow))


def _at_speed(rtf: float) -> str:
    """The grade's speed, before a run shows what it achieved: ``at 5x``, or ``as fast as the node keeps up``."""
    return f"at {rtf:g}x" if rtf > 0 else "as fast as the node keeps up"


def _factor(rtf: float) -> str:
    """A speed in words, from a factor achieved or set (``9.3x``, ``5x``, ``1x``)."""
    return f"{rtf:g}x" if rtf == round(rtf) else f"{rtf:.1f}x"


def _speed_of(row: Row | None, rtf: float) -> str:
    """A run's speed in words: ``at`` the grade's fixed ``rtf``, else what the run achieved (``at 9.3x``), else (no
    record of it) the words of ``--rtf 0``."""
    if rtf > 0 or ((row or {}).get("speed") or {}).get("rtf"):
        return f"at {_factor(achieved(row, rtf))}"
    return "as fast as the node kept up"


def _ended(row: Row | None, speed: str) -> str:
    """How one re-run at ``speed`` (:func:`_speed_of`: ``at 5x``) ended, in words."""
    if row is None:
        return f"{speed}: not run (stopped)"
    if not _judged(row):
        return f"{speed}: no verdict ({row['reason']})"
    if row["passed"]:
        return f"{speed}: passed"
    return f"{speed}: failed ({row['reason']})"


def decide(fast: Row, again: Row | None, slow: Row | None, rtf: float, slipped: str | None,
           again_planned: bool = True) -> tuple[Row, str]:
    """The row that stands for a failed run at ``rtf`` (``fast``) after its re-runs (``again`` at ``rtf``, ``slow``
    at 1x; None where one did not run), and the grade's words on it (see the module docstring for the rule).
    ``slipped``: :func:`slipped_timing` of the failed run. The row returned carries ``rerun``: each re-run's
    verdict, the decision (``load``, ``wall clock`` or ``stands``) and the words. At ``rtf`` 0 each run's speed is
    what it achieved (:func:`bt_nav.grading.exe.pace.achieved`): the words, the record and the wall clock's
    threshold use it. ``again_planned`` False: no re-run at ``rtf`` was meant (a wall clock found early,
    :mod:`bt_nav.grading.wallclock`), so the words do not name one that did not run."""
    failed_at, again_at = achieved(fast, rtf), achieved(again, rtf)
    said = [(again, _speed_of(again, rtf))] if again is not None or again_planned else []
    ended = "; ".join(_ended(r, speed) for r, speed in (*said, (slow, "at 1x")))
    again, slow = (r if r is not None and _judged(r) else None for r in (again, slow))
    runs = [(r, speed) for r, speed in ((again, again_at), (slow, 1.0)) if r is not None]
    head = f"failed {_speed_of(fast, rtf)} ({fast['reason']}); run again {ended}"
    passing = [r for r, _ in runs if r["passed"]]
    record = {"runs": [{"rtf": speed, "passed": r["passed"], "reason": r["reason"], "run_dir": r["run_dir"]}
                       for r, speed in runs], "failed": {"rtf": failed_at, "reason": fast["reason"],
                                                         "run_dir": fast["run_dir"]}}
    if slipped is not None and passing:
        said = (f"{head}: {slipped}, so the failure is put down to the machine's load, not to the node; graded by the "
                "re-run that passed")
        return _regraded(passing[0], fast, {**record, "decision": "load", "said": said}, said), said
    wall = wall_clock_evidence((slow or {}).get("verdict"), fast.get("verdict"), failed_at)
    if wall is not None and slow is not None and slow["passed"]:
        said = f"{head}: {wall_clock_finding(wall)}; graded at 1x"
        return _regraded(slow, fast, {**record, "decision": "wall clock", "said": said}, said), said
    # the decisions are compared at the same speed (at 1x a wall-clock node's turns differ for its clock); at 1x
    # only when the run at the grade's speed did not end with a verdict
    twin = again if again is not None else slow
    differed = decisions_differ(fast.get("verdict"), twin.get("verdict")) if twin is not None else None
    stretched = stretched_turn(fast.get("verdict"), again.get("verdict"), slow.get("verdict")) \
        if differed is None and again is not None and again["passed"] and slow is not None and slow["passed"] else None
    if stretched is not None:
        said = (f"{head}: {stretched}, so the failure is put down to the machine's load, not to the node; graded by "
                "the re-run that passed")
        return _regraded(again, fast, {**record, "decision": "load", "said": said}, said), said
    if differed is not None:
        why = (f"the runs differed ({differed}): a re-run that passes does not overturn a failure of a node whose "
               "decisions change from run to run" if passing else f"the runs differed ({differed})")
    elif passing:
        why = ("nothing in the failed run shows its timing slipped (the simulator waited for the node's commands "
               "throughout) or a wall clock")
    else:
        why = "it failed again"
    said = f"{head}: {why}; the failure stands"
    row = dict(fast)
    row["rerun"] = {**record, "decision": "stands", "said": said}
    row["realtime_probe"] = {"passed": bool(slow and slow["passed"]), "reason": said,
                             "run_dir": (slow or again or fast)["run_dir"]}
    return row, said


def _regraded(graded: Row, fast: Row, record: dict[str, Any], finding: str) -> Row:
    """The re-run's row that replaces the failed one, with what the failed run said and the finding."""
    row = dict(graded)
    row["rerun"] = record
    row["realtime"] = {"rtf": record["failed"]["rtf"], "passed": False, "reason": fast["reason"],
                       "run_dir": fast["run_dir"]}
    row["findings"] = [*row.get("findings", []), finding]
    row["reason"] = f"{row['reason']}; {finding}"
    return row


def rerun_settings(settings: ExeSettings) -> ExeSettings:
    """The grid's settings for its re-runs at its own speed, into ``<out>/rerun``."""
    return replace(settings, out=settings.out / RERUN_DIR)


def realtime_settings(settings: ExeSettings) -> ExeSettings:
    """The grid's settings at 1x, into ``<out>/realtime``."""
    return replace(settings, rtf=1.0, rtf_max=0.0, out=settings.out / REALTIME_DIR,
                   limit=max(settings.limit, REALTIME_LIMIT))


#: One grid to check: its jobs, settings and rows (job key -> row, replaced in place), and who sees a new row.
Grid = tuple[Sequence[Job], ExeSettings, dict[str, Row], Callable[[Row], None] | None]
#: Who hears the words on each re-run (the grid's index among those checked, and the line).
Say = Callable[[int, str], None]


def confirm_at_real_time(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row], workers: Workers,
                         stop: StopRequest | None = None, on_row: Callable[[Row], None] | None = None,
                         say: Callable[[str], None] | None = None) -> int:
    """Run one grid's failures again (see the module docstring), replacing ``rows`` (job key -> row) in place with
    the row that stands for each; ``on_row`` sees each row a re-run overturned (its reason ends with the words),
    ``say`` hears the words on each failure that stands (``bt-nav grade: <run>: ...``). Returns how many failures
    were overturned. Nothing runs at ``0 < rtf <= 1``, with the check off, or without a failure."""
    heard = None if say is None else (lambda _index, line: say(line))
    return confirm_grids([(jobs, settings, rows, on_row)], workers, stop, heard)[0]


def confirm_grids(grids: Sequence[Grid], workers: Workers, stop: StopRequest | None = None,
                  say: Say | None = None) -> list[int]:
    """:func:`confirm_at_real_time` for several grids (a class) in one pool: every grid's probe (its first failure
    to check, at both speeds) at once, then the other failures of the grids whose probe did not fail both re-runs;
    how many failures each grid had overturned. ``workers``: where the re-runs go, as the grids' runs went
    (:func:`~bt_nav.grading.exe.grid.run_pool`: threads here, or a Dask cluster's tasks)."""
    plans = []  # per grid: its failed jobs, its settings at its speed and at 1x, the re-runs finished there
    for jobs, settings, rows, _on_row in grids:
        failed = failed_jobs(jobs, settings, rows)
        fast, slow = rerun_settings(settings), realtime_settings(settings)
        done_fast, done_slow = _finished(fast, failed), _finished(slow, failed)
        # a probe already run (a resumed grade, or bt_nav.grading.wallclock's beside the grid's runs) goes first
        failed.sort(key=lambda job: not (job.key in done_fast and job.key in done_slow))
        plans.append((failed, fast, slow, done_fast, done_slow))

    def tasks(index: int, chosen: Sequence[Job]) -> list[tuple[Job, ExeSettings, dict[str, Row]]]:
        _, fast, slow, done_fast, done_slow = plans[index]
        return [task for job in chosen for task in ((job, fast, done_fast), (job, slow, done_slow))]

    probes = _run_missing([t for i, plan in enumerate(plans) if plan[0] for t in tasks(i, plan[0][:1])], workers, stop)
    rest = []
    for index, (failed, fast, slow, _, _) in enumerate(plans):
        if not failed:
            continue
        if not _failed_both(*(probes.get((str(s.out), failed[0].key)) for s in (fast, slow))):
            rest += tasks(index, failed[1:])
    results = {**probes, **_run_missing(rest, workers, stop)}
    return [_settle(index, grid, plans[index], results, say) for index, grid in enumerate(grids)]


def _settle(index: int, grid: Grid, plan: tuple[Any, ...], results: dict[tuple[str, str], Row],
            say: Say | None) -> int:
    """Decide every failure of one grid on its re-runs (:func:`decide`); a failure not run again (its probe failed
    at both speeds) stands with words that say so. Returns how many were overturned."""
    _jobs, settings, rows, on_row = grid
    failed, fast, slow = plan[0], plan[1], plan[2]
    overturned = 0
    probe_failed = bool(failed) and _failed_both(*(results.get((str(s.out), failed[0].key)) for s in (fast, slow)))
    for number, job in enumerate(failed):
        again, at_1x = (results.get((str(s.out), job.key)) for s in (fast, slow))
        if again is None and at_1x is None:
            if not (number and probe_failed):
                continue  # stopped before it ran: its failure stands as it was, unchecked
            probe = rows[failed[0].key]
            said = f"not run again: {run_label(probe)}, the first failure, failed again at both speeds; the " \
                   "failure stands"
            rows[job.key] = {**rows[job.key], "rerun": {"runs": [], "decision": "stands", "said": said}}
        else:
            fast_row = rows[job.key]
            rows[job.key], said = decide(fast_row, again, at_1x, settings.rtf,
                                         run_slipped(fast_row) if again or at_1x else None)
            overturned += bool(rows[job.key]["passed"])
            if on_row is not None and rows[job.key]["passed"]:
                on_row(rows[job.key])  # its line says it all: the reason ends with the words
                continue
        if say is not None:
            say(index, f"bt-nav grade: {run_label(rows[job.key])}: {said}")
    return overturned


def _finished(settings: ExeSettings, failed: Sequence[Job]) -> dict[str, Row]:
    """The re-runs of ``failed`` that finished in ``settings.out`` already (a resumed grade)."""
    return finished_runs(settings.out, failed) if failed and settings.out.is_dir() else {}


def _run_missing(tasks: Sequence[tuple[Job, ExeSettings, dict[str, Row]]], workers: Workers,
                 stop: StopRequest | None) -> dict[tuple[str, str], Row]:
    """Each (job, re-run settings, finished re-runs): the finished row, else the job run now (all in one pool); by
    (re-run directory, job key), nothing for a run that never started."""
    out = {(str(s.out), job.key): done[job.key] for job, s, done in tasks if job.key in done}
    todo = [(job, s) for job, s, done in tasks if job.key not in done]
    for index, row in run_pool(todo, workers, stop):
        if row is not None:
            out[(str(todo[index][1].out), todo[index][0].key)] = row
    return out
