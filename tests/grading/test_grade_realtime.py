"""The real-time check's bookkeeping (:mod:`bt_nav.grading.realtime`) with the runs replaced by a table of
verdicts: which runs are run again at 1x, when, and what replaces a row. Its DDS run is
``tests/ros/test_grade_realtime_dds.py``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading import realtime
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import Job
from bt_nav.ros.nodes import findings as kinds
from bt_nav.ros.nodes.findings import Finding


def _job(seed: int) -> Job:
    return Job("lab_object", "C", seed, "lab", sim_params=(("lidar", "lds01"),))


def _row(job: Job, passed: bool, outcome: str = "verdict", where: str = "fast") -> dict[str, Any]:
    return {"job": job.key, "passed": passed, "outcome": outcome, "reason": "passed" if passed else "failed: angle",
            "findings": [], "run_dir": f"/{where}/{job.seed}", "world": job.world, "maneuver": job.maneuver,
            "lidar": "lds01", "seed": job.seed}


@pytest.fixture
def ran(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, float]]:
    """Every run the check starts, as (seed, rtf); a 1x run passes unless its seed is odd."""
    started: list[tuple[int, float]] = []

    def fake_pool(tasks: list[tuple[Job, ExeSettings]], workers: int, stop: Any) -> Any:
        for index, (job, settings) in enumerate(tasks):
            started.append((job.seed, settings.rtf))
            yield index, _row(job, job.seed % 2 == 0, where="slow")

    monkeypatch.setattr(realtime, "run_pool", fake_pool)
    return started


def _settings(tmp_path: Path, **kw: Any) -> ExeSettings:
    return ExeSettings("python3 node.py", "lab", tmp_path, **kw)


def test_a_node_passing_at_1x_has_every_failed_run_graded_there(tmp_path: Path, ran: list) -> None:
    jobs = [_job(s) for s in (0, 2, 4, 6)]
    rows = {j.key: _row(j, j.seed == 4) for j in jobs}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 3
    assert ran == [(0, 1.0), (2, 1.0), (6, 1.0)]  # the probe first, then the other failures; never a pass
    for job in jobs:
        row = rows[job.key]
        assert row["passed"]
        if job.seed == 4:
            assert row["run_dir"] == "/fast/4" and "realtime" not in row
        else:
            assert row["run_dir"] == f"/slow/{job.seed}" and row["realtime"]["reason"] == "failed: angle"
            assert "failed at 5x real time (failed: angle) and passed at 1x" in row["findings"][0]


def test_a_node_failing_at_1x_too_keeps_its_verdicts_after_one_run(tmp_path: Path, ran: list) -> None:
    jobs = [_job(s) for s in (1, 3)]
    rows = {j.key: _row(j, False) for j in jobs}
    before = json.loads(json.dumps(rows))
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 0
    assert ran == [(1, 1.0)]
    assert rows[jobs[0].key].pop("realtime_probe")["passed"] is False
    assert rows == before


@pytest.mark.parametrize("kw", [{"rtf": 1.0}, {"realtime_check": False}])
def test_nothing_runs_at_1x_or_with_the_check_off(tmp_path: Path, ran: list, kw: dict) -> None:
    jobs = [_job(0)]
    rows = {jobs[0].key: _row(jobs[0], False)}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path, **kw), rows, 2) == 0
    assert ran == []


def test_bt_nav_errors_and_stopped_runs_are_not_the_nodes_failures(tmp_path: Path, ran: list) -> None:
    jobs = [_job(0), _job(2)]
    rows = {jobs[0].key: _row(jobs[0], False, "bt_nav error"), jobs[1].key: _row(jobs[1], False, "stopped")}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 0
    assert ran == []


def test_a_class_probes_every_student_in_one_pool(tmp_path: Path, ran: list) -> None:
    a, b = [_job(0), _job(2)], [_job(1), _job(3)]
    rows_a = {j.key: _row(j, False) for j in a}
    rows_b = {j.key: _row(j, False) for j in b}
    grids = [(a, _settings(tmp_path / "a"), rows_a, None), (b, _settings(tmp_path / "b"), rows_b, None)]
    assert realtime.confirm_grids(grids, 2) == [2, 0]
    assert ran == [(0, 1.0), (1, 1.0), (2, 1.0)]  # both probes, then only the passing student's other failure


def test_a_resumed_check_reuses_the_finished_1x_runs(tmp_path: Path, ran: list) -> None:
    jobs = [_job(0), _job(2)]
    done = tmp_path / realtime.REALTIME_DIR / "lab_object_C_lds01_seed0"
    done.mkdir(parents=True)
    (done / "result.json").write_text(json.dumps(_row(jobs[0], True, where="kept")))
    rows = {j.key: _row(j, False) for j in jobs}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 2
    assert ran == [(2, 1.0)]
    assert rows[jobs[0].key]["run_dir"] == "/kept/0"


def _verdict(durations: list[float], called: float | None = None) -> dict[str, Any]:
    return {"maneuvers": [{"t": 10.0 * k, "settled": 10.0 * k + d} for k, d in enumerate(durations)],
            "evaluation_called": called}


def test_the_wall_clock_is_named_only_on_evidence() -> None:
    """Both readings of a run that failed at 5x and passed at 1x: turns that lasted five times longer in sim time
    (the same wall time) name the wall clock, with the figures; a ROS-time node whose 90 deg pivot overshot to 114 deg
    under load (its turn as long in sim time at both speeds) is not told it keeps time by the wall clock."""
    wall = realtime.wall_clock_evidence(_verdict([2.6, 2.7]), _verdict([13.1, 13.0]), 5.0)
    assert wall == "its turns lasted 13.1 sim s at 5x and 2.7 sim s at 1x: the same wall time"
    assert realtime.wall_clock_evidence(_verdict([2.6]), _verdict([3.2]), 5.0) is None
    finding = realtime.wall_clock_finding(5.0, "failed: maneuver 1 turned 114 deg left", None)
    assert "wall clock" not in finding and "followed sim time at both speeds" in finding
    assert "keeps time by the wall clock" in realtime.wall_clock_finding(5.0, "failed: ...", wall)


def test_a_homework_timer_by_the_wall_clock_shows_in_its_evaluation_call() -> None:
    """The homework's 50 s by the wall clock: called at 50 s at 1x, never within the mission at 5x (250 sim s)."""
    said = realtime.wall_clock_evidence(_verdict([], called=50.1), _verdict([], called=None), 5.0)
    assert said == "its evaluation call came at t=50.1 s at 1x and never at 5x"
    assert realtime.wall_clock_evidence(_verdict([], called=50.1), _verdict([], called=50.3), 5.0) is None


def _verdict_row(job: Job, failed: list[str], findings: tuple[Finding, ...] = (), **verdict: Any) -> dict[str, Any]:
    """A failed row with a verdict: ``failed`` the names of its failed checks (one passed check besides), the audit's
    ``findings`` as the judge writes them (their sentences and, in the same order, their kinds)."""
    checks = [{"name": name, "passed": False} for name in failed] + [{"name": "no collision", "passed": True}]
    return {**_row(job, False), "verdict": {"passed": False, "checks": checks, "findings": [f.text for f in findings],
                                            "finding_kinds": [f.record() for f in findings], **verdict}}


def _crashed(job: Job, exception: str | None = None, starting: bool = False) -> dict[str, Any]:
    """A row whose node exited with an error, with the crash its traceback showed (None: no traceback)."""
    row = {**_row(job, False, "node exited"), "verdict": None}
    if exception is not None:
        row["crash"] = {"exception": exception, "where": "node.py:10 in __init__", "starting": starting}
    return row


_STAMPED = ("reactive_navigator publishes /cmd_vel as geometry_msgs/msg/TwistStamped, but bt_nav_sim reads "
            "geometry_msgs/msg/Twist")
TWIST_STAMPED = Finding(kinds.TYPE_MISMATCH, f"{_STAMPED}: not one message passes", "/cmd_vel", _STAMPED)
NO_SCAN = Finding(kinds.NO_SUBSCRIBER, "no node subscribed to /scan: the node never received one message from it",
                  "/scan", "no node subscribed to /scan")
NO_CLOCK = Finding(kinds.NO_SUBSCRIBER, "no node subscribed to /clock: the node does not run on sim time "
                   "(use_sim_time:=true was given with --ros-args; does it pass its arguments to rclpy.init?)",
                   "/clock", "no node subscribed to /clock")


def test_which_failures_a_speed_can_change() -> None:
    """Settled before the simulation moves (no 1x run): a crash while starting, the arm service never offered,
    ``parameters declared`` the only failed check, scans or commands no message carries. Everything a turn, a
    stop, a lateness or a callback racing the clock decides may depend on the speed (a 1x run)."""
    job = _job(0)
    cannot = realtime.speed_cannot_matter
    assert cannot(_crashed(job, "rclpy.exceptions.ParameterNotDeclaredException: Invalid access to undeclared "
                                "parameter(s): safety_distance", starting=True)) == \
        "the node crashed while starting (ParameterNotDeclaredException)"
    assert cannot(_crashed(job, "ModuleNotFoundError: No module named 'rclpy'", starting=True)) == \
        "the node crashed while starting (ModuleNotFoundError)"
    assert cannot(_crashed(job, "ValueError: min() arg is an empty sequence")) is None  # in its scan callback
    assert cannot(_crashed(job)) is None  # no traceback: nothing says when or why
    never = "the service /toggle_navigation never appeared within 20 s wall"
    assert cannot(_verdict_row(job, ["/toggle_navigation offered"], not_started=never)) == f"not judged: {never}"
    assert cannot(_verdict_row(job, ["parameters declared"])) == "only parameters declared failed"
    assert cannot(_verdict_row(job, ["maneuvers performed"], (TWIST_STAMPED,))) == _STAMPED
    assert cannot(_verdict_row(job, ["maneuvers performed"], (NO_SCAN,))) == "no node subscribed to /scan"
    for failed in (["maneuver 1"], ["parameters declared", "maneuver 1"], ["no collision"], ["static at the end"],
                   ["evaluation service called"], ["minimum travelled distance"], ["recovery turns"]):
        assert cannot(_verdict_row(job, failed)) is None, failed
    assert cannot(_verdict_row(job, ["maneuvers performed"], (NO_CLOCK,))) is None  # on the wall clock: right at 1x
    assert cannot(_verdict_row(job, ["parameters declared"], timed_out=True)) is None
    assert cannot({**_row(job, False, "timeout"), "verdict": None}) is None


def test_a_cut_off_is_read_from_the_findings_kinds_not_their_words() -> None:
    """The decision reads ``finding_kinds``: a sentence reworded (or in another language) decides the same, and a
    sentence alone, without its kind, decides nothing."""
    job = _job(0)
    reworded = Finding(kinds.NO_PUBLISHER, "nothing was ever published on /cmd_vel", "/cmd_vel")
    assert realtime.speed_cannot_matter(_verdict_row(job, ["maneuvers performed"], (reworded,))) == reworded.text
    flood = Finding(kinds.FLOOD, "no node subscribed to /scan: ...", "/cmd_vel")  # the words of a cut-off, not its kind
    assert realtime.speed_cannot_matter(_verdict_row(job, ["maneuvers performed"], (flood,))) is None
    words_only = _verdict_row(job, ["maneuvers performed"])
    words_only["verdict"]["findings"] = [NO_SCAN.text]
    assert realtime.speed_cannot_matter(words_only) is None
    qos = Finding(kinds.QOS_MISMATCH, "incompatible QoS on /clock: ...", "/clock", "incompatible QoS on /clock")
    assert realtime.speed_cannot_matter(_verdict_row(job, ["maneuvers performed"], (qos,))) is None


def test_only_failures_a_speed_can_change_run_at_1x(tmp_path: Path, ran: list) -> None:
    jobs = [_job(s) for s in (0, 2, 4)]
    rows = {jobs[0].key: _crashed(jobs[0], "ModuleNotFoundError: No module named 'rclpy'", starting=True),
            jobs[1].key: _verdict_row(jobs[1], ["maneuver 1"]), jobs[2].key: _verdict_row(jobs[2], ["maneuver 1"])}
    settings = _settings(tmp_path)
    assert realtime.check_plan(jobs, settings, rows) == [
        f"bt-nav grade: lab_object C lds01 seed 2 again at 1x real time before the failures stand, then the 1 other "
        f"failed run that may depend on speed if it passes there (--realtime-check off skips it): into "
        f"{tmp_path / 'realtime'}/",
        "bt-nav grade: not re-run at 1x, no speed changes their verdict: lab_object C lds01 seed 0 (the node crashed "
        "while starting (ModuleNotFoundError))"]
    assert realtime.confirm_at_real_time(jobs, settings, rows, 2) == 2
    assert ran == [(2, 1.0), (4, 1.0)]
    assert rows[jobs[0].key]["outcome"] == "node exited"


def test_nothing_runs_at_1x_when_no_failure_depends_on_speed(tmp_path: Path, ran: list) -> None:
    jobs = [_job(s) for s in (0, 2, 4, 6)]
    rows = {jobs[0].key: _verdict_row(jobs[0], ["parameters declared"]),
            jobs[1].key: _verdict_row(jobs[1], ["parameters declared"]),
            jobs[2].key: _verdict_row(jobs[2], ["maneuvers performed"], (NO_SCAN,)), jobs[3].key: _row(jobs[3], True)}
    assert realtime.check_plan(jobs, _settings(tmp_path), rows) == [
        "bt-nav grade: no failed run depends on speed, so none is re-run at 1x: lab_object C lds01 seed 0, "
        "lab_object C lds01 seed 2 (only parameters declared failed); lab_object C lds01 seed 4 (no node subscribed "
        "to /scan)"]
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 0
    assert ran == []
    assert realtime.check_plan(jobs, _settings(tmp_path, realtime_check=False), rows) == []
