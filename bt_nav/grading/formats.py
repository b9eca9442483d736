"""A grade in the formats platforms and CI read: Gradescope's autograder ``results.json`` and JUnit XML.

Why from the result files and not from the grader's internals: ``grade.json`` (one node's grid, what
``bt-nav grade --exe`` writes) and ``class.json`` (a class) are what a grade *is*; a format written from them says
exactly what the report says, can be written again later from a finished grade, and does not change when the
grader's insides do. A *record* here is one node's ``grade.json`` document, optionally with:

- ``"launch"``: the hand-in's launch-file checks (:meth:`bt_nav.grading.launchfile.LaunchReport.to_dict`:
  ``{"file", "passed", "checks": [{"name", "passed", "reason", "line"}], "notes"}``), a test / testcase each;
- ``"refused"``: why the hand-in was not run at all (a class's refused student: no node file, no maneuver).

Gradescope (https://gradescope-autograders.readthedocs.io/en/latest/specs/): one test per run of the grid and one
per launch-file check; a run's points are the runs' share of the total split by weight (every run alike unless
the weights file weighs a world more), the launch-file checks share the rest equally (:func:`load_weights`,
``gradescope_weights.yaml`` beside this file). A run that hit a bt_nav error is none of the node's failure: it is
listed with 0 points of 0 and the others share its points. JUnit: one testsuite per node (per student in a class),
one testcase per run with ``<failure message="the reason">``, a bt_nav error as ``<error>``, a launch-file check as
a testcase of its own (classname ``...launch_file``).

Pure: no rclpy; the only files read are the weights (:func:`load_weights`) and a finished grade
(:func:`read_record`, :func:`class_records`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from bt_nav.grading.grid import cell_label, failure_groups, run_label, runs_label
from bt_nav.grading.report import GRADE_FILE, read_grade

#: bt_nav's default weights (installed as package data); ``--weights FILE`` changes some of them.
WEIGHTS_FILE = Path(__file__).with_name("gradescope_weights.yaml")
#: Gradescope's visibility values (results.json's ``visibility`` and each test's).
VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
#: A run whose outcome is this is bt_nav's failure, not the node's (:data:`bt_nav.grading.exe.grid.ERROR`).
ERROR = "bt_nav error"
#: How many failed checks of a run its test's output lists before "and N more".
CHECKS_SHOWN = 5


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


def _launch_checks(record: dict[str, Any]) -> list[dict[str, Any]]:
    launch = record.get("launch")
    return list(launch.get("checks") or []) if isinstance(launch, dict) else []


def _runs(record: dict[str, Any]) -> list[dict[str, Any]]:
    return [] if record.get("refused") else list(record.get("runs") or [])


def _run_text(row: dict[str, Any]) -> str:
    """A run's verdict for a student: its reason, the checks it failed, its findings, where its pictures are."""
    if row.get("outcome") == ERROR:
        return (f"bt_nav error (not your node's failure; not scored): {row.get('reason', '?')}. "
                "Ask for a regrade: the run is run again.")
    reason = str(row.get("reason", "?"))
    lines = [("PASSED" if row.get("passed") else "FAILED")  # the reason without the verdict said twice
             + (f": {rest}" if (rest := reason.removeprefix("passed").removeprefix("failed: ").lstrip(": ")) else "")]
    failed = [c for c in (row.get("verdict") or {}).get("checks", []) if not c.get("passed")]
    for check in failed[:CHECKS_SHOWN]:
        why = str(check.get("reason") or check.get("detail") or "failed")
        lines.append(f"- {why}" if why.startswith(str(check.get("name"))) else f"- {check.get('name')}: {why}")
    if len(failed) > CHECKS_SHOWN:
        lines.append(f"- and {len(failed) - CHECKS_SHOWN} more failed checks")
    probe = row.get("realtime_probe")
    if isinstance(probe, dict):
        lines.append(f"checked again at 1x real time: {probe.get('reason', '?')}")
    lines += [f"finding: {f}" for f in row.get("findings") or []]
    lines += [f"note: {n}" for n in row.get("notes") or []]
    media = row.get("media") or {}
    where = Path(str(row.get("run_dir", ""))).name
    shown = [f"{what} {where}/{media[what]}" for what in ("picture", "video") if media.get(what)]
    if shown:
        lines.append("in the grade's directory: " + ", ".join(shown))
    return "\n".join(lines)


def _run_points(runs: Sequence[dict[str, Any]], points: float, weights: Weights) -> list[float]:
    """Each run's max score: ``points`` split by world weight among the judged runs (a bt_nav error: 0)."""
    scale = [0.0 if r.get("outcome") == ERROR else weights.worlds.get(r.get("world", ""), 1.0) for r in runs]
    whole = sum(scale)
    return [points * s / whole if whole else 0.0 for s in scale]


def _points(record: dict[str, Any], weights: Weights) -> tuple[float, float]:
    """(the runs' points, the launch-file checks' points)."""
    launch = weights.total * weights.launch_share if _launch_checks(record) else 0.0
    return weights.total - launch, launch


def _test(name: str, score: float, max_score: float, output: str, visibility: str, **extra: Any) -> dict[str, Any]:
    return {"name": name, "score": score, "max_score": max_score, "output": output,  # unrounded: they add up
            "visibility": visibility, **extra}


def gradescope_results(record: dict[str, Any], weights: Weights | None = None) -> dict[str, Any]:
    """Gradescope's ``results.json`` for one node's grade (a record: see the module's docstring)."""
    weights = weights or load_weights()
    run_points, launch_points = _points(record, weights)
    runs = _runs(record)
    tests: list[dict[str, Any]] = []
    judged = [r for r in runs if r.get("outcome") != ERROR]
    if judged:
        for i, (row, points) in enumerate(zip(runs, _run_points(runs, run_points, weights), strict=True), 1):
            passed = bool(row.get("passed")) and row.get("outcome") != ERROR
            status = {} if row.get("outcome") == ERROR else {"status": "passed" if passed else "failed"}
            tests.append(_test(f"run {run_label(row)}", points if passed else 0.0, points, _run_text(row),
                               weights.test_visibility, number=f"1.{i}", **status,
                               tags=[t for t in (row.get("world"), row.get("maneuver"), row.get("lidar")) if t]))
    else:
        reason = record.get("refused") or ("every run hit a bt_nav error (not your node's failure): ask for a regrade"
                                           if runs else "no run of the grid ended")
        tests.append(_test("the node's runs", 0.0, run_points, f"not graded: {reason}", weights.test_visibility,
                           status="failed", number="1"))
    checks = _launch_checks(record)
    for i, check in enumerate(checks, 1):
        share = launch_points / len(checks)
        passed = bool(check.get("passed"))
        line = f" (line {check['line']})" if check.get("line") else ""
        tests.append(_test(f"launch file: {check.get('name')}", share if passed else 0.0, share,
                           f"{'PASSED' if passed else 'FAILED'}: {check.get('reason', '')}{line}",
                           weights.test_visibility, status="passed" if passed else "failed", number=f"2.{i}",
                           tags=["launch file"]))
    return {"score": round(sum(t["score"] for t in tests), 4), "output": _overall_text(record, runs, checks),
            "visibility": weights.visibility, "stdout_visibility": weights.stdout_visibility,
            "execution_time": math.ceil(sum(r.get("wall_time", 0.0) for r in runs)), "tests": tests}


def _overall_text(record: dict[str, Any], runs: Sequence[dict[str, Any]], checks: Sequence[dict[str, Any]]) -> str:
    """The hand-in's summary for a student: runs passed, launch-file checks passed, failures grouped by reason
    with the runs that failed so, the grid's findings."""
    if record.get("refused"):
        lines = [f"Not run: {record['refused']}"]
    else:
        judged = [r for r in runs if r.get("outcome") != ERROR]
        lines = [f"{sum(1 for r in judged if r.get('passed'))}/{len(judged)} runs passed."]
        lines += [f"- {runs_label(group)}: {reason}" for reason, group in failure_groups(runs)]
        errors = len(runs) - len(judged)
        if errors:
            lines.append(f"{errors} run(s) hit a bt_nav error (not your node's failure; not scored): ask for a "
                         "regrade.")
    if checks:
        lines.append(f"Launch file: {sum(1 for c in checks if c.get('passed'))}/{len(checks)} checks passed.")
    lines += [f"Finding: {f}" for f in record.get("findings") or []]
    if runs:
        media = [r.get("media") or {} for r in runs]
        shown = [f"{sum(1 for m in media if m.get(k))} {k}(s)" for k in ("picture", "video")
                 if any(m.get(k) for m in media)]
        lines.append("The grade's directory holds rules.md (the rules your node was judged by) and report.html"
                     + (f" ({', '.join(shown)} of the runs)." if shown else "."))
    return "\n".join(lines)


def _testsuite(name: str, record: dict[str, Any]) -> ET.Element:
    """One node's testsuite: a testcase per run (``<failure message=reason>``, a bt_nav error as ``<error>``), a
    testcase per launch-file check, or one failed testcase saying why the hand-in was not run."""
    suite = ET.Element("testsuite", name=name)
    props = ET.SubElement(suite, "properties")
    for key in ("command", "profile"):
        value = (record.get("settings") or {}).get(key)
        if value:
            ET.SubElement(props, "property", name=key, value=str(value))
    counts = {"tests": 0, "failures": 0, "errors": 0}
    runs = _runs(record)
    for row in runs:
        case = ET.SubElement(suite, "testcase", classname=_classname(name, cell_label(row)), name=run_label(row),
                             time=f"{float(row.get('wall_time', 0.0)):.3f}")
        if row.get("outcome") == ERROR:
            ET.SubElement(case, "error", message=str(row.get("reason", "?")), type=ERROR).text = _run_text(row)
            counts["errors"] += 1
        elif not row.get("passed"):
            ET.SubElement(case, "failure", message=str(row.get("reason", "?")), type="failed").text = _run_text(row)
            counts["failures"] += 1
    if not runs:
        case = ET.SubElement(suite, "testcase", classname=_classname(name, "hand-in"), name="the node's runs")
        ET.SubElement(case, "failure", message=str(record.get("refused") or "no run of the grid ended"),
                      type="not run")
        counts["failures"] += 1
    for check in _launch_checks(record):
        case = ET.SubElement(suite, "testcase", classname=_classname(name, "launch_file"),
                             name=str(check.get("name")))
        if not check.get("passed"):
            ET.SubElement(case, "failure", message=str(check.get("reason", "")), type="launch file")
            counts["failures"] += 1
    counts["tests"] = len(suite.findall("testcase"))
    suite.set("time", f"{sum(float(r.get('wall_time', 0.0)) for r in runs):.3f}")
    for key, value in {**counts, "skipped": 0}.items():
        suite.set(key, str(value))
    return suite


def _classname(suite: str, what: str) -> str:
    """A JUnit classname (dotted: CI's reports group testcases by it): the suite, then the cell or part."""
    return ".".join(part.replace(".", "_").replace(" ", ".") for part in (suite, what))


def junit_xml(records: Sequence[tuple[str, dict[str, Any]]]) -> str:
    """JUnit XML with one testsuite per ``(name, record)``: a node (``--exe``: one) or every student of a class."""
    root = ET.Element("testsuites", name="bt-nav grade")
    suites = [_testsuite(name, record) for name, record in records]
    for key in ("tests", "failures", "errors"):
        root.set(key, str(sum(int(s.get(key, "0")) for s in suites)))
    root.set("time", f"{sum(float(s.get('time', '0')) for s in suites):.3f}")
    root.extend(suites)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def read_record(grade_dir: Path) -> dict[str, Any]:
    """The record of a node's finished grade: its ``grade.json`` (ValueError when it cannot be read)."""
    record = read_grade(Path(grade_dir))
    if record is None:
        raise ValueError(f"cannot read {Path(grade_dir) / GRADE_FILE}: no such file")
    return record


def class_records(class_dir: Path) -> list[tuple[str, dict[str, Any]]]:
    """Every student's record from a finished class (``class.json`` and each student's ``grade.json``): a refused
    student's holds the reason, a student whose grid wrote no grade.json has no runs; the launch-file checks are
    taken from the student's grade.json, else from their line of class.json (a folder of hand-ins:
    ``handin.launch``, :meth:`bt_nav.grading.handins.HandIn.record`)."""
    from bt_nav.grading.classroom import read_class_page

    doc = read_class_page(Path(class_dir))
    out = []
    for student in doc.get("students", []):
        name = str(student["name"])
        if student.get("refused"):
            record: dict[str, Any] = {"refused": student["refused"], "runs": []}
        elif (Path(class_dir) / student.get("dir", name) / GRADE_FILE).is_file():
            record = read_record(Path(class_dir) / student.get("dir", name))
        else:
            record = {"runs": []}
        launch = (student.get("handin") or {}).get("launch") or student.get("launch")
        if "launch" not in record and isinstance(launch, dict):
            record["launch"] = launch
        record.setdefault("settings", {}).setdefault("command", (doc.get("commands") or {}).get(name, ""))
        out.append((name, record))
    return out
