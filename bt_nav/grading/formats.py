"""A grade in the formats platforms and CI read: Gradescope's autograder ``results.json`` and JUnit XML.

Why from the result files and not from the grader's internals: ``grade.json`` (one node's grid, what
``bt-nav grade --exe`` writes) and ``class.json`` (a class) are what a grade *is*; a format written from them says
exactly what the report says, can be written again later from a finished grade, and does not change when the
grader's insides do. A *record* here is one node's ``grade.json`` document, optionally with:

- ``"launch"``: the hand-in's launch-file checks (:meth:`bt_nav.grading.launch.check.LaunchReport.to_dict`:
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

import csv
import io
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bt_nav.grading.grid import cell_label, failure_groups, preview_said, run_label, runs_label
from bt_nav.grading.hints import check_rule, finding_hints, launch_hint, not_graded_hint, run_hints, student_words
from bt_nav.grading.report import GRADE_FILE, read_grade
from bt_nav.grading.scores import (  # noqa: F401  (WEIGHTS_FILE, Weights: this module's API since it began)
    CHECKED,
    ERROR,
    NOT_GRADED,
    WEIGHTS_FILE,
    Weights,
    check_counts,
    check_depends,
    check_line,
    check_not_checked,
    graded_runs,
    handin_verdict,
    launch_checks,
    load_weights,
    not_graded_reason,
    run_not_graded,
    score,
    student_record,
    unscored,
)
from bt_nav.grading.scores import tests as scored_tests
from bt_nav.judge.referee_core import check_reason

#: How many failed checks of a run its test's output lists before "and N more" (and failures, the summary).
CHECKS_SHOWN = 5
#: The lines of a crashed node's output its test quotes.
NODE_LOG_LINES = 12
#: Gradescope's Markdown: each test's ``output`` and the top-level one are Markdown.
OUTPUT_FORMAT = "md"


def node_output(row: dict[str, Any], lines: int = NODE_LOG_LINES) -> str:
    """The last ``lines`` lines the node printed in a run (its ``node.log`` in the finished grade; '' when there is
    none): a crash's traceback, quoted where the student reads the verdict."""
    try:
        text = (Path(str(row.get("run_dir", ""))) / "node.log").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    return student_words("\n".join(text.rstrip().splitlines()[-lines:]))


def _md(text: str) -> str:
    """``text`` safe inside Markdown prose: no character starts a heading, a list, a link or emphasis by accident;
    code in backticks stays code."""
    parts = re.split(r"(`[^`]+`)", text)  # odd: code spans, kept as they are
    return "".join(p if i % 2 else re.sub(r"([\\*_#<>\[\]])", r"\\\1", p) for i, p in enumerate(parts))


def _check_line(check: dict[str, Any]) -> str:
    """A failed check for a student: what happened, and the rule it broke (the check's ``required``)."""
    name = str(check.get("name"))
    why = student_words(check_reason(check))
    rule = check_rule(check)  # the rule of the check's own fault: the trigger's for a trigger that did not hold
    rule_text = f" (the rule: {_md(rule)})" if rule and rule not in why else ""
    what = why if why.startswith(name) else f"{name}: {why}"
    return f"- {_md(what)}{rule_text}"


def _run_again(row: dict[str, Any]) -> str:
    """How a preview's failed run went at 1x, whose verdict this is (:func:`preview_said`): one line."""
    said = preview_said(row)
    return f"{said[0].upper()}{said[1:]}." if said else ""


def _run_text(row: dict[str, Any]) -> str:
    """A run's verdict for a student, in Markdown (Gradescope's ``output_format`` md): the failure's words, each
    failed check with the rule it broke, what to change (:mod:`bt_nav.grading.hints`), how it went when run again,
    findings, and a crash's last output; no file of the grader's, nor the grader's notes about itself."""
    if unscored(row):
        what = "Not graded" if run_not_graded(row) else "bt_nav error"
        why = str(row.get(NOT_GRADED) or row.get("reason", "?"))
        hint = not_graded_hint(why)
        return (f"**{what}** (not your node's failure; not scored): {_md(student_words(why))}.\n\n"
                f"**What happened:** {hint[0].upper()}{hint[1:]}.")
    reason = student_words(str(row.get("reason", "?")))
    rest = reason.removeprefix("passed").removeprefix("failed: ").lstrip(": ")  # the verdict said once
    checks = (row.get("verdict") or {}).get("checks") or []
    failed = [c for c in checks if not c.get("passed")]
    head = f"{len(failed)} of {len(checks)} checks failed" if failed else rest  # the checks below say the words
    lines = [("**PASSED**" if row.get("passed") else "**FAILED**") + (f": {_md(head)}" if head else "")]
    if failed:
        lines += ["", "What failed, and the rule it broke:", *(_check_line(c) for c in failed[:CHECKS_SHOWN])]
        if len(failed) > CHECKS_SHOWN:
            lines.append(f"- and {len(failed) - CHECKS_SHOWN} more failed checks")
    hints = run_hints(row) if not row.get("passed") else []
    if hints:
        lines += ["", "**How to fix:** " + " Also: ".join(h[0].upper() + h[1:] + "." for h in hints)]
    again = _run_again(row)
    if again:
        lines += ["", again]
    said = [f"Finding: {_md(student_words(str(f)))}" for f in row.get("findings") or []]
    if said:
        lines += ["", *said]
    found = finding_hints(row)
    if found:
        lines += ["", "**About the findings** (they did not fail the run): "
                  + " Also: ".join(h[0].upper() + h[1:] + "." for h in found)]
    output = node_output(row) if not row.get("passed") and not failed else ""
    if output:
        lines += ["", "What your node printed last:", "", "~~~", output.replace("~~~", "~ ~ ~"), "~~~"]
    return "\n".join(lines)


def _test(name: str, score: float, max_score: float, output: str, visibility: str, **extra: Any) -> dict[str, Any]:
    return {"name": name, "score": score, "max_score": max_score, "output": output,  # unrounded: they add up
            "visibility": visibility, "output_format": OUTPUT_FORMAT, **extra}


def _launch_text(check: dict[str, Any]) -> str:
    """A launch-file check for a student: its verdict, why and on which line, and what to change when it failed; a
    check that ended "not checked" says a TA looks at it (it scores as passed)."""
    line = f" ({check_line(check)})" if check.get("line") else ""
    verdict = "NOT CHECKED: a TA will look" if check_not_checked(check) else \
        f"NOT CHECKED: depends on {_md(check_depends(check) or '')}" if check_depends(check) else \
        "PASSED" if check.get("passed") else "FAILED"
    text = f"**{verdict}**: {_md(student_words(str(check.get('reason', ''))))}{line}"
    hint = None if check_counts(check) else launch_hint(check)
    return text + (f"\n\n**How to fix:** {hint[0].upper()}{hint[1:]}." if hint else "")


def gradescope_results(record: dict[str, Any], weights: Weights | None = None,
                       wall_time: float | None = None) -> dict[str, Any]:
    """Gradescope's ``results.json`` for one node's grade (a record: see the module's docstring), every output in
    Markdown that names no file the student cannot open there. ``wall_time``: the seconds the grade took (the
    ``bt-nav grade`` command's), Gradescope's ``execution_time`` (left out when unknown: the runs ran in parallel,
    so their sum is not it). A hand-in with a run not graded has no results.json (:func:`not_graded_reason`)."""
    weights = weights or load_weights()
    out: list[dict[str, Any]] = []
    for i, test in enumerate(scored_tests(record, weights), 1):
        tags = [t for t in (test.row.get("world"), test.row.get("maneuver"), test.row.get("lidar")) if t]
        status = {} if test.state == "not scored" else {"status": "failed" if test.state == "failed" else "passed"}
        if test.name.startswith("launch file: "):
            output, tags = _launch_text(test.row), ["launch file"]
        elif test.row:
            output = _run_text(test.row)
        else:
            reason = record.get("refused") or ("no run was graded (not your node's failure): ask for a regrade"
                                               if graded_runs(record) else "no run of the grid ended")
            output = f"**Not run**: {_md(student_words(str(reason)))}"
        out.append(_test(test.name, test.score, test.max_score, output, weights.test_visibility, number=str(i),
                         **status, **({"tags": tags} if tags else {})))
    doc = {"score": round(sum(t["score"] for t in out), 4),
           "output": _overall_text(record, graded_runs(record), launch_checks(record)),
           "output_format": OUTPUT_FORMAT, "test_output_format": OUTPUT_FORMAT,
           "visibility": weights.visibility, "stdout_visibility": weights.stdout_visibility, "tests": out}
    if wall_time is not None:
        doc["execution_time"] = math.ceil(wall_time)
    return doc


def _overall_text(record: dict[str, Any], runs: Sequence[dict[str, Any]], checks: Sequence[dict[str, Any]]) -> str:
    """The hand-in's summary for a student, in Markdown: runs passed, each failure with the runs that failed so,
    the launch-file checks passed, the grid's findings; each failed test below says why and what to change."""
    if record.get("refused"):
        lines = [f"**Not run**: {_md(student_words(str(record['refused'])))}"]
    else:
        judged = [r for r in runs if not unscored(r)]
        lines = [f"**{sum(1 for r in judged if r.get('passed'))}/{len(judged)} runs passed.**"]
        groups = failure_groups(judged)
        lines += [f"- {runs_label(group)}: {_md(student_words(reason))}" for reason, group in groups[:CHECKS_SHOWN]]
        if len(groups) > CHECKS_SHOWN:
            lines.append(f"- and {len(groups) - CHECKS_SHOWN} more (each failed test below)")
        errors = len(runs) - len(judged)
        if errors:
            lines.append(f"\n{errors} run(s) without a grade (not your node's failure; not scored): ask for a "
                         "regrade.")
    if checks:
        shown = sum(1 for c in checks if check_counts(c))
        lines.append(f"\nLaunch file: {shown}/{len(checks)} checks passed.")
    lines += [f"\nFinding: {_md(student_words(str(f)))}" for f in record.get("findings") or []]
    if any(not r.get("passed") for r in runs) or not all(check_counts(c) for c in checks):
        lines.append("\nEach failed test below says what happened, the rule it broke and what to change.")
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
    runs = graded_runs(record)
    for row in runs:
        case = ET.SubElement(suite, "testcase", classname=_classname(name, cell_label(row)), name=run_label(row),
                             time=f"{float(row.get('wall_time', 0.0)):.3f}")
        if unscored(row):
            ET.SubElement(case, "error", message=str(row.get("reason", "?")),
                          type=str(row.get("outcome"))).text = _run_text(row)
            counts["errors"] += 1
        elif not row.get("passed"):
            ET.SubElement(case, "failure", message=str(row.get("reason", "?")), type="failed").text = _run_text(row)
            counts["failures"] += 1
    if not runs:
        case = ET.SubElement(suite, "testcase", classname=_classname(name, "hand-in"), name="the node's runs")
        ET.SubElement(case, "failure", message=str(record.get("refused") or "no run of the grid ended"),
                      type="not run")
        counts["failures"] += 1
    for check in launch_checks(record):
        case = ET.SubElement(suite, "testcase", classname=_classname(name, "launch_file"),
                             name=str(check.get("name")))
        if not check_counts(check):
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
    """Every student's record from a finished class (``class.json`` and each student's ``grade.json``,
    :func:`bt_nav.grading.scores.student_record`)."""
    from bt_nav.grading.classroom import read_class_page

    doc = read_class_page(Path(class_dir))
    return [(str(s["name"]), student_record(Path(class_dir), s, doc.get("commands"))) for s in doc.get("students", [])]


#: The CSV's first columns; a column per run and launch-file check follows, each cell that part's state.
CSV_HEAD = ("student", "score", "max_score", "verdict")


def scores_csv(records: Sequence[tuple[str, dict[str, Any]]], weights: Weights | None = None) -> str:
    """A gradebook's CSV of a class: a row per student with their score (the Gradescope points; empty for a hand-in
    not graded), the points possible, the hand-in's verdict, and a column per run and launch-file check (``passed``,
    ``failed``, ``not checked`` (a TA looks), ``not scored`` (not the node's doing), empty: not in their grade)."""
    weights = weights or load_weights()
    parts = {name: {t.name: t.state for t in scored_tests(record, weights)} for name, record in records}
    columns = list(dict.fromkeys(test for states in parts.values() for test in states))
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow([*CSV_HEAD, *columns])
    for name, record in records:
        got = score(record, weights)
        writer.writerow([name, "" if got is None else f"{got:g}", f"{weights.total:g}", handin_verdict(record),
                         *(parts[name].get(c, "") for c in columns)])
    return text.getvalue()
