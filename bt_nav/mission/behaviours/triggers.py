"""Maneuver triggers: the lab's conditions, fired on their rising edge so that they cannot trap the robot.

The lab says: A and C fire when the front is nearer than their distance, B when left AND right are.
Taken literally ("fire whenever it holds"), a condition that persists re-fires the maneuver the moment it
ends: in a 0.8 m corridor both sides are within 0.5 m everywhere, so B spins 180 deg forever and the
robot never leaves its spot. A trigger here fires on the condition's rising edge and then stays quiet
(the reactive close / far / none branches drive meanwhile) until it re-arms, which takes either

- the condition seen cleared with hysteresis: the reading rose above ``distance + hysteresis`` (a reading
  hovering around the threshold is not a new situation; for B one side is enough: no longer squeezed), or
- ``rearm_distance`` metres driven since it fired (0 turns this rule off). The maneuvers rotate on the
  spot, so this is the distance driven since the maneuver ended; it bounds how often a condition that
  never clears (an endless corridor) can fire: once per ``rearm_distance``. Odometry positions measure
  it (the path length, sample to sample); while the odometry has no position (NaN) or is older than
  ``odom_timeout`` the commanded speed is integrated instead (the command in force since the previous
  tick), so the rule works on a robot without odometry too, never counting a stop as motion.

A new arming (``arm_count`` changes) is a fresh start: the trigger is armed, so a condition that already
holds then fires at once (a robot armed beside a wall meets a new situation). A trigger that has never
been ticked is armed too. An unknown reading (too few beams with a return) neither fires nor clears a
trigger: the sheet's conditions are readings ("front < safety_distance"), and what a TurtleBot3's LDS-01
(0.0) and LDS-02 (NaN) publish for a sector with nothing within range is no reading at all. Firing there
spun the robot in any room wider than the LiDAR's 3.5 m (and fired B beside one wall with open space on
the other side). Not driving blind is the other branches' job: the homework's close branch rotates in
place on an unknown front, the lab creeps at ``creep_speed`` and brakes on any return in its path. The
latch is :class:`EdgeLatch`, pure state with no py_trees in it.

With ``repeat`` (the lab's front triggers) the trigger is level-triggered instead: it is only ticked when
no maneuver runs, so a front still blocked after a turn fires the next turn, until the front is clear.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import py_trees

from bt_nav.mission.behaviours.base import Condition, port
from bt_nav.mission.behaviours.perception import SECTORS_PORT
from bt_nav.mission.datatypes import NO_ODOM, Command, OdomSample
from bt_nav.mission.scan import SectorReading, Sectors

Status = py_trees.common.Status


@dataclass(frozen=True)
class Rearm:
    """When a fired trigger re-arms: ``clear_away`` metres from where it fired for a clearing to count,
    or after ``distance`` metres driven (0: never by driving)."""

    clear_away: float
    distance: float


@dataclass
class EdgeLatch:
    """Rising-edge detector that re-arms on clearing or after driving (see the module docstring)."""

    armed: bool = True
    driven: float = 0.0  # metres driven since the last firing (path length)
    fired_at: tuple[float, float] | None = None  # odometry position of the last firing (None: unknown)
    position: tuple[float, float] | None = None  # latest known odometry position
    fresh: bool = True  # not fired since the last arming: a clearing anywhere arms

    @property
    def away(self) -> float:
        """Straight-line distance from the last firing; the path driven when positions are unknown."""
        if self.fired_at is None or self.position is None:
            return self.driven
        return math.hypot(self.position[0] - self.fired_at[0], self.position[1] - self.fired_at[1])

    def step(self, holds: bool, cleared: bool, rearm: Rearm) -> bool:
        """One observation; True when the trigger fires now (and the latch disarms)."""
        if not self.armed and ((cleared and (self.fresh or self.away >= rearm.clear_away))
                               or 0.0 < rearm.distance <= self.driven):
            self.armed = True
        if self.armed and holds:
            self.armed, self.fresh, self.driven, self.fired_at = False, False, 0.0, self.position
            return True
        return False

    def reset(self, fire_at_once: bool = True) -> None:
        """A fresh start (a new arming). ``fire_at_once``: armed, so a condition that already holds fires
        now; otherwise the latch waits until it sees the condition clear (anywhere) first."""
        self.armed, self.fresh, self.driven, self.fired_at = fire_at_once, True, 0.0, None


class Odometer:
    """Metres driven: odometry path length, or the commanded speed integrated when positions are unknown.

    One observation per tick. A position counts only when it is finite and its sample fresh; a gap (no
    position, stale odometry) is bridged by dead reckoning, and the first position after a gap starts a
    new chain instead of adding the jump, so nothing is counted twice.
    """

    #: A longer pause between observations (a stalled clock, a leaf not ticked) is not counted as motion.
    MAX_DT = 0.5

    def __init__(self) -> None:
        self.position: tuple[float, float] | None = None  # the latest fresh position (None: unknown)
        self._stamp = -math.inf
        self._time: float | None = None

    def observe(self, now: float, odom: OdomSample, odom_timeout: float, command: Command) -> float:
        """Advance to ``now``; returns the metres added."""
        dt = 0.0 if self._time is None else min(max(0.0, now - self._time), self.MAX_DT)
        self._time = now
        fresh = abs(now - odom.stamp) <= odom_timeout
        added = 0.0
        if fresh and math.isfinite(odom.x) and math.isfinite(odom.y):
            if odom.stamp != self._stamp:
                if self.position is not None:
                    added = math.hypot(odom.x - self.position[0], odom.y - self.position[1])
                self.position, self._stamp = (odom.x, odom.y), odom.stamp
        else:
            self.position = None
            speed = abs(command.linear) if math.isfinite(command.linear) else 0.0
            added = speed * dt
        return added


def _near(reading: SectorReading, distance: float) -> bool:
    """Known and nearer than ``distance`` (an unknown sector is no reading: see the module docstring)."""
    return reading.known and reading.min_range < distance


def _clear(reading: SectorReading, distance: float) -> bool:
    """Known and farther than ``distance``."""
    return reading.known and reading.min_range > distance


class _EdgeTrigger(Condition, register=False):
    """SUCCESS on the tick the condition's rising edge is seen; FAILURE otherwise."""

    INPUT_PORTS = {
        **SECTORS_PORT,
        "distance": port(float, "the lab's trigger distance", default=0.5),
        "hysteresis": port(float, "re-arm once the reading exceeds distance + hysteresis", default=0.1),
        "clear_away": port(float, "a clearing re-arms only this far (straight line) from the last firing",
                           default=1.5),
        "rearm_distance": port(float, "re-arm after driving this far since firing (0: only on clearing)",
                               default=5.0),
        "odom": port(OdomSample, "odometry pose (metres driven since firing)", default=NO_ODOM),
        "odom_timeout": port(float, "older odometry: integrate the commanded speed instead", default=0.5),
        "cmd_vel": port(Command, "the command in force since the previous tick (dead reckoning)",
                        default=Command()),
        "arm_count": port(int, "a new arming re-arms the trigger", default=0),
        "fire_at_arming": port(bool, "a condition already holding at an arming fires (else: wait for a clear)",
                               default=True),
        "repeat": port(bool, "a condition still holding after the maneuver fires again (level, not edge)",
                       default=False),
    }
    OUTPUT_PORTS = {}

    def __init__(self, name: str, **kwargs: object) -> None:
        super().__init__(name=name, **kwargs)
        self.latch = EdgeLatch()
        self.odometer = Odometer()
        self._arm_count = 0

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """The lab's condition."""
        raise NotImplementedError

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """The condition is over, beyond the hysteresis band."""
        raise NotImplementedError

    def answer(self) -> bool:
        """Observe this tick's readings and motion; fire on a rising edge."""
        arm_count = int(self.get_input("arm_count"))
        if arm_count != self._arm_count:
            self.latch.reset(bool(self.get_input("fire_at_arming")))
            self._arm_count = arm_count
        self.latch.driven += self.odometer.observe(self.clock(), self.get_input("odom"),
                                                   float(self.get_input("odom_timeout")),
                                                   self.get_input("cmd_vel"))
        self.latch.position = self.odometer.position
        sectors, distance = self.get_input("sectors"), float(self.get_input("distance"))
        rearm = Rearm(float(self.get_input("clear_away")), float(self.get_input("rearm_distance")))
        if self.get_input("repeat"):
            self.latch.armed = True  # level-triggered: the maneuver is over when this leaf is ticked again
        fired = self.latch.step(self.holds(sectors, distance),
                                self.cleared(sectors, distance + float(self.get_input("hysteresis"))), rearm)
        if fired:
            self.feedback_message = "fired"
        elif self.latch.armed:
            self.feedback_message = "armed"
        else:
            self.feedback_message = (f"waiting to re-arm ({self.latch.away:.1f} m from the last firing, "
                                     f"{self.latch.driven:.1f} of {rearm.distance:.1f} m driven)")
        return fired


class FrontTrigger(_EdgeTrigger):
    """Front sector nearer than ``distance``, on its rising edge: the trigger of every maneuver whose
    spec's trigger reads ``front`` (:mod:`bt_nav.mission.maneuver_spec`; A and C)."""

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """Front near."""
        return _near(sectors.front, distance)

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """Front clear."""
        return _clear(sectors.front, distance)


class SqueezeTrigger(_EdgeTrigger):
    """Left AND right sectors nearer than ``distance``, on its rising edge: the trigger of every maneuver
    whose spec's trigger reads ``sides`` (B)."""

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """Both sides near."""
        return _near(sectors.left, distance) and _near(sectors.right, distance)

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """At least one side clear: no longer squeezed."""
        return _clear(sectors.left, distance) or _clear(sectors.right, distance)
