"""When a judge's t0 may come for a robot on sim time (``robot_clock_wait``): its ``/clock`` subscription must have
existed ``robot_clock_settle`` wall s, counted from the later of the subscription and the first ``/clock`` (a node
started before the simulator subscribed before there was anything to match). The judge's method on a stand-in."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from bt_nav.ros.nodes import judging
from bt_nav.ros.nodes.judging import JudgeNode
from tests.judge.truthkit import truth_judge


class Wall:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _judge(subscribers: list[str], matched: bool | None = None) -> SimpleNamespace:
    """A judge's state for ``_robot_clock_ready``; ``matched``: a hosting simulator's answer (None: not hosted)."""
    return SimpleNamespace(robot_clock_wait=20.0, robot_clock_settle=0.5, wall_start=100.0, _robot_clock_since=None,
                           _clock_wall=None, get_subscriptions_info_by_topic=lambda topic: [
                               SimpleNamespace(node_name=name) for name in subscribers],
                           clock_matched=None if matched is None else (lambda: matched))


def test_the_settling_counts_from_the_later_of_the_subscription_and_the_first_clock(
        monkeypatch: pytest.MonkeyPatch) -> None:
    wall = Wall()
    monkeypatch.setattr(judging.time, "monotonic", wall)
    judge = _judge(["reactive_control", "bt_nav_referee"])
    assert not JudgeNode._robot_clock_ready(judge), "subscribed just now"
    wall.now = 101.0
    assert not JudgeNode._robot_clock_ready(judge), "subscribed a second ago, but no /clock yet: nothing to match"
    judge._clock_wall = 101.0
    wall.now = 101.4
    assert not JudgeNode._robot_clock_ready(judge), "0.4 s since the first /clock"
    wall.now = 101.5
    assert JudgeNode._robot_clock_ready(judge)


def test_a_hosted_judge_starts_once_its_simulator_has_matched_the_subscription(
        monkeypatch: pytest.MonkeyPatch) -> None:
    wall = Wall()
    monkeypatch.setattr(judging.time, "monotonic", wall)
    judge = _judge(["reactive_control"], matched=False)
    judge._clock_wall = 100.0
    assert not JudgeNode._robot_clock_ready(judge), "seen on the graph, not matched yet: settle as a lone judge"
    judge.clock_matched = lambda: True
    assert JudgeNode._robot_clock_ready(judge), "matched by the simulator's own publisher: no settling"
    assert not JudgeNode._robot_clock_ready(_judge(["bt_nav_referee"], matched=True)), "the robot's, not ours"


def test_only_a_foreign_subscription_counts_and_the_wait_ends(monkeypatch: pytest.MonkeyPatch) -> None:
    wall = Wall()
    monkeypatch.setattr(judging.time, "monotonic", wall)
    judge = _judge(["bt_nav_referee", "bt_nav_recorder"])
    judge._clock_wall = 100.0
    wall.now = 110.0
    assert not JudgeNode._robot_clock_ready(judge), "bt_nav's own readers are not the robot's"
    wall.now = 120.0
    assert JudgeNode._robot_clock_ready(judge), "after robot_clock_wait t0 comes anyway (the audit names it)"


@pytest.mark.parametrize(("passed", "missing", "code"), [(True, [], 0), (True, ["no node declares safety_distance"], 1),
                                                         (False, [], 1)])
def test_the_verdict_file_and_the_exit_code_say_the_same(passed: bool, missing: list[str], code: int,
                                                          tmp_path, capsys) -> None:
    """A check the file adds (the check-off's declared parameters) fails the exit code too, and the file carries the
    code (a hosted judge's process is the simulator's: its readers take the code from the file)."""
    import json
    from dataclasses import dataclass

    from bt_nav.run.rosmission import _verdict_code

    @dataclass
    class Config:
        rate_hz: float = 20.0

    results = {"passed": passed, "checks": []}
    judge = SimpleNamespace(
        json_path=str(tmp_path / "v.json"), exit_code=judging.EXIT_PASSED if passed else judging.EXIT_FAILED,
        audit=SimpleNamespace(finding_records=lambda exclude: [], parameter_findings=lambda: missing,
                               parameter_report=lambda: []),
        judge=SimpleNamespace(results=lambda: dict(results), t0=1.0), not_started=None,
        required_parameters=("safety_distance",), findings=[], timed_out=False, foreign=None, config=Config(),
        wall_start=0.0, calls=[], get_logger=lambda: None, started=True, t0_wall=None)
    JudgeNode._write_json(judge, ["overall: PASSED" if passed else "overall: FAILED"])
    written = json.loads((tmp_path / "v.json").read_text())
    assert judge.exit_code == code and written["exit_code"] == code and written["passed"] is (code == 0)
    assert _verdict_code(tmp_path / "v.json") == code
    assert _verdict_code(tmp_path / "absent.json") == 2
    capsys.readouterr()


def test_a_run_never_started_reports_the_robots_own_motion_and_no_check_passes(tmp_path) -> None:
    """A node that never offered the service: the verdict file carries what the robot did from ground truth (not
    the schedule's zeros), and none of the schedule's checks over no data (``no collision: PASSED``)."""
    import json
    from dataclasses import dataclass

    from bt_nav_sim.world import world_from_dict

    from bt_nav.judge.checkoff_core import CheckoffConfig
    from bt_nav.judge.unjudged import FreeMotion

    @dataclass
    class Config:
        rate_hz: float = 2.0

    free = FreeMotion()
    for k in range(101):  # 10 s at 0.3 m/s, a wall hit at 6 s
        free.observe(2.0 + k * 0.1, 0.03 * k, 0.0, 0.0)
    free.on_collision(6.0, 1.2, 0.0)
    checkoff = truth_judge(CheckoffConfig(maneuver="C"), world_from_dict({"name": "t", "segments": []}))
    judge = SimpleNamespace(
        json_path=str(tmp_path / "v.json"), exit_code=judging.EXIT_FAILED, started=False, free=free,
        audit=None, judge=checkoff, required_parameters=(), findings=[], finding_kinds=[], t0_wall=None,
        not_started="the service /toggle_navigation never appeared within 20 s wall", timed_out=False,
        foreign=None, config=Config(), wall_start=0.0, calls=0, get_logger=lambda: None,
        resolve_service_name=lambda name: "/toggle_navigation", activate_name="toggle_navigation")
    judge._unjudged_checks = lambda: JudgeNode._unjudged_checks(judge)
    JudgeNode._write_json(judge, [])
    written = json.loads((tmp_path / "v.json").read_text())
    assert not written["passed"] and not any(c["passed"] for c in written["checks"]), written["checks"]
    assert [c["name"] for c in written["checks"]] == ["/toggle_navigation offered", "still while not armed",
                                                      "no collision"]
    assert written["travelled"] == 3.0 and written["collisions"] == 1
    assert written["unjudged"].startswith("it moved without being armed (travelled 3.00 m")
