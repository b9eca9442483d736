"""How far the robot has turned since a rotation started: odometry yaw increments, dead reckoning between.

The rotation leaves (the maneuvers, the rotation in place) all stop on an angle, and a stop decided on
the 10 Hz scan alone overshoots by the angle turned between scans; odometry (30 Hz on a TurtleBot3)
closes that loop. Summing wrapped yaw increments makes a 180 deg spin and the +-pi seam no special
cases. Between samples, or when odometry stops altogether, the commanded rate is integrated instead
(open loop), so a rotation still ends.
"""

from __future__ import annotations

import math

from bt_nav.mission.datatypes import OdomSample
from bt_nav.mission.geometry import wrap_angle


class TurnMeter:
    """Signed angle turned (rad, + is CCW) since :meth:`start`, from odometry with dead reckoning between."""

    def __init__(self) -> None:
        self.turned = 0.0
        self.open_loop_ticks = 0  # updates without fresh odometry past the timeout
        self.elapsed = 0.0  # seconds since the start, summed per update so a clock jumping back cannot stretch it
        self._odom_turned = 0.0  # sum of yaw increments between odometry samples
        self._since_sample = 0.0  # commanded rate integrated since the last sample (dead reckoning)
        self._last_yaw: float | None = None
        self._last_stamp = -math.inf
        self._last_time = 0.0
        self.rate = 0.0  # the rate commanded since the last update (rad/s)

    def start(self, now: float, odom: OdomSample, timeout: float) -> None:
        """Begin a rotation at ``now`` (the latest sample, if fresh, is the reference yaw)."""
        self.turned = self._odom_turned = self._since_sample = self.elapsed = self.rate = 0.0
        self.open_loop_ticks = 0
        self._last_time = now
        self._last_yaw, self._last_stamp = None, -math.inf
        if self._fresh(now, odom, timeout):
            self._last_yaw, self._last_stamp = odom.yaw, odom.stamp

    def _fresh(self, now: float, odom: OdomSample, timeout: float) -> bool:
        """A usable sample not counted yet."""
        return (odom.stamp != self._last_stamp and math.isfinite(odom.yaw)
                and -timeout <= now - odom.stamp <= timeout)

    def measure(self, now: float, odom: OdomSample, timeout: float) -> float:
        """Update and return :attr:`turned`.

        A new sample's increment covers the interval that dead reckoning bridged, so the bridge is
        dropped then; when samples stop coming the bridge simply keeps growing (open loop).
        """
        dt = max(0.0, now - self._last_time)
        self.elapsed += dt
        if not self._fresh(now, odom, timeout):
            self._since_sample += self.rate * dt
            if now - self._last_stamp > timeout:
                self.open_loop_ticks += 1
        else:
            if self._last_yaw is None:  # first sample of this rotation: keep what was dead-reckoned, to now
                self._odom_turned += self._since_sample + self.rate * dt
            else:
                self._odom_turned += float(wrap_angle(odom.yaw - self._last_yaw))
            self._since_sample = 0.0
            self._last_yaw, self._last_stamp = odom.yaw, odom.stamp
        self._last_time = now
        self.turned = self._odom_turned + self._since_sample
        return self.turned

    @property
    def open_loop(self) -> bool:
        """Has the last update gone without fresh odometry past the timeout?"""
        return self.open_loop_ticks > 0


def approach_rate(remaining: float, peak: float, decel: float, floor: float) -> float:
    """Signed turn rate for ``remaining`` rad still to turn: the fastest that can still stop on the angle
    at ``decel`` rad/s^2 (``sqrt(2 decel remaining)``), within [floor, peak]."""
    return math.copysign(min(peak, max(floor, math.sqrt(2.0 * decel * abs(remaining)))), remaining)
