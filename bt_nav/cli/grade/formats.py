"""``bt-nav grade ... --gradescope results.json --junit report.xml [--weights FILE]``: a finished grade written in
the formats platforms and CI read (:mod:`bt_nav.grading.formats`), from its ``grade.json`` / ``class.json``.

Why the options are checked before any run: a weights file with a typo found after an hour of grading would
leave a class graded with points nobody meant.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from bt_nav.grading.formats import Weights, class_records, gradescope_results, junit_xml, load_weights, read_record


def add_format_options(parser: argparse.ArgumentParser) -> None:
    """The three options, for ``--exe`` and ``--class``."""
    parser.add_argument("--gradescope", default=None, metavar="results.json",
                        help="--exe/--class: also write Gradescope's autograder results.json here (a test per run and "
                        "per launch-file check); a class: each student's in --out/_gradescope/<name>/results.json, "
                        "and here the only student's results.json (several students: a JSON object name: results)")
    parser.add_argument("--junit", default=None, metavar="report.xml",
                        help="--exe/--class: also write JUnit XML here (a testsuite per node or student, a testcase "
                        "per run, the failure's message its reason)")
    parser.add_argument("--weights", default=None, metavar="FILE.yaml",
                        help="--gradescope's points and visibility (default: bt_nav's gradescope_weights.yaml, every "
                        "run alike, the launch-file checks 0.2 of 100 points)")


def check_format_options(args: argparse.Namespace) -> Weights | None:
    """The weights to write with (None: no --gradescope); ValueError for options that do not fit."""
    if args.exe is None and args.klass is None and (args.gradescope or args.junit):
        raise ValueError("--gradescope and --junit are written for --exe or --class grades")
    if args.weights and not args.gradescope:
        raise ValueError("--weights sets --gradescope's points: give --gradescope FILE too")
    return load_weights(Path(args.weights) if args.weights else None) if args.gradescope else None


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def _json(doc: Any) -> str:
    return json.dumps(doc, indent=1) + "\n"


def write_exe_formats(args: argparse.Namespace, grade_dir: Path) -> list[Path]:
    """One node's grade (``grade_dir/grade.json``) as ``--gradescope`` and ``--junit`` ask; the paths written."""
    if not (args.gradescope or args.junit):
        return []
    record = read_record(grade_dir)
    written = []
    if args.gradescope:
        weights = check_format_options(args)
        written.append(_write(Path(args.gradescope), _json(gradescope_results(record, weights))))
    if args.junit:
        name = str((record.get("settings") or {}).get("command") or grade_dir.name)
        written.append(_write(Path(args.junit), junit_xml([(name, record)])))
    return written


def write_class_formats(args: argparse.Namespace, class_dir: Path) -> list[Path]:
    """A class (``class_dir/class.json`` and the students' grades): each student's results.json in
    ``class_dir/_gradescope/<name>/`` (no student's name begins with _, so no student's grid is there),
    ``--gradescope``'s path (a class of one: that student's results.json; more: a JSON object name: results) and
    ``--junit``'s (a testsuite per student); the paths written."""
    if not (args.gradescope or args.junit):
        return []
    records = class_records(class_dir)
    written = []
    if args.gradescope:
        weights = check_format_options(args)
        results = {name: gradescope_results(record, weights) for name, record in records}
        for name, doc in results.items():
            written.append(_write(class_dir / "_gradescope" / name / "results.json", _json(doc)))
        only = next(iter(results.values())) if len(results) == 1 else results
        written.append(_write(Path(args.gradescope), _json(only)))
    if args.junit:
        written.append(_write(Path(args.junit), junit_xml(records)))
    return written
