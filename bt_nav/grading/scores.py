"""A hand-in's score and verdict, read from its finished grade: the points of each run and launch-file check (the
instructor's weights), whether a run or a check counts, and the hand-in's verdict.

Why one module: Gradescope's ``results.json``, the gradebook's CSV and the class page all say a student's score and
verdict; computed once here they cannot disagree. A *record* is one node's ``grade.json`` document, optionally with
``"launch"`` (the hand-in's launch-file checks, :meth:`bt_nav.grading.launch.check.LaunchReport.to_dict`) and
``"refused"`` (why the hand-in was not run). A run that hit a bt_nav error, or that was not graded (a program
outside the node interfered), is none of the node's doing: it scores 0 of 0 and the others share its points; a
hand-in with a run not graded has no score at all (:func:`not_graded_reason`). A launch-file check that ended
"not checked" (a TA looks) scores as passed.

Pure: no rclpy; the files read are the weights (:func:`load_weights`) and a finished grade (:func:`student_record`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from bt_nav.grading.grid import run_label
from bt_nav.grading.hints import student_words
from bt_nav.grading.report import GRADE_FILE, read_grade

#: bt_nav's default weights (installed as package data); ``--weights FILE`` changes some of them.
WEIGHTS_FILE = Path(__file__).with_name("gradescope_weights.yaml")
#: Gradescope's visibility values (results.json's ``visibility`` and each test's).
VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
#: A run whose outcome is this is bt_nav's failure, not the node's (:data:`bt_nav.grading.exe.grid.ERROR`).
ERROR = "bt_nav error"

#: A run's key holding why it was not graded (``not graded: another program is on ROS_DOMAIN_ID 7: ...``): a program
#: outside the node interfered, not the student's doing (its outcome is :data:`ERROR` too).
NOT_GRADED = "not_graded"
#: A launch-file check's key, false when the grader could not follow the file: "not checked: a TA should look"
#: (:class:`bt_nav.grading.launch.report.LaunchCheck`); it scores as passed and says so, for the TA.
CHECKED = "checked"


@dataclass(frozen=True)
class Weights:
    """The Gradescope points: ``total`` for the hand-in, ``launch_share`` of it for the launch-file checks, a
    weight per world (default 1), and the visibility settings (``gradescope_weights.yaml`` documents each)."""

    total: float = 100.0
    launch_share: float = 0.2
    worlds: dict[str, float] = field(default_factory=dict)
    visibility: str = "visible"
    test_visibility: str = "visible"
    stdout_visibility: str = "hidden"


def load_weights(path: Path | None = None) -> Weights:
    """bt_nav's default weights, with the keys of ``path`` (an instructor's YAML) over them. ValueError naming the
    file and the key for an unknown key, a wrong type or value: a bad weights file refuses the grade before any
    run, as a typo would otherwise grade a whole class with the defaults."""
    doc = _yaml_mapping(WEIGHTS_FILE)
    if path is not None:
        doc.update(_yaml_mapping(Path(path)))
    where = path or WEIGHTS_FILE
    known = {f.name for f in fields(Weights)}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    try:
        total, share = float(doc["total"]), float(doc["launch_share"])
        worlds = {str(k): float(v) for k, v in (doc.get("worlds") or {}).items()}
    except (TypeError, ValueError, AttributeError) as exc:
        raise ValueError(f"{where}: total and launch_share are numbers, worlds a mapping world: number ({exc})") \
            from None
    if total <= 0 or not 0 <= share <= 1 or any(w < 0 for w in worlds.values()):
        raise ValueError(f"{where}: total must be > 0, launch_share within 0..1, a world's weight >= 0")
    for key in ("visibility", "test_visibility", "stdout_visibility"):
        if doc[key] not in VISIBILITIES:
            raise ValueError(f"{where}: {key} is {doc[key]!r}; Gradescope knows {', '.join(VISIBILITIES)}")
    return Weights(total, share, worlds, doc["visibility"], doc["test_visibility"], doc["stdout_visibility"])


def _yaml_mapping(path: Path) -> dict[str, Any]:
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read the weights file {path}: {exc}") from None
    if doc is None:
        return {}
    if not isinstance(doc, dict):
        raise ValueError(f"{path}: a weights file is a YAML mapping (key: value)")
    return doc


def launch_checks(record: dict[str, Any]) -> list[dict[str, Any]]:
    """The hand-in's launch-file checks (none: not a hand-in, or ``--exe``)."""
    launch = record.get("launch")
    return list(launch.get("checks") or []) if isinstance(launch, dict) else []


def graded_runs(record: dict[str, Any]) -> list[dict[str, Any]]:
    """The runs of the record (none for a refused hand-in)."""
    return [] if record.get("refused") else list(record.get("runs") or [])


def run_not_graded(row: dict[str, Any]) -> bool:
    """Whether a run was left without a grade (:data:`NOT_GRADED`: not the node's doing)."""
    return bool(row.get(NOT_GRADED))


def check_not_checked(check: dict[str, Any]) -> bool:
    """Whether a launch-file check ended "not checked" (:data:`CHECKED` false): it scores as passed, a TA looks
    (not one that depends on another check that failed: :func:`check_depends`)."""
    return check.get(CHECKED, True) is False and not check_depends(check)


def check_depends(check: dict[str, Any]) -> str | None:
    """The check a launch-file check was not checked for, because it failed (None: none): it scores as passed,
    the failed one is charged once; no TA need look."""
    depends = check.get("depends")
    return str(depends) if depends else None


def check_line(check: dict[str, Any]) -> str:
    """Where a launch-file check points: ``line 12``, or ``params.yaml line 3`` in another file ('' for none)."""
    if not check.get("line"):
        return ""
    return f"{Path(str(check['file'])).name} line {check['line']}" if check.get("file") else f"line {check['line']}"


def unscored(row: dict[str, Any]) -> bool:
    """A run that is none of the node's doing: a bt_nav error, or not graded; no points either way."""
    return row.get("outcome") == ERROR or run_not_graded(row)


def not_graded_reason(record: dict[str, Any]) -> str | None:
    """Why the hand-in of ``record`` cannot be given a score (None: it can): runs left without a verdict that are
    none of the node's doing (not graded: a program outside the node interfered; or a bt_nav error). A score from
    the other runs alone would be a guess: Gradescope must show an autograder error, never 0 and never full marks."""
    left = [r for r in graded_runs(record) if unscored(r)]
    if not left:
        return None
    why = str(left[0].get(NOT_GRADED) or left[0].get("reason") or "?")
    return f"{len(left)} of {len(graded_runs(record))} run(s) not graded ({student_words(why)})"


def run_points(runs: Sequence[dict[str, Any]], points: float, weights: Weights) -> list[float]:
    """Each run's max score: ``points`` split by world weight among the judged runs (a bt_nav error: 0)."""
    scale = [0.0 if unscored(r) else weights.worlds.get(r.get("world", ""), 1.0) for r in runs]
    whole = sum(scale)
    return [points * s / whole if whole else 0.0 for s in scale]


def points(record: dict[str, Any], weights: Weights) -> tuple[float, float]:
    """(the runs' points, the launch-file checks' points)."""
    launch = weights.total * weights.launch_share if launch_checks(record) else 0.0
    return weights.total - launch, launch


#: A hand-in's verdicts (the class page's colours, the CSV's column).
PASSED, FAILED, NOT_GRADED_VERDICT = "PASSED", "FAILED", "NOT GRADED"


def check_counts(check: dict[str, Any]) -> bool:
    """Whether a launch-file check scores: passed, not checked (a TA looks), or not checked for another check's
    failure (:func:`check_depends`)."""
    return bool(check.get("passed")) or check_not_checked(check) or bool(check_depends(check))


def handin_verdict(record: dict[str, Any]) -> str:
    """:data:`FAILED` (refused, or a run the node failed), else :data:`NOT_GRADED_VERDICT` (a run not graded),
    :data:`PASSED` (every run passed, every launch-file check counts), else :data:`FAILED`; as
    :func:`bt_nav.grading.handins.verdict` says it, with the two states the runs and checks may now end in."""
    runs = graded_runs(record)
    if record.get("refused") or any(not r.get("passed") and not unscored(r) for r in runs):
        return FAILED  # a verdict of the node's own at 1x: no run left without one can turn it into a pass
    if not_graded_reason(record):
        return NOT_GRADED_VERDICT
    if not runs or not all(r.get("passed") for r in runs):
        return FAILED
    return PASSED if all(check_counts(c) for c in launch_checks(record)) else FAILED


@dataclass(frozen=True)
class Test:
    """One scored part of a hand-in: a run or a launch-file check, its points, and how it ended (``passed``,
    ``failed``, ``not scored``: a bt_nav error or not graded, ``not checked``: a TA looks)."""

    name: str
    score: float
    max_score: float
    state: str
    row: dict[str, Any] = field(default_factory=dict, compare=False)


def tests(record: dict[str, Any], weights: Weights) -> list[Test]:
    """The hand-in's scored parts in order: a test per run (``run lab_object C lds01 seed 0``), one saying why
    there is none (``the node's runs``), then a test per launch-file check (``launch file: starts the node``)."""
    run_share, launch_share = points(record, weights)
    runs = graded_runs(record)
    out: list[Test] = []
    if any(not unscored(r) for r in runs):
        for row, most in zip(runs, run_points(runs, run_share, weights), strict=True):
            state = "not scored" if unscored(row) else "passed" if row.get("passed") else "failed"
            out.append(Test(f"run {run_label(row)}", most if state == "passed" else 0.0, most, state, row))
    else:
        out.append(Test("the node's runs", 0.0, run_share, "not scored" if runs else "failed"))
    checks = launch_checks(record)
    for check in checks:
        state = "not checked" if check_not_checked(check) or check_depends(check) else \
            "passed" if check.get("passed") else "failed"
        share = launch_share / len(checks)
        out.append(Test(f"launch file: {check.get('name')}", share if check_counts(check) else 0.0, share, state,
                        check))
    return out


def score(record: dict[str, Any], weights: Weights) -> float | None:
    """The hand-in's points (None: not graded, it has none)."""
    if not_graded_reason(record):
        return None
    return round(sum(t.score for t in tests(record, weights)), 4)


def student_record(class_dir: Path, student: dict[str, Any], commands: dict[str, str] | None = None) -> dict[str, Any]:
    """A class student's record (module docstring) from their line of ``class.json`` and their ``grade.json``: a
    refused student's holds the reason, a student whose grid wrote no grade.json has no runs; the launch-file checks
    are the grade.json's, else their class line's (a folder of hand-ins: ``handin.launch``)."""
    name = str(student["name"])
    if student.get("refused"):
        record: dict[str, Any] = {"refused": student["refused"], "runs": []}
    elif (Path(class_dir) / student.get("dir", name) / GRADE_FILE).is_file():
        record = read_grade(Path(class_dir) / student.get("dir", name)) or {"runs": []}
    else:
        record = {"runs": []}
    launch = (student.get("handin") or {}).get("launch") or student.get("launch")
    if "launch" not in record and isinstance(launch, dict):
        record["launch"] = launch
    record.setdefault("settings", {}).setdefault("command", (commands or {}).get(name, ""))
    return record
