"""The DDS grading benchmark's bookkeeping (not bt_nav's speed): where a run's wall time went, read from a run
directory as ``bt-nav grade --exe`` writes it, the target, and the section of ``latest.md``."""

from __future__ import annotations

import json
import os
from pathlib import Path

from bench.exe_throughput import _kind, _phases, targets
from bench.report import exe_section


def _run_dir(tmp_path: Path) -> dict:
    run_dir = tmp_path / "stage_4_none_seed0"
    run_dir.mkdir()
    start = 1_000.0
    # the judge's verdict says when t0 came on the wall clock and how long its mission was in sim s (the logs are
    # for people: what they say does not count)
    (run_dir / "verdict.json").write_text(json.dumps({"t0_wall": start + 2.75, "t0_sim": 0.01,
                                                      "times": {"t0": 0.0, "report": 57.575}}))
    (run_dir / "sim.log").write_text("[INFO] [1016.0] [bt_nav_sim]: simulated 72.02 s in 24.0 s wall (3.0x real "
                                     "time): 7202 steps\n")
    (run_dir / "result.json").write_text("{}")
    os.utime(run_dir / "verdict.json", (start + 14.5, start + 14.5))
    os.utime(run_dir / "result.json", (start + 15.5, start + 15.5))
    return {"run_dir": str(run_dir), "wall_time": 15.5, "passed": True}


def test_a_runs_wall_time_splits_into_its_phases(tmp_path: Path) -> None:
    phases = _phases(_run_dir(tmp_path))
    assert phases == {"wall_s": 15.5, "startup_s": 2.75, "mission_s": 11.75, "shutdown_s": 1.0, "sim_rtf": 4.9}
    assert _phases({"run_dir": str(tmp_path / "gone"), "wall_time": 3.0}) == {"wall_s": 3.0}
    (tmp_path / "stage_4_none_seed0" / "verdict.json").write_text("{}")  # a judge that never reached t0
    assert _phases(_run_dir_again(tmp_path)) == {"wall_s": 15.5, "startup_s": None, "mission_s": None,
                                                 "shutdown_s": 1.0, "sim_rtf": None}


def _run_dir_again(tmp_path: Path) -> dict:
    """The run directory of :func:`_run_dir` as it is now (its files' times kept)."""
    run_dir = tmp_path / "stage_4_none_seed0"
    os.utime(run_dir / "verdict.json", (1_014.5, 1_014.5))
    return {"run_dir": str(run_dir), "wall_time": 15.5, "passed": True}


def test_processes_are_told_apart_by_their_command_line() -> None:
    assert _kind(["/v/bin/python", "-m", "bt_nav.cli", "sim", "--ros-args"]) == "sim"
    assert _kind(["/v/bin/python", "-m", "bt_nav.cli", "sim", "--judge", "referee", "--ros-args"]) == "sim+judge"
    assert _kind(["/v/bin/python", "-m", "bt_nav.cli", "referee", "--ros-args"]) == "referee"
    assert _kind(["/v/bin/bt-nav", "executive", "--ros-args"]) == "node"
    assert _kind(["/v/bin/python", "/v/bin/bt-nav", "grade", "--exe", "x"]) == "grade"


def test_the_target_and_the_section(tmp_path: Path) -> None:
    grade = {"rtf": 5.0, "jobs": 2, "runs": 8, "passed": 7, "reasons": ["failed: static at the end"],
             "wall_s": 63.0, "missions_per_min": 7.62, "cpu_s_per_mission": 10.4, "cpu_share_of_cores": 0.66,
             "cpu_by_kind_s": {"sim": 28.0, "node": 25.6}, "mission_bound_per_min": 10.2,
             "phases_median": {"wall_s": 15.7, "startup_s": 2.8, "mission_s": 11.8, "shutdown_s": 1.1, "sim_rtf": 4.95}}
    result = {"seeds": 8, "jobs": 2, "grades": [grade, {"rtf": 8.0, "error": "bt-nav grade exited with 2"}]}
    [target] = targets(json.loads(json.dumps(result)))
    assert (target.value, target.met, target.unit) == (7.62, False, "missions/min")
    assert "7/8 passed" in target.description
    text = "\n".join(exe_section(result))
    row = "| 5 | 7/8 | 63 | 7.62 | 15.7 | 2.8 | 11.8 | 1.1 | 4.95 | 10.2 | 10.4 | sim 3.5, node 3.2 | 66 % | failed"
    assert row in text
    assert "rtf 8.0: failed" in text
    assert targets({"grades": []})[0].met is None
