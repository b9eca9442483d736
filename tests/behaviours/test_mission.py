"""The mission leaves alone: ArmService, IsArmed, MissionDeadline and EvaluateMission on a fake clock."""

from __future__ import annotations

import pytest
from leafkit import Board, Events, Status, make, tick

from bt_nav.mission.behaviours.mission import ArmService, EvaluateMission, IsArmed, MissionDeadline
from bt_nav.mission.local_services import LocalTriggerClient
from bt_nav.testing import FakeClock


# ----------------------------------------------------------------------------------- ArmService
def test_arm_service_is_always_success_and_reports_the_state() -> None:
    Board()
    leaf = make(ArmService, clock=FakeClock(2.0))
    assert tick(leaf) == Status.SUCCESS and leaf.feedback_message == "disarmed"
    assert leaf.handle(True)[0]
    assert tick(leaf) == Status.SUCCESS and leaf.feedback_message == "armed"
    assert leaf.service is None, "off-ROS (no node) there is no server: requests come through handle()"


def test_arming_starts_the_timer_once_and_counts_armings() -> None:
    board = Board()
    clock = FakeClock(2.0)
    leaf = make(ArmService, clock=clock)
    ok, message = leaf.handle(True)
    assert ok and "mission timer started at t=2.00" in message
    assert (board.get("armed"), board.get("first_armed_at"), board.get("arm_count")) == (True, 2.0, 1)
    assert leaf.handle(True) == (True, "already armed")
    assert board.get("arm_count") == 1
    clock.advance(3.0)
    assert leaf.handle(False) == (True, "disarmed: robot stopped") and board.get("armed") is False
    assert leaf.handle(False) == (True, "already disarmed: robot stays stopped")
    ok, message = leaf.handle(True)
    assert ok and message.startswith("armed again at mission t=3.00 s")
    assert (board.get("first_armed_at"), board.get("arm_count")) == (2.0, 2), "the timer is not restarted"


def test_arming_is_refused_before_the_clock_starts_and_after_the_mission() -> None:
    board = Board()
    clock = FakeClock(0.0)
    events = Events()
    leaf = make(ArmService, clock=clock, events=events)
    ok, message = leaf.handle(True)
    assert not ok and "clock has not started" in message and board.get("armed") is not True
    clock.advance(1.0)
    assert leaf.handle(True)[0]
    leaf.handle(False)
    board.set(mission_over=True)
    ok, message = leaf.handle(True)
    assert not ok and "mission ended" in message and board.get("armed") is False
    assert events.count("warning", "refused") == 2


def test_is_armed_answers_the_armed_flag() -> None:
    board = Board()
    leaf = make(IsArmed)
    assert tick(leaf) == Status.FAILURE  # nothing written: not armed
    board.set(armed=True)
    assert tick(leaf) == Status.SUCCESS


# ----------------------------------------------------------------------------------- MissionDeadline
def deadline(board: Board, clock: FakeClock, events: Events | None = None) -> MissionDeadline:
    board.set(mission_duration=10.0, stop_margin=0.5)
    return make(MissionDeadline, clock=clock, events=events)


def test_deadline_waits_for_the_first_arming_then_counts_down() -> None:
    board, clock = Board(), FakeClock(5.0)
    leaf = deadline(board, clock)
    assert tick(leaf) == Status.FAILURE and leaf.feedback_message == "not armed yet"
    board.set(first_armed_at=5.0)
    clock.advance(9.0)
    assert tick(leaf) == Status.FAILURE and leaf.feedback_message == "0.5 s left"
    assert board.get("mission_over") is not True


def test_deadline_latches_at_duration_minus_margin_even_if_the_clock_jumps_back() -> None:
    board, clock, events = Board(), FakeClock(5.0), Events()
    leaf = deadline(board, clock, events)
    board.set(first_armed_at=5.0)
    clock.advance(9.5)  # 5 + 10 - 0.5
    assert tick(leaf) == Status.SUCCESS and board.get("mission_over") is True
    clock.advance(-100.0)  # a simulator reset
    assert tick(leaf) == Status.SUCCESS, "once latched, always latched"
    assert events.count("info", "deadline reached") == 1


def test_a_live_duration_change_moves_the_deadline() -> None:
    board, clock = Board(), FakeClock(5.0)
    leaf = deadline(board, clock)
    board.set(first_armed_at=5.0)
    clock.advance(6.0)
    assert tick(leaf) == Status.FAILURE
    board.set(mission_duration=6.0)
    assert tick(leaf) == Status.SUCCESS


# ----------------------------------------------------------------------------------- EvaluateMission
def evaluate(client: LocalTriggerClient | None, clock: FakeClock, events: Events | None = None, *,
             retries: int = 2) -> EvaluateMission:
    """The leaf past its first tick, which only holds the request (see the test below)."""
    Board().set(timeout=1.0, retries=retries, retry_delay=0.5)
    leaf = make(EvaluateMission, clock=clock, events=events)
    leaf.setup(clock=clock, events=events or leaf.events, evaluation_client=client)
    if client is not None:
        assert tick(leaf) == Status.RUNNING and client.calls == [] and leaf.attempts == 0
    return leaf


def test_the_request_waits_for_the_tick_after_the_stop() -> None:
    """"Stop its motion and send the request": on the tick the deadline latches, the Stop before this leaf
    commands the zero twist the node publishes at the tick's end, so the request goes out on the next tick."""
    clock = FakeClock(1.0)
    client = LocalTriggerClient(clock=clock)
    Board().set(timeout=1.0, retries=2, retry_delay=0.5)
    leaf = make(EvaluateMission, clock=clock)
    leaf.setup(clock=clock, events=leaf.events, evaluation_client=client)
    assert tick(leaf) == Status.RUNNING and client.calls == [], "no request on the stop's own tick"
    assert "stopping first" in leaf.feedback_message
    clock.advance(0.05)
    assert tick(leaf) == Status.SUCCESS and client.calls == [1.05]


def test_evaluation_accepted_on_the_first_call_stays_success_without_calling_again() -> None:
    clock = FakeClock(1.0)
    client = LocalTriggerClient(clock=clock)
    leaf = evaluate(client, clock)
    assert tick(leaf) == Status.SUCCESS
    assert leaf.feedback_message == "evaluated: evaluation accepted"
    for _ in range(5):
        clock.advance(1.0)
        assert tick(leaf) == Status.SUCCESS
    assert len(client.calls) == 1 and leaf.successful_calls == 1


def test_a_refused_call_is_retried_after_the_delay() -> None:
    clock = FakeClock(1.0)
    client = LocalTriggerClient(["refuse"], clock=clock)
    leaf = evaluate(client, clock)
    assert tick(leaf) == Status.RUNNING and "attempt 1 failed" in leaf.feedback_message
    clock.advance(0.25)
    assert tick(leaf) == Status.RUNNING and len(client.calls) == 1, "still inside the retry delay"
    clock.advance(0.3)
    assert tick(leaf) == Status.SUCCESS and len(client.calls) == 2


def test_a_hanging_call_times_out_is_withdrawn_and_the_leaf_gives_up_after_its_retries() -> None:
    clock, events = FakeClock(1.0), Events()
    client = LocalTriggerClient(default="hang", clock=clock)
    leaf = evaluate(client, clock, events, retries=1)
    statuses = []
    for _ in range(60):
        statuses.append(tick(leaf))
        clock.advance(0.1)
    assert statuses[0] == Status.RUNNING and statuses[-1] == Status.FAILURE
    assert len(client.calls) == 2 and len(client.removed) == 2, "each timed-out request is withdrawn"
    assert events.count("error", "no retries left") == 1


def test_without_a_client_the_leaf_fails_at_once() -> None:
    leaf = evaluate(None, FakeClock(1.0))
    assert tick(leaf) == Status.FAILURE and "no evaluation client" in leaf.feedback_message


def test_a_missing_server_counts_as_a_failed_attempt_after_the_timeout() -> None:
    clock = FakeClock(1.0)
    client = LocalTriggerClient(clock=clock, absent_until=3.0)
    leaf = evaluate(client, clock)
    assert tick(leaf) == Status.RUNNING and "waiting for the evaluation service" in leaf.feedback_message
    clock.advance(1.0)
    assert tick(leaf) == Status.RUNNING and "not available" in leaf.feedback_message
    clock.advance(0.5)
    assert tick(leaf) == Status.RUNNING and leaf.attempts == 2 and client.calls == []
    clock.advance(0.5)  # the server is up now: the second attempt's request goes out and is answered
    assert tick(leaf) == Status.SUCCESS and client.calls == [3.0]


def test_terminate_keeps_the_request_in_flight_and_cancel_withdraws_it() -> None:
    clock = FakeClock(1.0)
    client = LocalTriggerClient(["hang"], clock=clock)
    leaf = evaluate(client, clock)
    assert tick(leaf) == Status.RUNNING and len(client.calls) == 1
    leaf.stop(Status.INVALID)  # a tree reset (an exception elsewhere) preempts the leaf
    assert client.removed == [] and leaf.future is not None
    clock.advance(0.1)
    assert tick(leaf) == Status.RUNNING and len(client.calls) == 1, "no second request after the reset"
    leaf.cancel()
    assert len(client.removed) == 1 and leaf.future is None
    leaf.cancel()
    assert len(client.removed) == 1, "cancel is idempotent"


@pytest.mark.parametrize("answer", ["raise", "refuse"])
def test_every_failed_attempt_is_logged_as_a_warning(answer: str) -> None:
    clock, events = FakeClock(1.0), Events()
    leaf = evaluate(LocalTriggerClient([answer], clock=clock), clock, events)
    tick(leaf)
    assert events.count("warning", "evaluation attempt 1 failed") == 1
