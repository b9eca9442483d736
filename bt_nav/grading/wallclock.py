"""A node that keeps wall-clock time, found early: its runs go at 1x, many at once, with no wasted fast pass.

Why: a node that times its turns with ``time.sleep`` or ``time.time`` is right on a robot at 1x and turns ``rtf``
times too far in a faster simulation (at ``--rtf 0``, where a light node keeps up with 10-40x, a 90 deg pivot
turns until its disarm). :mod:`bt_nav.grading.realtime` grades its runs at 1x on their evidence, but only after
the whole grid ran fast and each failure was run again at both speeds: for a grid of 12 lab runs, a fast pass
that is all failures and 24 re-runs, most of them at 1x, a few at a time. A run at 1x needs a fraction of a core
(it waits for the wall clock), so once the node's clock is known its runs can go at 1x together.

How (:func:`run_grid`, for a grid on this machine with the 1x check on):

1. The grid's runs go as usual (:func:`bt_nav.grading.exe.grid.run_exe_grid`), watched as they end.
2. The first failure a speed can change (:func:`bt_nav.grading.realtime.failed_at_speed`,
   :func:`~bt_nav.grading.realtime.speed_cannot_matter`) is looked at:

   - its own evidence (:func:`early_evidence`, the lab): its first failed turn lasted far longer in sim time than
     the assignment's turn would at the node's own turning rate (it turned at least :data:`FAR` times, and at least
     the square root of the run's factor times, the most the maneuver allows), while in its wall time (its sim
     duration over the factor the run achieved) it turned what the assignment asks, or less when the disarm cut it
     short. A node on ROS time turns the assignment's angle in sim time at every speed: a right one never turns
     twice its most. So the switch (3) comes at once;
   - else its two re-runs (the probe of :mod:`bt_nav.grading.realtime`: at the grade's speed and at 1x) start at
     once, beside the grid's other runs; if they decide "wall clock", the switch comes then.

3. The switch: the grid's runs in flight are stopped (their rows dropped, their directories kept), and every job
   without a finished row and every failure a speed can change run at 1x into ``<out>/realtime/`` (the 1x re-runs'
   directory: a resumed grade reuses them), started a few at a time while the cores stay idle, up to
   :data:`REALTIME_PER_CORE` per usable core (:func:`realtime_admission`). A 1x run that failed while its
   simulation fell behind real time (:func:`bt_nav.grading.exe.pace.fell_behind`: a machine too busy for so many
   runs, which makes a wall-clock turn short) runs once more at 1x after them, as few at once as the grid's runs.
4. Graded: the first failure by :func:`bt_nav.grading.realtime.decide` on its 1x run. Wall clock confirmed: every
   other failure likewise on its own 1x run, and every job run at 1x only by its 1x run, with the wall-clock
   finding when it passed (a failure at 1x stands: nothing excuses it). Not confirmed (an early guess its 1x run
   did not bear out, e.g. a node that spins until its disarm at every speed): the jobs not run yet go at the
   grade's speed as if nothing happened, and :func:`bt_nav.grading.realtime.confirm_at_real_time` then decides
   every failure as before, reusing the 1x runs on disk. Either way no verdict rests on the guess alone.

A Dask cluster's grid (its stop reaches every task of the grade) runs and is checked as before.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any

from bt_nav_sim.checkoff_core import CheckoffConfig

from bt_nav.grading.admission import Admission
from bt_nav.grading.exe.grid import STOPPED, Cluster, Workers, finished_runs, run_exe_grid, run_pool
from bt_nav.grading.exe.pace import fell_behind, node_factor
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job, run_label
from bt_nav.grading.realtime import (
    REALTIME_DIR,
    checked,
    decide,
    failed_at_speed,
    realtime_settings,
    rerun_settings,
    run_slipped,
    speed_cannot_matter,
    wall_clock_finding,
)
from bt_nav.mission.maneuver_spec import maneuver_spec
from bt_nav.ros.supervise import StopRequest, usable_cores

Row = dict[str, Any]
#: A first failed turn this many times the most the maneuver allows (or the square root of the run's factor, when
#: more) lasted far longer in sim time than the assignment's turn at the node's rate.
FAR = 2.0
#: Runs at 1x at most per usable core: one takes about a tenth of a core while it waits for the wall clock, most of
#: a core for a second or two while it starts.
REALTIME_PER_CORE = 6
#: Wall seconds between two starts of the 1x runs past the first few (a run's start-up is its busiest part).
REALTIME_GAP = 1.0
#: The least factor at which a wall clock's turns differ enough from ROS time's to be told from one run.
EARLY_MIN_RTF = 3.0


def early_evidence(row: Row, rtf: float) -> str | None:
    """What one failed run at ``rtf`` (its achieved factor at 0) shows of a wall clock, in words (module docstring,
    2); None where it shows nothing of it: not the lab, no failed turn, a factor under :data:`EARLY_MIN_RTF`."""
    factor = node_factor(row, rtf)  # the pace of its turns: while the node was followed
    verdict = row.get("verdict") or {}
    if factor < EARLY_MIN_RTF or not row.get("maneuver") or not verdict.get("maneuvers"):
        return None
    try:
        rule = maneuver_spec(str(row["maneuver"])).angle
    except (KeyError, ValueError):
        return None
    tolerance = CheckoffConfig.angle_tolerance_deg
    found = next(((n, m) for n, m in enumerate(verdict["maneuvers"], start=1) if not m.get("passed")), None)
    if found is None or "settled" not in found[1]:
        return None
    number, turn = found
    angle, lasted = abs(float(turn.get("angle_deg", 0.0))), float(turn["settled"]) - float(turn["t"])
    most, least = rule.high_deg + tolerance, rule.low_deg - tolerance
    walled = angle / factor  # what it turned per the wall seconds it lasted, as at 1x
    if angle < max(FAR, factor ** 0.5) * most or walled > FAR * most:
        return None
    if not turn.get("interrupted") and walled < least / FAR:
        return None
    cut = ", cut short by the disarm" if turn.get("interrupted") else ""
    return (f"maneuver {number} turned {angle:.0f} deg in {lasted:.1f} sim s at {factor:.1f}x (the node's pace){cut}: "
            f"{walled:.0f} deg in its {lasted / factor:.1f} s of wall time, where the assignment turns "
            f"{rule.words(tolerance).split(' deg')[0]} deg: a turn timed by the wall clock")


def realtime_admission(cores: int | None = None) -> Admission:
    """How many 1x runs at once: three per usable core at first, then one more every :data:`REALTIME_GAP` s, up to
    :data:`REALTIME_PER_CORE` per core; never all at once (a node starved while it starts would miss the judge's
    start wait). Not held back by busy cores as a fast grid's runs are (:mod:`bt_nav.grading.admission`): a 1x run's
    start-up is its only busy part, and the last run to start is the grade's end (measured: waiting for idle cores
    between starts put the twelfth start 28 s after the first, the grade 113 s)."""
    count = cores or usable_cores()
    return Admission(3 * count, REALTIME_PER_CORE * count, idle_needed=0.0, foreign_max=1.0, burst_idle=2.0,
                     gap=REALTIME_GAP)


class _Switch(StopRequest):
    """The stop of the grid's fast runs: the grade's own stop, or the switch to 1x (:meth:`flip`)."""

    def __init__(self, grade: StopRequest | None) -> None:
        super().__init__()
        self.grade = grade
        self.flipped = threading.Event()

    def flip(self) -> None:
        self.flipped.set()

    @property
    def grade_requested(self) -> bool:
        """The grade's own stop came (not the switch)."""
        return self.grade is not None and self.grade.requested

    @property
    def requested(self) -> bool:  # noqa: D102 - StopRequest's
        return self.flipped.is_set() or self.grade_requested

    @property
    def name(self) -> str:  # noqa: D102 - StopRequest's
        if self.grade_requested:
            return self.grade.name
        return "the switch to 1x (a wall clock)" if self.flipped.is_set() else ""


class _Watch:
    """The grid's runs as they end: the first failure a speed can change, its evidence, its probe."""

    def __init__(self, jobs: Sequence[Job], settings: ExeSettings, stop: StopRequest | None,
                 say: Callable[[str], None]) -> None:
        self.jobs, self.settings, self.say = {job.key: job for job in jobs}, settings, say
        self.switch = _Switch(stop)
        self.first: Row | None = None
        self.evidence: str | None = None  # the early evidence, or the probe's words
        self.probe: threading.Thread | None = None

    def look(self, row: Row) -> None:
        """A run ended (or was done already): the first failure a speed can change is looked at once."""
        if self.first is not None or not failed_at_speed(row) or speed_cannot_matter(row) is not None:
            return
        self.first = row
        evidence = early_evidence(row, self.settings.rtf)
        if evidence is not None:
            self.evidence = evidence
            self.switch.flip()
            return
        self.probe = threading.Thread(target=self._probe, args=(row,), name="wall-clock-probe", daemon=True)
        self.probe.start()

    def _probe(self, row: Row) -> None:
        """The first failure's two re-runs beside the grid's runs; a decision "wall clock" flips the switch."""
        job = self.jobs[row["job"]]
        tasks = [(job, rerun_settings(self.settings)), (job, realtime_settings(self.settings))]
        done = _reruns([job], self.settings)
        ran = [done[i].get(job.key) for i in (0, 1)]
        todo = [i for i in (0, 1) if ran[i] is None]
        for index, rerun in run_pool([tasks[i] for i in todo], 2, self.switch.grade):
            ran[todo[index]] = rerun
        again, slow = ran
        if slow is None or self.switch.grade_requested:
            return
        decided, said = decide(row, again, slow, self.settings.rtf, run_slipped(row))
        if decided.get("rerun", {}).get("decision") == "wall clock":
            self.evidence = said
            self.switch.flip()

    def seen(self, on_row: Callable[[Row], None] | None) -> Callable[[Row], None]:
        """The grid's ``on_row``: a run stopped by the switch is dropped unseen; every other row is shown, then
        looked at."""
        def ended(row: Row) -> None:
            if row.get("outcome") == STOPPED and self.switch.flipped.is_set() and not self.grade_stopped():
                return
            if on_row is not None:
                on_row(row)
            self.look(row)
        return ended

    def grade_stopped(self) -> bool:
        """The grade's own stop came (not the switch)."""
        return self.switch.grade_requested


def _reruns(jobs: Sequence[Job], settings: ExeSettings) -> tuple[dict[str, Row], dict[str, Row]]:
    """The re-runs of ``jobs`` finished already (a resumed grade): at the grade's speed, at 1x."""
    out = []
    for where in (rerun_settings(settings), realtime_settings(settings)):
        out.append(finished_runs(where.out, jobs) if where.out.is_dir() else {})
    return out[0], out[1]


def run_grid(jobs: Sequence[Job], settings: ExeSettings, workers: Workers, stop: StopRequest | None = None,
             on_row: Callable[[Row], None] | None = None, *, done: dict[str, Row] | None = None,
             progress: bool = False, say: Callable[[str], None] | None = None) -> list[Row]:
    """The grid's rows (module docstring): :func:`~bt_nav.grading.exe.grid.run_exe_grid`'s, with a wall-clock
    node's runs switched to 1x and graded there. ``on_row`` sees each row as :func:`run_exe_grid`'s does (a 1x
    run's once graded), ``say`` hears the switch and its outcome. The failures left are
    :func:`bt_nav.grading.realtime.confirm_at_real_time`'s to check, as before."""
    if isinstance(workers, Cluster) or not checked(settings):
        return run_exe_grid(jobs, settings, workers, stop, on_row, done=done, progress=progress)
    tell = say or (lambda _line: None)
    watch = _Watch(jobs, settings, stop, tell)
    # a resumed grade's failures, in the grid's order; one whose re-runs ran already first (its probe, reused)
    done = dict(done or {})
    earlier = [done[job.key] for job in jobs if job.key in done]
    again, slow = _reruns([job for job in jobs if job.key in done], settings) if earlier else ({}, {})
    for row in sorted(earlier, key=lambda row: not (row["job"] in again and row["job"] in slow)):
        watch.look(row)
    rows = run_exe_grid(jobs, settings, workers, watch.switch, watch.seen(on_row), done=done, progress=progress)
    if watch.probe is not None and not watch.switch.flipped.is_set():
        watch.probe.join()  # the grid ended first: the probe's decision still saves the other failures' fast re-run
    if not watch.switch.flipped.is_set() or watch.grade_stopped():
        return rows
    kept = {row["job"]: row for row in rows if row.get("outcome") != STOPPED}
    return _at_real_time(jobs, settings, kept, watch, workers, stop, on_row)


def _at_real_time(jobs: Sequence[Job], settings: ExeSettings, kept: dict[str, Row], watch: _Watch,
                  workers: Workers, stop: StopRequest | None, on_row: Callable[[Row], None] | None) -> list[Row]:
    """The switch (module docstring, 3 and 4): the failures and the jobs without a row at 1x, each graded as it
    ends once the first failure's 1x run has confirmed the wall clock (the report draws them meanwhile); not
    confirmed, the grid goes on at its speed (its 1x runs, on disk, serve the usual check of its failures)."""
    first = watch.first
    assert first is not None and watch.evidence is not None
    failures = [job for job in jobs if job.key in kept and failed_at_speed(kept[job.key])
                and speed_cannot_matter(kept[job.key]) is None]
    fresh = [job for job in jobs if job.key not in kept]
    admission = realtime_admission()
    watch.say(f"bt-nav grade: {run_label(first)}: {watch.evidence}; the node's runs go at 1x: the "
              f"{_runs(len(fresh))} not run yet and the {len(failures)} failed, up to {admission.limit} at once "
              f"(--realtime-check off skips it), into {settings.out / REALTIME_DIR}/")
    batch = [*failures, *fresh]
    again, slow = _reruns(batch, settings)
    grading = _Grading(first, kept, again, settings, on_row)
    for job in batch:
        if job.key in slow:
            grading.ended(job.key, slow[job.key])
    todo = [job for job in batch if job.key not in slow]
    for index, row in run_pool([(job, realtime_settings(settings)) for job in todo], workers, stop, admission):
        if row is not None and row.get("outcome") != STOPPED:
            grading.ended(todo[index].key, row)
    stopped = stop is not None and stop.requested
    if grading.behind and not stopped:
        _again_at_1x(grading, [job for job in batch if job.key in grading.behind], settings, workers, stop, watch)
    if grading.confirmed or stopped:
        return _ordered(jobs, {**kept, **grading.rows})
    watch.say(f"bt-nav grade: {run_label(first)}: its 1x run did not bear a wall clock out "
              f"({grading.said or 'it did not run'}); the {_runs(len(fresh))} not run yet go at the grade's speed")
    rest = run_exe_grid(fresh, settings, workers, stop, on_row)
    return _ordered(jobs, {**kept, **{row["job"]: row for row in rest}})


def _again_at_1x(grading: _Grading, retry: Sequence[Job], settings: ExeSettings, workers: Workers,
                 stop: StopRequest | None, watch: _Watch) -> None:
    """The 1x runs that failed while their simulation fell behind real time
    (:func:`bt_nav.grading.exe.pace.fell_behind`), once more at 1x, as many at once as the grid's own runs: a busy
    machine's, not the node's, unless they fail so again."""
    behind, grading.behind = grading.behind, {}
    watch.say(f"bt-nav grade: {_runs(len(retry))} failed at 1x while the simulation fell behind real time ("
              + ", ".join(f"{run_label(row)} at {behind[row['job']]:.2f}x" for row in grading.first_tries(retry))
              + "): a machine too busy for them; run again at 1x, fewer at once")
    for index, row in run_pool([(job, realtime_settings(settings)) for job in retry], workers, stop):
        if row is not None and row.get("outcome") != STOPPED:
            grading.ended(retry[index].key, row, last=True)


class _Grading:
    """The 1x runs of the switch as they end: the first failure's decides whether the node keeps wall-clock time
    (:attr:`confirmed`); once it has, each run is graded (:attr:`rows`) and shown, those that ended before it then.
    A run that failed while its simulation fell behind real time waits in :attr:`behind` to be run again."""

    def __init__(self, first: Row, kept: dict[str, Row], again: dict[str, Row], settings: ExeSettings,
                 on_row: Callable[[Row], None] | None) -> None:
        self.first, self.kept, self.again, self.settings, self.on_row = first, kept, again, settings, on_row
        self.confirmed: bool | None = None
        self.said = ""
        self.rows: dict[str, Row] = {}
        self.waiting: list[tuple[str, Row]] = []
        self.behind: dict[str, float] = {}  # job key -> the factor its 1x run kept
        self.tried: dict[str, Row] = {}  # the first 1x run of each job run again

    def ended(self, key: str, at_1x: Row, last: bool = False) -> None:
        """A 1x run of job ``key`` ended (or had ended before: a resumed grade); ``last``: its second."""
        kept = fell_behind(at_1x)
        if not last and not at_1x["passed"] and kept is not None:
            self.behind[key] = kept
            self.tried[key] = at_1x
            return
        if key in self.tried:
            tried = self.tried[key]
            at_1x = {**at_1x, "notes": [*at_1x.get("notes", []), f"run at 1x again: its first 1x run fell behind "
                                        f"real time ({fell_behind(tried)}x while it followed the node) and failed "
                                        f"({tried['reason']}), {tried['run_dir']}"]}
        if key == self.first["job"]:
            decided, self.said = decide(self.first, self.again.get(key), at_1x, self.settings.rtf,
                                        run_slipped(self.first), again_planned=False)
            self.confirmed = decided.get("rerun", {}).get("decision") == "wall clock"
        self.waiting.append((key, at_1x))
        if self.confirmed:
            for waited, row in self.waiting:
                self._grade(waited, row)
            self.waiting = []

    def first_tries(self, jobs: Sequence[Job]) -> list[Row]:
        """The first 1x runs of ``jobs`` (those run again)."""
        return [self.tried[job.key] for job in jobs if job.key in self.tried]

    def _grade(self, key: str, at_1x: Row) -> None:
        fast = self.kept.get(key)
        if fast is not None:
            self.rows[key], _ = decide(fast, self.again.get(key), at_1x, self.settings.rtf, run_slipped(fast),
                                       again_planned=False)
        else:
            self.rows[key] = _only_at_1x(at_1x, self.first, self.said)
        if self.on_row is not None:
            self.on_row(self.rows[key])


def _only_at_1x(row: Row, first: Row, said: str) -> Row:
    """A job run at 1x only, the node's wall clock found in ``first`` (``said``: its decision's words): graded by its
    1x run, with the wall-clock finding when it passed; a failure at 1x stands (nothing excuses it)."""
    graded = dict(row)
    graded["rerun"] = {"runs": [{"rtf": 1.0, "passed": row["passed"], "reason": row["reason"],
                                 "run_dir": row["run_dir"]}], "decision": "wall clock" if row["passed"] else "stands",
                       "said": f"run at 1x only: {run_label(first)} {said}"}
    if row["passed"]:
        finding = f"{wall_clock_finding(f'run at 1x only, as {run_label(first)} showed')}; graded at 1x"
        graded["findings"] = [*row.get("findings", []), finding]
        graded["reason"] = f"{row['reason']}; {finding}"
    return graded


def _runs(count: int) -> str:
    return f"{count} run{'' if count == 1 else 's'}"


def _ordered(jobs: Sequence[Job], rows: dict[str, Row]) -> list[Row]:
    return [rows[job.key] for job in jobs if job.key in rows]
