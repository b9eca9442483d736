"""``bt-nav grade --exe``: foreign nodes (tests/fixtures, plain rclpy) graded over real DDS, no process left."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import psutil
import pytest

from bt_nav.cli import grade
from bt_nav.grading.exe.run import exe_ros_args

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def _grade(tmp_path: Path, fixture: str, *extra: str) -> tuple[int, dict]:
    code = grade.main(["--exe", f"{sys.executable} {FIXTURES / fixture}", "--worlds", "stage_4", "--seeds", "1",
                       "--rtf", "0", "--realtime-check", "off",
                       "--lidars", "profile",
                       "--jobs", "1", "--out", str(tmp_path / "grid"), *extra])
    return code, json.loads((tmp_path / "grid" / "grade.json").read_text())


def _child_pids() -> set[int]:
    """This process's descendants now (e.g. multiprocessing's resource tracker, left by an earlier test's pool)."""
    return {p.pid for p in psutil.Process().children(recursive=True)}


def _no_children_left(before: set[int]) -> None:
    left = [p for p in psutil.Process().children(recursive=True) if p.pid not in before]
    assert not left, f"processes left behind: {[(p.pid, p.cmdline()) for p in left]}"


def test_what_is_appended() -> None:
    homework = ["-r", "arm:=/reactive_control/activate", "-r", "evaluate_mission:=/reactive_control/evaluate_mission"]
    assert exe_ros_args(None) == ["--ros-args", "-p", "use_sim_time:=true", *homework]
    assert exe_ros_args("A", "lab") == ["--ros-args", "-p", "use_sim_time:=true", "-r", "arm:=/toggle_navigation",
                                        "-p", 'maneuver:="A"']


def test_the_homework_fixture_gets_a_verdict(tmp_path: Path) -> None:
    before = _child_pids()
    code, doc = _grade(tmp_path, "homework_node.py", "--timeout", "120")
    [row] = doc["runs"]
    assert row["outcome"] == "verdict", row["reason"]
    checks = {c["name"]: c["passed"] for c in row["verdict"]["checks"]}
    assert checks["evaluation service called"] and checks["no collision"], row["verdict"]["report_lines"]
    assert code == (0 if row["passed"] else 1)
    assert row["wall_time"] < 60.0, "a node publishing from its scan callback runs at full speed"
    run_dir = Path(row["run_dir"])
    assert {"node.log", "sim.log", "result.json"} <= {p.name for p in run_dir.iterdir()}
    # the referee is hosted by the simulator's process: its lines are in sim.log, under its own node name
    assert not (run_dir / "referee.log").exists() and "[bt_nav_referee]: t0 = sim" in (run_dir / "sim.log").read_text()
    assert "evaluate_mission called" in (run_dir / "node.log").read_text()
    assert "| stage_4 |" in (tmp_path / "grid" / "summary.md").read_text()
    _no_children_left(before)


@pytest.mark.parametrize("profile", ["homework"])
def test_a_node_crashing_at_start_is_a_verdict(tmp_path: Path, profile: str) -> None:
    before = _child_pids()
    code, doc = _grade(tmp_path, "crash_node.py", "--timeout", "60", "--profile", profile)
    [row] = doc["runs"]
    assert code == 1 and not row["passed"]
    assert row["outcome"] == "node exited", row["reason"]
    # its traceback's last line and its own frame that raised it (below rclpy's none: create_node returned)
    assert row["reason"].startswith("the node crashed after ") and row["reason"].endswith(
        " s wall: RuntimeError: this node crashes at start (crash_node.py:10 in main; see node.log)"), row["reason"]
    assert row["crash"] == {"exception": "RuntimeError: this node crashes at start",
                            "where": "crash_node.py:10 in main", "starting": False}  # not in an __init__: see exe/log
    assert row["wall_time"] < 40.0
    assert "this node crashes at start" in (Path(row["run_dir"]) / "node.log").read_text()
    _no_children_left(before)
