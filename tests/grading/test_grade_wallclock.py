"""A wall-clock node found early (:mod:`bt_nav.grading.wallclock`) without DDS: the evidence one failed run gives,
and the grid switched to 1x with a stand-in for the run (:func:`bt_nav.grading.exe.run.run_exe_job` replaced)."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading import wallclock
from bt_nav.grading.exe import grid as exe_grid
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job
from bt_nav.grading.realtime import confirm_at_real_time
from bt_nav.ros.supervise import StopRequest
from bt_nav.run.rundir import make_run_dir


def _turn(angle: float, lasted: float, passed: bool = False, interrupted: bool = False) -> dict[str, Any]:
    return {"maneuvers": [{"t": 25.0, "settled": 25.0 + lasted, "angle_deg": -angle, "side": "right",
                           "passed": passed, "interrupted": interrupted}], "t0_sim": 0.0,
            "times": {"activated": 5.0, "deactivation_requested": 65.0}}


def _failed(angle: float, lasted: float, factor: float, maneuver: str = "C", interrupted: bool = False) -> dict:
    return {"passed": False, "outcome": "verdict", "reason": "failed: maneuver 1", "maneuver": maneuver,
            "verdict": _turn(angle, lasted, interrupted=interrupted), "rtf": factor,
            "speed": {"set": 0.0, "rtf": factor, "node_rtf": factor}}


def test_one_failed_run_shows_a_wall_clock_a_right_ros_time_node_never_shows() -> None:
    # measured: the wall-clock C node at --rtf 0 kept up with 39.7x; its 90 deg turn (1.57 s of wall time) ran
    # until the disarm at 65 s
    real = _failed(1374.07, 40.0, 39.74, interrupted=True)
    assert wallclock.early_evidence(real, 0.0) == (
        "maneuver 1 turned 1374 deg in 40.0 sim s at 39.7x (the node's pace), cut short by the disarm: 35 deg in its "
        "1.0 s of wall time, where the assignment turns 90 +- 10 deg: a turn timed by the wall clock")
    assert wallclock.early_evidence(_failed(450.0, 13.1, 5.0), 5.0) is not None  # at a fixed 5x, complete
    assert wallclock.early_evidence(_failed(900.0, 26.0, 10.0, "A"), 0.0) is not None  # A: 90-180 deg
    # none where a node on ROS time may be: an overshoot short of twice the most, a turn that is the right one in
    # wall time only at another factor, a slow run, a turn that did not fail, the homework
    assert wallclock.early_evidence(_failed(190.0, 5.4, 9.0), 0.0) is None
    assert wallclock.early_evidence(_failed(450.0, 13.1, 30.0), 0.0) is None  # 15 deg of wall time: no 90 deg turn
    assert wallclock.early_evidence(_failed(3000.0, 40.0, 9.0), 0.0) is None  # 333 deg of wall time: too far
    assert wallclock.early_evidence(_failed(450.0, 13.1, 2.5), 0.0) is None
    passed = {**_failed(900.0, 26.0, 10.0), "verdict": _turn(900.0, 26.0, passed=True)}
    assert wallclock.early_evidence(passed, 0.0) is None
    assert wallclock.early_evidence({**_failed(900.0, 26.0, 10.0), "maneuver": None, "verdict": {}}, 0.0) is None


class WallClockNode:
    """Stands in for ``run_exe_job``: a C node timing its turns by the wall clock (``mistaken``: one that spins
    until the disarm at every speed). A fast run fails after ``hold`` s unless stopped; a 1x run passes."""

    def __init__(self, factor: float = 10.0, hold: float = 0.3, mistaken: bool = False, loaded: int = 0) -> None:
        self.factor, self.hold, self.mistaken = factor, hold, mistaken
        self.loaded = loaded  # how many first 1x runs fall behind real time (a busy machine) and fail
        self.ran: list[tuple[int, float]] = []
        self.at_once = self.most_at_once = 0
        self.lock = threading.Lock()

    def __call__(self, job: Job, settings: ExeSettings, stop: StopRequest | None = None,
                 on_verdict: Any = None) -> dict[str, Any]:
        with self.lock:
            self.ran.append((job.seed, settings.rtf))
            self.at_once += 1
            self.most_at_once = max(self.most_at_once, self.at_once)
        try:
            return self._run(job, settings, stop)
        finally:
            with self.lock:
                self.at_once -= 1

    def _run(self, job: Job, settings: ExeSettings, stop: StopRequest | None) -> dict[str, Any]:
        fast = settings.rtf != 1.0
        end = time.monotonic() + (self.hold if fast else 0.05)
        while time.monotonic() < end and not (stop is not None and stop.requested):
            time.sleep(0.01)
        factor = self.factor if fast else 1.0
        passed = not fast and not self.mistaken
        with self.lock:
            if not fast and self.loaded and [s for s, rtf in self.ran if rtf == 1.0].count(job.seed) == 1:
                self.loaded -= 1
                factor, passed = 0.93, False
        verdict = _turn(91.0, 2.6, passed=True) if passed else \
            _turn(1400.0 if self.mistaken else 90.0 * factor, 40.0 if self.mistaken else 2.6 * factor)
        if not fast and not passed and not self.mistaken:  # its wall-clock turn cut short by the slow simulation
            verdict = _turn(60.0, 1.7)
        outcome = "stopped" if stop is not None and stop.requested else "verdict"
        run_dir = make_run_dir(settings.out, f"{job.world}_{job.maneuver}_seed{job.seed}")
        row = {"passed": passed and outcome == "verdict", "outcome": outcome,
               "reason": "passed" if passed else "failed: maneuver 1", "verdict": verdict, "findings": [],
               "job": job.key, "world": job.world, "maneuver": job.maneuver, "lidar": job.lidar, "seed": job.seed,
               "profile": "lab", "run_dir": str(run_dir), "wall_time": 0.1, "rtf": factor,
               "speed": {"set": settings.rtf, "rtf": factor, "node_rtf": factor}}
        (run_dir / "result.json").write_text(json.dumps(row))
        return row


JOBS = [Job("lab_dead_end", "C", seed, "lab", sim_params=(("lidar", "lds01"),)) for seed in range(8)]


def _grade(tmp_path: Path, node: WallClockNode, monkeypatch: pytest.MonkeyPatch) -> tuple[list[dict], list[str]]:
    monkeypatch.setattr(exe_grid, "run_exe_job", node)
    settings = ExeSettings("python3 node.py", "lab", tmp_path / "g", maneuvers=True)
    said: list[str] = []
    rows = wallclock.run_grid(JOBS, settings, 2, None, say=said.append)
    return rows, said


def test_a_wall_clock_node_s_runs_go_at_1x_at_once_after_its_first_failure(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    node = WallClockNode()
    rows, said = _grade(tmp_path, node, monkeypatch)
    fast = [seed for seed, rtf in node.ran if rtf == 0.0]
    assert len(fast) <= 4, node.ran  # the first failure switched the grid: no fast pass (2 ran, 2 stopped at most)
    assert sorted(seed for seed, rtf in node.ran if rtf == 1.0) == list(range(8))  # each once at 1x, none again fast
    assert not (tmp_path / "g" / "rerun").exists()
    assert [row["seed"] for row in rows] == list(range(8)) and all(row["passed"] for row in rows)
    assert all("the node keeps time by the wall clock" in row["reason"] for row in rows)
    failed_fast = [row for row in rows if "realtime" in row]  # graded by their own 1x runs
    assert 1 <= len(failed_fast) <= 2 and all(row["realtime"]["rtf"] == 10.0 for row in failed_fast)
    assert all(row["rerun"]["decision"] == "wall clock" for row in rows)
    assert len([row for row in rows if row["rerun"]["said"].startswith("run at 1x only")]) == 8 - len(failed_fast)
    seeds = {row["seed"] for row in failed_fast}  # the first of them to end is the one the line names
    assert any(said[0].startswith(f"bt-nav grade: lab_dead_end C lds01 seed {seed}: maneuver 1 turned 900 deg in "
                                  "26.0 sim s at 10.0x (the node's pace): 90 deg in its 2.6 s of wall time")
               for seed in seeds), said
    assert "the node's runs go at 1x" in said[0] and "up to " in said[0]
    assert node.most_at_once > 2  # 1x runs together, more than the grid's 2 at a time
    # the check afterwards has nothing left to run
    assert confirm_at_real_time(JOBS, ExeSettings("n", "lab", tmp_path / "g"), {r["job"]: r for r in rows}, 2) == 0


def test_an_early_guess_its_1x_run_does_not_bear_out_changes_no_verdict(tmp_path: Path,
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """A node spinning until its disarm at every speed looks like a wall clock in one fast run: its 1x run fails
    too, so the grid goes on at the grade's speed and its failures are left to the usual check."""
    node = WallClockNode(mistaken=True)
    rows, said = _grade(tmp_path, node, monkeypatch)
    assert [row["seed"] for row in rows] == list(range(8))
    assert all(not row["passed"] and "rerun" not in row and "/g/realtime/" not in row["run_dir"] for row in rows)
    assert "its 1x run did not bear a wall clock out" in said[1], said
    assert sorted({seed for seed, rtf in node.ran if rtf == 0.0}) == list(range(8))  # every job ran fast


def test_without_early_evidence_the_probe_runs_beside_the_grid(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """At 2.5x one run tells nothing (under EARLY_MIN_RTF): the first failure's re-runs run beside the grid's
    runs, and their decision (its turn 2.5 times as long at 2.5x: a wall clock) switches the rest to 1x."""
    node = WallClockNode(factor=2.5, hold=0.5)
    rows, said = _grade(tmp_path, node, monkeypatch)
    assert all(row["passed"] for row in rows) and len(rows) == 8
    assert "its turns lasted 6.5 sim s at 2.5x and 2.6 sim s at 1x: the same wall time" in said[0], said
    assert len([1 for _, rtf in node.ran if rtf == 0.0]) < 8 + 1  # the probe's one re-run, never a second pass


def test_the_1x_runs_start_three_per_core_then_more_up_to_six_per_core() -> None:
    admission = wallclock.realtime_admission(cores=2)
    assert (admission.base, admission.limit) == (6, 12)
    assert admission._open() == 6  # never every place at once, however idle the cores


def test_a_1x_run_that_fell_behind_real_time_runs_again_before_it_fails(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A machine too busy for the 1x runs slows their simulation below 1x, and a wall-clock turn falls short (its
    wall time is fixed): such a failure runs once more at 1x, after the others, and is graded by that run."""
    node = WallClockNode(loaded=3)
    rows, said = _grade(tmp_path, node, monkeypatch)
    assert all(row["passed"] for row in rows) and len(rows) == 8
    again = [row for row in rows if any(n.startswith("run at 1x again: its first 1x run fell behind real time "
                                                     "(0.93x") for n in row.get("notes", []))]
    assert len(again) == 3 and sum(1 for _, rtf in node.ran if rtf == 1.0) == 8 + 3
    assert "3 runs failed at 1x while the simulation fell behind real time (" in said[1] and "at 0.93x" in said[1]


def test_the_words_name_no_fast_re_run_where_none_was_meant(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    rows, _ = _grade(tmp_path, WallClockNode(), monkeypatch)
    failed_fast = [row for row in rows if "realtime" in row]
    assert failed_fast and all("; run again at 1x: passed: its turns lasted" in row["reason"] for row in failed_fast)
    assert not any("not run (stopped)" in row["reason"] for row in rows)
