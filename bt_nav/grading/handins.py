"""A folder of hand-ins as a class (``bt-nav grade --class DIR``), each student's whole hand-in judged (the node's
runs and the launch file), and one ``feedback.md`` per student.

Why a folder: a learning platform's download is a folder per student (a Moodle or GitHub Classroom export), or for
Gradescope one submission folder (``/autograder/submission``); writing a manifest by hand for it is the step that
goes wrong. Why the launch file counts: the lab sheet's hand-in is the node *and* ``turtlebot_bringup.launch.py``
(Task 3), so a student whose launch file does not pass the argument fails the hand-in even when every run passed;
the runs' own verdicts stay as they are (the node did what it did).

Layout (:func:`read_handins`): ``DIR`` is one student's submission when it holds a ``.py`` file, a ``package.xml``
or a ``setup.py`` at its top or is named ``submission`` (Gradescope's); otherwise each visible subfolder is a
student, named after it (characters a directory name may not hold become ``_``). In a student's folder (searched
to any depth, ``build``/``install``/``log`` and hidden folders skipped) the node is the lab's
``reactive_navigator.py``, else the one Python file defining a subclass of rclpy's ``Node``; the launch file is
``turtlebot_bringup.launch.py``, else the one ``*.launch.py``. Anything else is a reason naming the student and
what was found, and that student fails; the others are graded.

The API other formats build on (Gradescope, JUnit): :class:`StudentResult` and :func:`load_class` /
:func:`load_grid`, which read what a grade wrote (``class.json``, each student's ``grade.json``).
"""

from __future__ import annotations

import re
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav.grading.classroom import NAME, Student, read_class_page
from bt_nav.grading.exe.grid import declared_choice
from bt_nav.grading.handin_files import SKIPPED, find_node
from bt_nav.grading.launch import LAUNCH_NAME, LaunchReport, check_launch, find_launch, launch_ros_installed
from bt_nav.grading.report import read_grade
from bt_nav.grading.scores import NOT_GRADED_VERDICT, unscored

#: Files that make a folder one submission rather than a folder of students.
SUBMISSION_MARKS = ("package.xml", "setup.py", "setup.cfg")
FEEDBACK = "feedback.md"


@dataclass(frozen=True)
class HandIn:
    """One student's folder: the node file found (None: ``problem`` says why), and the launch file's checks."""

    name: str
    folder: Path
    node: Path | None
    launch: LaunchReport
    problem: str | None = None

    def command(self, python: str = sys.executable) -> str:
        """How the node is started: this grader's Python (it has rclpy) on the node file; '' without one."""
        return shlex.join([python, str(self.node)]) if self.node is not None else ""

    def student(self) -> Student:
        return Student(self.name, self.command())

    def record(self) -> dict[str, Any]:
        """The hand-in as ``class.json`` holds it (``"handin"`` of the student's row)."""
        return {"folder": str(self.folder), "node": None if self.node is None else str(self.node),
                "launch": self.launch.to_dict(), "problem": self.problem}


def is_submission(folder: Path) -> bool:
    """Whether ``folder`` is one student's submission (module docstring) rather than a folder of students."""
    if folder.name == "submission":
        return True
    return any(p.is_file() and (p.suffix == ".py" or p.name in SUBMISSION_MARKS) for p in folder.iterdir())


def student_name(raw: str, taken: set[str]) -> str:
    """A directory-safe, unique name for a student's folder (``Ann Lee_123`` -> ``Ann_Lee_123``)."""
    name = re.sub(r"[^A-Za-z0-9._-]", "_", raw).lstrip("._-")[:60] or "student"
    base, k = name, 2
    while name in taken or not NAME.match(name):
        name, k = f"{base}_{k}", k + 1
    taken.add(name)
    return name


def read_handin(name: str, folder: Path) -> HandIn:
    """One student's hand-in: the node found (or why not), the launch file checked against it."""
    node, problem = find_node(folder)
    launch_path = find_launch(folder)
    report = check_launch(launch_path, node, folder)
    notes = list(report.notes)
    if launch_path is not None and launch_path.name != LAUNCH_NAME:
        notes.append(f"read {launch_path.relative_to(folder)} (the sheet names it {LAUNCH_NAME})")
    if node is not None:
        notes.append(started_note(node.relative_to(folder)))
    report = LaunchReport(report.file, report.checks, tuple(notes))
    return HandIn(name, folder, node, report, None if problem is None else f"{problem} in {folder}")


def started_note(node: Path) -> str:
    """How the node was started, said in every hand-in's verdict (the launch file was evaluated, not started)."""
    how = f"the node was started as `{Path(sys.executable).name} {node}` (this grader's Python)"
    done = "launch file evaluated against stand-ins of launch/launch_ros, not started"
    if launch_ros_installed():
        return f"{done}; launch_ros is installed but bt_nav does not start launch files yet: {how}"
    return f"{done}; launch_ros not installed, {how}"


def read_handins(folder: Path) -> list[HandIn]:
    """The class a folder of hand-ins is (module docstring). ValueError: not a folder, or no student in it."""
    folder = Path(folder).absolute()
    if not folder.is_dir():
        raise ValueError(f"--class {folder}: neither a manifest file nor a folder of hand-ins")
    taken: set[str] = set()
    if is_submission(folder):
        return [read_handin(student_name(folder.name, taken), folder)]
    subs = sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".") and p.name not in SKIPPED)
    if not subs:
        raise ValueError(f"--class {folder}: no hand-ins (no subfolder per student, no Python file)")
    return [read_handin(student_name(p.name, taken), p) for p in subs]


# ---------------------------------------------------------------------------------------------- the verdicts
def verdict(row: dict[str, Any], launch: LaunchReport | None) -> tuple[bool, list[str]]:
    """A student's overall verdict from their class row and launch checks: (passed, why not). Passed only when
    graded, every run passed, none is left without a verdict, and (for a hand-in) every launch check passed."""
    why: list[str] = []
    if row.get("refused"):
        why.append(f"not run: {row['refused']}")
    elif not row.get("graded") or not row.get("runs"):
        why.append("no run ended")
    else:
        if row["passed"] < row["runs"]:
            why.append(f"{row['runs'] - row['passed']} of {row['runs']} runs failed")
        if row.get("errors"):
            why.append(f"{row['errors']} runs without a verdict (bt_nav errors: --resume runs them)")
    if launch is not None and not launch.passed:
        failed = [c.name for c in launch.checks if not c.passed]
        why.append("launch file: " + ", ".join(failed) + " failed")
    return not why, why


def add_verdicts(rows: list[dict[str, Any]], handins: dict[str, dict[str, Any]]) -> None:
    """Each class row of a hand-in gets its hand-in record, its launch lines and its overall verdict."""
    for row in rows:
        record = handins.get(row["name"])
        if record is None:
            continue
        launch = LaunchReport.from_dict(record["launch"])
        passed, why = verdict(row, launch)
        row["handin"] = {**record, "lines": [*launch.lines(), *(f"note: {n}" for n in launch.notes)]}
        left = not passed and bool(row.get("errors"))  # runs without a verdict: none of the node's doing
        row["verdict"] = "PASSED" if passed else NOT_GRADED_VERDICT if left else "FAILED"
        row["verdict_reasons"] = why


@dataclass
class StudentResult:
    """One student's result as a grade wrote it: what other report formats (Gradescope, JUnit) are built from.

    ``runs`` are the rows of the student's ``grade.json`` (each with ``world``, ``maneuver``, ``lidar``, ``seed``,
    ``passed``, ``reason``, ``run_dir``, ``verdict`` with ``report_lines``, ``media``); ``launch`` is None when the
    launch file was not part of the grade (``--exe``, a YAML manifest)."""

    name: str
    directory: Path
    node: str | None
    choice: str | None
    launch: LaunchReport | None
    runs: list[dict[str, Any]]
    refused: str | None
    passed: bool
    reasons: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> str:
        """PASSED, FAILED (a run the node failed, whatever the others), or NOT GRADED: runs left without a verdict
        that are none of the node's doing and no failure (the class
        page, the CSV and Gradescope say the same: :func:`bt_nav.grading.scores.handin_verdict`)."""
        if self.passed:
            return "PASSED"
        failed = self.refused or any(not r.get("passed") and not unscored(r) for r in self.runs)
        return NOT_GRADED_VERDICT if not failed and any(unscored(r) for r in self.runs) else "FAILED"


def _runs(grid: Path) -> list[dict[str, Any]]:
    try:
        return list((read_grade(grid) or {}).get("runs", []))
    except ValueError:
        return []


def _choice(runs: Sequence[dict[str, Any]]) -> str | None:
    maneuvers = sorted({str(r.get("maneuver")) for r in runs if r.get("maneuver") not in (None, "none")})
    return ",".join(maneuvers) or None


def load_class(out: Path) -> list[StudentResult]:
    """Every student of the class graded into ``out`` (its ``class.json`` and each student's ``grade.json``)."""
    doc = read_class_page(out)
    results = []
    for row in doc["students"]:
        handin = row.get("handin")
        launch = LaunchReport.from_dict(handin["launch"]) if handin else None
        runs = _runs(Path(out) / row["dir"])
        passed, why = verdict(row, launch)
        node = handin["node"] if handin else doc.get("commands", {}).get(row["name"])
        choice = _choice(runs) or (declared_choice(shlex.join(["python3", node]) if handin else node) if node
                                   else None)
        results.append(StudentResult(row["name"], Path(out) / row["dir"], node, choice, launch, runs,
                                     row.get("refused"), passed, why))
    return results


def load_grid(out: Path, name: str = "student") -> StudentResult:
    """One ``--exe`` grade in ``out`` as a student's result (its launch checks when ``--launch`` gave a file)."""
    runs = [r for r in _runs(Path(out)) if r.get("outcome") != "stopped"]
    judged = [r for r in runs if r.get("outcome") != "bt_nav error"]
    row = {"graded": bool(runs), "runs": len(judged), "passed": sum(1 for r in judged if r.get("passed")),
           "errors": len(runs) - len(judged)}
    try:
        doc = read_grade(Path(out)) or {}
    except ValueError:
        doc = {}
    launch = LaunchReport.from_dict(doc["launch"]) if isinstance(doc.get("launch"), dict) else None
    passed, why = verdict(row, launch)
    return StudentResult(name, Path(out), doc.get("settings", {}).get("command"), _choice(runs), launch, runs, None,
                         passed, why)


def read_class(path: Path) -> tuple[list[Any], dict[str, str], dict[str, Any]]:
    """(the students, those failed before admission with their reason, the hand-ins by name) of ``--class``: a
    manifest file, or a folder of hand-ins (:mod:`bt_nav.grading.handins`). ValueError refuses the class."""
    from bt_nav.grading.classroom import read_manifest

    if not path.is_dir():
        return read_manifest(path), {}, {}
    handins = read_handins(path)
    return ([h.student() for h in handins], {h.name: h.problem for h in handins if h.problem},
            {h.name: h for h in handins})
