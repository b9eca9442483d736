"""How far the robot has turned since a rotation started: odometry yaw increments, dead reckoning between.

The rotation leaves (the maneuvers, the rotation in place) all stop on an angle, and a stop decided on
the 10 Hz scan alone overshoots by the angle turned between scans; odometry (30 Hz on a TurtleBot3)
closes that loop. Summing wrapped yaw increments makes a 180 deg spin and the +-pi seam no special
cases. Between samples, or when odometry stops altogether, the commanded rate is integrated instead
(open loop), so a rotation still ends.

A real base turns a command into wheel motion some time later (0.1-0.15 s on a TurtleBot3: serial link,
motor controller). With that ``latency`` the meter integrates each command from when it reaches the wheels,
and :meth:`TurnMeter.pending` says how much turn has been commanded but not done yet, so a rotation can
stop on its angle instead of overshooting by rate x latency (a Smith predictor in its simplest form). With
latency 0 the arithmetic is exactly the latency-free one.
"""

from __future__ import annotations

import math
from collections import deque

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
        self.latency = 0.0  # s between a command and the wheels
        self._commands: deque[tuple[float, float]] = deque()  # (issued at, rate), while latency > 0

    def start(self, now: float, odom: OdomSample, timeout: float, latency: float = 0.0) -> None:
        """Begin a rotation at ``now`` (the latest sample, if fresh, is the reference yaw), the robot at rest."""
        self.turned = self._odom_turned = self._since_sample = self.elapsed = self.rate = 0.0
        self.open_loop_ticks = 0
        self.latency = max(0.0, latency)
        self._commands = deque([(now, 0.0)])
        self._last_time = now
        self._last_yaw, self._last_stamp = None, -math.inf
        if self._fresh(now, odom, timeout):
            self._last_yaw, self._last_stamp = odom.yaw, odom.stamp

    def command(self, now: float, rate: float) -> None:
        """The rate commanded from ``now`` on (what the next :meth:`measure` dead-reckons with)."""
        self.rate = rate
        if self.latency > 0.0:
            self._commands.append((now, rate))

    def _integral(self, start: float, end: float) -> float:
        """Commanded turn (rad) over [start, end] of issue time: the commands are piecewise constant."""
        total, entries = 0.0, list(self._commands)
        for i, (issued, rate) in enumerate(entries):
            until = entries[i + 1][0] if i + 1 < len(entries) else math.inf
            lo, hi = max(start, issued), min(end, until)
            if hi > lo:
                total += rate * (hi - lo)
        return total

    def _acted(self, start: float, dt: float) -> float:
        """Turn the wheels did over [start, start + dt]: the commands issued ``latency`` earlier."""
        if self.latency <= 0.0:
            return self.rate * dt
        end = start + dt
        while len(self._commands) > 1 and self._commands[1][0] <= end - 2.0 * self.latency - 1.0:
            self._commands.popleft()  # long past: no interval still asks about it
        return self._integral(start - self.latency, end - self.latency)

    def pending(self, now: float) -> float:
        """Turn commanded but not done yet at ``now`` (rad): what the wheels will still do of the commands
        issued in the last ``latency`` seconds."""
        return self._integral(now - self.latency, now) if self.latency > 0.0 else 0.0

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
        acted = self._acted(self._last_time, dt)
        if not self._fresh(now, odom, timeout):
            self._since_sample += acted
            if now - self._last_stamp > timeout:
                self.open_loop_ticks += 1
        else:
            if self._last_yaw is None:  # first sample of this rotation: keep what was dead-reckoned, to now
                self._odom_turned += self._since_sample + acted
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
