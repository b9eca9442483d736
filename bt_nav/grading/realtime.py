"""A failure at more than real time is checked at 1x before it stands: a node that keeps time by the wall clock is
not failed for the grader's speed.

Why: ``--exe`` runs the node's world faster than real time (``--rtf``, 5 by default) and gives the node sim time
(``use_sim_time``). A node that times its turn or its 50 s with ``time.sleep`` or ``time.time`` is right on a robot
at 1x and wrong in any faster simulation: at 5x its 90 deg pivot turns 450 deg, its evaluation comes at 250 sim s.
The grader must never fail a right node, so before failures stand one failed run is run again at 1x (the probe).
If it passes there, every failed run is run at 1x, graded there, and carries a finding that names the wall clock;
a node that fails at 1x too keeps its verdicts (its mistake is not the speed), at the cost of one run at 1x.

Only failures a speed can have caused are run again (:func:`speed_cannot_matter`): not a node that crashed while
starting, whose arm service never appeared, that only failed to declare a parameter, or whose scans or commands
no message could carry (a wrong topic, type or QoS). Those are fixed before the simulation moves.

The 1x runs live in ``<out>/realtime/`` (the faster runs stay where they are, linked from the finding); resuming
reuses the 1x runs that finished there.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from bt_nav.grading.exe.grid import ERROR, STOPPED, finished_runs, run_pool
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job, run_label
from bt_nav.ros.nodes.findings import CUT_OFF
from bt_nav.ros.supervise import StopRequest

Row = dict[str, Any]
#: Where a grid's 1x runs go, below its ``--out``.
REALTIME_DIR = "realtime"
#: Wall seconds a 1x run may take at least (a lab mission is ~75 sim s, start-up and shutdown besides).
REALTIME_LIMIT = 240.0


def failed_at_speed(row: Row | None) -> bool:
    """A run the node failed (not bt_nav's error, not stopped, not already a 1x run)."""
    return bool(row) and not row["passed"] and row["outcome"] not in (ERROR, STOPPED) and "realtime" not in row


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


def failed_jobs(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row]) -> list[Job]:
    """The jobs whose failure the grid checks at 1x: the failed runs a speed can have failed
    (:func:`speed_cannot_matter`); none at ``rtf <= 1`` or with the check off."""
    if settings.rtf <= 1.0 or not settings.realtime_check:
        return []
    return [job for job in jobs if failed_at_speed(rows.get(job.key)) and speed_cannot_matter(rows[job.key]) is None]


def check_plan(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row]) -> list[str]:
    """What the terminal says before the 1x check: the failed run that goes first at 1x (and that the others follow
    if it passes there), then the failed runs not run again, grouped by why; nothing at ``rtf <= 1``, with the check
    off, or without a failure."""
    if settings.rtf <= 1.0 or not settings.realtime_check:
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
        then = f", then the {others} other failed run{'s' if others > 1 else ''} that may depend on speed if it " \
            "passes there" if others else ""
        lines.append(f"bt-nav grade: {run_label(rows[again[0].key])} again at 1x real time before the failures "
                     f"stand{then} (--realtime-check off skips it): into {settings.out / REALTIME_DIR}/")
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


def wall_clock_finding(rtf: float, reason: str, evidence: str | None = None) -> str:
    """What a run that passed at 1x after failing faster tells its student: the wall clock only on ``evidence``
    (:func:`wall_clock_evidence`), else that its timing followed sim time and the load is the likelier cause."""
    if evidence is None:
        return (f"failed at {rtf:g}x real time ({reason}) and passed at 1x, graded at 1x; its timing followed sim "
                "time at both speeds, so the faster run's failure is put down to the machine's load, not to the node")
    return (f"failed at {rtf:g}x real time ({reason}) and passed at 1x ({evidence}): the node keeps time by the wall "
            "clock (time.sleep, time.time) where ROS time (self.get_clock(), sim time under use_sim_time) would keep "
            "it right in a simulation at any speed")


def _median(values: list[float]) -> float | None:
    values = sorted(values)
    return values[len(values) // 2] if values else None


def wall_clock_evidence(slow: dict[str, Any] | None, fast: dict[str, Any] | None, rtf: float) -> str | None:
    """What the two verdicts (at 1x and at ``rtf``) show of a node timing itself by the wall clock, in words; None
    where they show nothing of it. A wall-clock node's timed acts last the same *wall* time at every speed, so
    ``rtf`` times longer in sim time: its turns (the lab), or its 50 s (the homework: called at 1x, never or
    late at ``rtf``). A ROS-time node that overshot a turn under load took about as long in sim time."""
    if not slow or not fast:
        return None
    threshold = rtf ** 0.5  # the geometric midpoint of 1 (sim time) and rtf (wall time)
    durations = [_median([m["settled"] - m["t"] for m in v.get("maneuvers") or [] if "settled" in m])
                 for v in (slow, fast)]
    if durations[0] and durations[1] is not None and durations[1] / durations[0] >= threshold:
        return (f"its turns lasted {durations[1]:.1f} sim s at {rtf:g}x and {durations[0]:.1f} sim s at 1x: "
                "the same wall time")
    called_slow, called_fast = slow.get("evaluation_called"), fast.get("evaluation_called")
    if called_slow and (called_fast is None or called_fast / called_slow >= threshold):
        at = "never" if called_fast is None else f"at t={called_fast:.1f} s"
        return f"its evaluation call came at t={called_slow:.1f} s at 1x and {at} at {rtf:g}x"
    return None


def realtime_settings(settings: ExeSettings) -> ExeSettings:
    """The grid's settings at 1x, into ``<out>/realtime``."""
    return replace(settings, rtf=1.0, out=settings.out / REALTIME_DIR, limit=max(settings.limit, REALTIME_LIMIT))


#: One grid to check: its jobs, settings and rows (job key -> row, replaced in place), and who sees a new row.
Grid = tuple[Sequence[Job], ExeSettings, dict[str, Row], Callable[[Row], None] | None]


def confirm_at_real_time(jobs: Sequence[Job], settings: ExeSettings, rows: dict[str, Row], workers: int,
                         stop: StopRequest | None = None, on_row: Callable[[Row], None] | None = None) -> int:
    """Check one grid's failures at 1x (see the module docstring), replacing ``rows`` (job key -> row) in place
    where the node passes there; returns how many rows were replaced. Nothing runs at ``rtf <= 1``, with the check
    off, or without a failure."""
    return confirm_grids([(jobs, settings, rows, on_row)], workers, stop)[0]


def confirm_grids(grids: Sequence[Grid], workers: int, stop: StopRequest | None = None) -> list[int]:
    """:func:`confirm_at_real_time` for several grids (a class) in one pool: every grid's probe at once, then the
    other failed runs of the grids whose probe passed; how many rows each grid had replaced."""
    plans = []  # per grid: its failed jobs, its 1x settings, the 1x rows it has already
    for jobs, settings, rows, _on_row in grids:
        failed = failed_jobs(jobs, settings, rows)
        slow = realtime_settings(settings) if failed else settings
        plans.append((failed, slow, finished_runs(slow.out, failed) if failed and slow.out.is_dir() else {}))
    probes = _run_missing([(failed[0], slow, done) for failed, slow, done in plans if failed], workers, stop)
    rest, confirmed = [], []  # the other failed runs to run at 1x; per grid, whether its probe passed
    for (failed, slow, done), (_, _, rows, _) in zip(plans, grids, strict=True):
        probe = probes.get((str(slow.out), failed[0].key)) if failed else None
        confirmed.append(probe is not None and probe["passed"])
        if confirmed[-1]:
            rest += [(job, slow, done) for job in failed[1:]]
        elif probe is not None:
            rows[failed[0].key]["realtime_probe"] = {"passed": False, "reason": probe["reason"],
                                                     "run_dir": probe["run_dir"]}
    results = {**probes, **_run_missing(rest, workers, stop)}
    replaced = []
    for (failed, slow, _), passed_at_1x, (_, settings, rows, on_row) in zip(plans, confirmed, grids, strict=True):
        count = 0
        for job in failed if passed_at_1x else ():
            slow_row = results.get((str(slow.out), job.key))
            if slow_row is not None:
                rows[job.key] = _graded_at_real_time(slow_row, rows[job.key], settings.rtf)
                count += 1
                if on_row is not None:
                    on_row(rows[job.key])
        replaced.append(count)
    return replaced


def _run_missing(tasks: Sequence[tuple[Job, ExeSettings, dict[str, Row]]], workers: int,
                 stop: StopRequest | None) -> dict[tuple[str, str], Row]:
    """Each (job, 1x settings, finished 1x rows): the finished row, else the job run now (all in one pool); by
    (1x directory, job key), nothing for a run that never started."""
    out = {(str(slow.out), job.key): done[job.key] for job, slow, done in tasks if job.key in done}
    todo = [(job, slow) for job, slow, done in tasks if job.key not in done]
    for index, row in run_pool(todo, workers, stop):
        if row is not None:
            out[(str(todo[index][1].out), todo[index][0].key)] = row
    return out


def _graded_at_real_time(slow: Row, fast: Row, rtf: float) -> Row:
    """The 1x run's row, with what the faster run said: a finding when the 1x run passed."""
    row = dict(slow)
    row["realtime"] = {"rtf": rtf, "passed": fast["passed"], "reason": fast["reason"], "run_dir": fast["run_dir"]}
    if row["passed"]:  # a passed row is a verdict (never a bt_nav error nor stopped)
        finding = wall_clock_finding(rtf, fast["reason"], wall_clock_evidence(slow.get("verdict"),
                                                                              fast.get("verdict"), rtf))
        row["findings"] = [*row.get("findings", []), finding]
        row["reason"] = f"{row['reason']}; {finding}"
    return row
