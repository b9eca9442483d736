"""``class.html``: a class on one page an instructor skims, filters and sorts, one self-contained file.

Why it looks so: with 200 students the page must answer "who failed, and why" at a glance, for any class (each
student on their own maneuver, A, B and C mixed). So a row per student, short and no wider than a laptop's window
(1280 px): the hand-in's verdict coloured (red failed, amber not graded, green passed: a hand-in whose runs passed but
whose launch file failed is red, not green), the score (the points Gradescope and the gradebook's CSV give,
:mod:`bt_nav.grading.scores`), the runs passed and the launch-file checks passed (each count saying what it counts),
the maneuver the student chose (once per row), and the first failure's reason, in view. The rest is folded per
student (``<details>``, opened one student at a time): every failure with its arena, LiDAR and seeds, the runs
as a matrix of what varies within a choice (arena x LiDAR: a class mixing choices would otherwise get a sparse
column per arena x maneuver x LiDAR), what passed. Failures first; a note every hand-in shares said once above the
table. Filters by verdict, by reason (the failed checks' names, a crash, a launch-file check) and by name; every
column header with an arrow sorts. Markdown in the words (backticks) is shown as code, everything else escaped.

Why self-contained: the class directory is zipped and sent, or opened from a file manager; the page's script and
style are inline, it loads nothing from the network, and every link (each student's ``report.html`` and
``feedback.md``) is relative.

Pure: reads nothing; :func:`class_page_html` is given ``class.json``'s document and each student's record.
"""

from __future__ import annotations

import html
import json
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from bt_nav.grading.grid import CRASH_REASONS, failure_groups, lidar_label, params_text
from bt_nav.grading.html import STYLE, md_html, rate_colour
from bt_nav.grading.scores import (
    FAILED,
    NOT_GRADED,
    NOT_GRADED_VERDICT,
    PASSED,
    Weights,
    check_counts,
    check_depends,
    check_not_checked,
    graded_runs,
    handin_verdict,
    launch_checks,
    run_not_graded,
    score,
    unscored,
)

#: The verdicts' order on the page (failures first) and their CSS class.
VERDICT_ORDER = {FAILED: 0, NOT_GRADED_VERDICT: 1, PASSED: 2}
VERDICT_CLASS = {FAILED: "v-failed", NOT_GRADED_VERDICT: "v-notgraded", PASSED: "v-passed"}

PAGE_STYLE = STYLE + """
 body { max-width: none; margin: 1em; }
 .controls { margin: 0.6em 0; display: flex; gap: 1.2em; flex-wrap: wrap; align-items: center; }
 .counts span { margin-right: 1em; }
 #students { width: 100%; table-layout: fixed; }
 #students col.c-name { width: 9em; } #students col.c-verdict { width: 8.5em; } #students col.c-score { width: 6em; }
 #students col.c-runs { width: 7.5em; } #students col.c-launch { width: 6.5em; } #students col.c-man { width: 5.5em; }
 #students td { overflow-wrap: anywhere; }
 th.sort { cursor: pointer; user-select: none; white-space: nowrap; }
 th.sort::after { content: " \\2195"; color: #999; }
 tr.v-failed > td:first-child { border-left: 6px solid #c0392b; }
 tr.v-notgraded > td:first-child { border-left: 6px solid #d4a017; }
 tr.v-passed > td:first-child { border-left: 6px solid #2e8b57; }
 td.verdict { font-weight: bold; white-space: nowrap; }
 td.v-failed { background: #f6d6d6; color: #8b1010; }
 td.v-notgraded { background: #fde9b8; color: #6b4e00; }
 td.v-passed { background: #d8f0d8; color: #145214; }
 td.man { text-align: center; font-weight: bold; }
 .fail { margin: 0 0 0.4em; }
 .first { margin: 0 0 0.2em; }
 .where { font-size: 0.85em; color: #555; }
 .where b { color: #222; }
 .ta { background: #fff3c4; padding: 1px 4px; }
 details summary { cursor: pointer; color: #555; }
 details .matrix { margin: 0.4em 0; width: auto; }
 details .matrix td, details .matrix th { font-size: 0.85em; padding: 2px 6px; }
 tr.hidden { display: none; }
"""

#: The page's script: filters (verdict, reason, name) and sorting by any column with a ``data-key``.
SCRIPT = """
(function () {
  const table = document.getElementById('students');
  const body = table.tBodies[0];
  const verdict = document.getElementById('f-verdict');
  const reason = document.getElementById('f-reason');
  const name = document.getElementById('f-name');
  const shown = document.getElementById('shown');
  function filter() {
    let n = 0;
    for (const row of body.rows) {
      const reasons = JSON.parse(row.dataset.reasons);
      const ok = (!verdict.value || row.dataset.verdict === verdict.value)
        && (!reason.value || reasons.includes(reason.value))
        && (!name.value || row.dataset.name.toLowerCase().includes(name.value.toLowerCase()));
      row.classList.toggle('hidden', !ok);
      n += ok ? 1 : 0;
    }
    shown.textContent = n;
  }
  let last = null, up = true;
  function sort(key) {
    up = last === key ? !up : true;
    last = key;
    const rows = Array.from(body.rows);
    const value = (row) => { const v = row.dataset[key]; const x = parseFloat(v); return isNaN(x) ? v : x; };
    rows.sort((a, b) => {
      const x = value(a), y = value(b);
      const c = (typeof x === 'number' && typeof y === 'number') ? x - y : String(x).localeCompare(String(y));
      return (up ? c : -c) || (Number(a.dataset.order) - Number(b.dataset.order));
    });
    for (const row of rows) body.appendChild(row);
  }
  for (const th of table.tHead.rows[0].cells) {
    if (th.dataset.key) th.addEventListener('click', () => sort(th.dataset.key));
  }
  for (const control of [verdict, reason, name]) control.addEventListener('input', filter);
  filter();
})();
"""


def run_kinds(row: dict[str, Any]) -> list[str]:
    """What a failed run failed on, as the reason filter names it: its failed checks' names (``maneuver N`` as
    ``maneuver``), or how it ended without a verdict (``node crashed``, ``no verdict in time``, ``not judged``);
    a run none of the node's doing by its outcome."""
    if unscored(row):
        return [str(row.get("outcome"))]
    if row.get("passed"):
        return []
    checks = [str(c.get("name", "")) for c in (row.get("verdict") or {}).get("checks") or [] if not c.get("passed")]
    if checks:
        return list(dict.fromkeys("maneuver" if c.startswith("maneuver ") and c[9:].isdigit() else c for c in checks))
    reason = str(row.get("reason", ""))
    if reason.startswith(CRASH_REASONS):
        return ["node crashed"]
    if reason.startswith("no verdict within"):
        return ["no verdict in time"]
    return ["not judged" if reason.startswith("not judged") else str(row.get("outcome") or "failed")]


def reason_kinds(record: dict[str, Any]) -> list[str]:
    """Every reason a hand-in did not pass, as the filter lists them (:func:`run_kinds`, ``not run``, a
    launch-file check's name, ``launch file: a TA looks``)."""
    kinds = ["not run"] if record.get("refused") else []
    for row in graded_runs(record):
        kinds += run_kinds(row)
    for check in launch_checks(record):
        if check_not_checked(check):
            kinds.append("launch file: a TA looks")
        elif not check_counts(check):
            kinds.append(f"launch file: {check.get('name')}")
    return list(dict.fromkeys(kinds))


def _run_link(row: dict[str, Any], folder: str) -> str:
    """A link to the run's row in the student's report (``report.html#<run folder>``)."""
    run = Path(str(row.get("run_dir", ""))).name
    return f' <a href="{html.escape(folder)}/report.html#{quote(run)}">seed {html.escape(str(row.get("seed")))}</a>'


def _launch_failures(record: dict[str, Any]) -> list[str]:
    """The launch-file checks that failed, in the words of the terminal's lines (one line when all failed alike: no
    file, a syntax error), and those a TA must look at."""
    checks = launch_checks(record)
    failed = [c for c in checks if not check_counts(c)]

    def at(check: dict[str, Any]) -> str:
        if not check.get("line"):
            return ""
        return f"{check['file']}:{check['line']}: " if check.get("file") else f"line {check['line']}: "

    out = [f'<div class="fail"><span class="ta">TA: look at the launch file</span> '
           f"{html.escape(str(c.get('name')))}: {md_html(at(c) + str(c.get('reason', '')))}</div>"
           for c in checks if check_not_checked(c)]
    if failed and len(failed) == len(checks) and len({str(c.get("reason")) for c in failed}) == 1:
        return [f'<div class="fail">launch file: FAILED ({md_html(at(failed[0]) + str(failed[0].get("reason")))})'
                "</div>"]
    return out + [f'<div class="fail">launch file: {html.escape(str(c.get("name")))}: FAILED '
                  f"({md_html(at(c) + str(c.get('reason', '')))})</div>" for c in failed]


def _failures(record: dict[str, Any], folder: str) -> list[str]:
    """Each failure of a hand-in: its arena, LiDAR, maneuver and seeds (each a link to the run in the student's
    report), then the judge's words; the runs not scored; the launch-file checks that failed or that a TA must
    look at."""
    out = []
    if record.get("refused"):
        out.append(f'<div class="fail"><b>not run:</b> {md_html(str(record["refused"]))}</div>')
    runs = graded_runs(record)
    for reason, group in failure_groups([r for r in runs if not unscored(r)]):
        first = group[0]
        lidar = str(first.get("lidar") or "")
        where = (f'<span class="where">arena <b>{html.escape(str(first.get("world")))}</b>, LiDAR '
                 f'<b title="{html.escape(lidar_label(lidar))}">{html.escape(lidar or "profile")}</b>, maneuver '
                 f'<b>{html.escape(str(first.get("maneuver")))}</b>,' + ",".join(_run_link(r, folder) for r in group)
                 + "</span>")
        out.append(f'<div class="fail">{where}<br>{md_html(reason)}</div>')
    for row in (r for r in runs if unscored(r)):
        what = "not graded" if run_not_graded(row) else str(row.get("outcome"))
        why = str(row.get(NOT_GRADED) or row.get("reason", "?")).removeprefix("not graded: ")
        out.append(f'<div class="fail"><b>{html.escape(what)}</b> (not the node\'s; not scored): {md_html(why)}</div>')
    return out + _launch_failures(record)


def _passed_lines(row: dict[str, Any], record: dict[str, Any], shared: set[str]) -> list[str]:
    """What went right: the runs passed, the launch-file checks passed (and those not checked because another
    failed), the notes not every hand-in shares, the findings."""
    checks = launch_checks(record)
    lines = [f"launch file: {c.get('name')}: PASSED" for c in checks
             if c.get("passed") and not check_not_checked(c) and not check_depends(c)]
    lines += [f"launch file: {c.get('name')}: not checked: depends on {check_depends(c)}" for c in checks
              if check_depends(c)]
    lines += [f"note: {n}" for n in _notes(row) if n not in shared]
    lines += [f"finding: {f} (x{n})" for f, n in (row.get("findings") or {}).items()]
    passed = sum(1 for r in graded_runs(record) if r.get("passed"))
    if passed:
        lines.insert(0, f"{passed} run{'s' if passed != 1 else ''} passed")
    return lines


def _notes(row: dict[str, Any]) -> list[str]:
    return list((((row.get("handin") or {}).get("launch") or {}).get("notes")) or [])


def _matrix(record: dict[str, Any]) -> str:
    """A hand-in's runs as a table of what varies within its choice: a row per arena (with the cell's own
    parameters; its maneuver too when the hand-in was graded as several), a column per LiDAR; each cell the runs
    passed of those graded there, coloured by its rate (runs not graded said apart)."""
    runs = graded_runs(record)
    several = len({r.get("maneuver") for r in runs}) > 1
    cells: dict[tuple[str, str], list[int]] = {}
    for row in runs:
        arena = " ".join(p for p in (str(row.get("world")), str(row.get("maneuver")) if several else "",
                                     params_text(row.get("cell_params"))) if p)
        cell = cells.setdefault((arena, str(row.get("lidar") or "profile")), [0, 0, 0])
        if unscored(row):
            cell[2] += 1
        else:
            cell[0] += bool(row.get("passed"))
            cell[1] += 1
    if not cells:
        return ""
    arenas, lidars = sorted({a for a, _ in cells}), sorted({x for _, x in cells})

    def td(key: tuple[str, str]) -> str:
        if key not in cells:
            return '<td class="num">-</td>'
        ok, n, left = cells[key]
        more = f" +{left} not graded" if left else ""
        style = f' style="background:{rate_colour(ok, n)}"' if n else ""
        return f'<td class="rate"{style}>{ok}/{n}{more}</td>'

    head = "<tr><th>arena</th>" + "".join(f'<th title="{html.escape(lidar_label(x))}">{html.escape(x)}</th>'
                                          for x in lidars) + "</tr>"
    body = "".join(f"<tr><td>{html.escape(a)}</td>" + "".join(td((a, x)) for x in lidars) + "</tr>" for a in arenas)
    return f'<table class="matrix"><caption class="where">runs passed per arena and LiDAR</caption>{head}{body}</table>'


def _folded(row: dict[str, Any], record: dict[str, Any], failures: Sequence[str], shared: set[str]) -> str:
    """A student's details, folded: the failures after the first, the runs per arena and LiDAR, what passed;
    the summary says how many of each it holds."""
    passed = _passed_lines(row, record, shared)
    matrix = _matrix(record)
    runs = sum(1 for r in graded_runs(record) if r.get("passed"))
    checks = sum(1 for c in launch_checks(record) if c.get("passed") and not check_not_checked(c)
                 and not check_depends(c))
    found = sum(1 for line in passed if line.startswith("finding: "))

    def count(n: int, what: str) -> str:
        return f"{n} {what}{'s' if n != 1 else ''}" if n else ""

    said = [count(max(0, len(failures) - 1), "more failure"), "runs per arena and LiDAR" if matrix else "",
            f"passed: {', '.join(w for w in (count(runs, 'run'), count(checks, 'launch check')) if w)}"
            if runs or checks else "", count(found, "finding")]
    summary = ", ".join(w for w in said if w)
    if not summary:
        return ""
    return (f"<details><summary>{html.escape(summary)}</summary>{''.join(failures[1:])}{matrix}"
            + "<br>".join(md_html(line) for line in passed) + "</details>")


def _row(order: int, row: dict[str, Any], record: dict[str, Any], weights: Weights, shared: set[str]) -> str:
    """One student's ``<tr>`` (its ``data-*`` feed the script's filters and sorting)."""
    verdict = handin_verdict(record)
    got = score(record, weights)
    name = html.escape(str(row["name"]))
    where = html.escape(str(row.get("dir", row["name"])))
    links = (f'<a href="{where}/report.html">{name}</a><br><span class="where"><a href="{where}/feedback.md">'
             f"feedback.md</a></span>" if row.get("graded") else name)
    runs = [r for r in graded_runs(record) if not unscored(r)]
    passed = sum(1 for r in runs if r.get("passed"))
    checks = launch_checks(record)
    launch = f"{sum(1 for c in checks if check_counts(c))}/{len(checks)} checks" if checks else "-"
    maneuvers = sorted({str(r.get("maneuver")) for r in graded_runs(record) if r.get("maneuver")})
    failures = _failures(record, str(row.get("dir", row["name"])))
    first = failures[0].replace('class="fail"', 'class="first"', 1) if failures else ""
    data = {"name": str(row["name"]), "verdict": verdict, "rank": VERDICT_ORDER[verdict],
            "score": -1 if got is None else got, "runs": passed / len(runs) if runs else -1, "order": order,
            "reasons": json.dumps(reason_kinds(record))}
    attrs = " ".join(f'data-{k}="{html.escape(str(v))}"' for k, v in data.items())
    return (f'<tr class="{VERDICT_CLASS[verdict]}" {attrs}><td>{links}</td>'
            f'<td class="verdict {VERDICT_CLASS[verdict]}">{verdict}</td>'
            f'<td class="num">{"-" if got is None else f"{round(got, 1):g}"} / {weights.total:g}</td>'
            f'<td class="num">{passed}/{len(runs)} runs</td><td class="num">{launch}</td>'
            f'<td class="man">{html.escape(", ".join(maneuvers) or "-")}</td>'
            f'<td class="reason">{first}{_folded(row, record, failures, shared)}</td></tr>')


def _rank(row: dict[str, Any], record: dict[str, Any], weights: Weights) -> tuple[int, float, str]:
    """Failures first, then not graded, then passed; the lowest score first; by name."""
    got = score(record, weights)
    return VERDICT_ORDER[handin_verdict(record)], -1.0 if got is None else got, str(row["name"])


def class_page_html(doc: dict[str, Any], records: dict[str, dict[str, Any]], weights: Weights) -> str:
    """The whole page (module docstring) of ``class.json``'s document ``doc``, ``records`` by student name."""
    esc = html.escape
    title = str(doc.get("title", "Class grade"))
    rows = sorted(doc.get("students") or [], key=lambda r: _rank(r, records[r["name"]], weights))
    notes = Counter(n for r in rows for n in set(_notes(r)))
    shared = {n for n, k in notes.items() if k == len(rows) and len(rows) > 1}
    verdicts = Counter(handin_verdict(records[r["name"]]) for r in rows)
    kinds = sorted({k for r in rows for k in reason_kinds(records[r["name"]])})
    body = [_row(i, r, records[r["name"]], weights, shared) for i, r in enumerate(rows)]
    cols = "".join(f'<col class="c-{c}">' for c in ("name", "verdict", "score", "runs", "launch", "man", "reason"))
    head = ('<th class="sort" data-key="name">student</th><th class="sort" data-key="rank">hand-in</th>'
            '<th class="sort" data-key="score">score</th><th class="sort" data-key="runs">runs passed</th>'
            '<th title="launch-file checks passed">launch file</th><th>maneuver</th>'
            "<th>first failure (the rest, the runs per arena and LiDAR, what passed: folded)</th>")
    options = "".join(f'<option value="{esc(v)}">{esc(v)} ({verdicts.get(v, 0)})</option>' for v in VERDICT_ORDER)
    reasons = "".join(f'<option value="{esc(k)}">{esc(k)}</option>' for k in kinds)
    counts = "".join(f'<span class="{VERDICT_CLASS[v]}">{verdicts.get(v, 0)} {esc(v)}</span>' for v in VERDICT_ORDER)
    said = "".join(f"<p class=\"note\">Every hand-in: {md_html(n)}</p>" for n in sorted(shared))
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{esc(title)}</title>'
            f'<meta name="viewport" content="width=device-width"><style>{PAGE_STYLE}</style></head><body>'
            f"<h1>{esc(title)}</h1>"
            f'<p class="counts">{len(rows)} hand-in{"" if len(rows) == 1 else "s"}: {counts}</p>{said}'
            f'<div class="controls"><label>hand-in <select id="f-verdict"><option value="">all</option>{options}'
            f'</select></label><label>reason <select id="f-reason"><option value="">any</option>{reasons}</select>'
            f'</label><label>student <input id="f-name" type="search" placeholder="name"></label>'
            f'<span><span id="shown">{len(rows)}</span> shown; click a column to sort</span></div>'
            f'<table id="students"><colgroup>{cols}</colgroup><thead><tr>{head}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table>'
            f"<script>{SCRIPT}</script></body></html>\n")
