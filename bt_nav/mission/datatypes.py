"""Small value types shared by the tree, the ROS edge and the lock-step runner (no rclpy)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

Clock = Callable[[], float]
"""Seconds on the mission clock: the node clock (sim time aware) or an injected one in tests."""


@dataclass(frozen=True, slots=True)
class Command:
    """A velocity command and the leaf that chose it (the ``source`` shows up in traces and logs)."""

    linear: float = 0.0
    angular: float = 0.0
    source: str = "init"

    @property
    def is_zero(self) -> bool:
        """True for an exact stop."""
        return self.linear == 0.0 and self.angular == 0.0

    def is_finite(self) -> bool:
        """Both components finite."""
        return math.isfinite(self.linear) and math.isfinite(self.angular)


STOP = Command(0.0, 0.0, "stop")


def keep_wheels_within(linear: float, angular: float, wheel_limit: float, separation: float) -> tuple[float, float]:
    """Scale (linear, angular) down together until neither wheel exceeds ``wheel_limit`` (0: no limit).

    A differential drive whose motor controller saturates one wheel drives a wider arc than commanded
    (the Burger at 0.22 m/s and 2.5 rad/s turns at 1.3 rad/s): scaling both components by the same factor
    keeps the arc the controller chose and only slows along it.
    """
    if wheel_limit <= 0.0:
        return linear, angular
    fastest = abs(linear) + abs(angular) * 0.5 * separation
    if fastest <= wheel_limit:
        return linear, angular
    scale = wheel_limit / fastest
    return linear * scale, angular * scale


@dataclass(frozen=True, slots=True)
class OdomSample:
    """The robot's odometry pose (odom frame; NaN where unknown) and when it was received (mission clock s).

    Maneuvers use yaw increments; the maneuver triggers measure how far the robot drove from x, y.
    """

    yaw: float = math.nan
    stamp: float = -math.inf
    x: float = math.nan
    y: float = math.nan


NO_ODOM = OdomSample()
