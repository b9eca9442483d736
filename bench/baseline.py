"""The baseline for the tick-cost benchmark: the same work and decisions as the mission tree, hand-written
as one if/else function in the style of the lab's template (a flag, a few readings, branches).

It shares the scan geometry with the tree and does the same work per scan (one validation, one REP 117
cleaning, the three cones of :mod:`bt_nav.mission.scan` and the free paths of :mod:`bt_nav.mission.paths`,
as ``ProcessScan`` does) and per tick (the close / far / none class from the free path ahead, steering
with ``FreePaths.steer`` as the motion leaves do, maneuver C's pivot on the front cone), so the ratio
measured against it is the price of the behaviour tree itself: composites, ports and the blackboard.
The motion laws are simplified (the leaves' side hysteresis and speed grading are left out): they cost
a few arithmetic operations, not the numpy work that dominates both.

Before the tree drove on free paths the baseline computed the cones only; comparing that baseline with
the free-path tree would charge the tree for scan work the baseline skipped.
"""

from __future__ import annotations

import math

from bt_nav.mission.paths import FreePaths, free_paths_from_clean
from bt_nav.mission.scan import Scan, SectorConfig, Sectors, clean_validated, sectors_from_clean, validate_scan

#: As ``ProcessScan.HORIZON``: free paths are measured up to this many far_distances.
HORIZON = 1.5
#: As the motion leaves: turn rate per radian of heading error; FullSpeed's cost of turning (m/rad).
STEER_GAIN, CRUISE_TURN_COST = 2.5, 1.5


class IfElseController:
    """Armed flag, deadline latch, maneuver C, close / far / none on free paths — one function, no tree."""

    def __init__(self, params: dict) -> None:
        self.p = params
        self.config = SectorConfig.from_degrees(params["front_half_angle_deg"], params["side_center_deg"],
                                                params["side_half_angle_deg"], params["min_valid_beams"])
        self.armed = False
        self.first_armed_at = math.nan
        self.mission_over = False
        self.turn_left = 0.0
        self.turned = 0.0
        self.last_yaw = 0.0
        self._scan: Scan | None = None
        self._sectors: Sectors | None = None
        self._paths: FreePaths | None = None

    def _perceive(self, scan: Scan) -> tuple[Sectors, FreePaths]:
        """Cones and free paths, once per new scan."""
        if scan is not self._scan:
            validate_scan(scan)
            clean = clean_validated(scan)
            self._scan = scan
            self._sectors = sectors_from_clean(scan, clean, self.config)
            self._paths = free_paths_from_clean(scan, clean, self.p["path_half_width"],
                                                HORIZON * self.p["far_distance"])
        return self._sectors, self._paths  # type: ignore[return-value]

    def _steer(self, target: float | None) -> float:
        return max(-self.p["angular_speed"], min(self.p["angular_speed"], STEER_GAIN * (target or 0.0)))

    def step(self, now: float, scan: Scan, scan_stamp: float, yaw: float) -> tuple[float, float]:
        """(linear, angular) for this control period."""
        p = self.p
        if not self.mission_over and not math.isnan(self.first_armed_at):
            self.mission_over = now >= self.first_armed_at + p["mission_duration"] - p["stop_margin"]
        if self.mission_over or not self.armed:
            self.turn_left = 0.0
            return 0.0, 0.0
        if now - scan_stamp > p["scan_timeout"]:
            return 0.0, 0.0
        sectors, paths = self._perceive(scan)
        if self.turn_left:
            self.turned += math.remainder(yaw - self.last_yaw, 2 * math.pi)
            self.last_yaw = yaw
            remaining = self.turn_left - self.turned
            if abs(remaining) > math.radians(p["maneuver_tolerance_deg"]):
                return 0.0, math.copysign(min(p["maneuver_angular_speed"], max(0.3, 3 * abs(remaining))), remaining)
            self.turn_left = 0.0
        front = sectors.front
        if not front.known or front.min_range < p["pivot_distance"]:
            side = 1.0 if paths.side_room(1) >= paths.side_room(-1) else -1.0
            self.turn_left, self.turned, self.last_yaw = side * math.pi / 2, 0.0, yaw
            return 0.0, math.copysign(p["maneuver_angular_speed"], self.turn_left)
        far, ahead = p["far_distance"], paths.ahead
        if ahead < p["close_distance"]:
            target = paths.steer(far)
            side = (1.0 if target > 0 else -1.0) if target else (1.0 if paths.side_room(1) >= paths.side_room(-1)
                                                                 else -1.0)
            return 0.0, side * p["angular_speed"]
        if ahead < far:
            target = paths.steer(far, side=1)
            other = paths.steer(far, side=-1)
            if other is not None and (target is None or abs(other) < abs(target)):
                target = other
            depth = (far - ahead) / (far - p["close_distance"])
            linear = p["max_linear_speed"] - (p["max_linear_speed"] - p["slow_linear_speed"]) * depth * depth
            return linear, self._steer(target if target is not None else paths.roomiest(1))
        return p["max_linear_speed"], self._steer(paths.steer(far, turn_cost=CRUISE_TURN_COST))
