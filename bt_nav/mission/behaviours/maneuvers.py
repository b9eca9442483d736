"""The three evasive rotation maneuvers of the lab (A, B, C), each its own leaf.

All three share one closed-loop controller (:class:`RotationManeuver`): they differ only in how
much to turn, which they decide when they start. Rotation only — ``linear.x`` is exactly zero on
every tick of a maneuver. The angle turned is accumulated from odometry yaw increments (so a 180 deg
spin and the +-pi seam are no special cases); without fresh odometry the leaf integrates its own
commanded rate instead (open loop), and a time allowance ends a maneuver that cannot finish.
"""

from __future__ import annotations

import math
import random
from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import CMD_PORT, Condition, Leaf, port
from bt_nav.mission.behaviours.perception import PATHS_PORT, SECTORS_PORT
from bt_nav.mission.datatypes import NO_ODOM, OdomSample
from bt_nav.mission.paths import FreePaths
from bt_nav.mission.scan import Sectors, clearer_side
from bt_nav.mission.turning import TurnMeter, approach_rate

Status = py_trees.common.Status

ACTIVE_PORT = {"active": port(bool, "a maneuver is under way", default=False)}


class ManeuverActive(Condition):
    """Is a maneuver under way? Keeps its branch selected after the trigger has cleared."""

    INPUT_PORTS = dict(ACTIVE_PORT)
    OUTPUT_PORTS = {}

    def answer(self) -> bool:
        """``active`` as written by the maneuver leaf."""
        return bool(self.get_input("active"))


class RotationManeuver(Leaf, register=False):
    """Rotate in place by :meth:`choose_rotation` radians, closed loop on odometry yaw.

    SUCCESS when the remaining angle is within ``tolerance_deg``; FAILURE (with a stop) when the
    nominal time plus ``time_margin`` has passed. ``active`` is True from start to end, so the branch
    is not abandoned when the trigger clears mid-turn; a preemption (disarm, deadline) ends it through
    ``terminate`` with a zero twist.
    """

    INPUT_PORTS = {
        **SECTORS_PORT,
        "odom": port(OdomSample, "latest odometry yaw", default=NO_ODOM),
        "angular_speed": port(float, "peak turn rate", default=1.8),
        "tolerance_deg": port(float, default=3.0),
        "time_margin": port(float, default=2.0),
        "odom_timeout": port(float, default=0.5),
    }
    OUTPUT_PORTS = {**CMD_PORT, **ACTIVE_PORT}

    # rad/s^2: the approach slows as if braking at this rate (turning.approach_rate), so it is as fast as
    # it can be and still stops on the angle. The simulated Burger brakes at 10 rad/s^2; planning with 6
    # leaves room for the 20 Hz tick and the odometry lag. (A proportional approach, 6/s, took ~0.3 s
    # longer per maneuver.)
    DECEL = 6.0
    MIN_RATE = 0.3  # rad/s: below this a real base stalls; also bounds the approach time

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.rotation = 0.0
        self.meter = TurnMeter()
        self._allowance = 0.0
        self._open_loop_logged = False

    @property
    def turned(self) -> float:
        """Angle turned so far (rad)."""
        return self.meter.turned

    @property
    def open_loop_ticks(self) -> int:
        """Updates without fresh odometry past the timeout."""
        return self.meter.open_loop_ticks

    def choose_rotation(self, sectors: Sectors) -> float:
        """Signed angle to turn (rad, + is CCW / left), decided when the maneuver starts."""
        raise NotImplementedError

    def initialise(self) -> None:
        """Decide the rotation and start the clock."""
        self.rotation = self.choose_rotation(self.get_input("sectors"))
        self.meter.start(self.clock(), self.get_input("odom"), self.get_input("odom_timeout"))
        self._open_loop_logged = False
        rate = self.get_input("angular_speed")
        self._allowance = abs(self.rotation) / rate + 1.0 + self.get_input("time_margin")
        self._set_output("active", True)
        self.events.info(f"{self.label}: starting a {math.degrees(self.rotation):+.0f} deg rotation")

    def update(self) -> Status:
        """Advance the turn; RUNNING until within tolerance or out of time."""
        self.meter.measure(self.clock(), self.get_input("odom"), self.get_input("odom_timeout"))
        if self.meter.open_loop and not self._open_loop_logged:
            self._open_loop_logged = True
            self.events.warning(f"{self.label}: no fresh odometry — continuing open loop "
                                "(integrating the commanded turn rate)")
        remaining = self.rotation - self.turned
        if abs(remaining) <= math.radians(self.get_input("tolerance_deg")):
            return self._finish(Status.SUCCESS, f"done: turned {math.degrees(self.turned):+.1f} deg")
        if self.meter.elapsed > self._allowance:
            return self._finish(Status.FAILURE, f"out of time after {self.meter.elapsed:.1f} s, "
                                f"{math.degrees(remaining):+.0f} deg short")
        self.meter.rate = approach_rate(remaining, self.get_input("angular_speed"), self.DECEL, self.MIN_RATE)
        self.command(0.0, self.meter.rate)
        self.feedback_message = f"{math.degrees(remaining):+.0f} deg to go"
        return Status.RUNNING

    def _finish(self, status: Status, message: str) -> Status:
        self.command(0.0, 0.0)
        self.meter.rate = 0.0
        self._set_output("active", False)
        self.feedback_message = message
        if status == Status.SUCCESS:  # two call sites: rclpy refuses one call site with two severities
            self.events.info(f"{self.label}: {message}")
        else:
            self.events.warning(f"{self.label}: {message}")
        return status

    def terminate(self, new_status: Status) -> None:
        """Preempted (disarm, deadline, shutdown): stop turning and release the branch."""
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.command(0.0, 0.0)
            self._set_output("active", False)
            self.events.info(f"{self.label}: preempted, stopped")


class RandomizerManeuver(RotationManeuver):
    """A — The Randomizer: a random side, a random angle between 90 and 180 deg (seedable)."""

    MIN_DEG, MAX_DEG = 90.0, 180.0

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.rng = random.Random()

    def setup(self, **kwargs: Any) -> None:
        """Seed the generator from ``random_seed`` (None or -1: from the OS)."""
        super().setup(**kwargs)
        seed = kwargs.get("random_seed")
        self.rng = random.Random(None if seed is None or seed < 0 else seed)

    def choose_rotation(self, sectors: Sectors) -> float:
        """Random side, random magnitude."""
        side = self.rng.choice((-1.0, 1.0))
        return side * math.radians(self.rng.uniform(self.MIN_DEG, self.MAX_DEG))


class RetreatManeuver(RotationManeuver):
    """B — The Retreat: squeezed left and right, spin 180 deg.

    Either way round ends facing back, so the spin goes the way the robot is already turning (the last
    command's turn, when it was turning at all): reversing a rotation in place first costs ~0.5 s and
    ~35 deg of extra turn. A robot not turning spins towards the clearer side.
    """

    #: rad/s: a last command turning slower than this does not choose the way round.
    TURNING = 0.1

    def choose_rotation(self, sectors: Sectors) -> float:
        """Half a turn."""
        turning = getattr(self.last_output("cmd_vel"), "angular", 0.0)
        side = math.copysign(1.0, turning) if abs(turning) >= self.TURNING else clearer_side(sectors)
        return side * math.pi


class SmartPivotManeuver(RotationManeuver):
    """C — The Smart Pivot: 90 deg towards whichever side reads the larger distance.

    The lab's "distance reading" of a side is taken where the robot will face after the quarter turn:
    the free path of the robot's width along +-90 deg. Comparing the side cones beside the front instead
    turned a robot in a corner towards the near wall, and the rotation in place that followed undid the
    pivot and more. Equal readings (both clear to the horizon, or no paths yet) fall back to the cones.
    """

    INPUT_PORTS = {**RotationManeuver.INPUT_PORTS, **PATHS_PORT}

    def choose_rotation(self, sectors: Sectors) -> float:
        """A quarter turn to the clearer side."""
        paths: FreePaths = self.get_input("paths")
        left, right = paths.along(math.pi / 2), paths.along(-math.pi / 2)
        side = clearer_side(sectors) if math.isclose(left, right, abs_tol=1e-3) else (1 if left > right else -1)
        return side * math.pi / 2


class AlwaysFailure(Leaf):
    """BT.CPP ``AlwaysFailure``: the maneuver slot when no maneuver is chosen."""

    INPUT_PORTS = {}
    OUTPUT_PORTS = {}

    def update(self) -> Status:
        """FAILURE, so the priority list moves on."""
        return Status.FAILURE
