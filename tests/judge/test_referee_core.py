"""The homework referee state machine (sim/referee_core.py) on synthetic ground-truth streams.

A scripted robot drives a circle of radius 1 m at a constant speed whenever it is activated; each test
breaks one rule and checks that exactly the matching check fails, so the referee is shown able to fail
every check on its own.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import pytest

from bt_nav.judge.referee_core import CHECKS, Activate, Referee, RefereeConfig
from tests.judge.truthkit import truth_judge

RATE = 30.0  # ground-truth samples per second


@dataclass
class Robot:
    """A scripted robot: drives a circle while activated; each field is one way to misbehave."""

    speed: float = 0.22
    radius: float = 1.0
    move_early_at: float | None = None  # starts driving before anyone activated it
    ignores_deactivate: bool = False
    brake_time: float = 0.0  # keeps rolling this long after a deactivation
    evaluate_at: float | None = 54.5  # when it stops and calls evaluate_mission (None: never)
    moves_after_evaluate: bool = False
    collide_at: tuple[float, ...] = ()
    refuse_first_activations: int = 0

    def __post_init__(self) -> None:
        self.active = False
        self.arc = 0.0  # metres along the circle
        self.stopped_at: float | None = None
        self.activations = 0

    def pose(self) -> tuple[float, float, float]:
        phi = self.arc / self.radius
        return self.radius * math.sin(phi), self.radius * (1.0 - math.cos(phi)), math.remainder(phi, 2 * math.pi)

    def moving(self, t: float) -> bool:
        if self.evaluate_at is not None and t >= self.evaluate_at:
            return self.moves_after_evaluate
        if self.move_early_at is not None and t >= self.move_early_at and self.activations == 0:
            return True
        if self.active:
            return True
        return self.stopped_at is not None and t < self.stopped_at + self.brake_time

    def handle(self, t: float, data: bool) -> bool:
        if data:
            self.activations += 1
            if self.activations <= self.refuse_first_activations:
                return False
            self.active = True
        elif not self.ignores_deactivate:
            self.active = False
            self.stopped_at = t
        return True


def run(robot: Robot, config: RefereeConfig = RefereeConfig(), horizon: float = 70.0) -> Referee:  # noqa: B008
    """Drive the referee like the lock-step runner does: samples at 30 Hz, steps at 2 Hz."""
    ref = Referee(config)
    ref.start(0.0)
    dt = 1.0 / RATE
    steps_per = round(RATE / config.rate_hz)
    called = False
    for i in range(int(horizon * RATE) + 1):
        t = i * dt
        if i > 0 and robot.moving(t - dt):
            robot.arc += robot.speed * dt
        ref.observe(t, *robot.pose())
        if any(abs(t - c) < dt / 2 for c in robot.collide_at):
            x, y, _ = robot.pose()
            ref.on_collision(t, x, y)
        if robot.evaluate_at is not None and not called and t >= robot.evaluate_at:
            called = True
            ok, _ = ref.on_evaluate(t)
            assert ok
        if i % steps_per == 0:
            for action in ref.step(t):
                assert isinstance(action, Activate)
                ref.on_activate_result(t, action.data, robot.handle(t, action.data))
        if ref.done:
            break
    return ref


def failed(ref: Referee) -> set[str]:
    return {c["name"] for c in ref.results()["checks"] if not c["passed"]}


def test_perfect_run_passes() -> None:
    ref = run(Robot())
    assert ref.done and ref.passed
    res = ref.results()
    assert [c["name"] for c in res["checks"]] == list(CHECKS)
    assert res["travelled"] == pytest.approx(0.22 * (15.0 + 24.5), abs=0.05)
    assert res["max_distance_from_start"] == pytest.approx(2.0, abs=0.01)
    assert res["times"]["activation_requested"] == pytest.approx(5.0)
    assert res["times"]["deactivation_requested"] == pytest.approx(20.0)
    assert res["times"]["reactivated"] == pytest.approx(30.0)
    assert res["times"]["report"] == pytest.approx(57.5, abs=0.5)
    lines = ref.report_lines()
    assert len(lines) == len(CHECKS) + 1 and lines[-1] == "overall: PASSED"
    assert "minimum distance from start (reached 2.00 m, required 1.5 m): PASSED" in lines
    assert any(line.startswith("minimum travelled distance (travelled 8.") for line in lines)
    assert "no collision (0 collisions): PASSED" in lines


def test_schedule_actions() -> None:
    """activate(true) repeats until a success answer; one activate(false) at 20 s; true again at 30 s."""
    ref = Referee()
    ref.start(100.0)
    log: list[tuple[float, bool]] = []
    for k in range(0, 2 * 60):
        t = 100.0 + k * 0.5
        ref.observe(t, 0.0, 0.0, 0.0)
        for action in ref.step(t):
            log.append((t - 100.0, action.data))
            ref.on_activate_result(t, action.data, success=not (action.data and t - 100.0 < 6.0))
        if ref.done:
            break
    assert log[:3] == [(5.0, True), (5.5, True), (6.0, True)], "retried until success"
    assert (20.0, False) in log and (30.0, True) in log
    assert sum(1 for _, d in log if not d) == 2, "one deactivation at 20 s, one stop at the end"
    assert log[-1] == (56.0, False)
    assert ref.done and not ref.passed
    assert failed(ref) == {"evaluation service called", "minimum distance from start",
                           "minimum travelled distance"}


def test_moving_before_activation_fails() -> None:
    ref = run(Robot(move_early_at=3.0))
    assert failed(ref) == {"static before activation"}
    assert not ref.passed and ref.report_lines()[-1] == "overall: FAILED"


def test_moving_during_deactivation_fails() -> None:
    ref = run(Robot(ignores_deactivate=True))
    assert failed(ref) == {"static after deactivation"}


def test_braking_within_grace_is_fine_but_not_beyond() -> None:
    assert run(Robot(brake_time=2.5)).passed
    assert failed(run(Robot(brake_time=3.5, speed=0.24))) == {"static after deactivation"}


def test_no_evaluation_call_fails_and_ends_at_the_deadline() -> None:
    ref = run(Robot(evaluate_at=None, speed=0.24))
    assert ref.done
    assert ref.results()["times"]["report"] == pytest.approx(56.0)
    # it never stopped either, so the end is not static
    assert failed(ref) == {"evaluation service called", "static at the end"}


def test_moving_after_the_evaluation_call_fails() -> None:
    assert failed(run(Robot(moves_after_evaluate=True, speed=0.24))) == {"static at the end"}


def test_too_short_travel_fails() -> None:
    ref = run(Robot(speed=0.18))
    assert failed(ref) == {"minimum travelled distance"}
    assert "travelled 7.1" in ref.report_lines()[4]


def test_staying_near_the_start_fails() -> None:
    ref = run(Robot(radius=0.5))
    assert failed(ref) == {"minimum distance from start"}


def test_a_collision_fails() -> None:
    ref = run(Robot(collide_at=(12.0,)))
    assert failed(ref) == {"no collision"}
    assert ref.results()["collisions"] == 1
    assert "no collision (1 collision): FAILED" in ref.report_lines()


def test_refused_activation_is_retried() -> None:
    ref = run(Robot(refuse_first_activations=2, speed=0.23))
    assert ref.passed
    assert ref.results()["times"]["activated"] == pytest.approx(6.0)


def test_early_evaluation_ends_the_schedule() -> None:
    """A robot that gives up at 15 s: no deactivation test happens, and the distances are short."""
    ref = run(Robot(evaluate_at=15.0))
    assert ref.done and ref.results()["times"]["report"] == pytest.approx(18.0)
    assert failed(ref) == {"static after deactivation", "minimum travelled distance"}


def test_second_evaluation_call_is_answered_but_ignored() -> None:
    ref = Referee()
    ref.start(0.0)
    assert ref.on_evaluate(10.0)[0]
    assert ref.on_evaluate(11.0)[0]
    assert ref.results()["times"]["evaluation_called"] == 10.0
    assert ref.evaluation_calls == 2


def test_yaw_seam_is_not_a_spin() -> None:
    """A static robot whose yaw reads +-pi alternately is not turning."""
    ref = Referee()
    ref.start(0.0)
    for i in range(20):
        ref.observe(i / 30, 0.0, 0.0, math.pi - 1e-6 if i % 2 else -math.pi + 1e-6)
    _, peak_w, pairs = ref.max_motion(0.0, 1.0)
    assert pairs == 19 and peak_w < 0.01


def test_late_poses_stamped_before_the_report_are_judged_on_catch_up() -> None:
    """Over DDS a busy judge's clock runs ahead of the poses queued for it: the report comes when the last
    second's poses are not in yet, so "static at the end" has none; once they arrive, catch_up judges them."""
    ref = Referee()
    ref.start(0.0)
    held: list[float] = []
    for k in range(int(60 * RATE)):
        t = k / RATE
        if t >= 56.0:
            held.append(t)  # still queued when the clock says 57 s and the report is made
        else:
            ref.observe(t, 0.0, 0.0, 0.0)
        if t == 54.0:
            ref.on_evaluate(t)
        if k % 15 == 0:
            for action in ref.step(t):
                ref.on_activate_result(t, action.data, True)
        if ref.done:
            break
    assert ref.done and "static at the end" in failed(ref)
    for t in held:
        ref.observe(t, 0.0, 0.0, 0.0)
    ref.observe(ref.report_time + 0.5, 5.0, 5.0, 0.0)  # stamped after the report: not judged
    ref.catch_up()
    assert "static at the end" not in failed(ref)
    assert ref.results()["max_distance_from_start"] == 0.0


def test_a_step_on_a_schedule_time_acts_whatever_the_float_error_of_t0() -> None:
    """Over DDS t0 and t are node-clock ns x 1e-9: 19.5 - 14.500000000000002 is a hair under 5 s."""
    t0, t = 14_500_000_000 * 1e-9, 19_500_000_000 * 1e-9
    assert t - t0 < 5.0  # the float error the schedule must not see
    ref = Referee()
    ref.start(t0)
    assert ref.step(t) == [Activate(True)]  # static_before 5 s
    from bt_nav_sim.world import world_from_dict

    from bt_nav.judge.checkoff_core import CheckoffConfig

    judge = truth_judge(CheckoffConfig(maneuver="C"), world_from_dict({"name": "empty", "segments": []}))
    judge.start(t0)
    assert judge.step(t) == [Activate(True)]  # activate_at 5 s


def test_an_activation_refused_for_good_is_named_a_refusal_not_silence() -> None:
    """A node that answers every activate(true) with success false never drives: the distance checks say it was
    refused (and how often), not merely that the robot did not travel."""
    ref = run(Robot(refuse_first_activations=10_000, evaluate_at=None))
    detail = {c["name"]: c["detail"] for c in ref.results()["checks"]}
    assert "minimum travelled distance" in failed(ref)
    assert re.search(r"travelled \d\.\d\d m, required 8\.0 m \(activate\(true\) refused \d+ times: the node answered "
                     r"success false\)", detail["minimum travelled distance"]), detail


def test_an_unanswered_activation_is_named_silence_not_a_refusal() -> None:
    ref = Referee(RefereeConfig())
    ref.start(0.0)
    for k in range(0, 30):
        for action in ref.step(k * 0.5):
            ref.on_activate_result(k * 0.5, action.data, False, answer="unanswered")
        ref.observe(k * 0.5, 0.0, 0.0, 0.0)
    assert ref.answers.failed_text("activate", True).startswith("activate(true) never answered (")
    assert "calls unanswered" in ref.answers.failed_text("activate", True)
