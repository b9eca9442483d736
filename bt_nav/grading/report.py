"""The report of an ``--exe`` grid: per world and maneuver figures, a fixed-width table, and in the grid's directory
``grade.json``, ``summary.md`` and ``report.html`` with the pictures and videos it links
(:mod:`bt_nav.grading.media`, :mod:`bt_nav.grading.html`)."""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bt_nav.grading.exe.grid import ERROR, parameters_lines
from bt_nav.grading.exe.pace import achieved_text, speed_words
from bt_nav.grading.exe.run import ExeSettings, exe_ros_args
from bt_nav.grading.grid import (
    failure_groups,
    lidar_findings,
    lidar_label,
    maneuvers_text,
    params_text,
    per_lidar,
    rate_table,
    runs_label,
)
from bt_nav.grading.html import report_html
from bt_nav.grading.media import grid_figures, render_runs
from bt_nav.grading.rules import RULES_FILE, RULES_LINE_MD, grade_rules


def summarize_exe(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per world, maneuver and LiDAR: runs judged, passes, bt_nav errors (apart: never the node's failure), mean
    wall time, the median factor the runs achieved (:mod:`bt_nav.grading.exe.pace`) and the reasons of the failures
    (counted)."""
    cells: dict[tuple[str, str, str, str], list[dict[str, Any]]] = defaultdict(list)
    for row in rows:  # a cell's own node parameters (lab_hallway B safety_distance=0.7) make a cell of their own
        cells[(row["world"], row["maneuver"], row.get("lidar", ""), params_text(row.get("cell_params")))].append(row)
    out = []
    for (world, maneuver, lidar, params), cell in sorted(cells.items()):
        judged = [r for r in cell if r.get("outcome") != ERROR]
        reasons: dict[str, int] = defaultdict(int)
        for row in judged:
            if not row["passed"]:
                reasons[row["reason"]] += 1
        factors = sorted(float(r["rtf"]) for r in cell if r.get("rtf"))  # what each run achieved
        out.append({"world": world, "maneuver": maneuver, "lidar": lidar, "params": params, "runs": len(judged),
                    "passed": sum(1 for r in judged if r["passed"]), "errors": len(cell) - len(judged),
                    "wall_time_mean": sum(r["wall_time"] for r in cell) / len(cell), "reasons": dict(reasons),
                    "rtf_median": factors[len(factors) // 2] if factors else None})
    return out


def format_exe_table(summary: Sequence[dict[str, Any]]) -> str:
    """The summary as a fixed-width table, like ``bt-nav grade``'s (a LiDAR column when the grid varies it)."""
    lidars = any(s.get("lidar") for s in summary)
    head = (f"{'world':<15} {'man':<4} " + (f"{'lidar':<9} " if lidars else "")
            + f"{'pass':>7} {'wall/run':>8} {'speed':>6}  reasons of the failures")
    rows = [f"{' '.join(filter(None, (s['world'], s.get('params')))):<15} {s['maneuver']:<4} "
            + (f"{s.get('lidar') or 'profile':<9} " if lidars else "")
            + f"{s['passed']:>3}/{s['runs']:<3} {s['wall_time_mean']:>7.1f}s "
            + (f"{s['rtf_median']:>5.1f}x  " if s.get("rtf_median") else f"{'-':>6}  ")
            + ("; ".join([*(f"{reason} x{n}" for reason, n in s["reasons"].items()),
                          *([f"bt_nav error x{s['errors']} (not the node's)"] if s.get("errors") else [])]) or "-")
            for s in summary]
    return "\n".join([head, "-" * len(head), *rows])


def summary_markdown(summary: Sequence[dict[str, Any]], settings: ExeSettings,
                     rows: Sequence[dict[str, Any]] = ()) -> str:
    """The grid's report: pass rate per world and LiDAR (rows) and maneuver (columns), the pass rate per LiDAR and
    what differs across them, then every failure reason with the runs that failed so (each named with its LiDAR)."""
    maneuvers, table = rate_table(summary)
    lidars = any(lidar for _, lidar, _ in table)
    runs = sum(s["runs"] for s in summary)
    passed = sum(s["passed"] for s in summary)
    chosen = maneuvers_text(rows)
    lines = [f"# Grade of `{settings.command}` ({settings.profile} profile{', ' + chosen if chosen else ''})", "",
             f"**{passed}/{runs} passed ({100 * passed / max(1, runs):.1f} %)**; "
             f"{speed_words(settings.rtf, settings.rtf_max)}{achieved_text(rows)}, {settings.limit:g} s wall per run.",
             "",
             "| world | " + ("LiDAR | " if lidars else "") + " | ".join(maneuvers) + " |",
             "|---|" + ("---|" if lidars else "") + "---|" * len(maneuvers)]
    for world, lidar, cells in table:
        lines.append(f"| {world} | " + (f"{lidar or 'profile'} | " if lidars else "") + " | ".join(
            f"{cells[m][0]}/{cells[m][1]}" if m in cells else "-" for m in maneuvers) + " |")
    rates = per_lidar(rows)
    if len(rates) > 1:
        lines += ["", "| LiDAR | passed |", "|---|---|"] + [f"| {lidar_label(n)} | {p}/{r} |"
                                                          for n, (p, r) in rates.items()]
    lines += [f"\n**Finding:** {f}" for f in lidar_findings(rows)]
    errors = sum(1 for r in rows if r.get("outcome") == ERROR)
    if errors:
        lines += ["", f"{errors} run(s) hit a bt_nav error (not the node's failure; tracebacks in bt_nav_errors/, "
                  "`--resume` reruns them)."]
    shown: dict[str, list[str]] = {}  # per cell's own parameters, the first run's `ros2 param list` and applied
    for row in rows:
        said = parameters_lines(row)
        if said:
            shown.setdefault(params_text(row.get("cell_params")) or "the grid's", said)
    for cell, said in shown.items():
        lines += ["", f"## Parameters ({cell})", "", *(f"- {line}" for line in said)]
    failures = [f"- {runs_label(runs)}: {reason}" for reason, runs in failure_groups(rows)]
    if failures:
        lines += ["", "## Failures", "", *failures, "", RULES_LINE_MD + "."]
    lines += ["", "Every run's trajectory picture, the videos of the failed runs and the logs: "
              "[report.html](report.html)."]
    return "\n".join(lines) + "\n"


#: A node's grade in its grid directory: written by :func:`write_exe_report`, read by :func:`read_grade` only.
GRADE_FILE = "grade.json"


def read_grade(grid_dir: Path) -> dict[str, Any] | None:
    """The grade written in ``grid_dir`` (:data:`GRADE_FILE`): None when there is none (a grid that never ended);
    ValueError naming the file when it cannot be read."""
    path = Path(grid_dir) / GRADE_FILE
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None


def write_exe_report(rows: Sequence[dict[str, Any]], settings: ExeSettings, workers: int | None = None,
                     drawn: dict[str, dict[str, Any]] | None = None) -> tuple[Path, Path]:
    """``grade.json`` (settings, summary, every row with its pictures), ``summary.md`` and ``report.html`` in the
    grid's directory, after drawing the runs' pictures and videos (``workers`` processes, default one per core;
    ``drawn``: those a :class:`bt_nav.grading.media.Drawer` drew during the grid).

    Returns the JSON and Markdown paths; the page is ``report.html`` next to them.
    """
    summary = summarize_exe(rows)
    settings.out.mkdir(parents=True, exist_ok=True)
    drawn = dict(drawn or {})
    made = drawn.pop("figures", None)  # the grid's figures, when the Drawer's worker drew them
    media = render_runs(rows, settings.videos, settings.record, workers, drawn) if rows else {}
    figures = list(made["names"]) if made is not None else grid_figures(rows, settings.out)
    appended = exe_ros_args("X" if settings.maneuvers else None, settings.profile, settings.node_params)
    doc = {"settings": {"command": settings.command, "profile": settings.profile, "limit_s": settings.limit,
                        "rtf": settings.rtf, "rtf_max": settings.rtf_max, "appended": appended,
                        "record": settings.record, "videos": settings.videos},
           "summary": summary, "figures": figures,
           "per_lidar": {name or "profile": {"label": lidar_label(name), "passed": p, "runs": n}
                         for name, (p, n) in per_lidar(rows).items()},
           "findings": lidar_findings(rows), "bt_nav_errors": sum(1 for r in rows if r.get("outcome") == ERROR),
           "runs": [{**row, "media": media.get(row["job"])} for row in rows]}
    json_path, md_path = settings.out / GRADE_FILE, settings.out / "summary.md"
    json_path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    md_path.write_text(summary_markdown(summary, settings, rows), encoding="utf-8")
    (settings.out / RULES_FILE).write_text(grade_rules(settings, rows), encoding="utf-8")  # the failures link it
    (settings.out / "report.html").write_text(report_html(rows, summary, settings, media, figures), encoding="utf-8")
    return json_path, md_path
