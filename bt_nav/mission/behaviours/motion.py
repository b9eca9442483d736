"""Motion leaves: each one writes the velocity command of the branch that won this tick.

Turning directions are chosen when a leaf starts (``initialise``) and kept while it keeps running:
re-deciding every tick makes a robot facing a wall square-on dither left-right forever.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import CMD_PORT, Leaf, port
from bt_nav.mission.behaviours.perception import PATHS_PORT
from bt_nav.mission.paths import FreePaths

Status = py_trees.common.Status


class Stop(Leaf):
    """Command an exact zero twist; ``reason`` names why in traces and logs."""

    INPUT_PORTS = {}
    OUTPUT_PORTS = dict(CMD_PORT)
    ATTRIBUTES = ("reason",)  # constructor arguments set in the tree file (listed for Groot2's model)

    def __init__(self, name: str, reason: str = "stop", **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.reason = reason

    def update(self) -> Status:
        """Zero twist, SUCCESS."""
        self.command(0.0, 0.0)
        self.feedback_message = self.reason
        return Status.SUCCESS


class DriveForward(Leaf):
    """Full speed: nothing in the robot's path within ``far_distance``.

    It still steers, gently, for the heading :meth:`~bt_nav.mission.paths.FreePaths.steer` picks: straight
    ahead in the open, the middle of a corridor between two walls. Without it a robot that drifts
    towards a wall finds its path blocked late and has to turn hard.
    """

    INPUT_PORTS = {
        "speed": port(float, default=0.22),
        **PATHS_PORT,
        "far_distance": port(float, default=0.7),
        "angular_speed": port(float, default=1.5),
    }
    OUTPUT_PORTS = dict(CMD_PORT)
    #: m per rad: at full speed only small corrections pay (keeping clear of a wall), not chasing room.
    TURN_COST = 1.5

    def update(self) -> Status:
        """Full speed, steering towards the clear heading; RUNNING (driving is never "done")."""
        paths: FreePaths = self.get_input("paths")
        target = paths.steer(self.get_input("far_distance"), turn_cost=self.TURN_COST)
        self.command(self.get_input("speed"), steering(target or 0.0, self.get_input("angular_speed")))
        return Status.RUNNING


#: 1/s: turn rate per radian of heading error when steering for a clear heading.
STEER_GAIN = 2.5


def steering(target: float, limit: float) -> float:
    """Turn rate towards ``target`` (rad, robot frame), proportional and capped at ``limit``."""
    return max(-limit, min(limit, STEER_GAIN * target))


def initial_side(paths: FreePaths, need: float) -> float:
    """+1 (left) or -1 (right): the side of the heading to steer for; when that is straight ahead or no
    heading is clear, the side with more room (ties go left, as :func:`~bt_nav.mission.scan.clearer_side`)."""
    target = paths.steer(need)
    if target:
        return 1.0 if target > 0.0 else -1.0
    return 1.0 if paths.side_room(1) >= paths.side_room(-1) else -1.0


@dataclass(frozen=True, slots=True)
class TurnSide:
    """The side (+1 left, -1 right) the last avoiding leaf turned to, and when (mission clock s)."""

    side: float = 0.0
    stamp: float = -math.inf
    in_place: bool = False  # written by a rotation in place (not by steering)


#: Written by both avoiding leaves and read back by both (an output port: py_trees refuses a port that is
#: both input and output).
TURN_SIDE_PORT = {"turn_side": port(TurnSide, "the side the last avoiding leaf turned to, and when",
                                    default=TurnSide())}
#: s: an avoiding leaf (TurnAway, RotateInPlace) that starts within this of the last avoiding tick of
#: either starts on that side (unless :func:`keep_or_switch` finds the other side much better). Each
#: choosing afresh made a robot in a corner rotate one way in place, steer the other way at speed, and
#: again, for seconds.
SIDE_MEMORY = 0.5


#: rad: the other side must need this much less turning to override a remembered side (or, in
#: :class:`TurnAway`, the side it runs with).
SWITCH_MARGIN = math.radians(30.0)


def remembered_side(leaf: Leaf, paths: FreePaths, need: float) -> float:
    """The side an avoiding leaf starts with: the recent one unless the other side needs ``SWITCH_MARGIN``
    less turning to a heading clear for ``need`` (a rotation in place resuming another one keeps it
    outright); with no recent one, :func:`initial_side`."""
    memory: TurnSide = leaf.last_output("turn_side", TurnSide())
    if not memory.side or leaf.clock() - memory.stamp > SIDE_MEMORY:
        return initial_side(paths, need)
    if memory.in_place and isinstance(leaf, RotateInPlace):
        return memory.side  # a rotation resumed after a blip of driving goes on the same way
    return keep_or_switch(paths, need, memory.side)


def keep_or_switch(paths: FreePaths, need: float, side: float) -> float:
    """``side``, unless the other side has a heading clear for ``need`` that is ``SWITCH_MARGIN`` less turn."""
    kept, other = paths.steer(need, side=int(side)), paths.steer(need, side=-int(side))
    if other is not None and (kept is None or abs(other) + SWITCH_MARGIN < abs(kept)):
        return -side
    return side


class TurnAway(Leaf):
    """Keep driving while steering for the nearest clear heading (the path is blocked in the far band).

    The heading is the one :meth:`~bt_nav.mission.paths.FreePaths.steer` gives: the smallest turn that
    clears ``far_distance`` for the robot's whole width, so the robot turns no more than it must (on a
    wheel-limited base every radian turned at speed costs distance). Speed is graded by how deep into the
    band the path is blocked: ``max_speed`` at ``far_distance``, falling with the square of the depth to
    ``slow_speed`` at ``close_distance``, so it stays near full speed until the obstacle is really close.

    The side (left or right) is chosen when the leaf starts and kept: it flips only when the other side
    needs :data:`SWITCH_MARGIN` less turning (:func:`keep_or_switch`). Re-deciding every tick makes a
    robot facing a wall square-on dither left and right.
    """

    #: Speed falls as depth ** SPEED_EXPONENT (1: linear in depth).
    SPEED_EXPONENT = 2.0

    INPUT_PORTS = {
        **PATHS_PORT,
        "slow_speed": port(float, default=0.12),
        "max_speed": port(float, default=0.22),
        "angular_speed": port(float, default=1.5),
        "close_distance": port(float, default=0.3),
        "far_distance": port(float, default=0.7),
    }
    OUTPUT_PORTS = {**CMD_PORT, **TURN_SIDE_PORT}

    def initialise(self) -> None:
        """Pick the side to turn towards (kept unless the other side becomes clearly better)."""
        self.direction = remembered_side(self, self.get_input("paths"), self.get_input("far_distance"))

    def update(self) -> Status:
        """Graded forward speed, steering for the clear heading on the chosen side; RUNNING."""
        paths: FreePaths = self.get_input("paths")
        close, far = self.get_input("close_distance"), self.get_input("far_distance")
        self.direction = keep_or_switch(paths, far, self.direction)
        target = paths.steer(far, side=int(self.direction))
        if target is None:  # nothing clear for far_distance either way: towards the most room on this side
            target = paths.roomiest(int(self.direction))
        depth = min(1.0, max(0.0, (far - paths.ahead) / max(far - close, 1e-6)))
        slow, fast = self.get_input("slow_speed"), self.get_input("max_speed")
        linear = fast - (fast - slow) * depth ** self.SPEED_EXPONENT
        self.command(linear, steering(target, self.get_input("angular_speed")))
        self._set_output("turn_side", TurnSide(self.direction, self.clock()))
        self.feedback_message = f"steering {math.degrees(target):+.0f} deg"
        return Status.RUNNING


class RotateInPlace(Leaf):
    """Zero forward speed, turn towards the side with the clear heading (path blocked close, or front unknown)."""

    INPUT_PORTS = {**PATHS_PORT, "angular_speed": port(float, default=1.5), "far_distance": port(float, default=0.7)}
    OUTPUT_PORTS = {**CMD_PORT, **TURN_SIDE_PORT}

    def initialise(self) -> None:
        """Pick the rotation direction for this whole rotation."""
        self.direction = remembered_side(self, self.get_input("paths"), self.get_input("far_distance"))

    def update(self) -> Status:
        """Rotate, RUNNING."""
        self._set_output("turn_side", TurnSide(self.direction, self.clock(), in_place=True))
        self.command(0.0, self.direction * self.get_input("angular_speed"))
        self.feedback_message = f"rotating {'left' if self.direction > 0 else 'right'}"
        return Status.RUNNING
