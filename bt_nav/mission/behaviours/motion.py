"""Motion leaves: each one writes the velocity command of the branch that won this tick.

Turning directions are chosen when a leaf starts (``initialise``) and kept while it keeps running:
re-deciding every tick makes a robot facing a wall square-on dither left-right forever.
"""

from __future__ import annotations

from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import CMD_PORT, Leaf, port
from bt_nav.mission.behaviours.perception import SECTORS_PORT
from bt_nav.mission.scan import SectorReading, Sectors, clearer_side

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
    """Straight ahead at ``speed`` (nothing in front)."""

    INPUT_PORTS = {"speed": port(float, default=0.22)}
    OUTPUT_PORTS = dict(CMD_PORT)

    def update(self) -> Status:
        """Full speed, RUNNING (driving is never "done")."""
        self.command(self.get_input("speed"), 0.0)
        return Status.RUNNING


def _turn_direction(sectors: Sectors) -> float:
    """+1 turns left (CCW), -1 right: towards the clearer half of the front."""
    return float(clearer_side(sectors))


def _side_range(reading: SectorReading) -> float:
    """A side's nearest obstacle for choosing a direction; unknown reads 0 (never turn into the unseen)."""
    return reading.min_range if reading.known else 0.0


class TurnAway(Leaf):
    """Keep driving while turning away from the closer side (obstacle in the far band).

    Speed and turn rate are graded by how deep into the band the obstacle is: at ``far_distance`` the
    robot drives at ``max_speed`` and turns gently; towards ``close_distance`` it slows to ``slow_speed``
    and turns at ``angular_speed``. Grading rather than a step keeps the average speed high, which is
    what the 8 m in 50 s requirement needs: travelled distance counts arcs, so a hard turn at speed
    costs nothing while a stop or a rotation in place costs its whole duration. The speed falls with
    the square of the depth so it stays near ``max_speed`` until the obstacle is really close.

    The direction is chosen when the leaf starts and kept, with hysteresis: it flips only when the side
    being turned towards has become nearer than the other by ``SWITCH_MARGIN``. Keeping it blindly
    (the first version) made the robot sweep across a wide far band from one obstacle into the next;
    re-deciding every tick makes a robot facing a wall square-on dither.
    """

    #: m: the side turned towards must be this much nearer than the other before the direction flips.
    SWITCH_MARGIN = 0.15
    #: Turn rate at the far edge of the band, as a fraction of ``angular_speed``.
    MIN_TURN = 0.3
    #: Speed falls as depth ** SPEED_EXPONENT (1: linear in depth).
    SPEED_EXPONENT = 2.0

    INPUT_PORTS = {
        **SECTORS_PORT,
        "slow_speed": port(float, default=0.12),
        "max_speed": port(float, default=0.22),
        "angular_speed": port(float, default=1.5),
        "close_distance": port(float, default=0.3),
        "far_distance": port(float, default=0.7),
    }
    OUTPUT_PORTS = dict(CMD_PORT)

    def initialise(self) -> None:
        """Pick the side to turn towards (kept unless the other side becomes clearly better)."""
        self.direction = _turn_direction(self.get_input("sectors"))

    def update(self) -> Status:
        """Graded forward speed and turn rate, RUNNING."""
        sectors: Sectors = self.get_input("sectors")
        left, right = _side_range(sectors.left), _side_range(sectors.right)
        chosen, other = (left, right) if self.direction > 0 else (right, left)
        if other > chosen + self.SWITCH_MARGIN:
            self.direction = -self.direction
        close, far = self.get_input("close_distance"), self.get_input("far_distance")
        front = sectors.front.min_range if sectors.front.known else close
        depth = min(1.0, max(0.0, (far - front) / max(far - close, 1e-6)))
        slow, fast = self.get_input("slow_speed"), self.get_input("max_speed")
        linear = fast - (fast - slow) * depth ** self.SPEED_EXPONENT
        angular = self.direction * self.get_input("angular_speed") * (self.MIN_TURN + (1.0 - self.MIN_TURN) * depth)
        self.command(linear, angular)
        self.feedback_message = f"turning {'left' if self.direction > 0 else 'right'}"
        return Status.RUNNING


class RotateInPlace(Leaf):
    """Zero forward speed, turn towards the clearer side (obstacle close, or front unknown)."""

    INPUT_PORTS = {**SECTORS_PORT, "angular_speed": port(float, default=1.5)}
    OUTPUT_PORTS = dict(CMD_PORT)

    def initialise(self) -> None:
        """Pick the rotation direction for this whole rotation."""
        self.direction = _turn_direction(self.get_input("sectors"))

    def update(self) -> Status:
        """Rotate, RUNNING."""
        self.command(0.0, self.direction * self.get_input("angular_speed"))
        self.feedback_message = f"rotating {'left' if self.direction > 0 else 'right'}"
        return Status.RUNNING
