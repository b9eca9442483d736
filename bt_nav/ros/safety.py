"""The executive's own safety rules, apart from the node that applies them: the last look before the wire
and the clock watchdog. Pure Python (no rclpy), so both are tested without a node.

Veto: the core already clamps commands and the tree stops the robot when it may not move; the edge
checks once more, independently, just before publishing (:func:`veto_reason`).

Clock watchdog: with ``use_sim_time`` a stalled ``/clock`` (simulator paused or dead, bag player stopped) means no
ticks, and a robot base keeps executing the last ``cmd_vel`` it got: the tree, frozen with the clock,
cannot stop it. So the executive looks on the steady (wall) clock: when the last command was motion
and no tick has happened for ``clock_watchdog`` seconds, it publishes one zero twist. Times are
``time.monotonic()`` seconds.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bt_nav.mission.datatypes import Command

#: Slack when re-checking the limits (the core clamps exactly; this only absorbs float noise).
LIMIT_EPS = 1e-9


def veto_reason(command: Command, params: Mapping[str, Any], *, armed: bool, mission_over: bool) -> str:
    """Why ``command`` must not be published (empty when it may): non-finite, beyond the limits of
    ``params``, or motion while disarmed or after the deadline."""
    v_max = float(params["max_linear_speed"])
    w_max = max(float(params["angular_speed"]), float(params["maneuver_angular_speed"]))
    if not command.is_finite():
        return "non-finite"
    if abs(command.linear) > v_max + LIMIT_EPS or abs(command.angular) > w_max + LIMIT_EPS:
        return f"beyond the limits ({v_max} m/s, {w_max} rad/s)"
    if not command.is_zero and not armed:
        return "motion while disarmed"
    if not command.is_zero and mission_over:
        return "motion after the deadline"
    return ""


class ClockWatchdog:
    """Decides when a stalled tick timer calls for a stop, and when ticking has resumed.

    Args:
        timeout: wall seconds without a tick, while moving, before a stop (0 or less disables).
    """

    def __init__(self, timeout: float) -> None:
        self.timeout = float(timeout)
        self.last_tick: float | None = None
        self.moving = False  # the last command published was motion
        self.stalled = False  # a stop went out; cleared by the next tick
        self.stops = 0

    def ticked(self, now: float) -> float | None:
        """A tick happens at ``now``; returns the wall seconds it was awaited when it ends a watchdog stop."""
        resumed = now - self.last_tick if self.stalled and self.last_tick is not None else None
        self.stalled = False
        self.last_tick = now
        return resumed

    def due(self, now: float) -> float | None:
        """The idle wall seconds when a stop must be published now (counted once), else None."""
        if self.timeout <= 0.0 or not self.moving or self.last_tick is None:
            return None
        idle = now - self.last_tick
        if idle < self.timeout:
            return None
        self.moving = False
        self.stalled = True
        self.stops += 1
        return idle
