"""Perception leaves: turn the latest scan into sector minima and answer obstacle questions.

The ROS edge (or the lock-step runner) writes the raw :class:`~bt_nav.mission.scan.Scan` and the time it
arrived to the blackboard; :class:`ProcessScan` does the geometry once per new scan and decides
whether the scan is usable at all (fresh and well formed). Every question about obstacles treats an
unknown sector as an obstacle: a blind robot must not drive at full speed.
"""

from __future__ import annotations

import math
from typing import Any

import py_trees

from bt_nav.mission.behaviours.base import Condition, Leaf, port
from bt_nav.mission.scan import (
    Proximity,
    Scan,
    ScanError,
    SectorConfig,
    SectorReading,
    Sectors,
    classify,
    sector_minima,
)

Status = py_trees.common.Status

UNKNOWN_READING = SectorReading(math.nan, 0, 0)
UNKNOWN_SECTORS = Sectors(UNKNOWN_READING, UNKNOWN_READING, UNKNOWN_READING)
SECTORS_PORT = {"sectors": port(Sectors, "front/left/right minima of the latest scan", default=UNKNOWN_SECTORS)}


class ProcessScan(Leaf):
    """Sector minima of the newest scan, and whether the scan can be trusted (``scan_ok``).

    A scan is unusable when none has arrived, when the newest is older than ``scan_timeout`` (or
    stamped in the future, which happens when a simulator's clock is reset), or when it is malformed
    (:class:`~bt_nav.mission.scan.ScanError`). Each change of that verdict is logged once, in one line.
    """

    INPUT_PORTS = {
        "scan": port(Scan, "the newest scan", required=False),
        "scan_stamp": port(float, "mission-clock time the newest scan arrived", default=-math.inf),
        "scan_timeout": port(float, default=0.5),
        "front_half_angle_deg": port(float, default=30.0),
        "side_center_deg": port(float, default=15.0),
        "side_half_angle_deg": port(float, default=15.0),
        "min_valid_beams": port(int, default=3),
    }
    OUTPUT_PORTS = {
        **SECTORS_PORT,
        "scan_ok": port(bool, "the newest scan is fresh and well formed", default=False),
        "scan_status": port(str, "why the scan is (not) usable", default="no scan yet"),
    }

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self._last_scan: Scan | None = None
        self._last_config: SectorConfig | None = None
        self._sectors: Sectors = UNKNOWN_SECTORS
        self._error: str = ""
        self._status = "no scan yet"
        self._front_known: bool | None = None
        self._config_inputs: tuple[Any, ...] = ()
        self._config_cache = SectorConfig()

    def _config(self) -> SectorConfig:
        """The sector geometry from the parameters (rebuilt only when one of them changes)."""
        inputs = (self.get_input("front_half_angle_deg"), self.get_input("side_center_deg"),
                  self.get_input("side_half_angle_deg"), self.get_input("min_valid_beams"))
        if inputs != self._config_inputs:
            self._config_inputs = inputs
            self._config_cache = SectorConfig.from_degrees(
                front_half_deg=inputs[0], side_center_deg=inputs[1], side_half_deg=inputs[2],
                min_valid_beams=inputs[3])
        return self._config_cache

    def update(self) -> Status:
        """Always SUCCESS; the verdict goes to ``scan_ok``."""
        scan = self.blackboard_client.get("scan") if self.blackboard_client.exists("scan") else None
        if scan is None:
            return self._publish(False, "no scan yet", UNKNOWN_SECTORS)
        config = self._config()
        if scan is not self._last_scan or config != self._last_config:
            self._last_scan, self._last_config = scan, config
            try:
                self._sectors, self._error = sector_minima(scan, config), ""
            except ScanError as exc:
                self._sectors, self._error = UNKNOWN_SECTORS, f"malformed scan: {exc}"
        if self._error:
            return self._publish(False, self._error, UNKNOWN_SECTORS)
        age = self.clock() - self.get_input("scan_stamp")
        timeout = self.get_input("scan_timeout")
        if age > timeout:
            return self._publish(False, f"stale scan: none newer than {timeout:.2f} s", UNKNOWN_SECTORS)
        if age < -timeout:
            return self._publish(False, "scan stamped in the future (clock jumped back?)", UNKNOWN_SECTORS)
        return self._publish(True, "ok", self._sectors)

    def _watch_front(self, front: SectorReading) -> None:
        """One line when the front sector becomes unknown (the robot then only rotates) and one when
        it is known again: otherwise a robot turning on the spot for a blind LiDAR says nothing."""
        if front.known == self._front_known:
            return
        if not front.known:
            self.events.warning(f"{self.label}: front sector unknown ({front.valid_beams} of {front.total_beams} "
                                "beams valid) — treated as an obstacle")
        elif self._front_known is False:
            self.events.info(f"{self.label}: front sector known again")
        self._front_known = front.known

    def _publish(self, ok: bool, status: str, sectors: Sectors) -> Status:
        if status != self._status:
            if ok:  # two call sites: rclpy refuses one log call site with two severities
                self.events.info(f"{self.label}: {status} — scan usable again")
            else:
                self.events.warning(f"{self.label}: {status} — stopping")
            self._status = status
        if ok:
            self._watch_front(sectors.front)
        self._set_output("scan_ok", ok)
        self._set_output("scan_status", status)
        self._set_output("sectors", sectors)
        self.feedback_message = status
        return Status.SUCCESS


class ScanHealthy(Condition):
    """Is the newest scan fresh and well formed?"""

    INPUT_PORTS = {"scan_ok": port(bool, default=False)}
    OUTPUT_PORTS = {}

    def answer(self) -> bool:
        """``scan_ok`` from :class:`ProcessScan`."""
        return bool(self.get_input("scan_ok"))


class _FrontProximity(Condition, register=False):
    """Shared by the close / far questions: classify the front sector."""

    INPUT_PORTS = {
        **SECTORS_PORT,
        "close_distance": port(float, default=0.3),
        "far_distance": port(float, default=0.7),
    }
    OUTPUT_PORTS = {}
    MATCH: frozenset[Proximity] = frozenset()

    def answer(self) -> bool:
        """Does the front sector's class match?"""
        proximity = classify(self.get_input("sectors").front, self.get_input("close_distance"),
                             self.get_input("far_distance"))
        self.feedback_message = proximity.value
        return proximity in self.MATCH


class ObstacleClose(_FrontProximity):
    """Front obstacle within ``close_distance``, or the front is unknown."""

    MATCH = frozenset({Proximity.CLOSE, Proximity.UNKNOWN})


class ObstacleFar(_FrontProximity):
    """Front obstacle between ``close_distance`` and ``far_distance``."""

    MATCH = frozenset({Proximity.FAR})
