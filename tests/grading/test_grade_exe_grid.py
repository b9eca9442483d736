"""The ``--exe`` grid without DDS: the up-front checks, resume, stops and where runs go, with a stand-in for the
run (:func:`bt_nav.grading.exe.run.run_exe_job` replaced).
The runs over real DDS: tests/ros/test_grade_exe_grid_dds.py."""

from __future__ import annotations

import json
import os
import stat
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import grade
from bt_nav.grading.exe import grid as exe_grid
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job, make_jobs
from bt_nav.ros.supervise import StopRequest
from bt_nav.run.rundir import make_run_dir

JOBS = make_jobs(["stage_4", "corridor"], ["none"], 2)


def _settings(out: Path, **kwargs: Any) -> ExeSettings:
    return ExeSettings(f"{sys.executable} node.py", "homework", out, cwd=str(out.parent), **kwargs)


class FakeRuns:
    """Stands in for ``run_exe_job``: writes a run directory and ``result.json`` as the real one does; a job
    whose seed is in ``raise_for`` raises, one in ``hold_for`` runs until the stop request."""

    def __init__(self, raise_for: tuple[int, ...] = (), hold_for: tuple[int, ...] = ()) -> None:
        self.raise_for, self.hold_for = raise_for, hold_for
        self.ran: list[str] = []
        self.lock = threading.Lock()

    def __call__(self, job: Job, settings: ExeSettings, stop: StopRequest | None = None,
                 on_verdict: Callable[[], None] | None = None) -> dict[str, Any]:
        with self.lock:
            self.ran.append(job.key)
        if job.seed in self.raise_for:
            raise RuntimeError("bt_nav broke")
        outcome = "verdict"
        if job.seed in self.hold_for:
            end = time.monotonic() + 30
            while not (stop is not None and stop.requested) and time.monotonic() < end:
                time.sleep(0.02)
            outcome = "stopped" if stop is not None and stop.requested else "timeout"
        run_dir = make_run_dir(settings.out, f"{job.world}_{job.maneuver}_seed{job.seed}")
        row = {"passed": outcome == "verdict" and job.world == "stage_4", "outcome": outcome, "reason": outcome,
               "verdict": None, "job": job.key, "world": job.world, "maneuver": job.maneuver, "seed": job.seed,
               "profile": settings.profile, "run_dir": str(run_dir), "wall_time": 0.1}
        if on_verdict is not None:
            on_verdict()
        (run_dir / "result.json").write_text(json.dumps(row))
        return row


# ---------------------------------------------------------------------------------------------- the program
def test_a_python_without_rclpy_is_refused_before_any_run(tmp_path: Path) -> None:
    """``--exe "python3 node.py"`` that finds a Python without ROS 2 fails every run alike: refused up front,
    naming this venv's python instead."""
    bare = tmp_path / "python3"  # a Python that cannot import rclpy
    bare.write_text("#!/bin/sh\nexit 1\n")
    bare.chmod(0o755)
    with pytest.raises(ValueError, match=r"cannot import rclpy .* run the node with .*python"):
        exe_grid.resolve_program(f"{bare} node.py")
    assert exe_grid.resolve_program(f"{sys.executable} -c pass").startswith(sys.executable)


def test_a_bare_name_is_found_on_path_then_next_to_this_python(monkeypatch: pytest.MonkeyPatch) -> None:
    venv_bin = Path(sys.executable).parent
    monkeypatch.setenv("PATH", "/nonexistent")  # the venv not activated
    resolved = exe_grid.resolve_program("bt-nav executive --x 'a b'")
    assert resolved == f"{venv_bin.absolute() / 'bt-nav'} executive --x 'a b'"
    monkeypatch.setenv("PATH", str(venv_bin))
    assert exe_grid.resolve_program("python -c pass").startswith(str(venv_bin.absolute() / "python") + " ")


def test_a_missing_or_unusable_program_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(ValueError, match="'no-such-node-xyz' not found on PATH nor in"):
        exe_grid.resolve_program("no-such-node-xyz --ros-args")
    with pytest.raises(ValueError, match="not found"):
        exe_grid.resolve_program(str(tmp_path / "missing.py"))
    script = tmp_path / "node.sh"
    script.write_text("#!/bin/sh\n")
    with pytest.raises(ValueError, match="not executable"):
        exe_grid.resolve_program(str(script))
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    monkeypatch.chdir(tmp_path)
    assert exe_grid.resolve_program("./node.sh 1") == f"{script} 1"  # a relative path made absolute
    for bad in ("", "   ", "'unbalanced"):
        with pytest.raises(ValueError):
            exe_grid.resolve_program(bad)


def test_the_cli_refuses_a_missing_program_before_any_run(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        grade.main(["--exe", "no-such-node-xyz", "--seeds", "1", "--out", str(tmp_path / "g")])
    assert exc.value.code == 2
    assert "program 'no-such-node-xyz' not found" in capsys.readouterr().err
    assert not (tmp_path / "g").exists(), "nothing is written for a refused grade"


@pytest.mark.parametrize("mode", [["--exe", "python3 node.py"], ["--class", "class.yaml"], []])
def test_an_unknown_world_is_refused_before_any_run(mode: list[str], tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    """A typo in --worlds is one error naming the bundled worlds, not a grid of simulators refusing to start."""
    (tmp_path / "class.yaml").write_text("ann: python3 node.py\n")
    mode = [str(tmp_path / m) if m.endswith(".yaml") else m for m in mode]
    with pytest.raises(SystemExit) as exc:
        grade.main([*mode, "--worlds", "stage_4,stage_1", "--seeds", "1", "--out", str(tmp_path / "g")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "unknown world 'stage_1'; bundled worlds: " in err and "stage_4" in err.split("bundled worlds:")[1]
    assert not (tmp_path / "g").exists(), "nothing is written for a refused grade"


# ---------------------------------------------------------------------------------------------- the directory
def test_an_out_holding_anything_is_refused_without_resume(tmp_path: Path) -> None:
    out = tmp_path / "g"
    assert exe_grid.prepare_out(_settings(out), JOBS, resume=False) == {}
    assert json.loads((out / "grid.json").read_text())["jobs"] == [job.key for job in JOBS]
    with pytest.raises(ValueError, match="holds a grade already: add --resume"):
        exe_grid.prepare_out(_settings(out), JOBS, resume=False)
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="holds files already"):
        exe_grid.prepare_out(_settings(other), JOBS, resume=False)
    with pytest.raises(ValueError, match="holds no grade to continue"):
        exe_grid.prepare_out(_settings(other), JOBS, resume=True)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert exe_grid.prepare_out(_settings(empty), JOBS, resume=False) == {}


def test_resume_refuses_another_grade_and_keeps_only_finished_runs(tmp_path: Path) -> None:
    out = tmp_path / "g"
    settings = _settings(out)
    exe_grid.prepare_out(settings, JOBS, resume=False)
    with pytest.raises(ValueError, match="rtf 1.0 there, 8.0 now"):
        exe_grid.prepare_out(_settings(out, rtf=8.0), JOBS, resume=True)
    with pytest.raises(ValueError, match="command"):
        exe_grid.prepare_out(ExeSettings("/bin/true", "homework", out, cwd=str(tmp_path)), JOBS, resume=True)
    fake = FakeRuns()
    kept = fake(JOBS[0], settings)
    for job, outcome in ((JOBS[1], "stopped"), (JOBS[2], exe_grid.ERROR)):
        row = dict(fake(job, settings), outcome=outcome)
        (Path(row["run_dir"]) / "result.json").write_text(json.dumps(row))
    stray = dict(kept, job="maze|none|0|homework|-|0.05m10deg")  # another grid's job
    (make_run_dir(out, "stray") / "result.json").write_text(json.dumps(stray))
    (make_run_dir(out, "torn") / "result.json").write_text('{"passed": tr')  # killed mid-write
    done = exe_grid.prepare_out(settings, JOBS, resume=True)
    assert done == {JOBS[0].key: kept}


# ---------------------------------------------------------------------------------------------- running
def test_local_runs_keep_done_rows_and_a_raising_run_is_a_failed_row(tmp_path: Path,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    fake = FakeRuns(raise_for=(1,))
    monkeypatch.setattr(exe_grid, "run_exe_job", fake)
    settings = _settings(tmp_path / "g")
    done = {JOBS[0].key: fake(JOBS[0], settings)}
    fake.ran.clear()
    seen: list[str] = []
    rows = exe_grid.run_exe_grid(JOBS, settings, 2, on_row=lambda row: seen.append(row["job"]), done=done)
    assert [row["job"] for row in rows] == [job.key for job in JOBS]
    retried = [job.key for job in JOBS if job.seed == 1]  # the raising runs are tried twice, the others once
    assert sorted(fake.ran) == sorted([*(job.key for job in JOBS[1:]), *retried]), "a done run ran again"
    assert sorted(seen) == sorted(job.key for job in JOBS[1:])
    errors = [row for row in rows if row["outcome"] == exe_grid.ERROR]
    assert [row["seed"] for row in errors] == [1, 1] and "bt_nav broke" in errors[0]["reason"]
    assert errors[0]["reason"].startswith("bt_nav error (not the node's)")
    assert not any(exe_grid.finished(row) for row in errors)
    for row in errors:  # tried twice, each traceback kept
        kept = Path(row["traceback"])
        assert kept.name.endswith("_attempt2.txt") and "bt_nav broke" in kept.read_text()
        assert kept.with_name(kept.name.replace("attempt2", "attempt1")).is_file()


def test_a_local_stop_stops_running_runs_and_starts_no_other(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    fake = FakeRuns(hold_for=(0, 1))
    monkeypatch.setattr(exe_grid, "run_exe_job", fake)
    stop = StopRequest()
    threading.Timer(0.5, lambda: setattr(stop, "signum", 15)).start()
    rows = exe_grid.run_exe_grid(JOBS, _settings(tmp_path / "g"), 2, stop)
    assert [row["outcome"] for row in rows] == ["stopped", "stopped"]
    assert len(fake.ran) == 2, "runs started after the stop"


def test_dask_runs_each_job_once_and_a_stop_reaches_the_workers(tmp_path: Path,
                                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """The cluster path against an in-process cluster (worker threads of this process see the stand-in)."""
    from distributed import LocalCluster

    fake = FakeRuns(raise_for=(1,))
    monkeypatch.setattr(exe_grid, "run_exe_job", fake)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        rows = exe_grid.run_exe_grid(JOBS, _settings(tmp_path / "a"), scheduler=cluster.scheduler_address)
        assert [row["job"] for row in rows] == [job.key for job in JOBS]
        retried = [job.key for job in JOBS if job.seed == 1]  # a raising run is tried once more, no other twice
        assert sorted(fake.ran) == sorted([*(job.key for job in JOBS), *retried]), "a job ran twice"
        assert [row["outcome"] for row in rows] == ["verdict", exe_grid.ERROR, "verdict", exe_grid.ERROR]

        fake.hold_for, fake.raise_for = (0, 1), ()
        fake.ran.clear()
        stop = StopRequest()
        threading.Timer(2.0, lambda: setattr(stop, "signum", 15)).start()
        started = time.monotonic()
        rows = exe_grid.run_exe_grid(JOBS, _settings(tmp_path / "b"), stop=stop, scheduler=cluster.scheduler_address)
    assert time.monotonic() - started < 25, "the stop did not reach the running tasks"
    assert [row["outcome"] for row in rows] == ["stopped", "stopped"]
    assert all(row["reason"] == "stopped" for row in rows) and len(fake.ran) == 2


def test_the_cli_shows_progress_and_resumes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                            capsys: pytest.CaptureFixture) -> None:
    fake = FakeRuns()
    monkeypatch.setattr(exe_grid, "run_exe_job", fake)
    out = tmp_path / "g"
    argv = ["--exe", f"{sys.executable} -c pass", "--worlds", "stage_4,corridor", "--seeds", "2", "--out", str(out),
            "--lidars", "profile"]
    assert grade.main([*argv, "--progress", "on"]) == 1  # corridor fails
    captured = capsys.readouterr()
    assert "100%" in captured.err and "4/4" in captured.err and "2 passed" in captured.err
    assert "  stage_4 none seed 0: PASSED" in captured.out and "  corridor none seed 1: FAILED" in captured.out
    assert len(json.loads((out / "grade.json").read_text())["runs"]) == 4
    with pytest.raises(SystemExit) as exc:
        grade.main(argv)
    assert exc.value.code == 2 and "add --resume" in capsys.readouterr().err
    fake.ran.clear()
    assert grade.main([*argv, "--seeds", "3", "--resume", "--progress", "off"]) == 1
    assert "resuming: 4 of 6 runs" in capsys.readouterr().err
    assert sorted(fake.ran) == sorted(job.key for job in make_jobs(["stage_4", "corridor"], ["none"], [2]))
    assert os.path.exists(out / "grade.json") and len(json.loads((out / "grade.json").read_text())["runs"]) == 6


def test_the_simulator_keeps_real_time_and_a_preview_is_paced_to_the_graded_node(tmp_path: Path) -> None:
    """At 1x (the grade) the robot's world does not wait for its node (no follow), as on the robot; a preview follows
    the node's cmd_vel (read best effort, so any writer is heard), leading its latest command by at most 0.05 s (or
    its own command period) beyond the next scan it answers."""
    from bt_nav.grading.exe.run import exe_graph

    job = Job("lab_object", "C", 0, "lab", sim_params=(("lidar", "rplidar"),))
    spec = exe_graph(job, ExeSettings("python3 node.py", "lab", tmp_path), tmp_path / "verdict.json")
    assert spec.executable == "sim" and spec.parameters["real_time_factor"] == 1.0
    assert spec.parameters["follow"] is False
    spec = exe_graph(job, ExeSettings("python3 node.py", "lab", tmp_path, rtf=0.0), tmp_path / "verdict.json")
    assert {k: spec.parameters[k] for k in ("follow", "cmd_vel_reliability", "max_lag")} == {
        "follow": True, "cmd_vel_reliability": "best_effort", "max_lag": 0.05}
