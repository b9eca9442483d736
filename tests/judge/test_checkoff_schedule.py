"""The lab check-off's run as long as its checks need (bt_nav.judge.checkoff_schedule) and its creep check
(bt_nav.judge.checkoff_creep), on the default schedule: bt_nav's own executive in lock-step, and a small reactive node
played by a kinematic driver (commands 20 Hz, ground truth ~33 Hz, the schedule's calls at 2 Hz, obeyed)."""

from __future__ import annotations

import math

import pytest
from bt_nav_sim.world import world_from_dict

from bt_nav.judge.checkoff_core import CheckoffConfig, CheckoffJudge
from bt_nav.run.lockstep import Lockstep
from tests.judge.truthkit import truth_judge

DT = 0.01
ROOM = [[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]]
WALL_AHEAD = [[1.0, -2.0, 1.0, 2.0]]  # a wall across the room 1 m ahead of the spawn


class _Node:
    """A Randomizer as the sheet's flow has it: armed, creep at 0.05 m/s; when the front (the wall 1 m ahead) reads
    below 0.5 m, turn 90 deg left at 1 rad/s, then creep on; a false stops it. Its faults, by option: ``pause`` s
    standing after each arming, ``brake`` s standing at the trigger before the turn (an AEB stop), ``stand_after_rearm``
    (never creeps again after the toggle cycle's true), ``turn_after_rearm`` s after it a 90 deg turn on its own,
    ``spin`` (once triggered it turns on without a pause whenever armed, as maneuvers back to back)."""

    def __init__(self, *, pause: float = 0.0, brake: float = 0.0, stand_after_rearm: bool = False,
                 turn_after_rearm: float | None = None, spin: bool = False, spin_rate: float = 1.0) -> None:
        self.pause, self.brake, self.stand, self.turn_after = pause, brake, stand_after_rearm, turn_after_rearm
        self.spin, self.spinning, self.spin_rate = spin, False, spin_rate
        self.armed, self.armed_at, self.arms = False, 0.0, 0
        self.turn_to: float | None = None
        self.braked_at: float | None = None

    def toggle(self, t: float, data: bool) -> None:
        if data and not self.armed:
            self.armed_at, self.arms = t, self.arms + 1
        self.armed = data
        if not data:
            self.turn_to = self.braked_at = None

    def command(self, t: float, x: float, yaw: float) -> tuple[float, float]:
        if not self.armed or t < self.armed_at + self.pause:
            return 0.0, 0.0
        if self.spinning:
            return 0.0, self.spin_rate
        if self.turn_to is not None:
            if math.remainder(self.turn_to - yaw, 2 * math.pi) > 0.0:  # until it passed the target (left turns)
                return 0.0, 1.0
            self.turn_to = None
        rearmed = self.arms >= 2
        if rearmed and self.turn_after is not None and t >= self.armed_at + self.turn_after:
            self.turn_after, self.turn_to = None, yaw + math.pi / 2
            return 0.0, 1.0
        if rearmed and self.stand:
            return 0.0, 0.0
        front = (1.0 - x) / math.cos(yaw) if math.cos(yaw) > 0.87 else math.inf
        if front < 0.5:
            self.braked_at = t if self.braked_at is None else self.braked_at
            if t < self.braked_at + self.brake:
                return 0.0, 0.0
            self.turn_to, self.braked_at, self.spinning = yaw + math.pi / 2, None, self.spin
            return 0.0, 1.0
        return 0.05, 0.0


def _play(node: _Node, config: CheckoffConfig | None = None, end: float = 90.0, answer_false_after: float = 0.0
          ) -> CheckoffJudge:
    """Play ``node`` in the room with the wall ahead until the judge reports (the default schedule unless given);
    ``answer_false_after``: the node hears (and answers) each false that long after the judge first calls it."""
    world = world_from_dict({"name": "test", "segments": ROOM + WALL_AHEAD})
    judge = truth_judge(config or CheckoffConfig(maneuver="A"), world)
    judge.start(0.0)
    x = y = yaw = 0.0
    cmd = (0.0, 0.0)
    heard: float | None = None  # when the node hears the false under way
    for k in range(round(end / DT) + 1):
        t = k * DT
        if heard is not None and t >= heard - 1e-9:
            judge.on_activate_result(t, False, True)
            node.toggle(t, False)
            heard = None
        if k % 50 == 0:
            for action in judge.step(t):
                if not action.data and answer_false_after > 0:
                    heard = t + answer_false_after if heard is None else heard
                    continue
                judge.on_activate_result(t, action.data, True)
                node.toggle(t, action.data)
        if judge.done:
            break
        if k % 5 == 0:
            cmd = node.command(t, x, yaw)
            judge.on_command(t, *cmd)
        if k % 3 == 0:
            judge.observe(t, x, y, yaw)
        x += cmd[0] * DT * math.cos(yaw)
        y += cmd[0] * DT * math.sin(yaw)
        yaw = math.remainder(yaw + cmd[1] * DT, 2 * math.pi)
    assert judge.done
    return judge


def _check(judge: CheckoffJudge, name: str) -> dict:
    return next(c for c in judge.results()["checks"] if c["name"] == name)


# ------------------------------------------------------------------------------------------- the early end
@pytest.mark.parametrize(("world", "maneuver"), [("lab_object", "A"), ("lab_dead_end", "C"), ("lab_dead_end", "B")])
def test_bt_navs_executive_is_disarmed_once_it_drove_on_after_the_toggle_cycle(world: str, maneuver: str) -> None:
    """Lock-step, bt_nav's own executive: armed at 2 s, the toggle cycle after its first maneuver, the final false
    once it drove on for drive_on_for s (a turn it began then judged whole first), the verdict 4 s later: a run of
    20-40 s instead of the fixed 69 s."""
    run = Lockstep(world, maneuver, 0, None, "lab")
    run.run()
    judge = run.robots[0].referee
    res = judge.results()
    times, cfg = res["times"], judge.config
    assert res["passed"], judge.report_lines()
    assert times["activation_requested"] == pytest.approx(2.0)
    assert times["cycle_on"] is not None and times["cycle_on"] - times["cycle_off_requested"] == pytest.approx(3.0)
    assert cfg.drive_on_for <= times["deactivation_requested"] - times["cycle_on"] <= cfg.drive_on_for + 6.0
    assert times["report"] == pytest.approx(times["deactivation_requested"] + cfg.grace + cfg.static_after)
    assert times["report"] < 40.0 < cfg.activate_at + cfg.armed_for
    assert not any(m["interrupted"] for m in res["maneuvers"]), res["maneuvers"]  # none cut short by the early end
    assert _check(judge, "creep while armed")["passed"]


def test_a_turn_under_way_at_the_drive_on_end_is_waited_for() -> None:
    """The re-armed node turns 4.3 s after its true (in the open: its trigger did not hold): the final false waits
    until its last turning command is toggle_off_after s old, so the turn is judged whole, not interrupted."""
    judge = _play(_Node(turn_after_rearm=4.3))
    res = judge.results()
    times = res["times"]
    last = res["maneuvers"][-1]
    assert len(res["maneuvers"]) == 2 and not last["interrupted"] and abs(last["angle_deg"]) == pytest.approx(90, abs=3)
    assert times["deactivation_requested"] >= last["settled"] + judge.config.toggle_off_after - 0.2
    assert times["deactivation_requested"] > times["cycle_on"] + judge.config.drive_on_for
    assert [c["name"] for c in res["checks"] if not c["passed"]] == ["maneuver 2"]  # judged: nothing triggered it


def test_a_node_that_never_triggers_keeps_the_upper_bound() -> None:
    """No maneuver, no toggle cycle: the final false at activate_at + armed_for (2 + 60 s), the report 4 s later; its
    creep on passes the creep check (and it fails for performing no maneuver)."""
    never = _Node()
    never.command = lambda t, x, yaw: (0.02, 0.0) if never.armed else (0.0, 0.0)  # creeps, never turns
    judge = _play(never)
    times = judge.results()["times"]
    assert times["cycle_off_requested"] is None
    assert times["deactivation_requested"] == pytest.approx(62.0) and times["report"] == pytest.approx(66.0)
    assert _check(judge, "creep while armed")["passed"] and not _check(judge, "maneuvers performed")["passed"]


def test_a_right_node_is_disarmed_soon_after_it_drove_on() -> None:
    judge = _play(_Node())
    times = judge.results()["times"]
    assert judge.passed, judge.report_lines()
    assert times["cycle_on"] == pytest.approx(times["cycle_off_requested"] + 3.0)
    assert times["deactivation_requested"] == pytest.approx(times["cycle_on"] + 4.5, abs=0.5)
    assert times["report"] < 30.0


# ------------------------------------------------------------------------------------------- the creep check
def test_a_node_that_stops_creeping_after_the_rearm_fails_the_creep_check() -> None:
    judge = _play(_Node(stand_after_rearm=True))
    check = _check(judge, "creep while armed")
    assert not check["passed"] and not judge.passed
    assert check["reason"].startswith("stood still for 3.")
    assert ("while armed with nothing triggering (front 1.0" in check["reason"]  # the wall 30 deg off its right
            and "clear beyond safety_distance 0.50 m): the sheet says to maintain a slow forward velocity"
            in check["reason"]), check["reason"]
    assert [c["name"] for c in judge.results()["checks"] if not c["passed"]] == ["creep while armed"]


@pytest.mark.parametrize(("pause", "passes"), [(0.9, True), (4.5, False)])
def test_a_standstill_right_after_arming_counts_only_after_a_second(pause: float, passes: bool) -> None:
    """Standing 0.9 s after the true (its next scan, a slow start) is no fault; 4.5 s is 3.5 s past the second it
    has to start."""
    judge = _play(_Node(pause=pause))
    check = _check(judge, "creep while armed")
    assert check["passed"] is passes, check
    assert judge.passed is passes, judge.report_lines()


def test_a_node_braked_at_its_trigger_is_not_failed_for_standing() -> None:
    """An AEB stop at the wall (front below safety_distance, the trigger holding) for 4 s before the turn: standing
    there is no missing creep."""
    judge = _play(_Node(brake=4.0))
    assert _check(judge, "creep while armed")["passed"]
    assert judge.passed, judge.report_lines()


def test_a_run_whose_first_turn_was_a_recovery_goes_on_until_a_maneuver() -> None:
    """Lock-step, bt_nav's Retreat in lab_hallway, seed 10: it braked, turned 69 deg away (an emergency stop's
    recovery turn, no maneuver), and the toggle cycle followed that turn; its Retreat came only after the true again.
    Disarmed 4.5 s after the true, it failed "maneuvers performed"; the run goes on until a maneuver was made."""
    run = Lockstep("lab_hallway", "B", 10, None, "lab")
    run.run()
    judge = run.robots[0].referee
    res = judge.results()
    assert [e["kind"] for e in res["maneuvers"] + res["recovery_turns"]] == ["maneuver", "recovery"]
    assert res["maneuvers"][0]["t"] > res["times"]["cycle_on"] and not res["maneuvers"][0]["interrupted"]
    assert res["times"]["deactivation_requested"] > res["times"]["cycle_on"] + judge.config.drive_on_for
    assert res["passed"], judge.report_lines()


def test_a_node_turning_on_without_a_pause_gets_its_cycle_and_its_end_after_chain_for() -> None:
    """Turning back to back never leaves the 1 s pause the toggle cycle waits for (a Randomizer in a dead end until it
    faces out): its false comes chain_for (10) s after its first turning command, and the final false chain_for s
    after the true again, instead of holding it armed to the upper bound (62 s)."""
    judge = _play(_Node(spin=True))
    res = judge.results()
    times, cfg = res["times"], judge.config
    first = next(t for t, _, w in judge.commands if abs(w) >= cfg.rotation_min_rate)
    assert first + cfg.chain_for <= times["cycle_off_requested"] <= first + cfg.chain_for + 0.5
    rearm = times["cycle_on"]
    assert rearm + cfg.chain_for <= times["deactivation_requested"] <= rearm + cfg.chain_for + 0.5
    assert times["report"] < 40.0


@pytest.mark.parametrize(("late", "passes"), [(0.0, True), (1.3, True), (1.5, True), (2.8, False)])
def test_a_disarm_takes_effect_when_the_node_answers_it_within_the_allowance(late: float, passes: bool) -> None:
    """A node that hears each false ``late`` s after the call (a busy executor, a request sent again) and stops at
    once is still at rest from its answer plus the 1 s to brake: the sheet asks for a stop, not an answer within a
    time; past ``answer_allowance`` (1.5 s) the judge no longer waits for it, and the creep until then fails."""
    judge = _play(_Node(), answer_false_after=late)
    times = judge.results()["times"]
    assert times["cycle_off"] == pytest.approx(times["cycle_off_requested"] + late, abs=0.02)
    check = _check(judge, "static after deactivation")
    assert check["passed"] is passes, check["detail"]


def test_a_slow_node_that_never_stops_turning_is_cut_only_past_its_largest_angle() -> None:
    """A node that never stops turning once triggered, at 0.3 rad/s: cut at chain_for (10 s, 172 deg) it would be
    "interrupted by the disarm (angle not judged)" within A's 190 deg and pass; its false comes once it turned past
    190 + 10 deg, and it fails for turning past the rule."""
    judge = _play(_Node(spin=True, spin_rate=0.3))
    res = judge.results()
    first = res["maneuvers"][0]
    assert first["interrupted"] and not first["passed"], first
    assert "still turning at the disarm" in first["rule"], first
    cut = res["times"]["cycle_off_requested"]
    assert cut - first["t"] >= math.radians(200.0) / 0.3 - 0.6, (cut, first["t"])
