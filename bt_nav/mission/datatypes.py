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


@dataclass(frozen=True, slots=True)
class OdomSample:
    """The robot's heading from odometry and when it was received (mission-clock seconds)."""

    yaw: float = math.nan
    stamp: float = -math.inf


NO_ODOM = OdomSample()
