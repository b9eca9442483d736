"""Lab-mode leaves: the slow creep, and automatic emergency braking (AEB) with its way out.

The lab's robot "maintains a slow forward velocity" until its maneuver's trigger holds, and its title is an
Automatic Emergency Braking and evasive recovery system. Its maneuvers only turn, and only when their own
trigger holds, so something can still be in the robot's way: B (squeezed left AND right) facing a wall, an
object at A's or C's shoulder outside their front cone, an object that appears right in front. The creep
therefore brakes when the robot's swept path (its width, ``path_half_width``) is blocked within
``aeb_distance`` of travel, stands ``aeb_hold`` seconds (a person walking past has moved on by then) and,
if the path is still blocked, turns in place towards the side with more room until it is clear again.
Standing still forever would be safe but makes a poor check-off; the turn is rotation only, like the
maneuvers, and is announced as "AEB" in the log, not as the student's maneuver.
"""

from __future__ import annotations

from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import CMD_PORT, Condition, Leaf, port
from bt_nav.mission.behaviours.maneuvers import ACTIVE_PORT
from bt_nav.mission.behaviours.motion import initial_side
from bt_nav.mission.behaviours.perception import PATHS_PORT
from bt_nav.mission.paths import FreePaths

Status = py_trees.common.Status


class InMode(Condition):
    """Is the executive in ``mode`` (a tree-file attribute)? ``current`` is the ``mode`` parameter."""

    INPUT_PORTS = {"current": port(str, "the mode parameter (homework or lab)", default="homework")}
    OUTPUT_PORTS = {}
    ATTRIBUTES = ("mode",)  # constructor arguments set in the tree file (listed for Groot2's model)

    def __init__(self, name: str, mode: str = "lab", **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.mode = mode

    def answer(self) -> bool:
        """The parameter names this branch's mode."""
        return self.get_input("current") == self.mode


class Creep(Leaf):
    """Straight ahead at ``speed``, no steering: the lab's "slow forward velocity"."""

    INPUT_PORTS = {"speed": port(float, "the creep speed", default=0.05)}
    OUTPUT_PORTS = dict(CMD_PORT)

    def update(self) -> Status:
        """Creep; RUNNING (driving is never "done")."""
        speed = float(self.get_input("speed"))
        self.command(speed, 0.0)
        self.feedback_message = f"creeping at {speed:.2f} m/s"
        return Status.RUNNING


class PathBlocked(Condition):
    """Is the robot's swept path blocked within ``distance`` of travel (the AEB's guard)?"""

    INPUT_PORTS = {**PATHS_PORT, "distance": port(float, "brake when the free path ahead is shorter", default=0.1)}
    OUTPUT_PORTS = {}

    def answer(self) -> bool:
        """Free travel straight ahead below ``distance``."""
        ahead = self.get_input("paths").ahead
        self.feedback_message = f"path free for {ahead:.2f} m"
        return ahead < float(self.get_input("distance"))


class EmergencyStop(Leaf):
    """Brake, stand ``hold`` seconds, then turn in place towards the side with more room until the path is clear.

    SUCCESS once the free path ahead exceeds ``distance`` + :data:`CLEAR_MARGIN` (the creep resumes);
    RUNNING meanwhile, with ``active`` True so the branch is kept while the path is only partly clear. The
    side is chosen once, when the turn starts (re-deciding every tick dithers in front of a flat wall).
    A preemption (a maneuver's trigger, a disarm) stops it with a zero twist.
    """

    INPUT_PORTS = {
        **PATHS_PORT,
        "distance": port(float, "the AEB distance (free travel ahead)", default=0.1),
        "hold": port(float, "seconds to stand before turning away", default=1.0),
        "angular_speed": port(float, "turn rate of the way out", default=1.0),
    }
    OUTPUT_PORTS = {**CMD_PORT, **ACTIVE_PORT}
    #: m of free travel beyond ``distance`` the path must show before the creep resumes: without it the
    #: robot would creep, brake, turn a degree, creep again along the obstacle's edge.
    CLEAR_MARGIN = 0.2

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self._braked_at = 0.0
        self._side = 0.0

    def initialise(self) -> None:
        """Brake now; announce it."""
        self._braked_at = self.clock()
        self._side = 0.0
        self._set_output("active", True)
        ahead = self.get_input("paths").ahead
        self.tell("brake", f"path blocked {ahead:.2f} m ahead: emergency stop", warn=True, ahead_m=ahead)

    def update(self) -> Status:
        """Stand, then turn until clear."""
        paths: FreePaths = self.get_input("paths")
        if paths.ahead >= float(self.get_input("distance")) + self.CLEAR_MARGIN:
            self.command(0.0, 0.0)
            self._set_output("active", False)
            self.feedback_message = f"path clear for {paths.ahead:.2f} m"
            self.tell("brake_clear", f"path clear again ({paths.ahead:.2f} m): creeping on", ahead_m=paths.ahead)
            return Status.SUCCESS
        if self.clock() - self._braked_at < float(self.get_input("hold")):
            self.command(0.0, 0.0)
            self.feedback_message = f"stopped: path blocked {paths.ahead:.2f} m ahead"
            return Status.RUNNING
        if not self._side:
            self._side = initial_side(paths, float(self.get_input("distance")) + self.CLEAR_MARGIN)
            side = "left" if self._side > 0 else "right"
            self.tell("brake_turn", f"still blocked after {float(self.get_input('hold')):.1f} s: turning {side} "
                      "until the path is clear", side=side)
        self.command(0.0, self._side * float(self.get_input("angular_speed")))
        self.feedback_message = f"turning {'left' if self._side > 0 else 'right'} until clear"
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        """Preempted: stop and release the branch."""
        if new_status == Status.INVALID and self.status == Status.RUNNING:
            self.command(0.0, 0.0)
            self._set_output("active", False)
