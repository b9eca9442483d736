"""Lab mode, tick by tick: the real tree (trees/mission.xml) with the lab profile's parameters on a fake clock.

Each test states, per tick, which leaf is the tip and what it commands: creep straight until a maneuver's
trigger holds, the maneuver with no forward command, creep again; the emergency stop when the path is
blocked and no trigger turns the robot away; no deadline.
"""

from __future__ import annotations

import math

import pytest

from bt_nav.mission.profiles import profile_parameters
from bt_nav.testing import TickHarness
from tests.behaviours.leafkit import Events

MANEUVER_LEAF = {"A": "Randomizer", "B": "Retreat", "C": "SmartPivot"}


def lab(maneuver: str, **overrides: object) -> tuple[TickHarness, Events]:
    """The lab profile, armed with a clear view, one tick in."""
    events = Events()
    h = TickHarness(maneuver, {**profile_parameters("lab"), "maneuver": maneuver, **overrides}, events=events)
    h.tick()
    ok, message = h.arm()
    assert ok and "no deadline" in message, message
    h.tick()
    return h, events


def test_lab_mode_creeps_straight_and_has_no_deadline() -> None:
    h, _ = lab("A")
    for _ in range(20 * 120):  # two minutes: far past the homework's 50 s
        r = h.tick()
        assert r.tip == "Creep" and (r.command.linear, r.command.angular) == (0.05, 0.0), r
    assert r.statuses["DeadlineReached?"] == "FAILURE"
    assert not h.core.mission_over and h.core.evaluation_calls == 0


def test_lab_mode_does_not_steer_around_what_is_in_the_far_band() -> None:
    """The homework would turn away from an obstacle 0.6 m ahead; the lab creeps on towards it."""
    h, _ = lab("C")
    h.see((0.0, 0.6))
    r = h.tick()
    assert r.tip == "Creep" and r.command.angular == 0.0


@pytest.mark.parametrize(("maneuver", "obstacles", "degrees"), [
    ("A", [(0.0, 0.45)], (90.0, 180.0)),
    ("B", [(90.0, 0.4), (-90.0, 0.4)], (180.0, 180.0)),
    ("C", [(0.0, 0.25), (90.0, 0.6), (-90.0, 1.5)], (90.0, 90.0)),
])
def test_a_trigger_starts_its_maneuver_with_no_forward_command_then_the_creep_resumes(
        maneuver: str, obstacles: list[tuple[float, float]], degrees: tuple[float, float]) -> None:
    h, events = lab(maneuver)
    h.see(*obstacles)
    first = h.tick()
    assert first.tip == MANEUVER_LEAF[maneuver] and first.command.is_zero  # from rest (planned latency)
    h.see()  # the trigger clears mid-turn: the maneuver keeps its branch
    start_yaw = h.yaw
    during = [h.tick()]
    while during[-1].tip == MANEUVER_LEAF[maneuver]:
        during.append(h.tick())
        assert len(during) < 400
    assert all(r.command.linear == 0.0 for r in during[:-1]), "rotation only"
    assert during[-1].tip == "Creep" and during[-1].command.linear == 0.05
    turned = abs(math.degrees(h.yaw - start_yaw))
    turned = turned if turned <= 181.0 else 360.0 - turned
    assert degrees[0] - 10.0 <= turned <= degrees[1] + 10.0, turned
    announced = [msg for _, msg in events.lines if msg.startswith(MANEUVER_LEAF[maneuver] + ":")]
    assert "turning" in announced[0] and "done: turned" in announced[-1]
    if maneuver == "C":
        assert "turning right" in announced[0]  # right reads 1.5 m, left 0.6 m


def test_a_front_still_blocked_after_the_turn_turns_again() -> None:
    """trigger_repeat: A facing a wall it cannot turn away from in one go fires again at once."""
    h, events = lab("A")
    h.see((0.0, 0.4))
    h.run_until(lambda r: any("Randomizer: done" in msg for _, msg in events.lines))
    r = h.tick()  # the scan never changes: the front stays blocked, the next turn starts at once
    assert r.tip == "Randomizer" and r.command.linear == 0.0
    assert sum("turning" in msg for _, msg in events.lines if msg.startswith("Randomizer")) == 2


def test_an_object_in_the_path_that_triggers_nothing_brakes_stands_and_turns_away() -> None:
    """B (squeezed) meets a box at its shoulder, inside its swept path: the emergency stop, then the way out."""
    h, events = lab("B")
    h.see((12.0, 0.2))  # 0.2 m out, 12 deg left: in the robot's width, free travel ~0.02 m
    r = h.tick()
    assert r.tip == "AEB" and r.command.is_zero
    standing = [h.tick() for _ in range(19)]
    assert all(s.tip == "AEB" and s.command.is_zero for s in standing)
    turning = h.tick()
    assert turning.tip == "AEB" and turning.command.linear == 0.0 and turning.command.angular < 0.0  # away: right
    assert "emergency stop" in events.text() and "turning right until the path is clear" in events.text()
    h.see()
    assert h.tick().tip == "AEB"  # the tick that sees it clear ends the stop with a zero twist
    assert h.tick().tip == "Creep"


def test_disarming_in_lab_mode_stops_and_arming_again_creeps() -> None:
    h, _ = lab("A")
    assert h.tick().tip == "Creep"
    assert h.arm(False)[0]
    assert h.tick().command.is_zero
    assert h.arm(True)[0]
    assert h.tick().tip == "Creep"


def test_squeezed_and_braking_the_retreat_applies_not_the_brakes_way_out() -> None:
    """B fired on the way into a passage (its edge trigger then waits for a clearing); at the passage's
    closed end the brake holds while the robot is still squeezed: the Retreat fires again, no AEB turn."""
    h, events = lab("B")
    h.see((90.0, 0.4), (-90.0, 0.4))
    assert h.tick().tip == "Retreat"
    h.run_until(lambda r: r.tip == "Creep", 400)
    h.see((90.0, 0.4), (-90.0, 0.4), (0.0, 0.2))  # the closed end, 0.2 m ahead
    r = h.tick()
    assert r.tip == "Retreat" and r.command.is_zero
    assert "emergency stop" not in events.text()
    h2, events2 = lab("B")
    h2.see((0.0, 0.2))  # braking but not squeezed: the brake's way out
    assert h2.tick().tip == "AEB" and "emergency stop" in events2.text()
