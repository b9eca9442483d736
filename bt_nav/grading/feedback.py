"""One ``feedback.md`` per student: the overall verdict, a line per launch-file check and per run (each run's judge
checks), what to look at, and links to the pictures and videos the runs left. Markdown a learning platform can show
as it is (Gradescope, Moodle, a GitHub Classroom README); every link relative to the file's own folder.

Why one file and not the report pages: a student sees one text on the platform, not a directory of HTML; the
report pages stay for the instructor (``report.html``, ``class.html``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from bt_nav.grading.grid import failure_groups, preview_said, run_label, runs_label
from bt_nav.grading.handins import FEEDBACK, StudentResult, load_class, load_grid
from bt_nav.grading.hints import launch_hint, run_hints
from bt_nav.grading.rules import RULES_FILE


def _link(result: StudentResult, row: dict[str, Any], key: str, text: str) -> str | None:
    """A relative link to the run's ``key`` medium (picture, video) when the file is there."""
    name = (row.get("media") or {}).get(key)
    run_dir = Path(row.get("run_dir", ""))
    if not name or not (run_dir / name).is_file():
        return None
    try:
        rel = (run_dir / name).relative_to(result.directory)
    except ValueError:
        rel = run_dir / name
    return f"[{text}]({rel.as_posix()})"


def _run_lines(result: StudentResult) -> list[str]:
    lines: list[str] = []
    for row in result.runs:
        verdict = "PASSED" if row.get("passed") else "not graded (not yours)" if row.get("not_graded") else \
            "bt_nav error (not yours)" if row.get("outcome") == "bt_nav error" else "FAILED"
        links = [x for x in (_link(result, row, "picture", "picture"), _link(result, row, "video", "video")) if x]
        lines.append(f"- **{run_label(row)}: {verdict}** ({row.get('reason', '?')})"
                     + (" " + ", ".join(links) if links else ""))
        checks = (row.get("verdict") or {}).get("report_lines") or []
        lines += [f"  - {line}" for line in checks if not line.startswith("overall:")]
        lines += [f"  - finding: {f}" for f in row.get("findings") or []]
        said = preview_said(row)
        if said:  # a preview's failure, graded again at 1x (bt_nav.grading.exe.realtime)
            lines.append(f"  - {said}")
    return lines


def _look_at(result: StudentResult) -> list[str]:
    """What the student should look at first: each failed launch check's fix, each failure reason with its runs,
    the node's log of a failed run, the rules."""
    out = []
    if result.launch is not None:
        for check in (c for c in result.launch.checks if not c.passed):
            hint = launch_hint(asdict(check))
            out.append(f"- launch file: {check.name}: {hint or check.reason}" + ("" if check.fix else
                                                                                 f" (now: {check.reason})"))
    judged = [r for r in result.runs if r.get("outcome") != "bt_nav error"]
    for reason, runs in failure_groups(judged):
        hints = run_hints(runs[0])
        out.append(f"- {runs_label(runs)}: {reason}" + (f"; what to change: {'; '.join(hints)}" if hints else ""))
    failed = [r for r in judged if not r.get("passed")]
    if failed:
        log = Path(failed[0].get("run_dir", "")) / "node.log"
        if log.is_file():
            try:
                rel = log.relative_to(result.directory).as_posix()
            except ValueError:
                rel = str(log)
            out.append(f"- what your node printed in {run_label(failed[0])}: [node.log]({rel})")
        if (result.directory / RULES_FILE).is_file():
            out.append(f"- what your node must do, check by check: [{RULES_FILE}]({RULES_FILE})")
    return out


def feedback_markdown(result: StudentResult) -> str:
    """The student's ``feedback.md`` (module docstring)."""
    head = f"# {result.name}: {'PASSED' if result.passed else 'FAILED'}"
    lines = [head, ""]
    if result.reasons:
        lines += [f"- {why}" for why in result.reasons] + [""]
    if result.node or result.choice:
        lines += [f"Node: `{result.node}`"
                  + (f", maneuver {result.choice}" if result.choice else ""), ""]
    if result.launch is not None:
        lines += ["## Launch file" + (f" ({result.launch.file})" if result.launch.file else ""), ""]
        lines += [f"- {line.removeprefix('launch file: ')}" for line in result.launch.lines()]
        lines += [f"- note: {n}" for n in result.launch.notes] + [""]
    if result.refused:
        lines += ["## Runs", "", f"Not run: {result.refused}", ""]
    elif result.runs:
        judged = [r for r in result.runs if r.get("outcome") != "bt_nav error"]
        passed = sum(1 for r in judged if r.get("passed"))
        lines += [f"## Runs ({passed}/{len(judged)} passed)", "", *_run_lines(result), ""]
    look = _look_at(result)
    if look:
        lines += ["## What to look at", "", *look, ""]
    return "\n".join(lines).rstrip() + "\n"


def write_feedback(result: StudentResult) -> Path:
    """``feedback.md`` in the student's directory (made when a refused student has none)."""
    result.directory.mkdir(parents=True, exist_ok=True)
    path = result.directory / FEEDBACK
    path.write_text(feedback_markdown(result), encoding="utf-8")
    return path


def write_class_feedback(out: Path) -> list[Path]:
    """Every student's ``feedback.md`` of the class graded into ``out``."""
    return [write_feedback(result) for result in load_class(out)]


def write_grid_feedback(out: Path) -> Path:
    """The ``feedback.md`` of one ``--exe`` grade in ``out``."""
    return write_feedback(load_grid(out))


def drop_stale_feedback(out: Path, names: Sequence[str]) -> None:
    """A feedback.md left in the directory of a student who ran nothing then (refused): their grid starts there
    now, and a grid's directory must hold a grade or nothing (it is written again at the end)."""
    for name in names:
        stale = out / name / FEEDBACK
        if stale.is_file() and not (out / name / "grid.json").exists() and len(list(stale.parent.iterdir())) == 1:
            stale.unlink()
