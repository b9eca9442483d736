"""``bt-nav grade`` with ``--class``, ``--exe`` and ``--scheduler``: an option a mode cannot honour is refused before
any run (exit 2, the option named), and a scheduler out of reach refuses the grade instead of grading here. No DDS:
nothing may run, and the runners are replaced by ones that fail the test if called."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import grade
from bt_nav.grading import classroom
from bt_nav.grading.exe import grid as exe_grid

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "lab_student_node.py"


@pytest.fixture
def manifest(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A class of one right lab node; any run started fails the test."""

    def no_run(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("a run started")

    monkeypatch.setattr(classroom, "run_class", no_run)
    monkeypatch.setattr(exe_grid, "run_unless_stopped", no_run)
    path = tmp_path / "class.yaml"
    path.write_text(f"ann: {sys.executable} {FIXTURE} --choice C\n")
    return path


def _refused(argv: list[str], capsys: pytest.CaptureFixture) -> str:
    with pytest.raises(SystemExit) as exit_:
        grade.main(argv)
    assert exit_.value.code == 2
    return capsys.readouterr().err


LAB = ["--profile", "lab", "--maneuvers", "C", "--worlds", "lab_object", "--lidars", "lds01", "--seeds", "1"]


@pytest.mark.parametrize(("extra", "said"), [
    (["--scheduler", "tcp://127.0.0.1:9", "--jobs", "2"], "--jobs counts the runs at once on this machine"),
    (["--set", "max_speed=0.1"], "--set sets the parameters of bt_nav's own tree"),
    (["--kinematics", "burger"], "--kinematics sets the lock-step robot"),
    (["--json", "x.json"], "--json is one grid's results file; a class writes class.json"),
    (["--progress", "on"], "--class prints a line per run, no progress bar"),
])
def test_an_option_a_class_cannot_honour_is_refused(extra: list[str], said: str, manifest: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    err = _refused(["--class", str(manifest), *LAB, "--out", str(out), *extra], capsys)
    assert said in err, err
    assert not out.exists()


def test_exe_refuses_the_lock_step_options_too(capsys: pytest.CaptureFixture) -> None:
    err = _refused(["--exe", f"{sys.executable} {FIXTURE}", *LAB, "--set", "max_speed=0.1"], capsys)
    assert "--exe grades a node of its own: give it parameters with --node-param" in err, err


def test_jobs_with_a_scheduler_is_refused_in_lock_step_too(capsys: pytest.CaptureFixture) -> None:
    err = _refused(["--seeds", "1", "--scheduler", "tcp://127.0.0.1:9", "--jobs", "1"], capsys)
    assert "leave --jobs out" in err, err


def test_an_unreachable_scheduler_refuses_the_class(manifest: Path, tmp_path: Path, capsys: pytest.CaptureFixture,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(exe_grid, "CONNECT_TIMEOUT", 2.0)
    out = tmp_path / "out"
    err = _refused(["--class", str(manifest), *LAB, "--out", str(out), "--scheduler", "tcp://127.0.0.1:9"], capsys)
    assert "--scheduler tcp://127.0.0.1:9: cannot reach the Dask scheduler" in err, err
    assert "Traceback" not in err
    assert not out.exists(), "a refused class wrote into its --out"
    err = _refused(["--class", str(manifest), *LAB, "--scheduler", str(tmp_path / "scheduler.json")], capsys)
    assert f"--scheduler {tmp_path / 'scheduler.json'}: no such scheduler file" in err, err


def test_an_unreachable_scheduler_refuses_an_exe_grid(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(exe_grid, "CONNECT_TIMEOUT", 2.0)
    monkeypatch.setattr(exe_grid, "run_unless_stopped", lambda *a, **k: pytest.fail("a run started"))
    out = tmp_path / "out"
    err = _refused(["--exe", f"{sys.executable} {FIXTURE} --choice C", *LAB, "--out", str(out), "--scheduler",
                    "tcp://127.0.0.1:9"], capsys)
    assert "cannot reach the Dask scheduler" in err and not out.exists(), err


def test_a_lock_step_grid_with_no_scheduler_file_is_refused_without_a_traceback(tmp_path: Path,
                                                                                capsys: pytest.CaptureFixture) -> None:
    """bt_nav's own grid on a cluster whose scheduler file is not there: exit 2, the reason in one line."""
    code = grade.main(["--worlds", "stage_4", "--seeds", "1", "--scheduler", str(tmp_path / "nowhere.json")])
    err = capsys.readouterr().err
    assert code == 2 and "no such scheduler file" in err and "Traceback" not in err, err
