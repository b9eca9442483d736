"""Maneuver triggers: the lab's conditions, fired on their rising edge so that they cannot trap the robot.

The lab says: A and C fire when the front is nearer than their distance, B when left AND right are.
Taken literally ("fire whenever it holds"), a condition that persists re-fires the maneuver the moment it
ends: in a 0.8 m corridor both sides are within 0.5 m everywhere, so B spins 180 deg forever and the
robot never leaves its spot. A trigger here fires on the condition's rising edge and then stays quiet
(the reactive close / far / none branches drive meanwhile) until it re-arms, which takes both

- the condition seen cleared with hysteresis: the reading rose above ``distance + hysteresis`` (a reading
  hovering around the threshold is not a new situation), and
- the robot at least ``rearm_distance`` metres (straight line, odometry) from where the trigger last
  fired: turning on the spot sweeps the sectors across walls and openings, which changes what they
  read but not where the robot is, and coming back to the same doorway is not a new situation either.

A new arming (``arm_count`` changes) starts afresh: the trigger arms as soon as the condition is seen
clear, so a condition that already holds when the robot is armed is not a rising edge (a robot armed in
a corridor does not spin at once). An unknown reading counts as "near" (never drive into what cannot be
seen) and never as "cleared". Without odometry positions the distance rule is skipped. The latch is
:class:`EdgeLatch`, pure state with no py_trees in it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import py_trees

from bt_nav.mission.behaviours.base import Condition, port
from bt_nav.mission.behaviours.perception import SECTORS_PORT
from bt_nav.mission.datatypes import NO_ODOM, OdomSample
from bt_nav.mission.scan import SectorReading, Sectors

Status = py_trees.common.Status


@dataclass
class EdgeLatch:
    """Rising-edge detector that re-arms on clearing away from where it fired (see the module docstring)."""

    armed: bool = False
    fired_at: tuple[float, float] | None = None  # odometry position of the last firing (None: none yet)
    position: tuple[float, float] | None = None  # latest known odometry position

    def odometry(self, x: float, y: float) -> None:
        """The robot's latest position (NaN positions are skipped)."""
        if math.isfinite(x) and math.isfinite(y):
            self.position = (x, y)

    @property
    def away(self) -> float:
        """Straight-line distance from the last firing (inf when there was none or positions are unknown)."""
        if self.fired_at is None or self.position is None:
            return math.inf
        return math.hypot(self.position[0] - self.fired_at[0], self.position[1] - self.fired_at[1])

    def step(self, holds: bool, cleared: bool, rearm_distance: float) -> bool:
        """One observation; True when the trigger fires now (and the latch disarms)."""
        if not self.armed and cleared and self.away >= rearm_distance:
            self.armed = True
        if self.armed and holds:
            self.armed = False
            self.fired_at = self.position if self.position is not None else None
            return True
        return False

    def reset(self) -> None:
        """A fresh start (a new arming): armed as soon as the condition is seen clear, wherever the robot is,
        so a condition that already holds when the robot is armed is not a rising edge."""
        self.armed, self.fired_at = False, None


def _near(reading: SectorReading, distance: float) -> bool:
    """Nearer than ``distance``, or unknown."""
    return not reading.known or reading.min_range < distance


def _clear(reading: SectorReading, distance: float) -> bool:
    """Known and farther than ``distance``."""
    return reading.known and reading.min_range > distance


class _EdgeTrigger(Condition, register=False):
    """SUCCESS on the tick the condition's rising edge is seen; FAILURE otherwise."""

    INPUT_PORTS = {
        **SECTORS_PORT,
        "distance": port(float, "the lab's trigger distance", default=0.5),
        "hysteresis": port(float, "re-arm once the reading exceeds distance + hysteresis", default=0.1),
        "rearm_distance": port(float, "re-arm after driving this far (0: only on clearing)", default=3.0),
        "odom": port(OdomSample, "odometry pose (path driven since firing)", default=NO_ODOM),
        "arm_count": port(int, "a new arming re-arms the trigger", default=0),
    }
    OUTPUT_PORTS = {}

    def __init__(self, name: str, **kwargs: object) -> None:
        super().__init__(name=name, **kwargs)
        self.latch = EdgeLatch()
        self._arm_count = 0
        self._odom_stamp = -math.inf

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """The lab's condition."""
        raise NotImplementedError

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """The condition is over, beyond the hysteresis band."""
        raise NotImplementedError

    def answer(self) -> bool:
        """Observe this tick's readings and odometry; fire on a rising edge."""
        arm_count = int(self.get_input("arm_count"))
        if arm_count != self._arm_count:
            self.latch.reset()
            self._arm_count = arm_count
        odom: OdomSample = self.get_input("odom")
        if odom.stamp != self._odom_stamp:
            self._odom_stamp = odom.stamp
            self.latch.odometry(odom.x, odom.y)
        sectors, distance = self.get_input("sectors"), float(self.get_input("distance"))
        fired = self.latch.step(self.holds(sectors, distance),
                                self.cleared(sectors, distance + float(self.get_input("hysteresis"))),
                                float(self.get_input("rearm_distance")))
        away = self.latch.away
        self.feedback_message = ("fired" if fired else "armed" if self.latch.armed else
                                 "waiting to re-arm" + (f" ({away:.1f} m from where it fired)"
                                                        if math.isfinite(away) else ""))
        return fired


class FrontTrigger(_EdgeTrigger):
    """Front sector nearer than ``distance`` (or unknown), on its rising edge: maneuvers A and C."""

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """Front near."""
        return _near(sectors.front, distance)

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """Front clear."""
        return _clear(sectors.front, distance)


class SqueezeTrigger(_EdgeTrigger):
    """Left AND right sectors nearer than ``distance`` (or unknown), on its rising edge: maneuver B."""

    def holds(self, sectors: Sectors, distance: float) -> bool:
        """Both sides near."""
        return _near(sectors.left, distance) and _near(sectors.right, distance)

    def cleared(self, sectors: Sectors, distance: float) -> bool:
        """At least one side clear: no longer squeezed."""
        return _clear(sectors.left, distance) or _clear(sectors.right, distance)
