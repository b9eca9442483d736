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
from bt_nav.mission.behaviours.motion import TURN_SIDE_PORT, TurnSide
from bt_nav.mission.behaviours.perception import PATHS_PORT, SECTORS_PORT
from bt_nav.mission.datatypes import NO_ODOM, Command, OdomSample
from bt_nav.mission.paths import FreePaths
from bt_nav.mission.scan import SectorReading, Sectors, clearer_side
from bt_nav.mission.snapshot import TO_GO
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

    With an actuation ``latency`` (a real base) the turn is measured and stopped on what the wheels will
    have done (:meth:`TurnMeter.pending`), and the maneuver is framed by two stills of ``latency`` +
    :data:`SETTLE` seconds: before the turn when the robot was moving (so the rotation starts from rest:
    no forward motion left in it) and after it (so the angle is read once the robot has stopped, and the
    next command finds it still; it ends once a scan taken after that has arrived, so the triggers do not
    judge the front by a scan from mid-turn). Without latency both are skipped (the homework's tuning).

    At its end a maneuver with :attr:`HANDS_OVER_SIDE` writes ``turn_side`` (the side it turned, as a rotation
    in place): a front still close after it is then rotated away from on the same side
    (:func:`~bt_nav.mission.behaviours.motion.remembered_side`), instead of undoing the maneuver's turn and
    more (cluttered, 20 seeds: the Smart Pivot's quarter turn undone by a rotation back into the pocket it
    had turned away from cost two runs the 8 m).
    """

    INPUT_PORTS = {
        **SECTORS_PORT,
        "odom": port(OdomSample, "latest odometry yaw", default=NO_ODOM),
        "angular_speed": port(float, "peak turn rate", default=1.8),
        "tolerance_deg": port(float, default=3.0),
        "time_margin": port(float, default=2.0),
        "odom_timeout": port(float, default=0.5),
        "latency": port(float, "expected time between a command and the wheels", default=0.0),
        "scan_stamp": port(float, "when the newest scan arrived (a lagging turn ends on a scan taken at rest)",
                           default=-math.inf),
        "scan_timeout": port(float, "longest wait for that scan", default=0.5),
    }
    OUTPUT_PORTS = {**CMD_PORT, **ACTIVE_PORT, **TURN_SIDE_PORT}

    # rad/s^2: the approach slows as if braking at this rate (turning.approach_rate), so it is as fast as
    # it can be and still stops on the angle. The simulated Burger brakes at 10 rad/s^2; planning with 6
    # leaves room for the 20 Hz tick and the odometry lag. (A proportional approach, 6/s, took ~0.3 s
    # longer per maneuver.)
    DECEL = 6.0
    #: rad/s^2 with an actuation latency: the turn ends at the rate sqrt(2 DECEL tolerance), and what the
    #: latency is misjudged by, times that rate, is the error left in the angle; braking more gently ends
    #: slower (0.45 rad/s instead of 0.8 at a 3 deg tolerance), so a 0.05 s misjudgement costs 1.3 deg.
    DECEL_LAGGED = 2.0
    MIN_RATE = 0.3  # rad/s: below this a real base stalls; also bounds the approach time
    #: s beyond the latency that the robot is given to come to rest (the base's own deceleration).
    SETTLE = 0.1
    #: Does the side this maneuver turned say where the room is (so the avoiding leaves keep it)?
    HANDS_OVER_SIDE = True

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.rotation = 0.0
        self.meter = TurnMeter()
        self._allowance = 0.0
        self._open_loop_logged = False
        self._phase = "turn"  # "still" (before), "turn", "settle" (after)
        self._phase_end = 0.0

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

    def reading(self, sectors: Sectors) -> str:
        """The trigger's reading that started the maneuver, for the log line (e.g. ``front 0.47 m``)."""
        return _range_text("front", sectors.front)

    def initialise(self) -> None:
        """Decide the rotation; start turning now, or after a still when the robot moves and lags."""
        sectors = self.get_input("sectors")
        self.rotation = self.choose_rotation(sectors)
        self._open_loop_logged = False
        self._set_output("active", True)
        side, degrees = "left" if self.rotation > 0 else "right", f"{abs(math.degrees(self.rotation)):.0f}"
        self.tell("maneuver", f"{self.reading(sectors)}: turning {side} {degrees} deg", side=side,
                  angle_deg=float(degrees), readings=sector_readings(sectors))
        latency = float(self.get_input("latency"))
        moving = not self.last_output("cmd_vel", Command()).is_zero
        if latency > 0.0 and moving:
            self._phase, self._phase_end = "still", self.clock() + latency + self.SETTLE
        else:
            self._start_turn()

    def _start_turn(self) -> None:
        self._phase = "turn"
        self.meter.start(self.clock(), self.get_input("odom"), self.get_input("odom_timeout"),
                         float(self.get_input("latency")))
        rate = self.get_input("angular_speed")
        self._allowance = abs(self.rotation) / rate + 1.0 + self.get_input("time_margin")

    def update(self) -> Status:
        """Advance the turn; RUNNING until within tolerance (and still) or out of time."""
        if self._phase == "still":
            if self.clock() < self._phase_end:  # says what comes: the only snapshot a video may have of it
                side = "left" if self.rotation > 0 else "right"
                return self._hold(f"turning {side} {abs(math.degrees(self.rotation)):.0f} deg, from rest")
            self._start_turn()
        now = self.clock()
        self.meter.measure(now, self.get_input("odom"), self.get_input("odom_timeout"))
        if self._phase == "settle":
            if now < self._phase_end or (self.get_input("scan_stamp") < self._phase_end
                                         and now < self._phase_end + self.get_input("scan_timeout")):
                return self._hold(f"settling: turned {math.degrees(self.turned):+.0f} deg")
            return self._finish(Status.SUCCESS, f"done: turned {math.degrees(self.turned):+.1f} deg")
        if self.meter.open_loop and not self._open_loop_logged:
            self._open_loop_logged = True
            self.tell("open_loop", "no fresh odometry — continuing open loop (integrating the commanded turn rate)",
                      warn=True)
        remaining = self.rotation - self.turned - self.meter.pending(now)
        if abs(remaining) <= math.radians(self.get_input("tolerance_deg")):
            latency = float(self.get_input("latency"))
            if latency <= 0.0:
                return self._finish(Status.SUCCESS, f"done: turned {math.degrees(self.turned):+.1f} deg")
            self._phase, self._phase_end = "settle", now + latency + self.SETTLE
            self.meter.command(now, 0.0)
            return self._hold(f"settling: turned {math.degrees(self.turned):+.0f} deg")
        if self.meter.elapsed > self._allowance:
            return self._finish(Status.FAILURE, f"out of time after {self.meter.elapsed:.1f} s, "
                                f"{math.degrees(remaining):+.0f} deg short")
        decel = self.DECEL_LAGGED if self.meter.latency > 0.0 else self.DECEL
        self.meter.command(now, approach_rate(remaining, self.get_input("angular_speed"), decel, self.MIN_RATE))
        self.command(0.0, self.meter.rate)
        self.feedback_message = f"{math.degrees(remaining):+.0f} deg to go"
        self.snapshot_data = {TO_GO: math.degrees(remaining)}
        return Status.RUNNING

    def _hold(self, message: str) -> Status:
        """A still tick inside the maneuver (before or after the turn)."""
        self.command(0.0, 0.0)
        self.feedback_message = message
        self.snapshot_data = {}
        return Status.RUNNING

    def _finish(self, status: Status, message: str) -> Status:
        self.command(0.0, 0.0)
        self.meter.rate = 0.0
        self._set_output("active", False)
        if self.rotation and self.HANDS_OVER_SIDE:
            self._set_output("turn_side", TurnSide(math.copysign(1.0, self.rotation), self.clock(), in_place=True))
        self.feedback_message = message
        self.snapshot_data = {}
        self.tell("maneuver_end", message, warn=status != Status.SUCCESS, status=status.value,
                  turned_deg=math.degrees(self.turned))
        return status

    def terminate(self, new_status: Status) -> None:
        """Preempted (disarm, deadline, shutdown): stop turning and release the branch."""
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.command(0.0, 0.0)
            self._set_output("active", False)
            self.tell("maneuver_preempted", "preempted, stopped")


def sector_readings(sectors: Sectors) -> dict[str, float | None]:
    """The nearest return of the front and each side (m, None when unknown): a maneuver event's trigger readings."""
    return {name: round(float(reading.min_range), 4) if reading.known else None
            for name, reading in (("front", sectors.front), ("left", sectors.left), ("right", sectors.right))}


def _range_text(name: str, reading: SectorReading) -> str:
    """``front 0.47 m`` (``front unknown`` when the sector has too few valid beams)."""
    return f"{name} {reading.min_range:.2f} m" if reading.known else f"{name} unknown"


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
    #: A half turn faces back whichever way it went: its side says nothing about where the room is
    #: (handing it over cost cluttered B 3 of 20 runs the 8 m: the leaves then kept a side at random).
    HANDS_OVER_SIDE = False

    def reading(self, sectors: Sectors) -> str:
        """Both sides' nearest returns."""
        return f"{_range_text('left', sectors.left)}, {_range_text('right', sectors.right)}"

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
    With ``side_reading`` ``side_sectors`` (the lab) the side cones decide outright: the lab's literal
    rule, "whichever side has the higher distance reading", which the lab's check-off judges.
    """

    INPUT_PORTS = {**RotationManeuver.INPUT_PORTS, **PATHS_PORT,
                   "side_reading": port(str, "free_path or side_sectors (see the class docstring)",
                                        default="free_path")}

    def reading(self, sectors: Sectors) -> str:
        """The front and both sides."""
        return (f"{_range_text('front', sectors.front)} ({_range_text('left', sectors.left)}, "
                f"{_range_text('right', sectors.right)})")

    def choose_rotation(self, sectors: Sectors) -> float:
        """A quarter turn to the clearer side."""
        if self.get_input("side_reading") == "side_sectors":
            return clearer_side(sectors) * math.pi / 2
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
