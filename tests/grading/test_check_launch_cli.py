"""``bt-nav check-launch`` (the launch checks alone, exit 0/1/2) and ``bt-nav grade --exe ... --launch FILE`` (one
node's grade carrying the launch checks as a class's hand-in does), both on the launch-file suite's fixtures; the
runs of the grade stand in (:func:`bt_nav.grading.exe.run.run_exe_job` replaced), no DDS."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import check_launch, grade
from bt_nav.grading.exe import grid as exe_grid
from bt_nav.grading.formats import gradescope_results, read_record
from bt_nav.run.rundir import make_run_dir

LAUNCH = Path(__file__).resolve().parents[1] / "fixtures" / "launch"


@pytest.mark.parametrize(("name", "code", "said"), [
    ("sheet", 0, "passes safety_distance to the node: PASSED (sheet.launch.py:15: the node gets safety_distance=0.5)"),
    ("hardcoded_value", 1, "would not reach the node"),
    ("command_default", 2, "NOT CHECKED (command_default.launch.py:10: not checked: a TA should look;"),
])
def test_check_launch_prints_the_checks_and_exits_with_the_verdict(name: str, code: int, said: str,
                                                                   capsys: pytest.CaptureFixture) -> None:
    assert check_launch.main([str(LAUNCH / f"{name}.launch.py")]) == code
    out = capsys.readouterr().out
    assert out.startswith(f"{name}.launch.py (node: ") and said in out, out
    assert out.count("  launch file: ") == 3


def test_check_launch_reads_a_hand_in_folder_as_a_class_does(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A folder: its launch file and its node found as ``grade --class`` finds them; the node's own name counts."""
    folder = tmp_path / "ann" / "my_package"
    (folder / "launch").mkdir(parents=True)
    (folder / "my_nav.py").write_text("from rclpy.node import Node\n\n\nclass Nav(Node):\n    pass\n")
    text = (LAUNCH / "sheet.launch.py").read_text().replace("'reactive_navigator'", "'my_nav'")
    (folder / "launch" / "turtlebot_bringup.launch.py").write_text(text)
    assert check_launch.main([str(tmp_path / "ann")]) == 0
    assert capsys.readouterr().out.startswith("my_package/launch/turtlebot_bringup.launch.py (node: my_nav.py)")
    assert check_launch.main([str(folder / "launch" / "turtlebot_bringup.launch.py"), "--node", "other.py"]) == 1
    assert "its Node runs executable 'my_nav', not other or other.py" in capsys.readouterr().out


def test_check_launch_refuses_a_missing_path(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        check_launch.main(["/no/such/launch.py"])
    assert exc.value.code == 2 and "no such file or folder" in capsys.readouterr().err


def _passing_run(job: Any, settings: Any, stop: Any = None, on_verdict: Any = None) -> dict[str, Any]:
    run_dir = make_run_dir(settings.out, f"{job.world}_{job.maneuver}_seed{job.seed}")
    row = {"passed": True, "outcome": "verdict", "reason": "passed", "verdict": None, "job": job.key,
           "world": job.world, "maneuver": job.maneuver, "seed": job.seed, "profile": settings.profile,
           "run_dir": str(run_dir), "wall_time": 0.1}
    (run_dir / "result.json").write_text(json.dumps(row))
    return row


@pytest.mark.parametrize(("name", "code"), [("sheet", 0), ("hardcoded_value", 1)])
def test_grade_exe_with_launch_carries_the_checks(name: str, code: int, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch,
                                                   capsys: pytest.CaptureFixture) -> None:
    """Every run passes, so the launch file decides the exit code; grade.json, feedback.md and Gradescope's
    results carry the three checks as a class's hand-in's do."""
    monkeypatch.setattr(exe_grid, "run_exe_job", _passing_run)
    hand_in = tmp_path / "hand-in"
    shutil.copytree(LAUNCH, hand_in)
    (hand_in / "reactive_navigator.py").write_text("# CHOICE: C\n")
    out = tmp_path / "g"
    argv = ["--exe", f"{sys.executable} {hand_in / 'reactive_navigator.py'}", "--worlds", "stage_4", "--seeds", "1",
            "--lidars", "profile", "--record", "off", "--progress", "off", "--out", str(out),
            "--launch", str(hand_in / f"{name}.launch.py")]
    assert grade.main(argv) == code
    stdout = capsys.readouterr().out
    assert "  launch file: starts the node: PASSED" in stdout
    record = read_record(out)
    assert [c["passed"] for c in record["launch"]["checks"]] == ([True] * 3 if code == 0 else [True, False, True])
    feedback = (out / "feedback.md").read_text()
    assert f"## Launch file ({name}.launch.py)" in feedback
    tests = [t for t in gradescope_results(record)["tests"] if t["name"].startswith("launch file: ")]
    assert len(tests) == 3 and (all(t["status"] == "passed" for t in tests) == (code == 0))


def test_launch_without_exe_is_refused(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        grade.main(["--launch", str(LAUNCH / "sheet.launch.py"), "--seeds", "1"])
    assert exc.value.code == 2 and "--launch goes with --exe" in capsys.readouterr().err
