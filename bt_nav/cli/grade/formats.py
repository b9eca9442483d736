"""``bt-nav grade ... --gradescope results.json --junit report.xml --csv scores.csv [--weights FILE]``: a finished
grade written in the formats platforms, CI and gradebooks read (:mod:`bt_nav.grading.formats`), from its
``grade.json`` / ``class.json``.

Why the options are checked before any run: a weights file with a typo found after an hour of grading would
leave a class graded with points nobody meant. Why the wall time is the process's: Gradescope's ``execution_time``
is how long the autograder took, and the runs of a grade run in parallel (their sum is not it).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from bt_nav.grading.formats import (
    Weights,
    class_records,
    gradescope_results,
    junit_xml,
    load_weights,
    not_graded_reason,
    read_record,
    scores_csv,
)

#: Written instead of a student's results.json when their hand-in has runs not graded: Gradescope must show an
#: autograder error (``autograder/run_autograder`` prints this file and writes no results.json).
AUTOGRADER_ERROR = "autograder_error.md"
#: When this module was imported: the command's start when the process's own start cannot be read.
_IMPORTED = time.monotonic()


def command_wall_time() -> float:
    """Wall seconds since this process started (Linux: from ``/proc``; elsewhere since bt_nav's CLI was imported,
    a second or so later)."""
    try:
        started = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19]) / os.sysconf("SC_CLK_TCK")
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return max(0.0, uptime - started)
    except (OSError, ValueError, IndexError):
        return time.monotonic() - _IMPORTED


def add_format_options(parser: argparse.ArgumentParser) -> None:
    """The four options, for ``--exe`` and ``--class``."""
    parser.add_argument("--gradescope", default=None, metavar="results.json",
                        help="--exe/--class: also write Gradescope's autograder results.json here (a test per run and "
                        "per launch-file check); a class: each student's in --out/_gradescope/<name>/results.json, "
                        "and here the only student's results.json (several students: nothing here; Gradescope "
                        "grades each submission with run_autograder)")
    parser.add_argument("--junit", default=None, metavar="report.xml",
                        help="--exe/--class: also write JUnit XML here (a testsuite per node or student, a testcase "
                        "per run, the failure's message its reason)")
    parser.add_argument("--csv", default=None, metavar="scores.csv",
                        help="--class: also write a gradebook's CSV here (a row per student: score, hand-in verdict, "
                        "each run and launch-file check)")
    parser.add_argument("--weights", default=None, metavar="FILE.yaml",
                        help="the points of --gradescope, --csv and class.html (default: bt_nav's "
                        "gradescope_weights.yaml, every run alike, the launch-file checks 0.2 of 100 points)")


def check_format_options(args: argparse.Namespace) -> Weights | None:
    """The weights to write with (None: no points asked for); ValueError for options that do not fit."""
    if args.exe is None and args.klass is None and (args.gradescope or args.junit):
        raise ValueError("--gradescope and --junit are written for --exe or --class grades")
    if getattr(args, "csv", None) and args.klass is None:
        raise ValueError("--csv is written for --class grades (a row per student)")
    scores = [name for name in ("gradescope", "junit", "csv") if getattr(args, name, None)]
    if scores and getattr(args, "rtf", 1.0) != 1.0:  # bt_nav.grading.exe.pace.preview
        raise ValueError(f"--{scores[0]} writes scores, which come from 1x runs only: --rtf {args.rtf:g} is a preview; "
                         "leave --rtf out to grade at real time")
    if args.weights and not (args.gradescope or getattr(args, "csv", None) or args.klass):
        raise ValueError("--weights sets the points of --gradescope, --csv or a class page: give one of them")
    return load_weights(Path(args.weights) if args.weights else None) \
        if args.gradescope or getattr(args, "csv", None) or args.weights else None


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _json(doc: Any) -> str:
    return json.dumps(doc, indent=1) + "\n"


def _results(name: str, record: dict[str, Any], weights: Weights | None, wall: float | None, where: Path,
             error_dir: Path) -> tuple[dict[str, Any] | None, list[Path]]:
    """One student's results and the files written for them: ``where`` (their results.json), or, for a hand-in with
    runs not graded, :data:`AUTOGRADER_ERROR` in ``error_dir`` and no results.json (an old one removed)."""
    reason = not_graded_reason(record)
    if reason is None:
        (error_dir / AUTOGRADER_ERROR).unlink(missing_ok=True)
        doc = gradescope_results(record, weights, wall)
        return doc, [_write(where, _json(doc))]
    where.unlink(missing_ok=True)
    print(f"bt-nav grade: {name}: not graded, no results.json: {reason}", file=sys.stderr, flush=True)
    text = (f"The autograder could not grade this submission: {reason}. This is not a failure of your code; your "
            "instructor will run the autograder again.\n")
    return None, [_write(error_dir / AUTOGRADER_ERROR, text)]


def write_exe_formats(args: argparse.Namespace, grade_dir: Path) -> list[Path]:
    """One node's grade (``grade_dir/grade.json``) as ``--gradescope`` and ``--junit`` ask; the paths written."""
    if not (args.gradescope or args.junit):
        return []
    record = read_record(grade_dir)
    written = []
    if args.gradescope:
        target = Path(args.gradescope)
        written += _results("the node", record, check_format_options(args), command_wall_time(), target,
                            target.parent)[1]
    if args.junit:
        name = str((record.get("settings") or {}).get("command") or grade_dir.name)
        written.append(_write(Path(args.junit), junit_xml([(name, record)])))
    return written


def write_class_formats(args: argparse.Namespace, class_dir: Path) -> list[Path]:
    """A class (``class_dir/class.json`` and the students' grades): each student's results.json in
    ``class_dir/_gradescope/<name>/`` (no student's name begins with _, so no student's grid is there),
    ``--gradescope``'s path for a class of one (that student's results.json, its ``execution_time`` the command's
    wall time; a class of several writes none there: Gradescope takes one submission's results.json, and a dict of
    students is no format any platform reads), ``--junit``'s (a testsuite per student), ``--csv``'s (a row per
    student), and ``class.html`` again with ``--weights``' points; the paths written."""
    csv_path = getattr(args, "csv", None)
    if not (args.gradescope or args.junit or csv_path or args.weights):
        return []
    records = class_records(class_dir)
    weights = check_format_options(args)
    written = []
    if args.weights:
        from bt_nav.grading.classroom import write_class_html

        write_class_html(class_dir, weights)
    if args.gradescope:
        wall = command_wall_time() if len(records) == 1 else None  # one student's grade is the whole command
        results = {}
        for name, record in records:
            doc, paths = _results(name, record, weights, wall, class_dir / "_gradescope" / name / "results.json",
                                  class_dir / "_gradescope" / name)
            written += paths
            if doc is not None:
                results[name] = doc
        if len(records) == 1 and results:
            written.append(_write(Path(args.gradescope), _json(next(iter(results.values())))))
        elif len(records) == 1:
            Path(args.gradescope).unlink(missing_ok=True)
        else:
            print(f"bt-nav grade: --gradescope: a class of {len(records)}: each student's results.json is in "
                  f"{class_dir / '_gradescope'}/<student>/ (for the instructor's records; Gradescope grades each "
                  f"submission with run_autograder); nothing written at {args.gradescope}", file=sys.stderr)
    if args.junit:
        written.append(_write(Path(args.junit), junit_xml(records)))
    if csv_path:
        written.append(_write(Path(csv_path), scores_csv(records, weights)))
    return written
