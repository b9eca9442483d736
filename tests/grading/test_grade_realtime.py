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


#: What a re-run of a seed shows, by (seed, rtf): passed, and its verdict (the maneuvers' turns); a seed not in the
#: table passes at every speed unless it is odd.
SHOWN: dict[tuple[int, float], tuple[bool, dict[str, Any] | None]] = {}


@pytest.fixture
def ran(monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, float]]:
    """Every run the check starts, as (seed, rtf); what each shows comes from :data:`SHOWN`."""
    started: list[tuple[int, float]] = []
    SHOWN.clear()

    def fake_pool(tasks: list[tuple[Job, ExeSettings]], workers: int, stop: Any) -> Any:
        for index, (job, settings) in enumerate(tasks):
            started.append((job.seed, settings.rtf))
            passed, verdict = SHOWN.get((job.seed, settings.rtf), (job.seed % 2 == 0, None))
            where = "slow" if settings.rtf == 1.0 else "again"
            yield index, {**_row(job, passed, where=where), "verdict": verdict}

    monkeypatch.setattr(realtime, "run_pool", fake_pool)
    return started


def _settings(tmp_path: Path, **kw: Any) -> ExeSettings:
    return ExeSettings("python3 node.py", "lab", tmp_path, **{"rtf": 5.0, **kw})  # the fixed factor these tests use


def _turning(*turns: tuple[str, float], passed: bool = True, durations: float = 2.6) -> dict[str, Any]:
    """A verdict with these maneuvers (side, degrees), each lasting ``durations`` sim s, at t=10, 20, ..."""
    return {"t0_sim": 0.0, "maneuvers": [{"t": 10.0 * k, "settled": 10.0 * k + durations, "side": side,
                                          "angle_deg": angle if side == "left" else -angle, "passed": passed}
                                         for k, (side, angle) in enumerate(turns, start=1)],
            "times": {"activated": 5.0, "deactivation_requested": 65.0}}


def test_a_passing_rerun_without_evidence_does_not_overturn_a_failure(tmp_path: Path, ran: list) -> None:
    """Both re-runs pass, the turns alike, nothing slipped: the failure stands, and the words say how each ended."""
    jobs = [_job(s) for s in (0, 2, 4)]
    rows = {j.key: {**_row(j, j.seed == 4), "verdict": _turning(("left", 120.0), passed=j.seed == 4)}
            for j in jobs}
    for seed in (0, 2):
        SHOWN[(seed, 5.0)] = SHOWN[(seed, 1.0)] = (True, _turning(("left", 124.0)))
    said: list[str] = []
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2, say=said.append) == 0
    assert ran == [(0, 5.0), (0, 1.0), (2, 5.0), (2, 1.0)]  # the probe first, then the other failure; never a pass
    assert not rows[jobs[0].key]["passed"] and rows[jobs[0].key]["run_dir"] == "/fast/0"
    assert said[0] == ("bt-nav grade: lab_object C lds01 seed 0: failed at 5x (failed: angle); run again at 5x: "
                       "passed; at 1x: passed: nothing in the failed run shows its timing slipped (the simulator "
                       "waited for the node's commands throughout) or a wall clock; the failure stands")
    assert rows[jobs[0].key]["rerun"]["decision"] == "stands" and len(said) == 2


def test_a_node_failing_at_both_speeds_keeps_its_verdicts_after_its_probe(tmp_path: Path, ran: list) -> None:
    jobs = [_job(s) for s in (1, 3)]
    rows = {j.key: _row(j, False) for j in jobs}
    said: list[str] = []
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2, say=said.append) == 0
    assert ran == [(1, 5.0), (1, 1.0)]
    assert said == ["bt-nav grade: lab_object C lds01 seed 1: failed at 5x (failed: angle); run again at 5x: failed "
                    "(failed: angle); at 1x: failed (failed: angle): it failed again; the failure stands",
                    "bt-nav grade: lab_object C lds01 seed 3: not run again: lab_object C lds01 seed 1, the first "
                    "failure, failed again at both speeds; the failure stands"]
    assert rows[jobs[0].key]["realtime_probe"]["passed"] is False
    assert all(not row["passed"] and row["rerun"]["decision"] == "stands" for row in rows.values())


@pytest.mark.parametrize("kw", [{"rtf": 1.0}, {"realtime_check": False}])
def test_nothing_runs_at_1x_or_with_the_check_off(tmp_path: Path, ran: list, kw: dict) -> None:
    jobs = [_job(0)]
    rows = {jobs[0].key: _row(jobs[0], False)}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path, **kw), rows, 2) == 0
    assert ran == []


def test_bt_nav_errors_stopped_and_ungraded_runs_are_not_the_nodes_failures(tmp_path: Path, ran: list) -> None:
    jobs = [_job(0), _job(2), _job(4)]
    rows = {jobs[0].key: _row(jobs[0], False, "bt_nav error"), jobs[1].key: _row(jobs[1], False, "stopped"),
            jobs[2].key: {**_row(jobs[2], False, "bt_nav error"), "not_graded": "another program ..."}}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 0
    assert ran == []


def test_a_class_probes_every_student_in_one_pool(tmp_path: Path, ran: list) -> None:
    a, b = [_job(0), _job(2)], [_job(1), _job(3)]
    rows_a = {j.key: _row(j, False) for j in a}
    rows_b = {j.key: _row(j, False) for j in b}
    grids = [(a, _settings(tmp_path / "a"), rows_a, None), (b, _settings(tmp_path / "b"), rows_b, None)]
    heard: list[tuple[int, str]] = []
    assert realtime.confirm_grids(grids, 2, say=lambda i, line: heard.append((i, line))) == [0, 0]
    # both probes, then only the other failure of the student whose probe did not fail at both speeds
    assert ran == [(0, 5.0), (0, 1.0), (1, 5.0), (1, 1.0), (2, 5.0), (2, 1.0)]
    assert [i for i, _ in heard] == [0, 0, 1, 1]  # every failure of each student, said once


def test_a_resumed_check_reuses_the_finished_reruns(tmp_path: Path, ran: list) -> None:
    jobs = [_job(0), _job(2)]
    for folder in (realtime.RERUN_DIR, realtime.REALTIME_DIR):
        done = tmp_path / folder / "lab_object_C_lds01_seed0"
        done.mkdir(parents=True)
        (done / "result.json").write_text(json.dumps({**_row(jobs[0], True, where="kept"), "verdict": None}))
    rows = {j.key: _row(j, False) for j in jobs}
    assert realtime.confirm_at_real_time(jobs, _settings(tmp_path), rows, 2) == 0
    assert ran == [(2, 5.0), (2, 1.0)]
    assert [r["run_dir"] for r in rows[jobs[0].key]["rerun"]["runs"]] == ["/kept/0", "/kept/0"]


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
    assert realtime.wall_clock_finding(wall).startswith(f"{wall}: the node keeps time by the wall clock")


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
        f"bt-nav grade: lab_object C lds01 seed 2 again at 5x and at 1x real time before the failures stand, then "
        f"the 1 other failed run that may depend on speed unless it fails at both (--realtime-check off skips it): "
        f"into {tmp_path / 'rerun'}/ and {tmp_path / 'realtime'}/",
        "bt-nav grade: not re-run at 1x, no speed changes their verdict: lab_object C lds01 seed 0 (the node crashed "
        "while starting (ModuleNotFoundError))"]
    assert realtime.confirm_at_real_time(jobs, settings, rows, 2) == 0  # passed again, but nothing excuses them
    assert ran == [(2, 5.0), (2, 1.0), (4, 5.0), (4, 1.0)]
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


def _failed(seed: int, verdict: dict[str, Any], reason: str = "failed: maneuver 1 turned 60 deg right") -> dict:
    return {**_row(_job(seed), False), "reason": reason, "verdict": verdict}


def _passed(seed: int, verdict: dict[str, Any], where: str) -> dict:
    return {**_row(_job(seed), True, where=where), "verdict": verdict}


def test_a_random_node_whose_runs_differed_keeps_its_failure() -> None:
    """Issue 41: a node that draws its angle failed at 5x (60 deg right, outside 90-180) and passed both re-runs
    with other draws, nothing slipped: the failure stands, the words say the runs differed, never the load."""
    fast = _failed(0, _turning(("right", 60.0), passed=False))
    again, slow = _passed(0, _turning(("left", 135.0)), "again"), _passed(0, _turning(("right", 101.0)), "slow")
    row, said = realtime.decide(fast, again, slow, 5.0, None)
    assert not row["passed"] and row["run_dir"] == "/fast/0" and row["rerun"]["decision"] == "stands"
    assert said == ("failed at 5x (failed: maneuver 1 turned 60 deg right); run again at 5x: passed; at 1x: passed: "
                    "the runs differed (maneuver 1 turned 60 deg right in the failed run, 135 deg left when run again "
                    "(turns: 60 deg right; again: 135 deg left)): a re-run that passes does not overturn a failure of "
                    "a node whose decisions change from run to run; the failure stands")
    assert "load" not in said


def test_a_slip_in_the_failed_run_puts_its_failure_down_to_the_load() -> None:
    """A right pivot that overshot (114 deg) while the simulator had stopped waiting for it mid-turn, and passed when
    run again: graded by the re-run, the words name the slip and the load."""
    fast = _failed(0, _turning(("left", 114.0), passed=False), "failed: maneuver 1 turned 114 deg left")
    slip = realtime.slipped_timing(fast["verdict"], [3.0, 11.2, 66.0])
    assert slip == ("the simulator stopped waiting for the node's commands at t=11.2 s, inside maneuver 1, which "
                    "failed (t=10.0-12.6 s): the node sent nothing for a wall second")
    again, slow = _passed(0, _turning(("left", 91.0)), "again"), _passed(0, _turning(("left", 90.0)), "slow")
    row, said = realtime.decide(fast, again, slow, 5.0, slip)
    assert row["passed"] and row["run_dir"] == "/again/0" and row["rerun"]["decision"] == "load"
    assert said.endswith("the node sent nothing for a wall second, so the failure is put down to the machine's load, "
                         "not to the node; graded by the re-run that passed")
    assert row["realtime"]["reason"] == "failed: maneuver 1 turned 114 deg left" and row["findings"] == [said]
    row, said = realtime.decide(fast, _failed(0, _turning(("left", 112.0), passed=False)), None, 5.0, slip)
    assert not row["passed"] and said.endswith("at 1x: not run (stopped): it failed again; the failure stands")


def test_no_slip_outside_a_failed_turn_or_while_disarmed() -> None:
    """A drop before the arming, after the disarm (the node has nothing to say) or after the failed maneuver is no
    slip; one while armed before it counts (the turn it split), and any while armed when no maneuver failed."""
    verdict = _turning(("left", 90.0), ("left", 2.0), passed=True)
    verdict["maneuvers"][1]["passed"] = False
    assert realtime.slipped_timing(verdict, [3.0, 23.0, 66.0]) is None
    assert realtime.slipped_timing(verdict, [11.2]) == (
        "the simulator stopped waiting for the node's commands at t=11.2 s, before maneuver 2, which failed "
        "(t=20.0-22.6 s): the node sent nothing for a wall second")
    assert realtime.slipped_timing(verdict, []) is None
    calm = _turning(("left", 90.0))
    assert realtime.slipped_timing(calm, [3.0, 66.0]) is None
    assert realtime.slipped_timing(calm, [40.0]) == ("the simulator stopped waiting for the node's commands at "
                                                     "t=40.0 s while it was armed: the node sent nothing for a wall "
                                                     "second")
    shifted = {**calm, "t0_sim": 0.24}
    assert "t=65.0 s while it was armed" in realtime.slipped_timing(shifted, [65.2])  # 64.96 s from t0: armed
    assert realtime.slipped_timing(shifted, [65.45]) is None  # the real run above: silent after its disarm


def test_a_wall_clock_node_is_graded_at_1x_on_its_evidence() -> None:
    fast = _failed(0, _turning(("left", 450.0), passed=False, durations=13.1), "failed: maneuver 1 turned 450 deg")
    slow = _passed(0, _turning(("left", 92.0), durations=2.6), "slow")
    again = _failed(0, _turning(("left", 452.0), passed=False, durations=13.0), "failed: maneuver 1 turned 452 deg")
    row, said = realtime.decide(fast, again, slow, 5.0, None)
    assert row["passed"] and row["run_dir"] == "/slow/0" and row["rerun"]["decision"] == "wall clock"
    assert said == ("failed at 5x (failed: maneuver 1 turned 450 deg); run again at 5x: failed (failed: maneuver 1 "
                    "turned 452 deg); at 1x: passed: its turns lasted 13.1 sim s at 5x and 2.6 sim s at 1x: the same "
                    "wall time: the node keeps time by the wall clock (time.sleep, time.time) where ROS time "
                    "(self.get_clock(), sim time under use_sim_time) would keep it right in a simulation at any "
                    "speed; graded at 1x")
    assert row["findings"] == [said] and row["reason"] == f"passed; {said}"


def test_a_rerun_without_a_verdict_is_said_and_not_counted() -> None:
    fast = _failed(0, _turning(("left", 60.0), passed=False))
    lost = {**_row(_job(0), False, "bt_nav error"), "reason": "bt_nav error (not the node's): boom"}
    row, said = realtime.decide(fast, lost, None, 5.0, None)
    assert not row["passed"] and row["rerun"]["runs"] == []
    assert "run again at 5x: no verdict (bt_nav error (not the node's): boom); at 1x: not run (stopped)" in said


def _pace_file(run_dir: Path, *stops: tuple[str, float, float | None]) -> Path:
    """A run directory's ``pace.json`` as the simulator writes it at exit (``pace_path``): (who, t, resumed) each."""
    run_dir.mkdir(parents=True, exist_ok=True)
    record = {"follower_timeout": 1.0, "hold_timeout": 5.0, "t_end": 70.0,
              "stops": [{"who": who, "t": t, "why": "silent", "resumed": resumed} for who, t, resumed in stops]}
    (run_dir / "pace.json").write_text(json.dumps(record) + "\n", encoding="utf-8")
    return run_dir


def test_pace_drops_are_read_from_the_simulators_pace_file(tmp_path: Path) -> None:
    """The stops as the simulator recorded them in a real run (lab_object A, seed 0, 5x: silent after the disarm,
    following again at 69.37), and a sim_sync follower's that is not the node's: only the node's ``cmd_vel`` counts.
    No file (a simulator killed before its exit, a run from before pace.json): no drop, no slip."""
    run = _pace_file(tmp_path / "run", ("cmd_vel", 65.45, 69.37), ("referee", 30.0, None))
    assert realtime.run_drops(run) == [65.45]
    assert realtime.run_drops(tmp_path / "none") == []
    verdict = {"t0_sim": 0.0, "times": {"activated": 5.0, "deactivation_requested": 66.0}, "maneuvers": []}
    assert realtime.run_slipped({"run_dir": str(run), "verdict": verdict}) == (
        "the simulator stopped waiting for the node's commands at t=65.5 s while it was armed: the node sent nothing "
        "for a wall second")
    assert realtime.run_slipped({"run_dir": str(tmp_path / "none"), "verdict": verdict}) is None
    assert realtime.run_slipped({"run_dir": None, "verdict": verdict}) is None


def test_the_slip_of_a_real_stalled_run_is_found_before_the_maneuver_it_split(tmp_path: Path) -> None:
    """Recorded from a real run (2026-11-27, ``varying_node.py --odd stall --stall 1.5 --choice C``, lab_object, 5x):
    the node was not scheduled for 1.5 s wall right after its first turn command; the judge saw its one turn as
    maneuver 1 (89 deg, passed) and maneuver 2 (2 deg, failed). The simulator's drops (sim s, not from t0): 19.45
    (the stall, inside maneuver 1), 23.45 (after maneuver 2), 65.65 (after the disarm)."""
    verdict = {"t0_sim": 0.26, "times": {"activated": 5.0, "deactivation_requested": 65.0},
               "maneuvers": [{"t": 18.97, "settled": 21.6, "side": "right", "angle_deg": -89.04, "passed": True},
                             {"t": 21.6, "settled": 21.74, "side": "right", "angle_deg": -2.02, "passed": False},
                             {"t": 62.99, "settled": 65.24, "side": "left", "angle_deg": 75.56, "passed": True}]}
    stalled = _pace_file(tmp_path / "stalled", ("cmd_vel", 19.45, 19.7), ("cmd_vel", 23.45, 23.6),
                         ("cmd_vel", 65.65, None))
    assert realtime.run_slipped({"run_dir": str(stalled), "verdict": verdict}) == (
        "the simulator stopped waiting for the node's commands at t=19.2 s, before maneuver 2, which failed "
        "(t=21.6-21.7 s): the node sent nothing for a wall second")
    later = _pace_file(tmp_path / "later", ("cmd_vel", 23.45, 23.6), ("cmd_vel", 65.65, None))
    assert realtime.run_slipped({"run_dir": str(later), "verdict": verdict}) is None  # the other two are no slip


def test_decisions_are_compared_at_the_grades_speed() -> None:
    """A node whose turn is five times too long at 5x and that fails at 1x too (its angle wrong at any speed): the
    1x run's turns differ for the clock, not for a decision; the same-speed re-run made the same turns, so the words
    are that it failed again, not that the runs differed."""
    fast = _failed(0, _turning(("left", 450.0), passed=False), "failed: maneuver 1 turned 450 deg left")
    again = _failed(0, _turning(("left", 455.0), passed=False), "failed: maneuver 1 turned 455 deg left")
    slow = _failed(0, _turning(("left", 45.0), passed=False), "failed: maneuver 1 turned 45 deg left")
    row, said = realtime.decide(fast, again, slow, 5.0, None)
    assert not row["passed"] and said.endswith(": it failed again; the failure stands"), said
    row, said = realtime.decide(fast, None, slow, 5.0, None)  # no run at 5x: the 1x run is all there is to compare
    assert "the runs differed (maneuver 1 turned 450 deg left in the failed run, 45 deg left" in said, said


def test_the_same_turn_stretched_in_sim_time_is_put_down_to_the_load() -> None:
    """Measured beside a test suite: a right Retreat timed on the ROS clock turned 195 deg in 3.45 sim s, and 180 deg
    in 3.2 s at the same speed again and at 1x. Same decisions, the failed turn longer and larger for it: its timing
    slipped behind sim time (the load). A node that draws its angle looks alike run by run, so its two re-runs must
    agree: a Randomizer drawing 197 and then 185 and 120 deg keeps its failure."""
    fast = _failed(0, _turning(("left", 195.0), passed=False, durations=3.45), "failed: maneuver 1 turned 195 deg")
    again = _passed(0, _turning(("left", 180.0), durations=3.2), "again")
    slow = _passed(0, _turning(("left", 181.0), durations=3.19), "slow")
    row, said = realtime.decide(fast, again, slow, 5.0, None)
    assert row["passed"] and row["run_dir"] == "/again/0" and row["rerun"]["decision"] == "load", said
    assert ("maneuver 1 lasted 3.45 sim s and turned 195 deg, the same turn 3.20 s and 180 deg when run again at the "
            "same speed: the node's timing slipped behind sim time, so the failure is put down to the machine's load"
            ) in said
    drawn = _passed(0, _turning(("left", 120.0), durations=2.1), "slow")
    row, said = realtime.decide(fast, _passed(0, _turning(("left", 185.0), durations=3.25), "again"), drawn, 5.0, None)
    assert not row["passed"] and row["rerun"]["decision"] == "stands" and "load" not in said
    same_length = _passed(0, _turning(("left", 180.0), durations=3.44), "again")
    row, _ = realtime.decide(fast, same_length, slow, 5.0, None)
    assert not row["passed"]  # not longer: nothing slipped


# ---------------------------------------------------------------------------------------------- --rtf 0
def _at(row: dict[str, Any], node_rtf: float) -> dict[str, Any]:
    """``row`` of a run at ``--rtf 0`` whose node kept up with ``node_rtf`` (bt_nav.grading.exe.pace.with_speed)."""
    return {**row, "rtf": node_rtf, "speed": {"set": 0.0, "rtf": node_rtf, "node_rtf": node_rtf}}


def test_a_failure_as_fast_as_the_node_keeps_up_is_checked_at_its_speed_and_at_1x(tmp_path: Path, ran: list) -> None:
    """At --rtf 0 the check is on (it used to be off at rtf <= 1, which 0 is): the probe runs again at the grade's
    speed (0) and at 1x; the words say what the runs achieved, never "0x"."""
    jobs = [_job(s) for s in (1, 3)]  # odd seeds: their re-runs fail too (SHOWN)
    rows = {j.key: _at(_row(j, False), 9.3) for j in jobs}
    settings = _settings(tmp_path, rtf=0.0)
    assert realtime.failed_jobs(jobs, settings, rows) == jobs
    plan = realtime.check_plan(jobs, settings, rows)
    assert plan[0].startswith("bt-nav grade: lab_object C lds01 seed 1 again as fast as the node keeps up and at 1x "
                              "real time before the failures stand"), plan
    said: list[str] = []
    assert realtime.confirm_at_real_time(jobs, settings, rows, 2, say=said.append) == 0
    assert ran == [(1, 0.0), (1, 1.0)]  # failed at both: the other failure stands unchecked, as at 5x
    assert said[0].startswith("bt-nav grade: lab_object C lds01 seed 1: failed at 9.3x (failed: angle); run again "
                              "as fast as the node kept up: failed"), said  # its re-run here has no speed record
    assert not any("0x" in line.replace("10x", "") for line in said), said


def test_a_wall_clock_node_at_rtf_0_is_judged_by_the_factor_its_run_achieved() -> None:
    """Threshold and words from the failed run's achieved factor: 24.2 sim s at 9.3x is 2.6 s of wall time."""
    fast = _at(_failed(0, _turning(("left", 837.0), passed=False, durations=24.2),
                       "failed: maneuver 1 turned 837 deg"), 9.3)
    slow = _passed(0, _turning(("left", 91.0), durations=2.6), "slow")
    again = _at(_failed(0, _turning(("left", 850.0), passed=False, durations=24.5),
                        "failed: maneuver 1 turned 850 deg"), 9.5)
    row, said = realtime.decide(fast, again, slow, 0.0, None)
    assert row["passed"] and row["rerun"]["decision"] == "wall clock" and row["run_dir"] == "/slow/0"
    assert said.startswith("failed at 9.3x (failed: maneuver 1 turned 837 deg); run again at 9.5x: failed (failed: "
                           "maneuver 1 turned 850 deg); at 1x: passed: its turns lasted 24.2 sim s at 9.3x and 2.6 "
                           "sim s at 1x: the same wall time"), said
    assert row["realtime"]["rtf"] == 9.3 and [r["rtf"] for r in row["rerun"]["runs"]] == [9.5, 1.0]
    # the same turns at a run that only reached 1.2x say nothing of a wall clock (1.2 < its threshold)
    slow_node = _at(_failed(0, _turning(("left", 100.0), passed=False, durations=2.9)), 1.2)
    assert realtime.wall_clock_evidence(slow["verdict"], slow_node["verdict"], 1.2) is None
