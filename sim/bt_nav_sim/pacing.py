"""Pacing bookkeeping of the simulator node: which followers sim time must wait for (pure: no ROS, no threads).

The simulator node (:mod:`bt_nav.ros.nodes.simulator`, whose docstring explains following and pacing) keeps
one :class:`Followers` under its lock; keeping the bookkeeping here lets it be tested without rclpy.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field


@dataclass
class Follower:
    """One process the simulator's loop waits for (see :class:`Followers`)."""

    t_ns: int  # its time at its latest message, sim ns
    hold: bool  # it asked to hold sim time
    seen: float  # monotonic wall time of its latest message
    active: bool = True
    intervals: deque[int] = field(default_factory=lambda: deque(maxlen=20))  # between its messages, sim ns


class Followers:
    """Bookkeeping of the followers (no threads, no ROS; the node guards it with its lock).

    How far sim time may lead a follower: ``max_lag``, or the follower's own period when that is longer
    (the shortest gap between its last 20 messages). A follower that speaks once per period P (the
    executive's tick, the referee's heartbeat) must be allowed to reach its next message time, which
    is up to P after its last one; any lead beyond P lets a slow follower skip its own timer ticks
    (rcl fires a late timer once), so P itself is the right bound, and learning it per follower keeps
    a 10 Hz executive from stalling on a 0.05 s default.

    Args:
        max_lag_ns: the smallest lead allowed, sim ns.
        silence_s: wall seconds without a message after which a follower is dropped.
        hold_s: wall seconds after which a hold is ignored (the follower is dropped).
    """

    def __init__(self, max_lag_ns: int, silence_s: float, hold_s: float) -> None:
        self.max_lag_ns = int(max_lag_ns)
        self.silence_s = float(silence_s)
        self.hold_s = float(hold_s)
        self.members: dict[str, Follower] = {}

    def report(self, who: str, t_ns: int, hold: bool, wall: float) -> bool:
        """A message from ``who``; returns True when it (re)joins the active followers."""
        member = self.members.get(who)
        if member is None:
            self.members[who] = Follower(int(t_ns), bool(hold), float(wall))
            return True
        joined = not member.active
        if t_ns > member.t_ns:
            # A gap that spans a silence counts too: the silence was in wall time, while sim time waited for this
            # follower, so a slow follower's first gap is its period (cleared, a node on a 5 Hz timer behind a
            # faster lead was given up for silent before every message and never learnt). A long gap before a
            # follower's arming only widens the lead until its next, shorter one.
            member.intervals.append(int(t_ns) - member.t_ns)
        member.t_ns, member.hold, member.seen, member.active = int(t_ns), bool(hold), float(wall), True
        return joined

    def leave(self, who: str) -> bool:
        """``who`` is done (the referee after its verdict); returns whether it was a follower."""
        return self.members.pop(who, None) is not None

    def active(self, who: str) -> bool:
        """Is ``who`` being followed?"""
        member = self.members.get(who)
        return member is not None and member.active

    def any_active(self, exclude: tuple[str, ...] = ()) -> bool:
        """Is anybody (but ``exclude``) being followed?"""
        return any(m.active for who, m in self.members.items() if who not in exclude)

    def lead_ns(self, who: str) -> int:
        """How far sim time may lead ``who``."""
        m = self.members[who]
        return max(self.max_lag_ns, min(m.intervals, default=0))

    def blocking(self, sim_ns: int, wall: float) -> tuple[str | None, list[str]]:
        """(who keeps sim time from reaching ``sim_ns``, or None; who was just dropped for silence or for a
        hold that lasts too long)."""
        dropped: list[str] = []
        blocker = None
        for who, m in self.members.items():
            if not m.active:
                continue
            if m.hold:
                if wall - m.seen > self.hold_s:
                    m.active = False
                    dropped.append(who)
                elif blocker is None:
                    blocker = who
            elif sim_ns - m.t_ns > self.lead_ns(who):
                if wall - m.seen > self.silence_s:
                    m.active = False
                    dropped.append(who)
                elif blocker is None:
                    blocker = who
        return blocker, dropped
