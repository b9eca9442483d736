"""Maneuvers read as the node made them, at any speed: the check-off judge's last word on where one maneuver ends and
the next begins (pure, no rclpy; :mod:`bt_nav.judge.checkoff_core` finds the turns, :mod:`bt_nav.judge.chains` splits a
continuous rotation at the node's marks).

Why: how a node's commands fall on the sim clock depends on the machine's speed, and the node's own turn did not
change with it. Measured (issue 52): a closed-loop pivot that slows near 90 deg was cut into ``turned 0 deg right``
and an 89 deg maneuver 0.03 s later; a creep of one scan period between two announced maneuvers was joined into
the turn as another publisher's (``drove forward during the turn``). So:

- a piece smaller than half the maneuver's smallest angle is never judged alone: it joins the neighbour it is
  closest to in time (within :data:`JOIN_GAP` s, with no forward command between them), unless the disarm cut it
  short or a recording sets it apart (``judge.apart``: the intervals where the robot did not follow its commands,
  :func:`bt_nav.judge.feeds.not_followed`);
- a turn the node announced (a line it logged, timed by its own stamp) is never joined to the one before it.
"""

from __future__ import annotations

import bisect
import math
from typing import Any

from bt_nav.judge.chains import ANNOUNCE_WINDOW, INTERRUPT_SLACK, PAUSE_MIN

#: s: a small piece joins a neighbour at most this far away in time (the shortest silence that is a pause).
JOIN_GAP = PAUSE_MIN

Piece = tuple[int, int, float | None, str]  # (first command, last command, cut, what marked the next), as split_run


def announced_between(judge: Any, b: int, a: int) -> bool:
    """Whether the node logged a line from turning command ``b``'s time until just after command ``a``'s: the turn
    at ``a`` is one it announced, not the one before going on (:meth:`CheckoffJudge.episodes` never joins them)."""
    lo, hi = judge.commands[b][0], judge.commands[a][0] + ANNOUNCE_WINDOW
    return any(lo <= t <= hi for t in judge.announcement_times())


def _span(judge: Any, pieces: list[Piece], k: int) -> tuple[float, float]:
    """When piece ``k`` starts and where its rotation ends (its cut, else its settling before the next piece)."""
    a, b, cut, _ = pieces[k]
    start, last = judge.commands[a][0], judge.commands[b][0]
    if cut is not None:
        return start, cut
    nxt = judge.commands[pieces[k + 1][0]][0] if k + 1 < len(pieces) else math.inf
    return start, min(nxt, judge._settled_at(last, min(nxt, last + judge.config.settle_timeout)))


def _small(judge: Any, pieces: list[Piece], k: int, half: float) -> bool:
    """Piece ``k`` turned less than ``half`` deg, and the disarm did not cut it short."""
    start, end = _span(judge, pieces, k)
    if judge.commands[pieces[k][1]][0] >= judge.next_disarm(start) - INTERRUPT_SLACK:
        return False
    return abs(math.degrees(judge._interp(judge._uyaw, end) - judge._interp(judge._uyaw, start))) < half


def _joinable(judge: Any, pieces: list[Piece], k: int) -> float:
    """The gap (s) between piece ``k`` and the next, if they may join: close enough, no forward command between
    them, and no interval a recording sets apart touching the gap; else ``inf``."""
    b, a = pieces[k][1], pieces[k + 1][0]
    lo, hi = judge.commands[b][0], judge.commands[a][0]
    eps = judge.config.forward_epsilon
    if hi - lo > JOIN_GAP or any(abs(v) > eps for _, v, _ in judge.commands[b + 1:a]):
        return math.inf
    if any(s <= hi and e >= lo for s, e in getattr(judge, "apart", ())):
        return math.inf
    return hi - lo


def join_small(judge: Any, pieces: list[Piece]) -> list[Piece]:
    """``pieces`` with every small piece joined to its nearest joinable neighbour (see the module docstring)."""
    cfg = judge.config
    if not judge._t:
        return pieces
    half = 0.5 * (cfg.spec.angle.low_deg - cfg.angle_tolerance_deg)
    out = list(pieces)
    k = 0
    while k < len(out) and len(out) > 1:
        if not _small(judge, out, k, half):
            k += 1
            continue
        before = _joinable(judge, out, k - 1) if k > 0 else math.inf
        after = _joinable(judge, out, k) if k + 1 < len(out) else math.inf
        if math.isinf(before) and math.isinf(after):
            k += 1
            continue
        if after <= before:  # into the next: its start is this one's
            out[k:k + 2] = [(out[k][0], *out[k + 1][1:])]
        else:  # into the one before: its end and its cut are this one's
            out[k - 1:k + 1] = [(out[k - 1][0], *out[k][1:])]
            k -= 1
    return out


class ClockMap:
    """Where a wall-clock instant fell on the sim clock, from pairs seen as the sim clock ran: a node's log line is
    stamped with the wall clock (rclpy stamps ``/rosout`` so even under ``use_sim_time``), and its announcement is
    placed at its stamp, not at its arrival (a line that a busy machine delivers half a second late would mark the
    next maneuver half a second into it, where the judge's readings may no longer show the trigger).

    ``add(wall, sim)`` as the sim clock advances (a ground-truth pose, a hosted judge's step); :meth:`sim_at` maps a
    wall instant within the pairs kept (the last :data:`KEEP` s of wall time) by linear interpolation."""

    KEEP = 30.0  # wall s of pairs kept: a log line arrives well within it
    STEP = 0.01  # wall s: pairs closer than this to the last one are not kept

    def __init__(self) -> None:
        self.wall: list[float] = []
        self.sim: list[float] = []

    def add(self, wall: float, sim: float) -> None:
        """A pair: the sim clock read ``sim`` at wall time ``wall`` (out-of-order or too close pairs are dropped)."""
        if self.wall and (wall < self.wall[-1] + self.STEP or sim < self.sim[-1]):
            return
        self.wall.append(float(wall))
        self.sim.append(float(sim))
        if self.wall[-1] - self.wall[0] > 2 * self.KEEP:  # drop the old half at once: amortised O(1)
            cut = bisect.bisect_left(self.wall, self.wall[-1] - self.KEEP)
            del self.wall[:cut], self.sim[:cut]

    def sim_at(self, wall: float) -> float | None:
        """The sim time at wall instant ``wall``, or None outside the pairs kept (then the caller times it another
        way)."""
        if not self.wall or not self.wall[0] <= wall <= self.wall[-1]:
            return None
        i = bisect.bisect_left(self.wall, wall)
        if self.wall[i] == wall or i == 0:
            return self.sim[i]
        w0, w1, s0, s1 = self.wall[i - 1], self.wall[i], self.sim[i - 1], self.sim[i]
        return s0 + (s1 - s0) * (wall - w0) / (w1 - w0)
