"""The lab's check-off judge as a pure, clock-driven state machine (no rclpy), beside the homework's
:class:`bt_nav.judge.referee_core.Referee` and driven the same way.

The lab is checked off by watching the robot: after ``toggle_navigation`` (std_srvs/SetBool) true it
creeps ahead, and when its maneuver's trigger holds it rotates in place (each maneuver's trigger, angle and
side rules are its record in :mod:`bt_nav.mission.maneuver_spec`: e.g. the Randomizer, front <
safety_distance, 90-180 deg either side) without driving forward and without hitting anything, then moves on.
This judge automates that look from ground truth and from the commands
the robot's node publishes, so any node can be judged, not only bt_nav.

Driver protocol (the referee's, so one driver runs either): :meth:`CheckoffJudge.start` once the
``toggle_navigation`` service exists; :meth:`CheckoffJudge.step` at ``rate_hz``, performing the returned
:class:`Activate` actions as ``toggle_navigation`` calls and reporting each answer with
:meth:`CheckoffJudge.on_activate_result`; every ground-truth pose to :meth:`CheckoffJudge.observe`, every
collision event to :meth:`CheckoffJudge.on_collision`, every ``cmd_vel`` to
:meth:`CheckoffJudge.on_command`. The lab has no evaluation service: :meth:`CheckoffJudge.on_evaluate`
answers (False, ...) so a driver that serves one anyway gets a clear refusal.

Schedule (seconds from ``t0``): static until ``activate_at``; ``toggle_navigation(true)`` on every step
until an answer says success; the toggle cycle: ``toggle_navigation(false)`` ``toggle_off_after`` s after the first
maneuver ends (the robot creeping on: no turning command for that long), ``grace`` to brake once the node answered
it (``answer_allowance`` after the call at the latest: :meth:`CheckoffJudge.disarmed_from`), static for
``static_after``, and ``toggle_navigation(true)`` again ``toggle_off_for`` s after the false (a cycle that would not
end ``toggle_off_for`` s before the final disarm is left out; ``toggle_off_for`` 0: no cycle); ``drive_on_for`` s
after the cycle's true was answered (a turn under way ended first: :mod:`bt_nav.judge.checkoff_schedule`), or at
``activate_at + armed_for`` at the latest, ``toggle_navigation(false)`` until success; ``grace`` to brake; static for
``static_after``; then the report. Each call is asked on every step until an answer says success. While armed the
node must keep moving whenever nothing triggers (:mod:`bt_nav.judge.checkoff_creep`).

Announcements (:meth:`CheckoffJudge.on_announcement`): the lines the judged node logs (``/rosout`` over DDS; any
words, only their times count) mark where it began a new maneuver within one continuous rotation, so maneuvers
made back to back are judged one by one (:mod:`bt_nav.judge.chains`).

Maneuver episodes come from the commands: a maximal run of commands with |w| >= ``rotation_min_rate``, whatever
their forward speed (one that drives forward while turning is judged for that; a run that drives and turns the
robot less than ``steer_max_deg`` is steering, not a turn). Trigger readings (front, left and right sector
minima and the distance to the first obstacle in the robot's swept path) come from the judge's feed
(:class:`bt_nav.judge.feeds.TriggerFeed`), one per pose sample while armed: in the simulator cast noise-free from
the true pose in its world, as the world was at that moment (the simulator's truth feed, ``bt_nav_sim.truth``); from
a real robot, its recorded scans (:class:`bt_nav.judge.feeds.SourceReadings`). The judge owns no world: whoever
drives it (the ROS node, the lock-step runner, the recorded feed) hands it its feed. See
:meth:`CheckoffJudge._judge_episode` for the rules.

People walking (a world's ``walkers``): the truth feed's readings see them where they were at the pose's time,
from :meth:`CheckoffJudge.on_walkers` (the simulator's ``walkers`` samples; the latest one at or before the
pose), so a maneuver that a person passing in front of the robot triggered is judged like any other.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any

from bt_nav.judge.chains import INTERRUPT_SLACK, chain_check, split_run, turning_point
from bt_nav.judge.checkoff_creep import CREEP_CHECK, creep_check
from bt_nav.judge.checkoff_schedule import cycle_due, drove_on
from bt_nav.judge.checkoff_words import (
    MANEUVER_NAMES,
    _forward_text,
    maneuver_check,
    maneuver_problems,
    performed_check,
)
from bt_nav.judge.feeds import TriggerFeed
from bt_nav.judge.findings import implied_rules, maneuver_findings, strict_kinds
from bt_nav.judge.readings import Reading, SectorFamily
from bt_nav.judge.referee_core import ANSWERED, Activate, ServiceAnswers, Verdict, since_t0, static_check
from bt_nav.judge.segments import announced_between, join_small
from bt_nav.mission.maneuver_spec import ManeuverSpec, maneuver_spec
from bt_nav.mission.params import LAB_MANEUVERS as MANEUVERS  # what ``CheckoffConfig.maneuver`` may be (live)
from bt_nav.mission.params import SPECS  # the trigger distances' defaults are the executive's, never copies


@dataclass(frozen=True)
class CheckoffConfig:
    """Schedule and rules of the lab's check-off (seconds are relative to t0, distances in metres)."""

    maneuver: str = MANEUVERS[0]  # the first lab maneuver (the spec's order)
    activate_at: float = 2.0  # static before (t0 waited for the node's /clock and arm service); then true until success
    armed_for: float = 60.0  # toggle_navigation(false) at activate_at + armed_for at the latest (no maneuver, ...)
    grace: float = 1.0  # braking time after the disarm takes effect (:meth:`CheckoffJudge.disarmed_from`)
    answer_allowance: float = 1.5  # a disarm takes effect when the node answers it, this long after it at the latest
    static_after: float = 3.0  # must be static this long after the grace; then the report
    rate_hz: float = 2.0  # how often the driver calls step()
    moving_linear: float = 0.01  # m/s, as the homework referee
    moving_angular: float = 0.01  # rad/s
    # A and B trigger; C's too for a node that brakes there and pivots (the parameter table's default)
    safety_distance: float = float(SPECS["safety_distance"].default)
    pivot_distance: float = float(SPECS["pivot_distance"].default)  # C trigger (the sheet's; the table's default)
    trigger_margin: float = 0.05  # the trigger reading may exceed its threshold by this much (sensor noise)
    # The reasonable sector readings (bt_nav.judge.readings.SectorFamily): "did not hold" only when none held,
    # "late" only when every one held
    front_min_half_deg: float = 5.0
    front_max_half_deg: float = 30.0
    side_centre_min_deg: float = 60.0
    side_centre_max_deg: float = 110.0
    side_min_half_deg: float = 5.0
    side_max_half_deg: float = 30.0
    rotation_min_rate: float = 0.1  # rad/s: a command turning at least this fast ...
    turn_max_linear: float = 0.03  # m/s: a turning command driving faster is forward motion during the turn ...
    steer_max_deg: float = 20.0  # ... unless the robot turned less than this: then it was steering, not a turn
    late_distance: float = 0.04  # m: crept this far with the trigger holding before the turn: a late trigger ...
    late_time: float = 0.6  # s: ... over at least this long (a 5 Hz scan, a 10 Hz control loop and 0.15 s of
    # actuation latency take up to 0.45 s, and a node creeping faster than the template's 0.05 m/s covers 4 cm in it)
    forward_epsilon: float = 1e-3  # m/s: "zero forward command"
    angle_tolerance_deg: float = 10.0
    settle_rate: float = 0.05  # rad/s: the rotation has settled once the true yaw rate stays below this ...
    settle_hold: float = 0.2  # ... for this long
    settle_timeout: float = 2.0  # ... or this long after the episode's last command
    brake_allowance: float = 0.3  # s after an episode's start in which the robot may still roll
    forward_motion_max: float = 0.01  # m of true displacement allowed after the brake allowance
    move_on_within: float = 10.0  # s after settling in which the robot must move on ...
    move_on_distance: float = 0.02  # ... by this much (or start another episode)
    side_tie: float = 0.15  # a clearer-side rule: left and right closer than this count as a tie (either passes)
    # s: among people walking, the robot decided on a scan up to this old (LDS-01: a 0.2 s period, a 0.05 s
    # tick, up to 0.05 s of DDS delay in sim time, and slack): the trigger holds if it held at any sample this
    # long before the episode's start
    scan_age: float = 0.4
    open_space: float = 3.0  # a clearer-side rule: both sides beyond this count as a tie too
    aeb_distance: float = 0.35  # an obstacle this close in the swept path may make a turn an AEB recovery ...
    aeb_stop: float = 0.5  # s: ... when the robot stood at least this long before it (braked, then turned), not
    # every reading held its trigger, and it does not pass as the maneuver
    half_width: float = 0.18  # half the swept path's width (robot half width plus a margin)
    min_maneuvers: int = 1
    toggle_off_after: float = 1.0  # s: the toggle cycle's false this long after the first maneuver ends ...
    toggle_off_for: float = 3.0  # s: ... and its true again this long after it (0: no toggle cycle)
    # s after the cycle's true was answered: the node has been shown driving on (a turn under way ends first), so the
    # final false comes then (bt_nav.judge.checkoff_schedule; 0: only at activate_at + armed_for)
    drive_on_for: float = 4.5
    creep_start: float = 1.0  # s after an arming answered before a standstill counts (bt_nav.judge.checkoff_creep) ...
    creep_settle: float = 1.0  # ... and after a turning command
    creep_still: float = 3.0  # s: standing this long while armed with nothing triggering fails "creep while armed"
    # s: a node turning on without a pause (maneuvers back to back) gets the cycle's false this long after its first
    # turning command, and the final false this long after the true again (bt_nav.judge.checkoff_schedule)
    chain_for: float = 10.0
    # The robot's LiDAR (bt_nav_sim.lidar.LIDARS; empty: the world file's, else an LDS-01 at the robot's centre):
    # the lab measures its distances "from the LiDAR", so the readings are cast from its mount, along its beams.
    lidar: str = ""
    # The finding kinds (bt_nav.judge.findings: comma-separated, or "all") that fail their check instead: what the sheet
    # only implies is a finding unless the course teaches it (bt-nav grade --strict-findings)
    strict_findings: str = ""

    def __post_init__(self) -> None:
        self.family()  # refuses an empty or inverted sector family
        strict_kinds(self.strict_findings)  # refuses an unknown kind
        if self.maneuver not in MANEUVERS:  # an unknown maneuver is an error, never judged by another's rules
            raise ValueError(f"maneuver must be one of {', '.join(MANEUVERS)}, got {self.maneuver!r}")
        if not (self.armed_for > 0 and self.rate_hz > 0 and self.grace >= 0 and self.static_after > 0):
            raise ValueError("need armed_for > 0, rate_hz > 0, grace >= 0 and static_after > 0")
        if not (self.toggle_off_after >= 0 and self.toggle_off_for >= 0):
            raise ValueError("need toggle_off_after >= 0 and toggle_off_for >= 0")

    def family(self) -> SectorFamily:
        """The sector readings this config accepts as reasonable."""
        return SectorFamily(self.front_min_half_deg, self.front_max_half_deg, self.side_centre_min_deg,
                            self.side_centre_max_deg, self.side_min_half_deg, self.side_max_half_deg)

    def strict(self, kind: str) -> bool:
        """Whether the course makes finding ``kind`` a failure (``strict_findings``)."""
        return kind in strict_kinds(self.strict_findings)

    @property
    def spec(self) -> ManeuverSpec:
        """The maneuver's record: its trigger, angle and side rules (ValueError for an unknown maneuver)."""
        return maneuver_spec(self.maneuver)

    def distance(self, parameter: str) -> float:
        """This config's value of a trigger distance parameter (``safety_distance``, ``pivot_distance``)."""
        value = getattr(self, parameter, None)
        if isinstance(value, bool) or not isinstance(value, float | int):
            raise ValueError(f"the check-off has no trigger distance {parameter!r} (maneuver {self.maneuver})")
        return float(value)

    def limits(self) -> tuple[float, float]:
        """The maneuver's trigger distance as the loosest and as the tightest reasonable reading (m, no margin):
        the sheet's distance or, when the spec allows one (the Smart Pivot's ``safety_distance``), that of a node
        that brakes there and turns there."""
        values = [self.distance(p) for p in self.spec.trigger.distances]
        if len(values) == 1:
            return values[0], values[0]
        return max(values), min(values)

    def trigger_rule(self) -> str:
        """Which readings the trigger was judged by, in words (the maneuver lines and the docs say it)."""
        loose, tight = self.limits()
        trigger = self.spec.trigger
        also = (f" (the sheet's {trigger.distance} {self.distance(trigger.distance):.2f} m or {trigger.or_braked_at} "
                f"{self.distance(trigger.or_braked_at):.2f} m)" if trigger.or_braked_at else "")
        return (f"held: {trigger.words} < {loose:g} m{also} (+{self.trigger_margin:.2f} m sensor-noise tolerance) by "
                f"any of the {self.family().describe()}; late: only once every one of them read < {tight:g} m")

    def angle_rule(self, side: str = "either side") -> str:
        """The maneuver's angle rule in words, as a maneuver line and the rules page (bt-nav rules) say it; ``side``
        is where its readings put the clearer side, used by a maneuver whose spec turns towards it."""
        return self.spec.angle.words(self.angle_tolerance_deg, side)


#: Check names, in report order (one "maneuver N" line per maneuver sits where "maneuver" is).
CHECKS = ("static before activation", "toggle_navigation answered", "maneuvers performed", "maneuver",
          "back-to-back maneuvers", "recovery turns", CREEP_CHECK, "no collision", "static after deactivation")


class CheckoffJudge(Verdict):
    """The lab's check-off: schedule, ground truth and commands, the maneuver episodes, the verdict."""

    def __init__(self, config: CheckoffConfig, readings: TriggerFeed) -> None:
        """``readings``: where the trigger reading at each pose sample comes from (the simulator's truth feed, cast
        in its world; a real robot's scans, :class:`bt_nav.judge.feeds.SourceReadings`)."""
        self.config = config
        self.readings = readings
        self.t0: float | None = None
        self._t: list[float] = []
        self._x: list[float] = []
        self._y: list[float] = []
        self._yaw: list[float] = []
        self._uyaw: list[float] = []  # unwrapped yaw
        self.commands: list[tuple[float, float, float]] = []
        self.collisions: list[tuple[float, float, float]] = []
        self.travelled = 0.0
        self.max_distance = 0.0
        self.activation_requested: float | None = None
        self.activated: float | None = None
        self.answers = ServiceAnswers()
        self.deactivation_requested: float | None = None
        self.deactivated: float | None = None
        self.evaluation_calls = 0
        self.report_time: float | None = None
        self._results: dict[str, Any] | None = None
        self._init_cycle()

    # ------------------------------------------------------------------ driver inputs
    def start(self, t0: float) -> None:
        """The robot's ``toggle_navigation`` service exists: the schedule starts at ``t0``."""
        if self.t0 is None:
            self.t0 = float(t0)

    def step(self, t: float) -> list[Activate]:
        """Advance the schedule to ``t``; returns the ``toggle_navigation`` calls to make now."""
        if self.t0 is None or self.done:
            return []
        cfg = self.config
        rel = since_t0(t, self.t0)
        if rel >= cfg.activate_at + cfg.armed_for or self.deactivation_requested is not None or drove_on(self, t):
            if self.deactivation_requested is None:
                self.deactivation_requested = float(t)
            if t >= self.disarmed_from(self.deactivation_requested, self.deactivated) + cfg.grace + cfg.static_after:
                self._finish(t)
                return []
            return [] if self.deactivated is not None else [Activate(False)]
        if rel >= cfg.activate_at:
            if self.activation_requested is None:
                self.activation_requested = float(t)
            return self._cycle_step(t) if self.activated is not None else [Activate(True)]
        return []

    def _init_cycle(self) -> None:
        """The toggle cycle's state and the node's announcements (see the module docstring)."""
        self.announcements: list[tuple[float, str, str]] = []  # (t, node, text) as the node logged them
        self.cycle_off_requested: float | None = None
        self.cycle_off: float | None = None
        self.cycle_on_requested: float | None = None
        self.cycle_on: float | None = None
        self._turned = False  # a turning command came while armed, before the cycle
        self._calm_since: float | None = None  # the first command since the last turning one, if none turned since

    def _cycle_step(self, t: float) -> list[Activate]:
        """The toggle cycle while armed: false once the first maneuver has ended ``toggle_off_after`` s ago (no
        turning command since), until success; true again ``toggle_off_for`` s after the false, until success."""
        cfg = self.config
        if cfg.toggle_off_for <= 0:
            return []
        if self.cycle_off_requested is None:
            final = (self.t0 or 0.0) + cfg.activate_at + cfg.armed_for
            if not cycle_due(self, t) or t + 2 * cfg.toggle_off_for > final:
                return []
            self.cycle_off_requested = float(t)
        if t < self.cycle_off_requested + cfg.toggle_off_for:
            return [] if self.cycle_off is not None else [Activate(False)]
        if self.cycle_on_requested is None:
            self.cycle_on_requested = float(t)
        return [] if self.cycle_on is not None else [Activate(True)]

    def on_activate_result(self, t: float, data: bool, success: bool, answer: str = ANSWERED,
                           message: str = "") -> None:
        """The answer to an :class:`Activate` action (``success`` False also for a failed call: ``answer`` says
        whether a response came, ``message`` is the node's)."""
        self.answers.record(data, success, answer, message)
        if not success:
            return  # step() asks again
        final = self.deactivation_requested is not None
        if data and self.activated is None and not final:
            self.activated = float(t)
        elif data and self.cycle_on_requested is not None and self.cycle_on is None and not final:
            self.cycle_on = float(t)
        elif not data and final and self.deactivated is None:
            self.deactivated = float(t)
        elif not data and self.cycle_off_requested is not None and self.cycle_off is None \
                and self.cycle_on_requested is None:
            self.cycle_off = float(t)

    def on_command(self, t: float, v: float, w: float) -> None:
        """A ``cmd_vel`` the robot's node published (non-finite values read as 0, as the base does)."""
        if self._late(t):
            return
        v, w = float(v), float(w)
        self.commands.append((float(t), v if math.isfinite(v) else 0.0, w if math.isfinite(w) else 0.0))
        if self.cycle_off_requested is None and self._armed_at(t):  # when the first maneuver ends: the cycle's time
            if abs(self.commands[-1][2]) >= self.config.rotation_min_rate:
                self._turned, self._calm_since = True, None
            elif self._turned and self._calm_since is None:
                self._calm_since = float(t)

    def on_announcement(self, t: float, node: str, text: str) -> None:
        """A line the judged node logged at ``t`` (its clock: sim time). Any words: only when it came counts, as a
        mark that the node began a new maneuver there (:mod:`bt_nav.judge.chains`); never as a reading."""
        if not self._late(t) and math.isfinite(t):
            self.announcements.append((float(t), str(node), str(text)))

    def announcement_times(self) -> list[float]:
        """When the node logged its lines, in order."""
        return sorted(t for t, _, _ in self.announcements)

    def observe(self, t: float, x: float, y: float, yaw: float) -> None:
        """One ground-truth pose; out-of-order samples and those stamped after the report are ignored. While
        armed the feed takes its trigger reading here (the truth feed casts it against the world as it is now)."""
        if self._late(t) or (self._t and t <= self._t[-1]):
            return
        if self._t:
            if self._armed_at(t):
                self.travelled += math.hypot(x - self._x[-1], y - self._y[-1])
            self.max_distance = max(self.max_distance, math.hypot(x - self._x[0], y - self._y[0]))
            uyaw = self._uyaw[-1] + math.remainder(yaw - self._yaw[-1], 2 * math.pi)
        else:
            uyaw = float(yaw)
        self._t.append(float(t))
        self._x.append(float(x))
        self._y.append(float(y))
        self._yaw.append(float(yaw))
        self._uyaw.append(uyaw)
        self.readings.add(float(x), float(y), float(yaw), float(t), self._armed_at(t))

    def on_walkers(self, t: float, circles: Any) -> None:
        """Where the people walking were at ``t`` (circles (K, 3): x, y, r); out-of-order samples are dropped."""
        self.readings.on_walkers(t, circles)

    def on_collision(self, t: float, x: float, y: float) -> None:
        """A collision event (the start of one contact)."""
        if not self._late(t):
            self.collisions.append((float(t), float(x), float(y)))

    def on_evaluate(self, t: float) -> tuple[bool, str]:
        """The lab has no evaluation service: every call is refused (and counted)."""
        del t
        self.evaluation_calls += 1
        return False, "the lab has no evaluation service"

    # ------------------------------------------------------------------ ground truth helpers
    def _armed_at(self, t: float) -> bool:
        """From the first activation request until the disarm request plus the grace, but for the toggle cycle's
        off time (from its false plus the grace until its true)."""
        if self.activation_requested is None or t <= self.activation_requested:
            return False
        grace = self.config.grace
        if self.cycle_off_requested is not None and self.cycle_off_requested + grace < t \
                and (self.cycle_on_requested is None or t <= self.cycle_on_requested):
            return False
        return self.deactivation_requested is None or t <= self.deactivation_requested + grace

    def disarms(self) -> list[float]:
        """The disarm requests so far (the toggle cycle's, the final one), in order."""
        return [d for d in (self.cycle_off_requested, self.deactivation_requested) if d is not None]

    def disarmed_from(self, requested: float, answered: float | None) -> float:
        """When a disarm requested at ``requested`` took effect: when the node answered it (its service said it
        stopped), but ``answer_allowance`` after the request at the latest. The sheet asks the robot to stop on
        ``false``, not to answer within a time: a node whose executor was busy, or whose request DDS lost and the
        judge sent again, stops when it hears it; one that never answers is held to the allowance."""
        allowance = self.config.answer_allowance
        late = allowance if answered is None else min(max(answered - requested, 0.0), allowance)
        return requested + late

    def next_disarm(self, t: float) -> float:
        """The disarm in effect at ``t`` or the next one (its request; ``inf``: none yet)."""
        return min((d for d in self.disarms() if d + self.config.grace >= t), default=math.inf)

    def _armed_since(self, t: float) -> float:
        """The arming request in effect at ``t`` (the toggle cycle's true after it came)."""
        if self.cycle_on_requested is not None and t > self.cycle_on_requested:
            return self.cycle_on_requested
        return self.activation_requested if self.activation_requested is not None else -math.inf

    def _index_at(self, t: float) -> int:
        """The last sample at or before ``t`` (the first one if none is)."""
        return max(0, bisect.bisect_right(self._t, t + 1e-9) - 1)

    def _interp(self, series: list[float], t: float) -> float:
        """``series`` linearly interpolated at ``t`` (held at the ends)."""
        ts = self._t
        i = bisect.bisect_right(ts, t)
        if i == 0:
            return series[0]
        if i >= len(ts):
            return series[-1]
        a = (t - ts[i - 1]) / (ts[i] - ts[i - 1])
        return series[i - 1] + a * (series[i] - series[i - 1])

    def _settled_at(self, last: float, limit: float) -> float:
        """The first moment after ``last`` from which the true yaw rate stays below ``settle_rate`` for
        ``settle_hold`` (judged on sample pairs), capped at ``limit``."""
        cfg = self.config
        ts, uy = self._t, self._uyaw
        calm_since: float | None = None
        for i in range(max(1, bisect.bisect_right(ts, last)), len(ts)):
            if ts[i - 1] >= limit:
                break
            rate = abs(uy[i] - uy[i - 1]) / max(ts[i] - ts[i - 1], 1e-9)
            if rate >= cfg.settle_rate:
                calm_since = None
                continue
            calm_since = max(ts[i - 1], last) if calm_since is None else calm_since
            if ts[i] - calm_since >= cfg.settle_hold - 1e-9:
                return min(calm_since, limit)
        return limit

    def _path_length(self, start: float, end: float) -> float:
        """True path length over the samples in [start, end]."""
        i, j = bisect.bisect_left(self._t, start), bisect.bisect_right(self._t, end)
        return sum(math.hypot(self._x[k] - self._x[k - 1], self._y[k] - self._y[k - 1]) for k in range(i + 1, j))

    def _max_displacement(self, start: float, end: float) -> float:
        """Largest true distance from the pose at ``start`` over the samples in [start, end]."""
        x0, y0 = self._interp(self._x, start), self._interp(self._y, start)
        i, j = bisect.bisect_left(self._t, start), bisect.bisect_right(self._t, end)
        return max((math.hypot(self._x[k] - x0, self._y[k] - y0) for k in range(i, j)), default=0.0)

    # ------------------------------------------------------------------ episodes
    def episodes(self) -> list[tuple[int, int]]:
        """Rotation episodes as (first, last) command indices: maximal runs of turning commands given while
        armed, whatever their forward speed (a node that drives forward while it turns is judged for it, not
        left unseen), cut where the turn reverses (:meth:`_reversals`) and joined across another publisher's creep
        commands sent while it went on (:meth:`_interleaved`; never a turn the node announced: the creep before it
        lies between two maneuvers, :mod:`bt_nav.judge.segments`); a run that drove forward and turned less than
        ``steer_max_deg`` is steering, not a turn."""
        cfg = self.config
        runs: list[tuple[int, int]] = []
        first: int | None = None
        for i, (t, _, w) in enumerate(self.commands):
            turning = abs(w) >= cfg.rotation_min_rate and self._armed_at(t)
            if turning and first is None:
                first = i
            elif not turning and first is not None:
                runs.append((first, i - 1))
                first = None
        if first is not None:
            runs.append((first, len(self.commands) - 1))
        merged: list[tuple[int, int]] = []
        for a, b in (piece for run in runs for piece in self._reversals(*run)):
            if merged and self._interleaved(merged[-1][1], a) and not announced_between(self, merged[-1][1], a):
                merged[-1] = (merged[-1][0], b)
            else:
                merged.append((a, b))
        return [(a, b) for a, b in merged if not self._steering(a, b)]

    def _interleaved(self, b: int, a: int) -> bool:
        """Whether the commands between turning command ``b`` and the next one, ``a``, are another publisher's
        creep sent while the turn went on: all drive forward, and ``a`` came within one and a half of the turn's
        command periods (a maneuver that ends and starts again on the next scan leaves a longer gap, or a stop)."""
        between = self.commands[b + 1:a]
        if not between or any(v <= self.config.forward_epsilon for _, v, _ in between):
            return False
        turning = self.config.rotation_min_rate
        near = [k for k in range(max(0, b - 10), min(len(self.commands), a + 11))
                if abs(self.commands[k][2]) >= turning]
        gaps = [self.commands[k2][0] - self.commands[k1][0] for k1, k2 in zip(near, near[1:], strict=False)
                if (k1, k2) != (b, a)]  # the turn's command period, on both sides of this gap
        return 0.0 < self.commands[a][0] - self.commands[b][0] <= 1.5 * max(gaps, default=0.0) + 1e-9

    def _reversals(self, a: int, b: int) -> list[tuple[int, int]]:
        """Run ``a..b`` cut where the commanded turn changes direction and the robot then turns ``steer_max_deg`` or
        more the other way (a new maneuver that began without a stop; a few degrees back is a closed loop's
        correction of its overshoot, part of the turn)."""
        pieces, first = [], a
        for i in range(a + 1, b + 1):
            if self.commands[i][2] * self.commands[i - 1][2] < 0 and self._t:
                nxt = next((k for k in range(i + 1, b + 1) if self.commands[k][2] * self.commands[i][2] < 0), b)
                turned = self._interp(self._uyaw, self.commands[nxt][0]) - self._interp(self._uyaw, self.commands[i][0])
                if abs(math.degrees(turned)) >= self.config.steer_max_deg:
                    pieces.append((first, i - 1))
                    first = i
        return [*pieces, (first, b)]

    def _steering(self, a: int, b: int) -> bool:
        """Commands ``a..b`` drove forward and turned the robot less than ``steer_max_deg``: a course correction."""
        cfg = self.config
        if max(abs(v) for _, v, _ in self.commands[a:b + 1]) <= cfg.turn_max_linear or not self._t:
            return False
        start, end = self.commands[a][0], self.commands[b][0] + cfg.settle_timeout
        return abs(math.degrees(self._interp(self._uyaw, end) - self._interp(self._uyaw, start))) < cfg.steer_max_deg

    def _judge_all(self, now: float) -> list[dict[str, Any]]:
        """Every episode judged (see :meth:`_judge_episode`), with its settling time; a rotation that holds
        maneuvers back to back judged one by one (:func:`bt_nav.judge.chains.split_run`)."""
        runs = join_small(self, [piece for a, b in self.episodes() for piece in split_run(self, a, b)])
        starts = [self.commands[a][0] for a, _, _, _ in runs]
        out = []
        since = self.activation_requested if self.activation_requested is not None else -math.inf
        begin = None  # where the last turn's rotation really ended, when the next began before it settled
        for k, (a, b, cut, _why) in enumerate(runs):
            last = self.commands[b][0]
            nxt = starts[k + 1] if k + 1 < len(runs) else math.inf
            if cut is not None:  # the node began its next maneuver here, within one rotation
                settle = joined = cut
            else:
                limit = min(nxt, last + self.config.settle_timeout, now)
                settle = min(nxt, self._settled_at(last, limit))
                joined = None
                if k + 1 < len(runs) and settle >= nxt and self._t:  # back to back: split where the rotation turned
                    joined = turning_point(self, last, nxt, now, self.commands[b][2],
                                           self.commands[runs[k + 1][0]][2])
                    settle = joined
            episode = self._judge_episode(a, b, settle, nxt, now, begin)
            if begin is not None and runs[k - 1][2] is not None:
                episode["began_by"] = runs[k - 1][3]  # what marked this maneuver's start within the rotation
            whole = begin is None and cut is None
            if whole and not episode["angle_ok"] and not episode["interrupted"]:
                episode["unsplit"] = abs(episode["angle_deg"]) >= 2 * self.config.spec.angle.low_deg - \
                    2 * self.config.angle_tolerance_deg
            begin = joined
            if episode["kind"] == "maneuver":
                self._judge_lateness(episode, max(since, self._armed_since(self.commands[a][0])), self.commands[a][0])
            out.append(episode)
            since = settle
        return out

    def _judge_lateness(self, episode: dict[str, Any], since: float, start: float) -> None:
        """A maneuver whose trigger held by every reasonable reading (:meth:`_trigger_all`) while the robot crept
        on for ``late_distance`` or more before it turned fired late: its node does not react to its trigger's
        distance (e.g. a ``safety_distance`` parameter it declares but never reads). Only a trigger that began to
        hold while the robot crept counts: not one that held already at ``since`` (the arming, or the end of the
        last turn)."""
        cfg = self.config
        if not self._t or episode["interrupted"]:
            return
        i = self._index_at(start)
        k = i
        while k > 0 and self._t[k - 1] > since:
            if not self._trigger_all(self.readings.at(k - 1)):
                break
            k -= 1
        if k == 0 or self._t[k - 1] <= since:
            return  # it held already when the creeping began (at the arming, or as the last turn ended)
        crept = self._path_length(self._t[k], start) if k < i else 0.0
        episode["crept_with_trigger"] = round(crept, 3)
        held = start - self._t[k]
        episode["trigger_held_for"] = round(held, 2)
        if crept >= cfg.late_distance and held >= cfg.late_time:
            episode.update(late=True, passed=False, late_at=self._fired_at(self.readings.at(i)))

    def _fired_at(self, r: Reading | None) -> str:
        """Where a late trigger fired, in the figures a student compares with their parameter."""
        trigger, cfg = self.config.spec.trigger, self.config
        at = "" if r is None else (f"left {r.left:.2f} m and right {r.right:.2f} m" if trigger.reads == "sides"
                                   else f"front {r.front:.2f} m")
        return f"triggered at {at or 'an unknown reading'} with {trigger.distance} {cfg.distance(trigger.distance):.2f}"

    def _judge_episode(self, a: int, b: int, settle: float, next_start: float, now: float,
                       begin: float | None = None) -> dict[str, Any]:
        """One episode: trigger at its start, angle and side, no forward command or motion, moved on.

        A turn in place after the trigger held is the maneuver, whatever the pause before it. A turn after a
        standstill of ``aeb_stop`` whose swept path was blocked within ``aeb_distance`` may instead be the node's
        emergency-stop way out (it braked, stood and turns away): when not every reading held its trigger and it
        does not pass as the maneuver, it is a recovery turn, held to the forward rules only. So no turn's class
        rests on a centimetre at the trigger's distance: one that passes as the maneuver is one.
        """
        cfg = self.config
        start, last = self.commands[a][0], self.commands[b][0]
        candidates = self._readings_at(start, self._stood_before(a))
        reading = candidates[0]
        trigger, trigger_text = self._trigger(reading)
        interrupted = last >= self.next_disarm(start) - INTERRUPT_SLACK
        turn_from = start if begin is None else max(begin, start - 0.5)  # a turn begun while the last one coasted
        angle = math.degrees(self._interp(self._uyaw, settle) - self._interp(self._uyaw, turn_from)) if self._t else 0.0
        swung = self._swung(start, turn_from, angle)
        # the commands and the motion of one window: the turn's commands (those the node sent between its turning
        # ones too, in the order they came: several may share a stamp), and where they (not the creep that follows
        # the turn, from its first forward command on) can have moved the robot
        cmd_forward = max(abs(v) for _, v, _ in self.commands[a:b + 1])
        end = min(settle, last + cfg.brake_allowance, self._next_forward(b))
        motion = self._max_displacement(start + cfg.brake_allowance, end) if self._t else 0.0
        forward_ok = cmd_forward <= cfg.forward_epsilon and motion < cfg.forward_motion_max
        moved = self._moved_on(settle, next_start, now, start)  # the implied rules: findings unless strict
        travelled = self._travelled(turn_from, settle) if interrupted else 0.0
        angle_ok, rule, moved_on, found = implied_rules(cfg, angle, reading, self._judged_angle(
            angle + math.copysign(swung, angle), candidates, interrupted, travelled), moved)
        as_maneuver = trigger and angle_ok and forward_ok and moved_on
        # a turn with the maneuver's trigger and angle is the maneuver, whatever its side: never excused as a way out
        shaped = trigger and cfg.spec.angle.low_deg - cfg.angle_tolerance_deg <= abs(angle) <= \
            cfg.spec.angle.high_deg + cfg.angle_tolerance_deg
        recovery = (not as_maneuver and not shaped and reading is not None and reading.ahead < cfg.aeb_distance
                    and self._stood_before(a) >= cfg.aeb_stop and not self._trigger_all(reading))
        return {"t": start - (self.t0 or 0.0), "t0": self.t0 or 0.0, "settled": settle - (self.t0 or 0.0), "kind":
                "recovery" if recovery else "maneuver", "passed": forward_ok if recovery else as_maneuver,
                "trigger": trigger, "interrupted": interrupted,
                "trigger_detail": trigger_text, "angle_deg": round(angle, 2),
                "side": "left" if angle > 0 else "right", "angle_ok": angle_ok, "rule": rule, "swung_deg": swung,
                "size_ok": cfg.spec.angle.holds(abs(angle) + swung, cfg.angle_tolerance_deg),
                "trigger_rule": cfg.trigger_rule(),
                "forward_command": round(cmd_forward, 4), "forward_motion": round(motion, 4),
                "forward_ok": forward_ok, "moved_on": moved_on, "moved_on_detail": moved[1], "findings": found,
                "readings": None if reading is None else {k: (round(v, 3) if math.isfinite(v) else None)
                                                          for k, v in vars(reading).items() if k != "sides"}}

    def _swung(self, start: float, turn_from: float, angle: float) -> float:
        """Degrees the robot swung on the old way after this turn's first command, when it reversed a turn still
        under way (the base's inertia and latency, not the node: credited to the new turn's angle)."""
        if turn_from <= start or not self._t:
            return 0.0
        old_way = math.degrees(self._interp(self._uyaw, turn_from) - self._interp(self._uyaw, start))
        return round(abs(old_way), 2) if old_way * angle < 0 else 0.0

    def _next_forward(self, b: int) -> float:
        """When the node first commands forward speed after the turn's last command (``inf`` if never): the robot
        may coast on in rotation for a moment (an open-loop turn's commands end before the yaw settles), and the
        creep it was sent then is the node moving on, not forward motion during the turn."""
        eps = self.config.forward_epsilon
        return next((t for t, v, _ in self.commands[b + 1:] if abs(v) > eps), math.inf)

    def _judged_angle(self, angle: float, candidates: list[Reading | None], interrupted: bool,
                      travelled: float = 0.0) -> tuple[bool, str]:
        """The angle rule for a turn that may have been decided on any of ``candidates`` (the side may follow any
        reading the robot could have had), and what the disarm did to it (``travelled``: the deg its yaw went to and
        fro until then: a node rocking in place for half a minute has a small net angle, yet never ended a turn)."""
        angle_ok, rule = self._angle_rule(angle, candidates[0])
        for other in candidates[1:]:
            if not angle_ok:
                angle_ok, rule = self._angle_rule(angle, other)
        if interrupted and not self._within_max(travelled):
            return False, f"{rule}, and it was still turning at the disarm, {travelled:.0f} deg to and fro in place"
        if interrupted and self._within_max(angle):  # the disarm stopped it: its angle is what it had reached
            return True, "interrupted by the disarm (angle not judged)"
        if interrupted:  # ... but it had turned past its rule's largest angle: it would never have stopped
            return False, rule + ", and it was still turning at the disarm"
        return angle_ok, rule

    def _readings_at(self, start: float, stood: float = 0.0) -> list[Reading | None]:
        """The trigger readings an episode starting at ``start`` may have been decided on: those of the last
        ``scan_age`` s, and of the ``stood`` s the robot stood still before it (a node that decides, pauses, then
        turns), at which the trigger held, if any did, newest first (a scan takes that long to reach the robot's
        decision, and a person walking moves half a metre in it); else the sample at the start."""
        if not self._t:
            return [None]
        i = self._index_at(start)
        first = self._index_at(start - self.config.scan_age - stood)
        window = [self.readings.cast(k) for k in range(i, first - 1, -1)]
        held = [r for r in window if self._trigger(r)[0]]
        return held or [self.readings.at(i)]

    def _stood_before(self, a: int) -> float:
        """Seconds of zero commands just before command ``a`` (since the last moving command or the first)."""
        start = self.commands[a][0]
        for t, v, w in reversed(self.commands[:a]):
            if v != 0.0 or w != 0.0:
                return start - t
        return start - self.commands[0][0] if self.commands else 0.0

    def _trigger(self, r: Reading | None) -> tuple[bool, str]:
        """Whether the maneuver's trigger held for reading ``r`` by any reasonable reading (the widest sectors,
        the loosest limit, within the config's ``trigger_margin``), and how it read."""
        cfg = self.config
        if r is None:
            return False, "no ground truth at the start"
        limit = cfg.limits()[0] + cfg.trigger_margin
        sheet = f"{cfg.limits()[0]:g} m (+{cfg.trigger_margin:.2f} m sensor-noise tolerance)"
        if cfg.spec.trigger.reads == "sides":
            return r.left < limit and r.right < limit, f"left {r.left:.2f} m and right {r.right:.2f} m < {sheet}"
        return r.front < limit, f"front {r.front:.2f} m < {sheet}"

    def _trigger_all(self, r: Reading | None) -> bool:
        """Whether the trigger held by every reasonable reading: the narrowest front, every side centre, the
        tightest limit, no margin."""
        if r is None:
            return False
        tight = self.config.limits()[1]
        if self.config.spec.trigger.reads == "sides":
            return r.left_all < tight and r.right_all < tight
        return r.front_all < tight

    def _angle_rule(self, angle: float, r: Reading | None) -> tuple[bool, str]:
        """Whether ``angle`` (deg, + = left) obeys the maneuver's rule; the rule in words."""
        cfg = self.config
        rule = cfg.spec.angle
        size_ok = rule.holds(abs(angle), cfg.angle_tolerance_deg)
        if rule.side == "either":
            return size_ok, cfg.angle_rule()
        side = self._clearer_side(r)
        side_ok = side == "either side" or (side == "left") == (angle > 0)
        return size_ok and side_ok, cfg.angle_rule(side)

    def _clearer_side(self, r: Reading | None) -> str:
        """A clearer-side rule's side: "left" or "right" where every reasonable reading of the two sides
        (:class:`Reading`'s ``sides``) finds that side clearer by ``side_tie`` or more (and not both in open space);
        else "either side"."""
        cfg = self.config
        if r is None:
            return "either side"
        pairs = r.sides or ((r.left, r.right),)
        verdicts = {("left" if left > right else "right") if abs(left - right) >= cfg.side_tie
                    and not (left > cfg.open_space and right > cfg.open_space) else "tie" for left, right in pairs}
        return verdicts.pop() if len(verdicts) == 1 and "tie" not in verdicts else "either side"

    def _travelled(self, start: float, end: float) -> float:
        """Degrees the true yaw went, either way, from ``start`` to ``end``."""
        i, j = bisect.bisect_left(self._t, start), bisect.bisect_right(self._t, end)
        return math.degrees(sum(abs(self._uyaw[k] - self._uyaw[k - 1]) for k in range(i + 1, j)))

    def _within_max(self, angle: float) -> bool:
        """Whether ``angle`` (deg) is no larger than the maneuver's largest (its spec's, plus the tolerance)."""
        cfg = self.config
        return abs(angle) <= cfg.spec.angle.high_deg + cfg.angle_tolerance_deg

    def _moved_on(self, settle: float, next_start: float, now: float, start: float) -> tuple[bool, str]:
        """Within ``move_on_within`` of settling: travelled ``move_on_distance`` or another episode began
        (a disarm that comes first excuses it; ``start``: the episode's, whose disarm counts)."""
        cfg = self.config
        horizon = settle + cfg.move_on_within
        disarm = self.next_disarm(start)
        if next_start <= horizon and next_start <= disarm:
            return True, "another maneuver began"
        end = min(horizon, disarm, now)
        travelled = self._path_length(settle, end)
        if travelled >= cfg.move_on_distance:
            return True, f"travelled {travelled:.2f} m"
        if disarm <= horizon:
            return True, "disarmed first"
        if now < horizon:
            return True, "run still going"
        return False, f"travelled {travelled:.3f} m in {cfg.move_on_within:.0f} s"

    # ------------------------------------------------------------------ verdict
    @property
    def hard_stop(self) -> float:
        """Absolute time by which the report is made on schedule (a driver may stop a run that goes on longer):
        the disarm, the grace, the static window and a second of slack after t0."""
        cfg = self.config
        return (self.t0 or 0.0) + cfg.activate_at + cfg.armed_for + cfg.grace + cfg.static_after + 1.0

    def _evaluate(self, now: float) -> dict[str, Any]:
        cfg = self.config
        t0 = self.t0 or 0.0
        samples = (self._t, self._x, self._y, self._yaw)
        limits = (cfg.moving_linear, cfg.moving_angular)
        checks = [static_check("static before activation", samples, t0, self.activation_requested
                               if self.activation_requested is not None else now, "never activated", limits, t0)]
        checks.append(self._answered_check())
        episodes = self._judge_all(now)
        maneuvers = [e for e in episodes if e["kind"] == "maneuver"]
        recoveries = [e for e in episodes if e["kind"] == "recovery"]
        checks.append(performed_check(cfg, maneuvers, recoveries))
        checks += [maneuver_check(i + 1, cfg.maneuver, e) for i, e in enumerate(maneuvers)]
        chained, findings = chain_check(self, maneuvers, now)
        findings = [*maneuver_findings(maneuvers), *findings]  # what the sheet only implies
        if chained is not None:
            checks.append(chained)
        if recoveries:
            bad = [e for e in recoveries if not e["passed"]]
            checks.append({"name": "recovery turns", "passed": not bad, "value": len(recoveries), "required":
                           "no forward command or motion", "detail": f"{len(recoveries)} emergency-stop recovery "
                           f"turn{'s' if len(recoveries) != 1 else ''}, {len(bad)} with forward motion"})
        checks.append(creep_check(self, now))
        n = len(self.collisions)
        checks.append({"name": "no collision", "passed": n == 0, "value": n, "required": 0,
                       "detail": f"{n} collision{'s' if n != 1 else ''}"
                       + "".join(f", t={c[0] - t0:.1f} s ({c[1]:.2f}, {c[2]:.2f})" for c in self.collisions[:5])})
        checks.append(self._static_after_check(now, samples, limits))
        return {"passed": all(c["passed"] for c in checks), "checks": checks, "maneuver": cfg.maneuver,
                "maneuvers": maneuvers, "recovery_turns": recoveries, "travelled": round(self.travelled, 4),
                "max_distance_from_start": round(self.max_distance, 4), "collisions": n,
                "collision_events": [{"t": c[0] - t0, "x": c[1], "y": c[2]} for c in self.collisions],
                "times": {k: None if v is None else v - t0 for k, v in (
                    ("t0", self.t0), ("activation_requested", self.activation_requested),
                    ("activated", self.activated), ("cycle_off_requested", self.cycle_off_requested),
                    ("cycle_off", self.cycle_off), ("cycle_on_requested", self.cycle_on_requested),
                    ("cycle_on", self.cycle_on), ("deactivation_requested", self.deactivation_requested),
                    ("deactivated", self.deactivated), ("report", now))},
                "findings": [f["clause"] for f in findings], "finding_kinds": findings,
                "announcements": len(self.announcements),
                "evaluation_calls": self.evaluation_calls, "commands": len(self.commands),
                "samples": len(self._t), "done": self.done}

    def _static_after_check(self, now: float, samples: tuple[list[float], ...], limits: tuple[float, float]
                            ) -> dict[str, Any]:
        """Static for ``static_after`` after each disarm and its grace: the toggle cycle's (until its true) and
        the final one's; one check, both windows in its detail."""
        cfg, t0 = self.config, self.t0 or 0.0
        after = None if self.deactivation_requested is None else \
            self.disarmed_from(self.deactivation_requested, self.deactivated) + cfg.grace
        final = static_check("static after deactivation", samples, after,
                             None if after is None else min(now, after + cfg.static_after),
                             "the run ended before the deactivation", limits, t0)
        if self.cycle_off_requested is None:
            return final
        start = self.disarmed_from(self.cycle_off_requested, self.cycle_off) + cfg.grace
        rearm = self.cycle_on_requested if self.cycle_on_requested is not None else math.inf
        cycle = static_check("static after deactivation", samples, start, min(now, start + cfg.static_after, rearm),
                             "the run ended before the toggle cycle's deactivation", limits, t0)
        values = [c["value"] for c in (cycle, final)]
        return {**final, "passed": cycle["passed"] and final["passed"],
                "value": None if None in values else max(values),
                "detail": f"after the toggle cycle's false: {cycle['detail']}; "
                          f"after the final false: {final['detail']}"}

    def _answered_check(self) -> dict[str, Any]:
        """Every toggle_navigation call (true; the toggle cycle's false and true; the final false) was answered
        with success."""
        t0 = self.t0 or 0.0
        name = "toggle_navigation"
        calls = [(True, "true", self.activation_requested, self.activated),
                 (False, "false (toggle cycle)", self.cycle_off_requested, self.cycle_off),
                 (True, "true again", self.cycle_on_requested, self.cycle_on),
                 (False, "false", self.deactivation_requested, self.deactivated)]
        parts, ok = [], True
        for k, (data, words, requested, answered) in enumerate(calls):
            if requested is None and k > 0:
                continue
            ok = ok and answered is not None
            parts.append(f"{words} at t={answered - t0:.2f} s" if answered is not None
                         else self.answers.failed_text(name, data))
        ok = ok and self.deactivated is not None
        required = "true, false, true, false" if self.cycle_off_requested is not None else "true, then false"
        return {"name": "toggle_navigation answered", "passed": ok, "value": ok, "required": required,
                "detail": ", ".join(parts)}

    def report_lines(self) -> list[str]:
        """One line per check (``name (detail): PASSED|FAILED``), then the overall verdict."""
        res = self.results()
        lines = [f"{c['name']} ({c['detail']}): {'PASSED' if c['passed'] else 'FAILED'}" for c in res["checks"]]
        lines.append(f"overall: {'PASSED' if res['passed'] and self.done else 'FAILED'}")
        return lines


__all__ = ["CHECKS", "INTERRUPT_SLACK", "MANEUVERS", "MANEUVER_NAMES", "CheckoffConfig", "CheckoffJudge",
           "_forward_text", "maneuver_problems"]
