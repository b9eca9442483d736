"""A grid over several LiDARs, as its reports tell it: ``summary.md``, ``report.html`` and ``class.md`` name the
LiDAR of every failed run, count the pass rates per LiDAR and give the same cross-LiDAR findings (a crash with some
LiDARs only among them). Made-up rows, no DDS: the reports are written as ``bt-nav grade --exe`` and ``--class``
write them (:func:`bt_nav.grading.report.write_exe_report`, :func:`bt_nav.grading.classroom.write_class_page`)."""

from __future__ import annotations

import html
import re
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading.classroom import Student, write_class_page
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import lidar_findings, run_label
from bt_nav.grading.report import write_exe_report

CRASH = "the node exited with code 1 after 3.9 s wall, before the verdict (see node.log)"
NO_MANEUVER = "failed: performed no maneuver (0 performed, required >= 1)"
LATE = "failed: did not stop and stay still after the deactivation"


def _row(out: Path, lidar: str, seed: int, reason: str = "passed", outcome: str = "verdict") -> dict[str, Any]:
    run_dir = out / f"lab_object_C_{lidar}_seed{seed}"
    run_dir.mkdir(parents=True)
    return {"job": f"lab_object|C|{seed}|{lidar}", "world": "lab_object", "maneuver": "C", "lidar": lidar,
            "seed": seed, "passed": reason == "passed", "outcome": outcome, "reason": reason, "verdict": None,
            "run_dir": str(run_dir), "wall_time": 20.0}


def _grid(out: Path) -> list[dict[str, Any]]:
    """Two seeds per LiDAR: the LDS-01 and the LDS-02 pass but for one failure they share, the RPLIDAR crashes
    once and fails once."""
    return [_row(out, "lds01", 0), _row(out, "lds01", 1, LATE), _row(out, "lds02", 0), _row(out, "lds02", 1, LATE),
            _row(out, "rplidar", 0, CRASH, "node exited"), _row(out, "rplidar", 1, NO_MANEUVER)]


@pytest.fixture
def reports(tmp_path: Path) -> dict[str, Any]:
    """One student's grid reported as ``--exe`` writes it, and the class page over it."""
    grid = tmp_path / "alice"
    rows = _grid(grid)
    write_exe_report(rows, ExeSettings("python3 node.py", "lab", grid, record="off", videos="off"), workers=1)
    write_class_page(tmp_path, [Student("alice", "python3 node.py")], "Class grade (lab profile)")
    page = (grid / "report.html").read_text()
    return {"rows": rows, "summary.md": (grid / "summary.md").read_text(), "report.html": page,
            "class.md": (tmp_path / "class.md").read_text(),
            # what report.html lists as failures (above the table of every run, which names each run anyway)
            "why": html.unescape(re.sub(r"<[^>]+>", "", page.split("<h2>Why runs failed</h2>")[1].split("<h2>")[0]))}


def test_a_run_s_label_names_its_lidar() -> None:
    assert run_label({"world": "lab_object", "maneuver": "C", "lidar": "rplidar", "seed": 0}) \
        == "lab_object C rplidar seed 0"
    assert run_label({"world": "stage_4", "maneuver": "none", "lidar": "", "seed": 3}) == "stage_4 none seed 3"


def test_every_failed_run_is_named_with_its_lidar_in_every_report(reports: dict[str, Any]) -> None:
    failed = [r for r in reports["rows"] if not r["passed"]]
    failures_md = reports["summary.md"].split("## Failures")[1]
    student_md = reports["class.md"].split("## alice")[1]
    for row in failed:
        line = f"{run_label(row)}: {row['reason']}"
        assert f"- {line}" in failures_md, (line, failures_md)
        assert line in reports["why"], (line, reports["why"])
        assert f"- {line}" in student_md, (line, student_md)
    for text in (reports["summary.md"], reports["why"], reports["class.md"]):
        assert "lab_object C seed" not in text and "lab_object C:" not in text, "a run or cell without its LiDAR"


def test_pass_rates_are_counted_per_world_lidar_and_maneuver(reports: dict[str, Any]) -> None:
    md = reports["summary.md"]
    assert "| world | LiDAR | C |" in md
    for lidar, rate in (("lds01", "1/2"), ("lds02", "1/2"), ("rplidar", "0/2")):
        assert f"| lab_object | {lidar} | {rate} |" in md, md
        assert re.search(rf"<th>lab_object</th><th>{lidar}</th><td [^>]*>{rate} ", reports["report.html"]), lidar
    assert "| lab_object | 2/6 |" not in md, "not every LiDAR in one cell"


def test_a_crash_with_some_lidars_only_is_a_finding() -> None:
    crashed = "the node crashed: IndexError: array index out of range"  # as a crash may be told, with its exception
    found = lidar_findings([_dry("lds01", 0), _dry("lds02", 0), _dry("rplidar", 0, crashed), _dry("rplidar", 1)])
    assert found[0].startswith("crashes with TurtleBot4 RPLIDAR A1 (-pi..pi, inf = no return) only (1 of 2 runs), "
                               "never with TurtleBot3 LDS-01 (0..2pi, 0.0 = no return), TurtleBot3 LDS-02 "), found
    everywhere = [_dry(lidar, 0, CRASH) for lidar in ("lds01", "rplidar")]
    assert not any(f.startswith("crashes") for f in lidar_findings(everywhere)), "a crash with every LiDAR is no clue"
    apart = [_dry("lds01", 0), _dry("rplidar", 0, CRASH, "bt_nav error")]
    assert not lidar_findings(apart), "bt_nav's own errors are not the node's"


def _dry(lidar: str, seed: int, reason: str = "passed", outcome: str = "verdict") -> dict[str, Any]:
    """A row without a run directory (for the findings alone)."""
    return {"world": "lab_object", "maneuver": "C", "lidar": lidar, "seed": seed, "passed": reason == "passed",
            "outcome": outcome, "reason": reason}


def test_the_lidar_findings_read_the_same_in_the_three_reports(reports: dict[str, Any]) -> None:
    found = lidar_findings(reports["rows"])
    assert [f.split(" ", 1)[0] for f in found] == ["crashes", "passes"], found
    page = html.unescape(reports["report.html"])
    for finding in found:
        assert f"**Finding:** {finding}" in reports["summary.md"]
        assert f"Finding: {finding}" in re.sub(r"<[^>]+>", "", page)
        assert f"- finding: {finding} (x1)" in reports["class.md"].split("## alice")[1]
