"""The benchmark history (``bench/results/history.jsonl``): one line per run, the last runs side by side in
``latest.md``. No benchmark runs here: the functions are fed made-up results."""

from __future__ import annotations

import json
from pathlib import Path

from bench.report import history_section, render
from bench.run import append_history


def _doc(started: str, value: float, met: bool) -> tuple[dict, list[dict]]:
    doc = {"run": {"started": started, "mode": "full", "only": ["tick"], "load_start": [0.5, 0.4, 0.3]},
           "machine": {"cores": 2}}
    targets = [{"id": "tick_p99_360", "benchmark": "tick", "description": "tree tick p99 at 360 beams",
                "goal": "<= 0.25 ms", "value": value, "unit": "ms", "met": met}]
    return doc, targets


def test_each_run_appends_one_line_and_gets_the_whole_history_back(tmp_path: Path) -> None:
    path = tmp_path / "history.jsonl"
    first = append_history(path, *_doc("2026-11-23T10:00:00", 0.31, False))
    second = append_history(path, *_doc("2026-11-23T11:00:00", 0.21, True))
    assert len(first) == 1 and len(second) == 2
    lines = [json.loads(raw) for raw in path.read_text(encoding="utf-8").splitlines()]
    assert [line["targets"]["tick_p99_360"]["value"] for line in lines] == [0.31, 0.21]
    assert lines[1]["commit"] and lines[1]["load_start"] == [0.5, 0.4, 0.3]


def test_a_damaged_line_is_skipped_not_fatal(tmp_path: Path) -> None:
    path = tmp_path / "history.jsonl"
    path.write_text("not json\n", encoding="utf-8")
    assert len(append_history(path, *_doc("2026-11-23T10:00:00", 0.31, False))) == 1


def test_the_report_shows_a_regression_along_a_row(tmp_path: Path) -> None:
    path = tmp_path / "history.jsonl"
    append_history(path, *_doc("2026-11-23T10:00:00", 0.21, True))
    history = append_history(path, *_doc("2026-11-23T11:00:00", 0.31, False))
    lines = history_section(history)
    row = next(line for line in lines if line.startswith("| tree tick p99 at 360 beams"))
    assert row.index("0.21 met") < row.index("0.31 **MISSED**")
    assert history_section([]) == []


def test_latest_md_carries_the_history() -> None:
    doc, targets = _doc("2026-11-23T10:00:00", 0.21, True)
    doc["run"].update({"duration_s": 1.0, "command": "python -m bench.run", "load_end": [0.5, 0.4, 0.3]})
    doc["machine"].update({"cpu": "x", "cores_usable": 2, "os": "Linux", "python": "3.11", "numpy": "2",
                           "py_trees": "2.6.0", "rclpy": "7"})
    doc.update({"targets": targets, "benchmarks": {},
                "history": [{"started": "2026-11-23T10:00:00", "mode": "full", "commit": "abc1234",
                             "load_start": [0.5], "targets": {t["id"]: t for t in targets}}]})
    text = render(doc)
    assert "## History" in text and "`abc1234`" in text
