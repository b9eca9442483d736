"""A class graded in one command: a manifest of students (name and command each), one ``--exe`` grid per student
on the same worlds, maneuvers, LiDARs and seeds, and one class page over them.

Why a layer over the single grid and not a bigger grid: each student's grid stays exactly what ``bt-nav grade --exe``
writes for one node (its own directory, ``grade.json``, ``report.html``, resumable), so a student's result read from
the class directory equals grading that student alone, and an interrupted class resumes student by student. The class
page only reads those ``grade.json`` files: ``class.json`` (every student's cells and findings), ``class.md`` and
``class.html`` (:mod:`bt_nav.grading.classpage`: a row per student, the hand-in's verdict coloured and its score,
failures first with their arena and LiDAR, filters and sorting, links to each student's report).

The manifest (``--class FILE``) is YAML: a mapping ``name: command``, or a list of ``{name: ..., command: ...}``.
A name becomes a directory: letters, digits, ``.``, ``_`` and ``-`` only, unique.

A bad entry fails its student, not the class (:func:`admit`): an empty command, a program or Python file that is
not there, not readable or not Python source, a lab node that declares no maneuver. Its student is refused with
the reason, naming the file, and shown on the class page like any failed student; the others are graded. A
manifest that cannot be read, or options that do not fit, still refuse the class before any run.
"""

from __future__ import annotations

import json
import re
import shlex
from collections import Counter, defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from bt_nav.grading.grid import cell_label, failure_groups, runs_label

if TYPE_CHECKING:
    from bt_nav.grading.exe.grid import Workers

#: What a student's name may hold (it names their grid's directory).
NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")


@dataclass(frozen=True)
class Student:
    """One line of the manifest: who, and the command that starts their node."""

    name: str
    command: str


def read_manifest(path: Path) -> list[Student]:
    """The students of a manifest file (ValueError naming the problem: unreadable, empty, a bad or repeated name)."""
    try:
        doc = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"cannot read the class manifest {path}: {exc}") from None
    if isinstance(doc, dict) and set(doc) == {"students"}:
        doc = doc["students"]
    if isinstance(doc, dict):
        pairs = list(doc.items())
    elif isinstance(doc, list) and all(isinstance(e, dict) and {"name", "command"} <= set(e) for e in doc):
        pairs = [(e["name"], e["command"]) for e in doc]
    else:
        raise ValueError(f"{path}: a class manifest is a mapping 'name: command' or a list of "
                         "{name: ..., command: ...}")
    students = [Student(str(name), "" if command is None else str(command).strip()) for name, command in pairs]
    if not students:
        raise ValueError(f"{path}: no students")
    seen: set[str] = set()
    for s in students:
        if not NAME.match(s.name):
            raise ValueError(f"{path}: student name {s.name!r} must be letters, digits, '.', '_' or '-' "
                             "(it names a directory)")
        if s.name in seen:
            raise ValueError(f"{path}: student {s.name!r} appears twice")
        seen.add(s.name)  # an empty command fails its student (entry_problem), not the class
    return students


def file_problem(path: Path) -> str | None:
    """Why the Python file ``path`` cannot be a node (None: it can): not there, not a file, unreadable, or not a
    Python source file (binary, or not text in the encoding Python reads it in): each would fail every run of its
    student alike. Not compiled: the student's Python may be another version than the grader's."""
    import tokenize

    if not path.exists():
        return f"{path} does not exist"
    if not path.is_file():
        return f"{path} is not a file"
    try:
        source = path.read_bytes()
    except OSError as exc:
        return f"{path} cannot be read ({exc.strerror or exc})"
    if b"\0" in source:
        return f"{path} is not a Python source file (it holds binary data)"
    try:
        encoding, _ = tokenize.detect_encoding(iter(source.splitlines(keepends=True)).__next__)
        source.decode(encoding)
    except (SyntaxError, UnicodeDecodeError, LookupError) as exc:
        return f"{path} is not a Python source file ({exc})"
    return None


def entry_problem(student: Student) -> str | None:
    """Why ``student``'s entry cannot be run, naming the file (None: it can)."""
    from bt_nav.grading.exe.grid import node_file

    command = student.command
    if not command:
        return "no command"
    try:
        shlex.split(command)
    except ValueError as exc:
        return f"command {command!r} cannot be split into words: {exc}"
    path = node_file(command)
    return None if path is None else file_problem(path.absolute())


def choice_problem(command: str) -> str | None:
    """Why a lab node graded without ``--maneuvers`` has no maneuver (None: its file declares one)."""
    from bt_nav.grading.exe.grid import declared_choice, node_file

    if declared_choice(command) is not None:
        return None
    path = node_file(command)
    what = f"{path.absolute()} declares no maneuver" if path is not None else \
        f"command {command!r} runs no Python file to read its maneuver from"
    return f"{what} (the lab template's '# CHOICE: X' line), and --maneuvers is not given"


def admit(students: Sequence[Student], needs_choice: bool, resolve: Callable[[str], str]
          ) -> tuple[dict[str, str], dict[str, str]]:
    """(each admitted student's command as ``resolve`` gives it, each refused student's reason): a bad entry fails
    its student, so the rest of the class is graded. Bad: :func:`entry_problem`, a program ``resolve`` refuses with
    ValueError (:func:`~bt_nav.grading.exe.grid.resolve_program`: not found, or a Python without rclpy), and with
    ``needs_choice`` (a lab class without ``--maneuvers``) a node that declares no maneuver (:func:`choice_problem`)."""
    admitted: dict[str, str] = {}
    refused: dict[str, str] = {}
    for student in students:
        problem = entry_problem(student)
        if problem is None:
            try:
                admitted[student.name] = resolve(student.command)
            except ValueError as exc:
                problem = str(exc).removeprefix("--exe: ")
        if problem is None and needs_choice:
            problem = choice_problem(student.command)
        if problem is not None:
            admitted.pop(student.name, None)
            refused[student.name] = problem
    return admitted, refused


def refused_summary(name: str, reason: str) -> dict[str, Any]:
    """A refused student's line of the class (:func:`admit`): no run, failed for ``reason``."""
    return {"name": name, "dir": name, "graded": False, "refused": reason, "cells": {}, "findings": {}, "runs": 0,
            "passed": 0, "errors": 0, "reasons": {reason: 1}, "failures": [["not run", reason]]}


def cell_key(row: dict[str, Any]) -> str:
    """A grid cell's label: world, maneuver and (when the grid varies it) LiDAR (:func:`.grid.cell_label`)."""
    return cell_label(row)


def student_summary(name: str, grid_dir: Path) -> dict[str, Any]:
    """One student's line of the class: pass counts per cell, bt_nav errors apart, findings with their counts."""
    from bt_nav.grading.report import read_grade

    doc = read_grade(grid_dir)
    if doc is None:
        return {"name": name, "dir": grid_dir.name, "graded": False, "cells": {}, "findings": {}, "runs": 0,
                "passed": 0, "errors": 0}
    cells: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    findings: dict[str, int] = defaultdict(int)
    errors = 0
    for row in doc.get("runs", []):
        if row.get("outcome") == "bt_nav error":
            errors += 1
            continue
        cell = cells[cell_key(row)]
        cell[0] += bool(row.get("passed"))
        cell[1] += 1
        for finding in row.get("findings") or []:
            findings[finding] += 1
    for finding in doc.get("findings") or []:  # the grid's own (e.g. across LiDARs)
        findings[finding] += 1
    return {"name": name, "dir": grid_dir.name, "graded": True, "cells": {k: v for k, v in sorted(cells.items())},
            "findings": dict(findings), "runs": sum(v[1] for v in cells.values()),
            "passed": sum(v[0] for v in cells.values()), "errors": errors,
            "reasons": _reasons(doc.get("runs", [])),
            "failures": [[runs_label(runs), reason] for reason, runs in failure_groups(doc.get("runs", []))]}


def _reasons(rows: Sequence[dict[str, Any]]) -> dict[str, int]:
    """The failure reasons of a student's runs, counted (bt_nav errors are not a student's failure)."""
    out: dict[str, int] = defaultdict(int)
    for row in rows:
        if not row.get("passed") and row.get("outcome") != "bt_nav error":
            out[row.get("reason", "?")] += 1
    return dict(out)


#: A class's page in its output directory: written by :func:`write_class_page`, read by :func:`read_class_page`.
CLASS_FILE = "class.json"


def read_class_page(out: Path) -> dict[str, Any]:
    """The class graded into ``out`` (:data:`CLASS_FILE`); ValueError naming the file when it cannot be read."""
    path = Path(out) / CLASS_FILE
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None


def write_class_page(out: Path, students: Sequence[Student], title: str,
                     refused: dict[str, str] | None = None,
                     annotate: Callable[[list[dict[str, Any]]], None] | None = None) -> tuple[Path, Path, Path]:
    """``class.json``, ``class.md`` and ``class.html`` in ``out`` from each student's grid in ``out/<name>``, and
    each ``refused`` student's reason (:func:`admit`) in their place; ``annotate`` adds to the rows before they are
    written (a folder of hand-ins: each row's launch-file lines and the hand-in's overall verdict,
    :func:`bt_nav.grading.handins.add_verdicts`; this module does not import that one, which builds on it)."""
    refused = refused or {}
    out.mkdir(parents=True, exist_ok=True)  # a class whose every student was refused ran nothing there
    rows = [refused_summary(s.name, refused[s.name]) if s.name in refused else student_summary(s.name, out / s.name)
            for s in students]
    if annotate is not None:
        annotate(rows)
    cells = sorted({c for r in rows for c in r["cells"]})
    doc = {"title": title, "cells": cells, "students": rows,
           "commands": {s.name: s.command for s in students}}
    json_path, md_path = out / CLASS_FILE, out / "class.md"
    json_path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    md_path.write_text(class_markdown(rows, cells, title), encoding="utf-8")
    return json_path, md_path, write_class_html(out)


#: The class's page for an instructor (:mod:`bt_nav.grading.classpage`), beside :data:`CLASS_FILE`.
CLASS_HTML = "class.html"


def write_class_html(out: Path, weights: Any = None) -> Path:
    """``class.html`` of the class graded into ``out``, from its ``class.json`` and each student's ``grade.json``,
    the scores with ``weights`` (:class:`bt_nav.grading.scores.Weights`; default: bt_nav's)."""
    from bt_nav.grading.classpage import class_page_html
    from bt_nav.grading.scores import load_weights, student_record

    doc = read_class_page(out)
    records = {str(s["name"]): student_record(out, s, doc.get("commands")) for s in doc.get("students") or []}
    path = Path(out) / CLASS_HTML
    path.write_text(class_page_html(doc, records, weights or load_weights()), encoding="utf-8")
    return path


def _rate(cell: list[int] | None) -> str:
    return f"{cell[0]}/{cell[1]}" if cell else "-"


def class_markdown(rows: Sequence[dict[str, Any]], cells: Sequence[str], title: str) -> str:
    """The class as Markdown: one row per student (with a hand-in's overall verdict and launch checks when the class
    is a folder of hand-ins), one column per cell, then each student's launch lines, failures and findings."""
    handins = any("verdict" in r for r in rows)
    lines = [f"# {title}", "", "| student | " + ("hand-in | launch file | " if handins else "") + "passed | "
             + " | ".join(cells) + " | bt_nav errors |",
             "|---|" + ("---|---|" if handins else "") + "---|" + "---|" * len(cells) + "---|"]
    for r in rows:
        total = f"{r['passed']}/{r['runs']}" if r["graded"] else "FAILED, not run" if r.get("refused") else "not graded"
        name = f"[{r['name']}]({r['dir']}/report.html)" if r["graded"] else r["name"]  # a refused one has no report
        lines.append(f"| {name} | " + (f"{r.get('verdict', '-')} | {_launch_rate(r)} | " if handins else "")
                     + f"{total} | "
                     + " | ".join(_rate(r["cells"].get(c)) for c in cells) + f" | {r['errors']} |")
    for r in rows:
        said = _said(r)
        if said:
            lines += ["", f"## {r['name']}", "", *(f"- {line}" for line in said)]
    return "\n".join(lines) + "\n"


def _launch_rate(row: dict[str, Any]) -> str:
    """``2/3``: the launch checks a hand-in passed (``-`` when the class is not a folder of hand-ins)."""
    checks = (row.get("handin") or {}).get("launch", {}).get("checks", [])
    return f"{sum(1 for c in checks if c['passed'])}/{len(checks)}" if checks else "-"


def _said(row: dict[str, Any]) -> list[str]:
    """A hand-in's launch-file lines, the student's failures, each with the runs that failed so (named with their
    LiDAR: ``lab_side C rplidar seed 0: failed: ...``), then their findings with their counts (the grid's own across
    LiDARs among them)."""
    return [*(row.get("handin") or {}).get("lines", []),
            *(f"{runs}: {reason}" for runs, reason in row.get("failures", [])),
            *(f"finding: {f} (x{n})" for f, n in row["findings"].items())]


def run_class(students: Sequence[Student], plan: Callable[[Student], tuple[Any, Sequence[Any]]],
              workers: Workers, stop: Any = None, on_row: Callable[[str, dict[str, Any]], None] | None = None,
              resume: bool = False, say: Callable[[str], None] | None = None) -> dict[str, list[dict[str, Any]]]:
    """Every student's grid into ``out/<name>``, all their runs in one pool of ``workers`` (a student with fewer
    runs than workers leaves no slot idle), each grid's report written as ``bt-nav grade --exe`` writes it as soon
    as its last run ends. Returns the rows that ended, per student reached. ``workers`` is a count of runs at once
    here, or a :class:`~bt_nav.grading.exe.grid.Cluster`: then every cell is a Dask task there
    (:func:`~bt_nav.grading.exe.grid.run_pool`), the verdicts as here.

    ``plan(student)`` gives the student's :class:`bt_nav.grading.exe.run.ExeSettings` (its command, its
    directory) and jobs (the same worlds, LiDARs and seeds for all; the maneuver each one's own). Resuming keeps
    each student's finished runs (a student whose grid is complete runs nothing). Runs start student by student
    in the manifest's order. A stop request ends the class after the runs under way; the runs not started are
    left for ``--resume``. ``say``: kept for callers' lines (unused since a cell's re-runs are its own).
    """
    from bt_nav.grading.exe.grid import prepare_out

    grids: dict[str, tuple[Any, Sequence[Any], dict[str, dict[str, Any]]]] = {}
    todo: list[tuple[str, Any, Any]] = []
    for student in students:  # every directory checked before the first run
        settings, jobs = plan(student)
        done = prepare_out(settings, jobs, resume)
        grids[student.name] = (settings, jobs, dict(done))
        todo += [(student.name, settings, job) for job in jobs if job.key not in done]
    for name, (settings, jobs, rows) in grids.items():
        if not any(task[0] == name for task in todo):
            _write_student_report(settings, jobs, rows)  # nothing to run: its report as it stands
    _run_pooled(todo, grids, workers, stop, on_row)
    out: dict[str, list[dict[str, Any]]] = {}
    for name, (_settings, jobs, rows) in grids.items():
        ended = _ended(jobs, rows)
        if ended or not jobs:
            out[name] = ended
    return out


def _ended(jobs: Sequence[Any], rows: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """A student's rows that ended (not stopped), in the jobs' order."""
    from bt_nav.grading.exe.grid import STOPPED

    return [rows[job.key] for job in jobs if job.key in rows and rows[job.key]["outcome"] != STOPPED]


def _write_student_report(settings: Any, jobs: Sequence[Any], rows: dict[str, dict[str, Any]]) -> None:
    from bt_nav.grading.report import write_exe_report

    write_exe_report(_ended(jobs, rows), settings)


def _run_pooled(todo: list[tuple[str, Any, Any]], grids: dict[str, tuple[Any, Sequence[Any], dict[str, Any]]],
                workers: Workers, stop: Any, on_row: Callable[[str, dict[str, Any]], None] | None) -> None:
    """Every (student, settings, job) of ``todo`` in one thread pool; a student's report when their last run ends,
    and for every student with a run left when the class stops."""
    from bt_nav.grading.exe.grid import run_pool

    left = Counter(name for name, _, _ in todo)
    for i, row in run_pool([(job, settings) for _, settings, job in todo], workers, stop):
        name = todo[i][0]
        settings, jobs, rows = grids[name]
        if row is not None:
            rows[row["job"]] = row
            if on_row is not None:
                on_row(name, row)
        left[name] -= 1
        if left[name] == 0:
            _write_student_report(settings, jobs, rows)
    for name, count in left.items():
        if count > 0:  # stopped with runs of this student not started: the report of what ended
            _write_student_report(*grids[name])
