"""The lab check-off's run as long as its checks need: when the final ``toggle_navigation(false)`` may come before
``activate_at + armed_for`` (pure, no rclpy; the judge is :class:`bt_nav.judge.checkoff_core.CheckoffJudge`).

Why: grading runs at real time (1x), so every sim second is a wall second, and a lab grade of 12 runs must fit in a
minute. The fixed schedule kept a right node armed for 60 s although every check was decided long before: the
activation (static before it), the first maneuver, the toggle cycle (the stop, standing still, the true again) and the
re-armed node going on. Worse, a right node then crept on for half a minute more into corners none of the sheet's
triggers watches (lab_dead_end's side wall grazed at t=47-51 s), failing for what the sheet never asked.

So once the toggle cycle's true was answered, the judge watches the node drive on for ``drive_on_for`` s (its
``creep_start`` to start, then long enough for the creep check, :mod:`bt_nav.judge.checkoff_creep`, to see a standstill
of ``creep_still``), lets a turn under way end (no turning command for ``toggle_off_after`` s: the maneuver it began
is judged whole), and then disarms for good: the grace, the static window and the verdict follow as before. A node
that never triggers gets no toggle cycle and keeps the upper bound, ``activate_at + armed_for``.
"""

from __future__ import annotations

from typing import Any

#: Degrees past the maneuver's largest angle (its spec's plus the tolerance) a run of turning commands must have
#: turned before a disarm may interrupt it (:func:`chain_cut`).
CHAIN_MARGIN_DEG = 10.0


def drove_on(judge: Any, t: float) -> bool:
    """Whether the re-armed node of ``judge`` (a check-off judge) has been shown driving on by ``t``: its toggle
    cycle's true was answered ``drive_on_for`` s ago or more, no turn it began since is still under way (its last
    turning command ``toggle_off_after`` s ago or more; a node turning on without a pause is not waited for past
    ``chain_for`` s after the true), and a maneuver has been performed (:func:`performed`). False when the config
    turns the early end off (``drive_on_for`` 0) or there was no toggle cycle."""
    cfg = judge.config
    since = judge.cycle_on
    if cfg.drive_on_for <= 0 or since is None or t < since + cfg.drive_on_for:
        return False
    turn = turning_run(judge, since)
    if turn is not None and t < turn[1] + cfg.toggle_off_after and not chain_cut(judge, turn, t):
        return False  # a turn under way (one going on chain_for s without a pause is interrupted: chain_cut)
    return performed(judge, t)


def cycle_due(judge: Any, t: float) -> bool:
    """Whether the toggle cycle's false is due at ``t``: the first maneuver ended ``toggle_off_after`` s ago (no
    turning command since), or the node has turned on without such a pause for ``chain_for`` s (a Randomizer in a
    dead end turns back to back until it faces out: waiting for a pause held it armed to the upper bound, 66 s of a
    grade's minute; the false then interrupts a turn, whose angle is not judged)."""
    cfg = judge.config
    if judge._calm_since is not None and t >= judge._calm_since + cfg.toggle_off_after:
        return True
    turn = turning_run(judge, judge.activation_requested) if judge._turned else None
    return turn is not None and chain_cut(judge, turn, t)


def chain_cut(judge: Any, turn: tuple[float, float], t: float) -> bool:
    """Whether a run of turning commands without a pause (``turn``: its first and last command's times) may be
    interrupted at ``t``: ``chain_for`` s after it began, once the robot has turned in it past the maneuver's largest
    angle by :data:`CHAIN_MARGIN_DEG` (yaw either way, summed). Why the angle: a node that never stops turning, cut
    within its rule's largest angle, is judged "interrupted by the disarm (angle not judged)" and passes; at 0.3
    rad/s a Randomizer's 190 deg take 11 s, and cut at 10 s it passed every run. Turns back to back turn past it
    within ``chain_for`` at any usual rate, and the upper bound still holds."""
    if t < turn[0] + judge.config.chain_for:
        return False
    return not judge._within_max(judge._travelled(turn[0], t) - CHAIN_MARGIN_DEG)


def turning_run(judge: Any, since: float | None) -> tuple[float, float] | None:
    """The latest run of turning commands after ``since`` whose turning commands came less than ``toggle_off_after``
    s and a step apart (maneuvers back to back: a pause that short may fall between two steps of the schedule, and
    the cycle never sees it: a level-triggered Retreat creeping 1-1.4 s between its spins in lab_dead_end was armed
    for 41 s before its cycle), as (its first, its last command's time); None: none."""
    cfg = judge.config
    gap = cfg.toggle_off_after + 1.0 / cfg.rate_hz
    first = last = None
    for stamp, _, w in reversed(judge.commands):  # newest first
        if since is None or stamp < since:
            break
        if abs(w) < cfg.rotation_min_rate:
            continue
        if first is not None and first - stamp >= gap:
            break
        first, last = stamp, stamp if last is None else last
    return None if first is None else (first, last)


def performed(judge: Any, t: float) -> bool:
    """Whether ``judge`` has judged ``min_maneuvers`` turns as the maneuver by ``t`` (passed or not: decided). The
    toggle cycle follows the first turn of any kind, and an emergency stop's recovery turn is no maneuver: bt_nav's
    own Retreat in lab_hallway braked, turned 69 deg away, and made its Retreat only after the cycle (seeds 10-14 of
    20); ended there, it failed "maneuvers performed"."""
    episodes = judge._judge_all(t)
    return sum(e["kind"] == "maneuver" for e in episodes) >= judge.config.min_maneuvers


def schedule_words(cfg: Any) -> str:
    """When the final false comes, in words (the judge node's schedule line and the rules page say it)."""
    bound = cfg.activate_at + cfg.armed_for
    if cfg.drive_on_for <= 0 or cfg.toggle_off_for <= 0:
        return f"false at {bound:g} s"
    return (f"false {cfg.drive_on_for:g} s after the toggle cycle's true is answered (once a turn under way has "
            f"ended: no turning command for {cfg.toggle_off_after:g} s), at {bound:g} s at the latest")
