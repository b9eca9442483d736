"""``bt-nav grade --exe`` on students' nodes (tests/fixtures, plain rclpy): two written as the course suggests get
their verdicts at full speed; each faulty one gets a verdict within its limit whose reason names the fault, its
output kept in node.log, and no process left behind."""

from __future__ import annotations

import json
import re
import signal
import sys
from pathlib import Path
from typing import Any

import psutil

from bt_nav.cli import grade
from bt_nav.grading.exe.run import _ending_findings, _with_findings

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def _grade(tmp_path: Path, fixture: str, timeout: float, *extra: str) -> dict[str, Any]:
    """The one row of grading ``fixture`` once (stage_4 seed 0 unless ``extra`` says otherwise)."""
    out = tmp_path / "grid"
    before = {p.pid for p in psutil.Process().children(recursive=True)}  # the test process's own (a resource tracker)
    code = grade.main(["--exe", f"{sys.executable} {FIXTURES / fixture}", "--worlds", "stage_4", "--seeds", "1",
                       "--rtf", "0", "--realtime-check", "off",
                       "--lidars", "profile",
                       "--jobs", "1", "--timeout", str(timeout), "--out", str(out), *extra])
    [row] = json.loads((out / "grade.json").read_text())["runs"]
    assert code == (0 if row["passed"] else 1), row["reason"]
    assert row["wall_time"] < timeout, f"over its limit: {row['wall_time']} s"
    left = [p for p in psutil.Process().children(recursive=True) if p.pid not in before]
    assert not left, f"processes left behind: {[(p.pid, p.cmdline()) for p in left]}"
    return row


def _sim_seconds(row: dict[str, Any]) -> float:
    """Sim seconds from the simulator's start to the judge's report."""
    return row["verdict"]["t0_sim"] + row["verdict"]["times"]["report"]


def _checks(row: dict[str, Any]) -> dict[str, bool]:
    return {c["name"]: c["passed"] for c in row["verdict"]["checks"]}


# ---------------------------------------------------------------------------------------------- as suggested
def test_the_suggested_timer_node_passes_at_full_speed(tmp_path: Path) -> None:
    """The homework's suggested approach, cmd_vel from a 10 Hz timer, scan best effort: passed, nothing found."""
    row = _grade(tmp_path, "timer_node.py", 90)
    assert row["outcome"] == "verdict" and row["passed"], row["reason"]
    assert row["findings"] == [] and row["reason"] == "passed"
    assert row["wall_time"] < 0.6 * _sim_seconds(row), "not graded faster than real time"
    assert "evaluate_mission called" in (Path(row["run_dir"]) / "node.log").read_text()


def test_the_lab_template_node_gets_its_checkoff_verdict(tmp_path: Path) -> None:
    """The lab's template (reliable scan of depth 10, commands from the scan callback, toggle_navigation) turning
    only until its front is clear: armed, creeping and turning as the judge saw it, never the Randomizer's
    90-180 deg."""
    row = _grade(tmp_path, "lab_template_node.py", 120, "--profile", "lab", "--worlds", "lab_object",
                 "--maneuvers", "A")
    assert row["outcome"] == "verdict" and not row["passed"] and row["findings"] == [], row["reason"]
    checks = _checks(row)
    maneuvers = {name: ok for name, ok in checks.items() if name.startswith("maneuver ")}
    assert maneuvers and not all(maneuvers.values()), row["verdict"]["report_lines"]
    assert all(ok for name, ok in checks.items() if name not in maneuvers), row["verdict"]["report_lines"]
    failed = [line for line in row["verdict"]["report_lines"] if line.startswith("maneuver ") and "FAILED" in line]
    assert failed and all("the Randomizer needs 80-190 deg either side" in line for line in failed), failed
    assert "maneuver 1 turned" in row["reason"] and "the Randomizer needs 80-190 deg" in row["reason"], row["reason"]
    assert row["wall_time"] < 0.6 * _sim_seconds(row), "not graded faster than real time"


# ---------------------------------------------------------------------------------------------- faults
def test_a_node_that_never_offers_the_service(tmp_path: Path) -> None:
    row = _grade(tmp_path, "noservice_node.py", 60)
    assert row["outcome"] == "verdict" and not row["passed"]
    # the judge's wait: a third of (60 - 5) s
    assert row["reason"] == ("not judged: the service /reactive_control/activate never appeared within 18.3 s wall "
                             "(the node offers std_srvs/srv/SetBool as /activate)"), row["reason"]
    assert row["wall_time"] < 40.0
    assert not any(c["passed"] for c in row["verdict"]["checks"]), row["verdict"]["checks"]
    assert row["verdict"]["travelled"] == 0.0 and row["verdict"]["report_lines"] == [
        "/reactive_control/activate offered (" + row["reason"].removeprefix("not judged: ") + "): FAILED",
        "overall: FAILED"]


def test_a_node_that_drives_without_the_service_is_told_what_its_robot_did(tmp_path: Path) -> None:
    """Never armed, it drives on (0.3 m/s) for the judge's whole wait (sim time at 1x: nothing is judged before t0,
    and it hits a wall after about 0.7 m): the verdict gives its own ground-truth motion and its collisions (the
    simulator's events), not ``travelled 0.00 m`` and ``no collision: PASSED``."""
    row = _grade(tmp_path, "noservice_node.py --drive 0.3", 60)
    verdict, sim_log = row["verdict"], (Path(row["run_dir"]) / "sim.log").read_text()
    assert not row["passed"] and not any(c["passed"] for c in verdict["checks"]), verdict["checks"]
    assert verdict["travelled"] > 0.3 and "it moved without being armed (travelled" in row["reason"], row["reason"]
    logged = int(re.search(r"(\d+) collision events", sim_log).group(1))
    assert 0 < verdict["collisions"] <= logged, (verdict["collisions"], logged)  # the simulator runs on a moment
    assert any(line.startswith("no collision (") and line.endswith("FAILED") for line in verdict["report_lines"])


def test_nan_commands_are_counted(tmp_path: Path) -> None:
    row = _grade(tmp_path, "nan_node.py", 90)
    assert row["outcome"] == "verdict" and not row["passed"]
    [nan] = [f for f in row["findings"] if "NaN" in f]
    assert nan in row["reason"]
    count, _, received = nan.split()[:3]
    assert 0 < int(count) <= int(received) and nan.endswith("held NaN or inf values (the simulator takes them as a "
                                                            "stop)")
    assert not _checks(row)["minimum travelled distance"]


def test_a_cmd_vel_flood_is_reported_with_its_rate(tmp_path: Path) -> None:
    row = _grade(tmp_path, "flood_node.py", 120)
    assert row["outcome"] == "verdict"
    [flood] = [f for f in row["findings"] if f.startswith("cmd_vel flood: ")]
    assert float(flood.split()[2]) > 1000.0 and "per sim s" in flood and flood in row["reason"]


def test_twist_stamped_on_a_twist_topic_is_named(tmp_path: Path) -> None:
    row = _grade(tmp_path, "stamped_node.py", 90)
    assert row["outcome"] == "verdict" and not row["passed"]
    assert row["findings"] == ["reactive_control publishes /cmd_vel as geometry_msgs/msg/TwistStamped, but bt_nav_sim "
                               "reads geometry_msgs/msg/Twist: not one message passes"], row["findings"]


def test_a_node_ignoring_sigint_is_killed_and_named(tmp_path: Path) -> None:
    row = _grade(tmp_path, "hang_node.py", 90)
    assert row["outcome"] == "verdict"
    assert row["findings"][-1].startswith("the node ignored SIGINT (stopped by SIGKILL after "), row["findings"]
    assert row["reason"].endswith(row["findings"][-1])
    assert "evaluate_mission called" in (Path(row["run_dir"]) / "node.log").read_text()  # its output is kept


# ---------------------------------------------------------------------------------------------- the row's words
class _Ended:
    """What _ending_findings reads of a launched child."""

    def __init__(self, code: int | None, stopped_by: signal.Signals | None, seconds: float = 0.0,
                 sigints: int = 1) -> None:
        self.code, self.stopped_by, self.stop_seconds = code, stopped_by, seconds
        self.sigints = sigints if stopped_by is not None else 0

    def poll(self) -> int | None:
        return self.code


def test_how_the_node_ended() -> None:
    assert _ending_findings(_Ended(-2, signal.SIGINT, 0.4)) == ([], [])  # stopped as asked
    assert _ending_findings(_Ended(1, None)) == ([], [])  # a crash: the reason already says so
    assert _ending_findings(_Ended(0, None)) == (["the node ended by itself (exit code 0) before the run was over "
                                                  "(see node.log)"], [])
    assert _ending_findings(_Ended(-15, signal.SIGTERM, 3.04)) == (["the node ignored SIGINT (stopped by SIGTERM "
                                                                    "after 3.0 s)"], [])
    assert _ending_findings(_Ended(0, signal.SIGINT, 0.1)) == ([], [])  # caught KeyboardInterrupt: fine
    crashed, notes = _ending_findings(_Ended(1, signal.SIGINT, 0.2))  # e.g. "rcl_shutdown already called"
    assert crashed[0].startswith("the node crashed while shutting down (exit code 1 after SIGINT") and not notes
    assert _ending_findings(_Ended(0, signal.SIGINT, 1.6, sigints=2)) == ([], [
        "the node stopped at the second SIGINT (1.6 s): its first was lost, as one can be inside rclpy's executor; "
        "not held against it"])
    row = _with_findings({"reason": "passed"}, ["a", "b"])
    assert row == {"reason": "passed; a; b", "findings": ["a", "b"]}
    assert _with_findings({"reason": "passed", "findings": ["a"]}, []) == {"reason": "passed", "findings": ["a"]}


def test_a_missing_module_in_the_node_log_is_named(tmp_path: Path) -> None:
    """The node ran with a Python without ROS 2: its log says so, and the row names the missing module."""
    log = tmp_path / "node.log"
    log.write_text("Traceback (most recent call last):\n  File \"node.py\", line 1\n"
                   "ModuleNotFoundError: No module named 'rclpy'\n")
    [found], _ = _ending_findings(None, log)
    assert found.startswith("the node could not import rclpy (ModuleNotFoundError)")
    log.write_text("all fine\n")
    assert _ending_findings(None, log) == ([], [])


def test_a_run_whose_domain_another_program_uses_moves_and_says_so(tmp_path: Path) -> None:
    """A program that is not the run's sits on the first domain the run claims (a talker publishing cmd_vel, as
    someone's shell with a fixed ROS_DOMAIN_ID would): the run is not blamed on the node; it starts again on another
    domain, passes there, and its row says why it moved."""
    import os
    import subprocess

    from bt_nav.grading.grid import Job
    from bt_nav.run.settings import DEFAULT_JITTER

    low = 150 + os.getpid() % 40  # three domains: the first the run claims (hash of its key) is the talker's
    key = Job("lab_object", "C", 0, "lab", jitter=DEFAULT_JITTER, sim_params=(("lidar", "lds01"),)).key
    seed = next(s for s in range(100) if subprocess.run(
        [sys.executable, "-c", f"print(hash({key!r}) % 3)"], env={**os.environ, "PYTHONHASHSEED": str(s)},
        capture_output=True, text=True).stdout.strip() == "0")
    talker = subprocess.Popen([sys.executable, str(FIXTURES / "noservice_node.py")],
                              env={**os.environ, "ROS_DOMAIN_ID": str(low)}, start_new_session=True)
    try:
        out = tmp_path / "grid"
        subprocess.run([sys.executable, "-m", "bt_nav.cli", "grade", "--profile", "lab", "--exe",
                        f"{sys.executable} {FIXTURES / 'lab_student_node.py'} --variant c_stands_05",
                        "--worlds", "lab_object", "--maneuvers", "C", "--lidars", "lds01", "--seeds", "1",
                        "--rtf", "0", "--realtime-check", "off", "--record", "off", "--out", str(out)],
                       env={**os.environ, "PYTHONHASHSEED": str(seed), "BT_NAV_DOMAIN_RANGE": f"{low}-{low + 2}"},
                       check=False, timeout=240)
    finally:
        talker.terminate()
        talker.wait(10)
    [row] = json.loads((out / "grade.json").read_text())["runs"]
    assert row["job"] == key, "the job's key changed: the test no longer knows which domain the run claims first"
    assert row["passed"] and row["domain"] != low, row["reason"]
    [move] = [note for note in row["notes"] if "another program" in note]  # (a lost SIGINT may be noted too)
    assert re.match(rf"no verdict: another program is on ROS_DOMAIN_ID {low}: (node reactive_control|a participant) "
                    rf"of pid {talker.pid} \(.*noservice_node.py\) \(not the run's, not the node's\): the run "
                    rf"started again on ROS_DOMAIN_ID {row['domain']} \(that attempt on {low}: ", move), move
