"""``bt-nav grade --exe``'s recording and ``report.html`` over real DDS, with the foreign fixture nodes.

The homework fixture is graded with its evaluation call remapped to a service nobody serves, so its run fails
whatever distance it drives (it drives ~7.4-8.7 m, around the 8 m requirement): a failed run with a full bag, hence
a video. The crash fixture dies at start: its run has a bag without ground truth, hence the world only.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import psutil
import pytest

from bt_nav.cli import grade
from bt_nav.media.bagread import read_bag
from tests.media.reportkit import broken_links, mp4_frames

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
NO_EVALUATION = "--ros-args -r /reactive_control/evaluate_mission:=/nobody_serves_this"


#: The test process's own children before the last grade began (a resource tracker an earlier test started).
_BEFORE: set[int] = set()


def _grade(out: Path, command: str, *extra: str) -> tuple[int, dict]:
    _BEFORE.clear()
    _BEFORE.update(p.pid for p in psutil.Process().children(recursive=True))
    code = grade.main(["--exe", command, "--worlds", "stage_4", "--seeds", "1", "--rtf", "0", "--realtime-check", "off",
                       "--lidars", "profile", "--jobs", "1", "--out", str(out),
                       *extra])
    return code, json.loads((out / "grade.json").read_text())


def _no_children_left() -> None:
    left = [p for p in psutil.Process().children(recursive=True) if p.pid not in _BEFORE]
    assert not left, f"processes left behind: {[(p.pid, p.cmdline()) for p in left]}"


def test_a_failed_run_is_recorded_pictured_and_filmed(tmp_path: Path) -> None:
    out = tmp_path / "grid"
    code, doc = _grade(out, f"{sys.executable} {FIXTURES / 'homework_node.py'} {NO_EVALUATION}", "--timeout", "120")
    [row] = doc["runs"]
    assert code == 1 and not row["passed"] and row["outcome"] == "verdict", row["reason"]
    assert "did not call the evaluation service in time (never called)" in row["reason"], row["reason"]
    run_dir = Path(row["run_dir"])
    assert row["bag"] == "bag" and row["bag_bytes"] > 500_000, row
    record = read_bag(run_dir / "bag")
    t0, activation = row["verdict"]["t0_sim"], row["verdict"]["times"]["activated"]
    assert record.truth.t[0] == pytest.approx(row["bag_truth_from"], abs=0.006)  # the recorder's line: 2 decimals
    assert record.truth.t[0] < t0 + activation, \
        "the bag holds the ground truth from before the robot was first activated (its first move)"
    assert record.truth.t[0] <= t0 and row["bag_after_t0_s"] == 0.0, "the simulator records from its first step"
    assert row["bag_after_t0_s"] == pytest.approx(max(0.0, record.truth.t[0] - t0), abs=0.011)
    assert record.truth.t[-1] >= t0 + 55.0, "... to the verdict (the schedule's 55 s and more)"
    assert row["wall_time"] < 90.0
    media = row["media"]
    assert media["picture"] == "trajectory.png" and (run_dir / "trajectory.png").stat().st_size > 20_000
    frames, _ = mp4_frames(run_dir / "video.mp4")
    assert frames == media["frames"] >= 550, "the video spans the schedule from t0 at 10 frames per sim second"
    page = out / "report.html"
    assert not broken_links(page), broken_links(page)
    text = page.read_text()
    assert "0/1 passed (0.0 %)" in text and 'src="stage_4_none_seed0/video.mp4"' in text
    assert (out / "distance.png").is_file() and doc["figures"] == ["distance.png"]
    files = {p.name for p in run_dir.iterdir()}
    assert {"sim.log", "result.json", "verdict.json"} <= files and "record.log" not in files, \
        "the simulator's process writes the bag: no recorder process of its own"
    _no_children_left()


def test_a_crashed_node_gets_the_world_only(tmp_path: Path) -> None:
    out = tmp_path / "grid"
    code, doc = _grade(out, f"{sys.executable} {FIXTURES / 'crash_node.py'}", "--timeout", "60")
    [row] = doc["runs"]
    assert code == 1 and row["outcome"] == "node exited"
    assert row["wall_time"] < 40.0, "the run does not wait out the recorder's ground truth once the node is gone"
    media = row["media"]
    assert media["picture"] == "trajectory.png", "a bag names its world: the world is drawn, path or not"
    if row["bag_truth_from"] is None:  # the node died before the simulator's first step, or before its bag at all
        assert media["note"] in ("no ground truth in the bag: the world only, no video",
                                 "no bag: the node ended before the simulator recorded; the world only, no video"), \
            media["note"]
        assert media["video"] is None
    assert not broken_links(out / "report.html")
    assert "0/1 passed" in (out / "report.html").read_text()
    _no_children_left()


def test_recording_off_leaves_no_bag(tmp_path: Path) -> None:
    out = tmp_path / "grid"
    _, doc = _grade(out, f"{sys.executable} {FIXTURES / 'crash_node.py'}", "--timeout", "60", "--record", "off")
    [row] = doc["runs"]
    assert row["bag"] is None and not (Path(row["run_dir"]) / "bag").exists()
    assert row["media"]["note"] == "no bag (recording off)"
    _no_children_left()
