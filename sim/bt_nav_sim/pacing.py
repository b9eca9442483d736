"""Pacing bookkeeping of the simulator node: which followers sim time must wait for, and when it stopped waiting
for one (pure: no ROS, no threads).

The simulator node (:mod:`bt_nav.ros.nodes.simulator`, whose docstring explains following and pacing) keeps
one :class:`Followers` and one :class:`PaceStops` under its lock; keeping the bookkeeping here lets it be tested
without rclpy. :class:`PaceStops` is also the data a grade reads of a run's pacing (:data:`PACE_FILE`, written by
the node at exit, read by :func:`read_pace_stops`): the node's log line says the same to people, never to programs.
"""

from __future__ import annotations

import json
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

#: The follower name of a robot's ``cmd_vel`` publisher (``<robot name>/cmd_vel`` with several robots).
CMD_VEL = "cmd_vel"
#: The file the simulator writes its :class:`PaceStops` into, in the run directory (its ``pace_path`` parameter).
PACE_FILE = "pace.json"
#: Sim ns within which a follower's messages are one burst (a node that publishes twice in one callback): such a
#: gap says nothing of its period.
BURST_NS = 10_000_000
#: Gaps without a scan between them, among a follower's last ones, that show it speaks on a timer of its own (not
#: only in answer to its sensor): it is no longer led to its sensor's next message (:meth:`Followers.limit_ns`).
TIMER_EVIDENCE = 2
#: Wall seconds a node on a timer of its own may stay silent at its lead before it is led to its sensor's next
#: message after all: between two maneuvers such a node may wait for a scan (it says nothing until the next one).
FLOOR_WAIT = 0.1
#: Wall seconds a follower disarmed by its judge (:meth:`Followers.disarmed`) may stay silent while its latest
#: command stands the robot still: it is not waited for longer (see :meth:`Followers.blocking`).
DISARMED_SILENCE = 0.1
#: :class:`StayBehind`: the speed a run starts at, its floor, its growth (x per wall second), its back-off factor, how
#: often it may back off (wall s) and the steps the speed is used in (each change re-anchors the pace).
STAY_START = 4.0
STAY_FLOOR = 1.0
STAY_GROWTH = 2.0
#: :class:`StayBehind`'s growth (x per wall second) while the robot's command does not turn it (below
#: :data:`STAY_TURNING`): standing or creeping, a node's lag costs the robot millimetres; turning, degrees.
STAY_GROWTH_STRAIGHT = 4.0
#: rad/s: a command that turns the robot at least this fast is a turn for :class:`StayBehind`.
STAY_TURNING = 0.1
STAY_BACKOFF = 0.75
STAY_REFRACTORY = 0.2
STAY_QUANTUM = 0.5


@dataclass
class Follower:
    """One process the simulator's loop waits for (see :class:`Followers`)."""

    t_ns: int  # its time at its latest message, sim ns
    hold: bool  # it asked to hold sim time
    seen: float  # monotonic wall time of its latest message
    active: bool = True
    intervals: deque[int] = field(default_factory=lambda: deque(maxlen=20))  # between its messages, sim ns
    unprompted: deque[bool] = field(default_factory=lambda: deque(maxlen=20))  # per gap: no sensor message in it
    held_since: float | None = None  # monotonic wall time sim time began to wait for it since its latest message
    at_limit: bool = False  # its latest message came while sim time waited for it (it was at its lead)
    still: bool = False  # its latest message asked for no motion (a zero twist)
    disarmed: bool = False  # its judge disarmed it (the arm service answered success to false) and did not rearm it


class Followers:
    """Bookkeeping of the followers (no threads, no ROS; the node guards it with its lock).

    How far sim time may lead a follower: its own period P plus the margin (at least ``max_lag``). A follower that
    speaks once per period (the executive's tick, the referee's heartbeat, a node's timer) must be allowed to reach
    its next message time, up to P after its last one, and a little more. P is the lower median of its last 20 gaps
    (bursts within :data:`BURST_NS` left out), not the shortest: one stray message (a zero twist sent from a service
    callback between two ticks) made the shortest gap a third of a 10 Hz node's period, and sim time then stopped
    short of each of its ticks until it was given up for silent, a wall second per tick. A gap that ended while sim
    time was held for this follower is its lead, not its period (a node slower than the simulator answers at the
    limit): it counts less the margin, so the lead of a node that never keeps up does not grow by the margin
    with each of its messages. A follower whose true period is longer than its lead is given up for silent once;
    its next gap, run freely, teaches it.

    A follower that answers a sensor (a robot's ``cmd_vel``, answering its scans: :attr:`floors`) may in any case
    be led until that sensor's first message after its latest one is out, plus ``max_lag``: it can say nothing
    before it has it, so a scan-driven node is never given up for silent while sim time waits for it, and
    ``max_lag`` can stay small. Once it has spoken :data:`TIMER_EVIDENCE` times of its last 20 gaps with no sensor
    message in between, it speaks on a timer of its own and this floor applies only after it has been silent at its
    lead for :data:`FLOOR_WAIT` wall seconds (between maneuvers, such a node may wait for a scan too): led to the
    next scan at once, a 50 Hz node fell a scan period behind whenever the simulator was faster than it, and its
    ROS-timed turns ran on (222 deg for a 100-170 deg draw, uncapped). A small lead is what keeps a node that times
    its turns on the ROS clock within a few degrees on a busy machine: its turn lasts its clock's duration plus the
    change of its lag behind sim time from the turn's first command to its last, and the lag is bounded by the lead
    (0.25 s of lead cost a 1 rad/s Retreat 13 deg). A node that turns closed loop on odometry overshoots by its lag
    too: while the simulator is faster than the node, the lag is the whole lead (a 2 rad/s Retreat on a 50 Hz loop:
    190-258 deg uncapped), which is why ``bt-nav grade`` keeps the simulator just behind the node (:class:`StayBehind`).

    Args:
        max_lag_ns: the smallest lead allowed, sim ns.
        silence_s: wall seconds without a message after which a follower is dropped.
        margin_ns: sim ns added to a learnt period (``bt-nav grade --exe``: ``max_lag``; 0, the default, keeps
            bt_nav's own executive paced exactly as lock-step predicts).
        hold_s: wall seconds after which a hold is ignored (the follower is dropped).
    """

    def __init__(self, max_lag_ns: int, silence_s: float, hold_s: float, margin_ns: int = 0) -> None:
        self.max_lag_ns = int(max_lag_ns)
        self.margin_ns = int(margin_ns)
        self.silence_s = float(silence_s)
        self.hold_s = float(hold_s)
        self.members: dict[str, Follower] = {}
        #: follower -> when its sensor next publishes after a given sim ns (see the class docstring)
        self.floors: dict[str, Callable[[int], int]] = {}
        self.held_for: str | None = None  # whom sim time waited for at the latest :meth:`blocking`

    def report(self, who: str, t_ns: int, hold: bool, wall: float, still: bool = False) -> bool:
        """A message from ``who`` (``still``: a command for no motion); returns True when it (re)joins the active
        followers."""
        member = self.members.get(who)
        if member is None:
            self.members[who] = Follower(int(t_ns), bool(hold), float(wall), still=bool(still))
            return True
        joined = not member.active
        gap = int(t_ns) - member.t_ns
        member.at_limit = member.active and self.held_for == who
        if gap >= BURST_NS:
            # A gap that spans a silence counts too: the silence was in wall time, while sim time waited for this
            # follower, so a slow follower's first gap is its period (cleared, a node on a 5 Hz timer behind a
            # faster lead was given up for silent before every message and never learnt). A long gap before a
            # follower's arming is one of 20: the median forgets it.
            # it answered at the limit: the gap is its lead
            member.intervals.append(max(0, gap - self.margin_ns) if member.at_limit else gap)
            floor = self.floors.get(who)
            member.unprompted.append(floor is not None and floor(member.t_ns) > int(t_ns))
        member.t_ns, member.hold, member.seen, member.active = int(t_ns), bool(hold), float(wall), True
        member.held_since, member.still = None, bool(still)
        return joined

    def disarmed(self, who: str, disarmed: bool) -> None:
        """``who``'s judge disarmed it (True) or armed it (False). Disarmed with the robot standing still, its
        silence ends the wait after :data:`DISARMED_SILENCE` wall seconds instead of ``silence_s``: a node that says
        nothing once disarmed (most do) has no command to come that sim time should wait for, and the robot cannot
        move meanwhile; a wrong node that moves again is followed again at its next command (sim time ran on at
        most its latency). Not while its latest command moves the robot: a node short of CPU may still owe its stop,
        and sim time must not run on with the robot turning."""
        member = self.members.get(who)
        if member is not None:
            member.disarmed = bool(disarmed)

    def silence_of(self, member: Follower) -> float:
        """Wall seconds of silence after which ``member`` is dropped (see :meth:`disarmed`)."""
        return min(self.silence_s, DISARMED_SILENCE) if member.disarmed and member.still else self.silence_s

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
        """How far sim time may lead ``who``'s latest message (its sensor's floor aside: :meth:`limit_ns`)."""
        gaps = sorted(self.members[who].intervals)
        period = gaps[(len(gaps) - 1) // 2] if gaps else 0  # the lower median (see the class docstring)
        return max(self.max_lag_ns, self.margin_ns + period)

    def limit_ns(self, who: str, wall: float | None = None) -> int:
        """The sim time ``who`` keeps sim time from passing at wall time ``wall``: its latest message plus its lead,
        and at least its sensor's next message after it plus ``max_lag`` when it answers one; a node on a timer of
        its own (:meth:`on_timer`) only once it has been silent at its lead for :data:`FLOOR_WAIT` wall seconds."""
        m = self.members[who]
        floor = self.floors.get(who)
        limit = m.t_ns + self.lead_ns(who)
        if floor is None:
            return limit
        if self.on_timer(who) and (m.held_since is None or wall is None or wall - m.held_since < FLOOR_WAIT):
            return limit
        return max(limit, floor(m.t_ns) + self.max_lag_ns)

    def on_timer(self, who: str) -> bool:
        """Whether ``who`` spoke :data:`TIMER_EVIDENCE` times (of its last 20 gaps) with no message of its sensor
        since its previous one: a node on a timer of its own, not one that only answers its scans."""
        return sum(self.members[who].unprompted) >= TIMER_EVIDENCE

    def blocking(self, sim_ns: int, wall: float) -> tuple[str | None, list[str]]:
        """(who keeps sim time from reaching ``sim_ns``, or None; who was just dropped for silence or for a
        hold that lasts too long)."""
        dropped: list[str] = []
        blocker = None
        self.held_for = None
        for who, m in self.members.items():
            if not m.active:
                continue
            if m.hold:
                if wall - m.seen > self.hold_s:
                    m.active = False
                    dropped.append(who)
                elif blocker is None:
                    blocker = who
            elif sim_ns > self.limit_ns(who, wall):
                m.held_since = wall if m.held_since is None else m.held_since
                if wall - m.seen > self.silence_of(m):
                    m.active = False
                    dropped.append(who)
                elif blocker is None:
                    blocker = who
        self.held_for = blocker
        return blocker, dropped


class StayBehind:
    """The simulator's speed at ``real_time_factor`` 0 kept just below the pace the robot's node keeps (``afap_adapt``):
    it grows by :data:`STAY_GROWTH` x per wall second while the node answers before its limit and the robot turns
    (:data:`STAY_GROWTH_STRAIGHT` while it does not, and a turn starts at no more than the speed the last one ended
    at: :meth:`rate`), and drops to :data:`STAY_BACKOFF` of itself when it answers at its limit (sim time had to
    wait for it), at most once per :data:`STAY_REFRACTORY` wall seconds.

    Why: the followers' bound alone lets the simulator run ahead of a node that cannot keep up, and the node then
    lags by its whole lead at every message; worse, the bound grants one message per lead (70 ms for a 50 Hz node),
    while odometry comes every 33 ms, so the node's reliable odometry queue fills and it steers on readings a third
    of a second old (a 2 rad/s Retreat closed loop on odometry turned 190-258 deg uncapped). A node that is
    answered before its limit has time to spare: it drains its queues and its lag is its own latency.

    Args:
        cap: the highest speed (``afap_max_rtf``; 0: none).
        start: the speed a run starts at.
    """

    def __init__(self, cap: float = 0.0, start: float = STAY_START) -> None:
        self.cap = float(cap) if cap > 0.0 else math.inf
        self.value = min(float(start), self.cap)
        self.turn_value = self.value  # the speed the latest turn ended at: where the next one starts, at most
        self.backoffs = 0
        self._seen: float | None = None  # wall s of the latest :meth:`rate` while following
        self._backed_off = -math.inf  # wall s of the latest back-off
        self._turning = False

    def rate(self, wall: float, turning: bool = False) -> float:
        """The speed for the next step at wall time ``wall`` (called while the node is followed), in steps of
        :data:`STAY_QUANTUM` so the pace re-anchors only when it changes. ``turning``: the robot's command turns it.

        While it does not, the speed grows :data:`STAY_GROWTH_STRAIGHT` x per wall second, else :data:`STAY_GROWTH`;
        a turn starts at no more than the speed the latest turn ended at. Why: after a turn the speed, cut at every
        answer at the bound, recovered at the turn's growth while the robot crept, and six runs' recoveries left the
        cores idle together (12 % of a grade); a faster growth throughout made a 2 rad/s turn start too fast (29 deg
        off), which the turn's own speed prevents."""
        if turning and not self._turning:
            self.value = min(self.value, self.turn_value)
        if self._seen is not None:
            growth = STAY_GROWTH if turning else STAY_GROWTH_STRAIGHT
            self.value = min(self.cap, self.value + growth * max(0.0, min(wall - self._seen, 1.0)))
        if turning:
            self.turn_value = self.value
        self._turning, self._seen = turning, wall
        return min(self.cap, max(STAY_FLOOR, round(self.value / STAY_QUANTUM) * STAY_QUANTUM))

    def idle(self) -> None:
        """The node is not followed: no growth until it is again (a silent node says nothing of its pace)."""
        self._seen = None

    def at_limit(self, wall: float) -> None:
        """The node answered while sim time waited for it: slow down (once per :data:`STAY_REFRACTORY`)."""
        if wall - self._backed_off >= STAY_REFRACTORY:
            self.value = max(STAY_FLOOR, self.value * STAY_BACKOFF)
            self._backed_off = wall
            self.backoffs += 1
        if self._seen is not None:  # it grows again from here: until now the node did not keep up
            self._seen = max(self._seen, wall)


@dataclass
class PaceStop:
    """One time sim time stopped waiting for a follower (:meth:`Followers.blocking` dropped it)."""

    who: str  # the follower (:data:`CMD_VEL` for the robot's node)
    t: float  # sim s (the simulator's clock, not from the judge's t0) at which it stopped waiting
    why: str  # "silent" (nothing for follower_timeout wall s) or "holding" (a hold longer than hold_timeout)
    resumed: float | None = None  # sim s of the follower's next message (waited for again); None: never


class PaceStops:
    """When the simulator stopped waiting for each follower and when it waited again, in sim time: the run's own
    evidence of whether its pacing held (a grade's re-run rule reads it: :func:`bt_nav.grading.realtime.run_slipped`).
    Whether the robot's node was armed then is the judge's to say (its verdict's times), not the simulator's.

    Also how long sim time followed each follower, in sim and wall seconds (:meth:`followed`): at ``real_time_factor``
    0 the simulator runs as fast as its followers keep up, so the sim seconds per wall second while it followed the
    robot's ``cmd_vel`` are how fast the robot's node kept up (``bt-nav grade --exe`` reports it per run).

    Args:
        clock: the wall clock of the spans (the one the node passes :meth:`Followers.report`).
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.stops: list[PaceStop] = []
        self.clock = clock
        self._open: dict[str, tuple[float, float]] = {}  # follower -> (sim s, wall s) where its current span began
        # who, sim, wall, sim, wall, holding, the wall s of silence (or hold) that ended it (None: the followers')
        self._spans: list[tuple[str, float, float, float, float, bool, float | None]] = []

    def stopped(self, who: str, t: float, holding: bool, quiet_s: float | None = None) -> None:
        """Sim time no longer waits for ``who`` from sim ``t`` s on (silent, or ``holding`` too long; ``quiet_s``:
        the wall seconds since its latest message, None: the followers' ``silence_s`` or ``hold_s``)."""
        self.stops.append(PaceStop(who, round(float(t), 4), "holding" if holding else "silent"))
        began = self._open.pop(who, None)
        if began is not None:
            self._spans.append((who, *began, float(t), self.clock(), bool(holding), quiet_s))

    def resumed(self, who: str, t: float) -> None:
        """``who`` spoke again at sim ``t`` s (or for the first time: it joins): it is followed from here, and its
        latest stop, if still open, ends (a first message ends none)."""
        self._open.setdefault(who, (float(t), self.clock()))
        for stop in reversed(self.stops):
            if stop.who == who:
                if stop.resumed is None:
                    stop.resumed = round(float(t), 4)
                return

    def followed(self, followers: Followers | None = None, t_end: float | None = None) -> dict[str, dict[str, float]]:
        """Per follower, the sim and wall seconds sim time followed it (``sim_s``, ``wall_s``): from each (re)join to
        its drop, less the silence (or hold) that dropped it, which the follower did not spend keeping up; a span
        still open ends at the follower's latest message (``followers``' bookkeeping), else at ``t_end`` and now."""
        silence, hold = (followers.silence_s, followers.hold_s) if followers is not None else (0.0, 0.0)
        spans = [(who, s0, w0, s1, max(w0, w1 - (quiet if quiet is not None else hold if holding else silence)))
                 for who, s0, w0, s1, w1, holding, quiet in self._spans]
        for who, (s0, w0) in self._open.items():
            member = followers.members.get(who) if followers is not None else None
            if member is not None and member.active:
                spans.append((who, s0, w0, max(s0, member.t_ns * 1e-9), max(w0, member.seen)))
            elif t_end is not None:
                spans.append((who, s0, w0, max(s0, float(t_end)), max(w0, self.clock())))
        out: dict[str, dict[str, float]] = {}
        for who, s0, w0, s1, w1 in spans:
            total = out.setdefault(who, {"sim_s": 0.0, "wall_s": 0.0})
            total["sim_s"] += s1 - s0
            total["wall_s"] += w1 - w0
        return {who: {k: round(v, 3) for k, v in total.items()} for who, total in out.items()}

    def record(self, followers: Followers | None = None, **extra: Any) -> dict[str, Any]:
        """The JSON of :data:`PACE_FILE`: ``stops`` (each :class:`PaceStop`'s fields), ``followed``
        (:meth:`followed`, ended by ``followers`` and ``extra``'s ``t_end``) and ``extra`` (the node's settings, its
        final sim time ``t_end`` and its wall time ``wall_s``)."""
        followed = self.followed(followers, extra.get("t_end"))
        return {**extra, "followed": followed, "stops": [asdict(stop) for stop in self.stops]}


def read_pace_stops(path: str | Path) -> list[PaceStop] | None:
    """The stops a simulator wrote into ``path`` (:data:`PACE_FILE`); None when it wrote none (no such file: killed
    before its exit, or a simulator not asked to) or the file cannot be read. An empty list: it never stopped
    waiting."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        return [PaceStop(str(s["who"]), float(s["t"]), str(s["why"]),
                         None if s.get("resumed") is None else float(s["resumed"])) for s in data["stops"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def read_pace(path: str | Path) -> dict[str, Any] | None:
    """The whole record a simulator wrote into ``path`` (:meth:`PaceStops.record`); None when there is none or it
    cannot be read (see :func:`read_pace_stops`)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


#: Wall seconds late a step may be and still count as on time: a thread woken a little late by the scheduler.
ON_TIME_S = 0.02
#: Wall seconds of the window :class:`RealTimeKeeping` sums the time written off in: about the length of a turn
#: (90 deg at 0.8 rad/s), within which a stalled world shows in a node's angle.
KEEPING_WINDOW_S = 2.0


class RealTimeKeeping:
    """How well a simulator at a fixed factor kept it while its hosted judge was judging: the run's own evidence of
    whether it was a real-time run (``bt-nav grade``'s verdict is that of a 1x run; one that fell behind is run
    again, :mod:`bt_nav.grading.exe.realtime`).

    At a fixed factor the loop sleeps until each step is due; when a step comes late (the simulator lacked CPU) the
    wall clock has run ahead of sim time, and a backlog the loop writes off (it re-anchors instead of bursting to
    catch up) is time the robot's world stood still while the wall clock did not. A node on sim time sees its clock
    stand still with it; a node on the wall clock sees its turn run on in a world that stood still. Counted only
    while judging: a node's start-up and shutdown are not judged. Written into :data:`PACE_FILE` as ``realtime``
    (:meth:`record`): the latest step, the time written off in all and the most of it within any
    :data:`KEEPING_WINDOW_S` wall seconds.
    """

    def __init__(self) -> None:
        self.judged_sim_s = 0.0
        self.judged_wall_s = 0.0
        self.worst_s = 0.0  # the latest a step came, in wall s past its due time
        self.lost_s = 0.0  # wall s written off (sim time did not make them up)
        self.window_lost_s = 0.0  # the most wall s written off within any KEEPING_WINDOW_S
        self.late_steps = 0  # steps later than ON_TIME_S
        self._recent: deque[tuple[float, float]] = deque()  # (wall, s written off) within the window
        self._since: tuple[float, float] | None = None  # (wall, sim) where the judged span began

    def judging(self, on: bool, wall: float, sim_s: float) -> None:
        """The hosted judge started (``on``) or stopped judging at ``wall`` s (monotonic), sim ``sim_s`` s."""
        if on and self._since is None:
            self._since = (wall, sim_s)
        elif not on and self._since is not None:
            self.judged_wall_s += wall - self._since[0]
            self.judged_sim_s += sim_s - self._since[1]
            self._since = None

    def step(self, late_s: float, written_off: bool, wall: float) -> None:
        """A step came ``late_s`` wall s past its due time (0 or less: on time) at ``wall`` s (monotonic);
        ``written_off``: the loop re-anchored rather than catch up. Ignored while not judging."""
        if self._since is None or late_s <= ON_TIME_S:
            return
        self.late_steps += 1
        self.worst_s = max(self.worst_s, late_s)
        if not written_off:
            return
        self.lost_s += late_s
        self._recent.append((wall, late_s))
        while self._recent and self._recent[0][0] < wall - KEEPING_WINDOW_S:
            self._recent.popleft()
        self.window_lost_s = max(self.window_lost_s, sum(lost for _, lost in self._recent))

    def record(self, wall: float, sim_s: float) -> dict[str, float | int]:
        """What :data:`PACE_FILE` carries as ``realtime`` (a span still open ends at ``wall``, ``sim_s``)."""
        open_wall = wall - self._since[0] if self._since is not None else 0.0
        open_sim = sim_s - self._since[1] if self._since is not None else 0.0
        return {"judged_wall_s": round(self.judged_wall_s + open_wall, 3),
                "judged_sim_s": round(self.judged_sim_s + open_sim, 3), "worst_s": round(self.worst_s, 3),
                "lost_s": round(self.lost_s, 3), "window_lost_s": round(self.window_lost_s, 3),
                "late_steps": self.late_steps}
