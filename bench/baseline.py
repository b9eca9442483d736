"""The baseline for the tick-cost benchmark: the same decisions as the mission tree, hand-written
as one if/else function in the style of the lab's template (a flag, a few sector minima, branches).

It shares the scan geometry (bt_nav.mission.scan) with the tree, so the ratio measured against it is the
price of the behaviour tree itself: composites, ports and the blackboard.
"""

from __future__ import annotations

import math

from bt_nav.mission.scan import Proximity, Scan, SectorConfig, classify, clearer_side, sector_minima


class IfElseController:
    """Armed flag, deadline latch, maneuver C, close / far / none — one function, no tree."""

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
        sectors = sector_minima(scan, self.config)
        if self.turn_left:
            self.turned += math.remainder(yaw - self.last_yaw, 2 * math.pi)
            self.last_yaw = yaw
            remaining = self.turn_left - self.turned
            if abs(remaining) > math.radians(p["maneuver_tolerance_deg"]):
                return 0.0, math.copysign(min(p["maneuver_angular_speed"], max(0.3, 3 * abs(remaining))), remaining)
            self.turn_left = 0.0
        front = sectors.front
        if not front.known or front.min_range < p["pivot_distance"]:
            self.turn_left, self.turned, self.last_yaw = clearer_side(sectors) * math.pi / 2, 0.0, yaw
            return 0.0, math.copysign(p["maneuver_angular_speed"], self.turn_left)
        proximity = classify(front, p["close_distance"], p["far_distance"])
        if proximity in (Proximity.CLOSE, Proximity.UNKNOWN):
            return 0.0, clearer_side(sectors) * p["angular_speed"]
        if proximity == Proximity.FAR:
            depth = (p["far_distance"] - front.min_range) / (p["far_distance"] - p["close_distance"])
            linear = p["max_linear_speed"] - (p["max_linear_speed"] - p["slow_linear_speed"]) * depth
            return linear, clearer_side(sectors) * p["angular_speed"] * (0.35 + 0.65 * depth)
        return p["max_linear_speed"], 0.0
