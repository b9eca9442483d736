"""``report.html``: the page of an ``--exe`` grid, one static file next to ``grade.json``.

Why static and relative: the grid's directory is what a teaching assistant zips and sends, or opens from a file
manager; the page needs no server, no script and nothing from the network, and every link (pictures, videos,
logs, JSON, bags) is relative to the page, so the directory works wherever it is unpacked. What it shows:

- the command graded, the profile, the real-time factor and the wall-time limit per run;
- the overall pass rate and the pass rate per world and LiDAR (rows) and maneuver (columns), each cell coloured
  from red (none passed) to green (all passed); per LiDAR, the pass rate and what differs across them (a finding);
  then every failure reason with the runs that failed so, each named ``world maneuver lidar seed N``;
- the grid's figures (:func:`bt_nav.grading.media.grid_figures`);
- one row per run: its trajectory picture as a thumbnail (a link to the full picture), verdict, reason, travelled
  distance, wall time, the judge's findings when it gives any, links to its logs, ``verdict.json``,
  ``result.json`` and bag, and the video of a failed run as a player.
"""

from __future__ import annotations

import html
import json
import os
import re
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from bt_nav.grading.exe.pace import achieved_text, speed_words
from bt_nav.grading.exe.run import ExeSettings, exe_ros_args
from bt_nav.grading.grid import (
    cell_label,
    failure_groups,
    lidar_findings,
    lidar_label,
    maneuvers_text,
    per_lidar,
    rate_table,
    run_label,
)
from bt_nav.grading.rules import RULES_LINE_HTML
from bt_nav.run.terminal import shell_text

STYLE = """
 body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 1400px; }
 code { background: #f2f2ee; padding: 1px 4px; }
 table { border-collapse: collapse; margin: 0.6em 0 1.2em; }
 th, td { border: 1px solid #ccc; padding: 4px 8px; vertical-align: top; text-align: left; }
 th { background: #f2f2ee; }
 td.rate { text-align: center; font-weight: bold; }
 .PASSED { background: #d8f0d8; color: #145214; font-weight: bold; }
 .FAILED { background: #f6d6d6; color: #8b1010; font-weight: bold; }
 .overall { font-size: 1.3em; }
 .files a { margin-right: 0.6em; white-space: nowrap; }
 td.num { white-space: nowrap; text-align: right; }
 .note { color: #777; font-style: italic; }
 img.thumb { width: 180px; border: 1px solid #ccc; }
 img.figure { max-width: 100%; }
"""


#: Inline code in Markdown words: `name`.
_CODE = re.compile(r"`([^`]+)`")


def md_html(text: str) -> str:
    """Words written in Markdown (a judge's reason, a launch-file note) as HTML: inline code (backticks) as
    ``<code>``, everything else escaped."""
    parts = _CODE.split(text)  # even: prose, odd: code
    return "".join(f"<code>{html.escape(p)}</code>" if i % 2 else html.escape(p) for i, p in enumerate(parts))


def rate_colour(passed: int, runs: int) -> str:
    """A cell's background: hue 0 (red, none passed) to 120 (green, all passed)."""
    rate = passed / runs if runs else 0.0
    return f"hsl({round(120 * rate)}, 65%, 82%)"


def _rel(out: Path, path: Path) -> str:
    """``path`` as a URL relative to the page in ``out`` (quoted, so any run name works)."""
    return quote(Path(os.path.relpath(path, out)).as_posix())


def _link(out: Path, path: Path, text: str) -> str:
    """``<a>`` to ``path``, relative to the page in ``out``."""
    return f'<a href="{_rel(out, path)}">{html.escape(text)}</a>'


def _header(rows: Sequence[dict[str, Any]], settings: ExeSettings) -> list[str]:
    passed = sum(1 for r in rows if r.get("passed"))
    # the student's choice by its letter (maneuver C); the arguments as one would type them (-p maneuver:=C, not the
    # argv's maneuver:="C"), shell-quoted only where needed
    chosen = maneuvers_text(rows)
    letters = chosen.split(" ", 1)[1] if chosen and "," not in chosen else "X"
    appended = shell_text(exe_ros_args(letters if settings.maneuvers else None, settings.profile,
                                       settings.node_params))
    return [f"<h1>Grade of <code>{html.escape(settings.command)}</code>"
            + (f", {html.escape(chosen)}" if chosen else "") + "</h1>",
            f'<p class="overall">overall: <b>{passed}/{len(rows)} passed '
            f"({100 * passed / max(1, len(rows)):.1f} %)</b></p>",
            "<table>",
            f"<tr><th>command</th><td><code>{html.escape(settings.command)}</code> + "
            f"<code>{html.escape(appended)}</code></td></tr>",
            f"<tr><th>profile</th><td>{html.escape(settings.profile)}</td></tr>",
            *([f"<tr><th>maneuver</th><td>{html.escape(chosen.split(' ', 1)[1])}</td></tr>"] if chosen else []),
            f"<tr><th>real-time factor</th><td>{html.escape(speed_words(settings.rtf, settings.rtf_max))}"
            f"{html.escape(achieved_text(rows))}</td></tr>",
            f"<tr><th>limit per run</th><td>{settings.limit:g} s wall</td></tr>",
            f"<tr><th>recording</th><td>bags {html.escape(settings.record)}, videos "
            f"{html.escape(settings.videos)}</td></tr>",
            f"<tr><th>report made</th><td>{time.strftime('%Y-%m-%d %H:%M:%S')}</td></tr>",
            "</table>"]


def _rates(summary: Sequence[dict[str, Any]]) -> list[str]:
    """The pass rate per world and LiDAR (rows, when the grid varies it) and maneuver, each cell coloured by its
    rate."""
    maneuvers, table = rate_table(summary)
    lidars = any(lidar for _, lidar, _ in table)
    lines = [f"<h2>Pass rate per world{', LiDAR' if lidars else ''} and maneuver</h2>", "<table>",
             "<tr><th>world</th>" + ("<th>LiDAR</th>" if lidars else "")
             + "".join(f"<th>{html.escape(m)}</th>" for m in maneuvers) + "</tr>"]
    for world, lidar, cells in table:
        tds = []
        for m in maneuvers:
            passed, runs = cells.get(m, (0, 0))
            tds.append("<td>-</td>" if m not in cells else
                       f'<td class="rate" style="background: {rate_colour(passed, runs)}">'
                       f"{passed}/{runs} ({100 * passed / max(1, runs):.0f} %)</td>")
        name = f"<th>{html.escape(lidar or 'profile')}</th>" if lidars else ""
        lines.append(f"<tr><th>{html.escape(world)}</th>{name}{''.join(tds)}</tr>")
    lines.append("</table>")
    return lines


def _lidars(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The pass rate per LiDAR and what differs across them (:func:`bt_nav.grading.grid.lidar_findings`, the words
    of ``summary.md`` and ``class.md``); nothing for a grid of one LiDAR."""
    rates = per_lidar(rows)
    if len(rates) < 2:
        return []
    lines = ["<h2>Per LiDAR</h2>", "<table>", "<tr><th>LiDAR</th><th>passed</th></tr>"]
    lines += [f'<tr><td>{html.escape(lidar_label(n))}</td><td class="rate" style="background: {rate_colour(p, r)}">'
              f"{p}/{r}</td></tr>" for n, (p, r) in rates.items()]
    return [*lines, "</table>", *(f"<p><b>Finding:</b> {html.escape(f)}</p>" for f in lidar_findings(rows))]


def _failures(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Every failure reason with the runs that failed so, each named with its LiDAR and linked to its row."""
    groups = failure_groups(rows)
    if not groups:
        return []

    def link(row: dict[str, Any], text: str) -> str:
        return f'<a href="#{quote(Path(row["run_dir"]).name)}">{html.escape(text)}</a>'

    def named(runs: list[dict[str, Any]]) -> str:  # as runs_label names them, each run a link to its row
        if len(runs) == 1:
            return link(runs[0], run_label(runs[0]))
        return f"{html.escape(cell_label(runs[0]))} seeds " + ", ".join(link(r, str(r["seed"])) for r in runs)

    items = [f"<li>{named(runs)}: {html.escape(reason)}</li>" for reason, runs in groups]
    return ["<h2>Why runs failed</h2>", "<ul>", *items, "</ul>", RULES_LINE_HTML]


def _findings(row: dict[str, Any]) -> str:
    """The judge's findings of a run (any JSON), one line each; empty when it gives none."""
    found = row.get("findings")
    if not found:
        return ""
    items = found if isinstance(found, list) else [found]
    text = [item if isinstance(item, str) else json.dumps(item, sort_keys=True) for item in items]
    return "<ul>" + "".join(f"<li>{html.escape(t)}</li>" for t in text) + "</ul>"


def _files(out: Path, run_dir: Path) -> str:
    """Links to a run's logs, JSON and bag (those that exist)."""
    names = sorted(p.name for p in run_dir.glob("*.log")) + [
        n for n in ("verdict.json", "result.json") if (run_dir / n).is_file()]
    links = [_link(out, run_dir / n, n) for n in names]
    if (run_dir / "bag").is_dir():
        links.append(_link(out, run_dir / "bag", "bag/"))
    return '<span class="files">' + " ".join(links) + "</span>"


def _media_cells(out: Path, row: dict[str, Any], media: dict[str, Any]) -> tuple[str, str]:
    """A run's thumbnail (a link to its full picture, or why there is none; a bag that began after the judge's t0
    says so) and its video player with a link."""
    run_dir = Path(row["run_dir"])
    if media.get("picture"):
        pic = _rel(out, run_dir / media["picture"])
        thumb = f'<a href="{pic}"><img class="thumb" src="{pic}" loading="lazy" alt="trajectory"></a>'
        if row.get("bag_after_t0_s"):
            thumb += f'<br><span class="note">bag from t0 + {row["bag_after_t0_s"]:g} s</span>'
        if media.get("note") and media["note"] != "drawn before":  # e.g. the world only: why no path is drawn
            thumb += f'<br><span class="note">{html.escape(media["note"])}</span>'
    else:
        pic, thumb = "", f'<span class="note">no picture: {html.escape(media.get("note") or "not drawn")}</span>'
    video = ""
    if media.get("video"):
        video = (f'<video controls preload="none" width="360" src="{_rel(out, run_dir / media["video"])}" '
                 f'poster="{pic}"></video><br>' + _link(out, run_dir / media["video"], media["video"]))
    return thumb, video


def _run_row(out: Path, row: dict[str, Any], media: dict[str, Any]) -> str:
    """One run's table row (see the module docstring)."""
    run_dir = Path(row["run_dir"])
    verdict = "PASSED" if row.get("passed") else "FAILED"
    thumb, video = _media_cells(out, row, media)
    travelled = (row.get("verdict") or {}).get("travelled")
    reason = html.escape(str(row.get("reason", ""))) + _findings(row)
    cells = [thumb, _link(out, run_dir, run_label(row)), verdict, reason,
             "-" if travelled is None else f"{travelled:.2f} m", f"{row.get('wall_time', 0):.1f} s",
             _files(out, run_dir), video]
    classes = ["", "", verdict, "", "num", "num", "", ""]
    tds = "".join(f'<td class="{c}">{text}</td>' if c else f"<td>{text}</td>" for c, text in zip(classes, cells,
                                                                                                strict=True))
    return f'<tr id="{html.escape(run_dir.name)}">{tds}</tr>'


def report_html(rows: Sequence[dict[str, Any]], summary: Sequence[dict[str, Any]], settings: ExeSettings,
                media: dict[str, dict[str, Any]], figures: Sequence[str]) -> str:
    """The whole page (see the module docstring); ``media`` by job key, ``figures`` relative to the page."""
    out = settings.out
    lines = ["<!doctype html>", '<html lang="en"><head><meta charset="utf-8">',
             f"<title>grade: {html.escape(settings.command)}</title><style>{STYLE}</style></head><body>",
             *_header(rows, settings), *_rates(summary), *_lidars(rows), *_failures(rows)]
    if figures:
        lines.append("<h2>Figures</h2>")
        lines += [f'<p><img class="figure" src="{quote(f)}" alt="{html.escape(f)}"></p>' for f in figures]
    lines += ["<h2>Runs</h2>", "<table>",
              "<tr><th>trajectory</th><th>run</th><th>verdict</th><th>reason</th><th>travelled</th>"
              "<th>wall</th><th>files</th><th>video</th></tr>"]
    lines += [_run_row(out, row, media.get(row["job"], {})) for row in rows]
    lines += ["</table>", "</body></html>"]
    return "\n".join(lines) + "\n"
