"""A cell's verdict is that of a valid 1x run: a preview's failure is graded again at 1x before it is shown, and a
1x run whose simulator fell behind real time is run once more, then not graded.

Why: a check-off is a real-time event (:mod:`bt_nav.grading.exe.pace`). A 1x run's verdict is the one the node would
earn on the robot, so nothing re-runs or overturns it, with one exception that is no verdict of the node's: a
machine too busy for the run (its simulator measured its own lag while judged, :func:`bt_nav.grading.exe.pace.
fell_behind`). That run is run again (into ``<out>/again/``); if it falls behind again, the cell is NOT GRADED (an
autograder error, never a 0), and the grade says why. A preview (``--rtf 0`` or above 1) is for a student iterating:
its passes are shown as preview passes, and each failure is run at 1x (into ``<out>/realtime/``), whose verdict is
the one shown, with the preview's reason kept beside it (``preview``).

Each attempt is one :func:`bt_nav.grading.exe.grid.run_unless_stopped` through the grid's admission (a run that
fell behind calms the machine first: :meth:`bt_nav.grading.admission.Admission.fell_behind`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

from bt_nav.grading.exe.pace import REAL_TIME, fell_behind, preview
from bt_nav.grading.exe.run import ERROR, ExeSettings

Row = dict[str, Any]
#: Where a cell's second attempts go, below the grid's ``--out``: 1x runs again after one fell behind; a preview's
#: failures at 1x.
AGAIN_DIR, REALTIME_DIR = "again", "realtime"
#: Outcomes of a run that say something of the node at any speed (a verdict, or a run that ran out of wall time).
JUDGED = ("verdict", "timeout")


def real_time(settings: ExeSettings) -> ExeSettings:
    """A preview grid's settings at 1x, writing below ``<out>/realtime/``."""
    return replace(settings, rtf=REAL_TIME, rtf_max=0.0, out=settings.out / REALTIME_DIR)


def graded_run(attempt: Callable[[ExeSettings], Row | None], settings: ExeSettings,
               on_behind: Callable[[], None] | None = None) -> Row | None:
    """The row of one cell (module docstring): ``attempt(settings)`` runs the cell once with those settings (None:
    stopped before it started). A preview's failure becomes its 1x run's row; a 1x run that fell behind is run
    again (``on_behind`` called first: the admission calms the machine), then NOT GRADED."""
    row = attempt(settings)
    if row is None or row.get("outcome") not in JUDGED:
        return row
    if preview(settings.rtf):
        if row["passed"] or not settings.realtime_check:
            row["preview"] = {"rtf": settings.rtf, "said": f"{'passed' if row['passed'] else 'failed'} in the preview"}
            return row
        first, settings = row, real_time(settings)
        row = attempt(settings)
        if row is None:
            return first
        row["preview"] = {"rtf": first.get("rtf") or settings.rtf, "reason": first["reason"],
                          "run_dir": first["run_dir"], "said": "failed in the preview; graded again at 1x"}
        if row.get("outcome") not in JUDGED:
            return row
    behind = fell_behind(row)
    if behind is None:
        return row
    if on_behind is not None:
        on_behind()
    again = attempt(replace(settings, out=settings.out / AGAIN_DIR))
    if again is None or again.get("outcome") not in JUDGED:
        return again or row
    still = fell_behind(again)
    if still is None:
        again["notes"] = [*again.get("notes", []), f"run again: its first run ({row['run_dir']}): {behind}"]
        return again
    return not_real_time(again, still)


def not_real_time(row: Row, why: str) -> Row:
    """``row`` NOT GRADED: its simulator fell behind real time twice (``why``); the node's verdict there is kept as
    ``unkept`` for the curious, never counted."""
    said = f"not graded: {why}, twice; grade again on a quieter machine (not the node's doing)"
    return {**row, "passed": False, "outcome": ERROR, "reason": said, "not_graded": said,
            "unkept": {"passed": row["passed"], "reason": row["reason"]}}
