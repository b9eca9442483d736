"""Perception leaves: turn the latest scan into sector minima and free paths, and answer obstacle questions.

The ROS edge (or the lock-step runner) writes the raw :class:`~bt_nav.mission.scan.Scan` and the time it
arrived to the blackboard; :class:`ProcessScan` does the geometry once per new scan and decides
whether the scan is usable at all (fresh and well formed). It produces two views: the lab's cones
(front / left / right minima, which the maneuver triggers read) and the free paths of the robot's width
along candidate headings (:mod:`bt_nav.mission.paths`), which the close / far / none decision and the
steering read. Every question about obstacles treats an unknown front as an obstacle: a blind robot
must not drive at full speed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import py_trees

from bt_nav.mission.behaviours.base import Condition, Leaf, port
from bt_nav.mission.paths import HEADINGS, FreePaths, free_paths_from_clean
from bt_nav.mission.scan import (
    Proximity,
    Scan,
    ScanError,
    SectorConfig,
    SectorReading,
    Sectors,
    clean_validated,
    sectors_from_clean,
    validate_scan,
)

Status = py_trees.common.Status

UNKNOWN_READING = SectorReading(math.nan, 0, 0)
UNKNOWN_SECTORS = Sectors(UNKNOWN_READING, UNKNOWN_READING, UNKNOWN_READING)
SECTORS_PORT = {"sectors": port(Sectors, "front/left/right minima of the latest scan", default=UNKNOWN_SECTORS)}
BLOCKED_PATHS = FreePaths(HEADINGS, np.zeros_like(HEADINGS))
PATHS_PORT = {"paths": port(FreePaths, "free travel of the robot's width along each heading", default=BLOCKED_PATHS)}


class ProcessScan(Leaf):
    """Sector minima of the newest scan, and whether the scan can be trusted (``scan_ok``).

    A scan is unusable when none has arrived, when the newest is older than ``scan_timeout`` (or
    stamped in the future, which happens when a simulator's clock is reset), or when it is malformed
    (:class:`~bt_nav.mission.scan.ScanError`). Each change of that verdict is logged once, in one line.
    """

    #: Free paths are measured up to this many far_distances: beyond, every heading is equally good.
    HORIZON = 1.5

    INPUT_PORTS = {
        "scan": port(Scan, "the newest scan", required=False),
        "scan_stamp": port(float, "mission-clock time the newest scan arrived", default=-math.inf),
        "scan_timeout": port(float, default=0.5),
        "front_half_angle_deg": port(float, default=30.0),
        "side_center_deg": port(float, default=15.0),
        "side_half_angle_deg": port(float, default=15.0),
        "min_valid_beams": port(int, default=3),
        "path_half_width": port(float, default=0.18),
        "far_distance": port(float, "free paths are measured up to HORIZON times this", default=0.7),
        "scan_mount_x": port(float, "the LiDAR's place ahead of the robot's centre (m)", default=0.0),
        "scan_mount_y": port(float, "the LiDAR's place left of the robot's centre (m)", default=0.0),
    }
    OUTPUT_PORTS = {
        **SECTORS_PORT,
        **PATHS_PORT,
        "scan_ok": port(bool, "the newest scan is fresh and well formed", default=False),
        "scan_status": port(str, "why the scan is (not) usable", default="no scan yet"),
    }

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self._last_scan: Scan | None = None
        self._last_config: SectorConfig | None = None
        self._sectors: Sectors = UNKNOWN_SECTORS
        self._paths: FreePaths = BLOCKED_PATHS
        self._path_inputs: tuple[float, ...] = ()
        self._error: str = ""
        self._status = "no scan yet"
        self._front_known: bool | None = None
        self._no_returns = False
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
        scan = self.read_optional("scan")
        if scan is None:
            return self._publish(False, "no scan yet", UNKNOWN_SECTORS)
        config = self._config()
        path_inputs = (float(self.get_input("path_half_width")), self.HORIZON * float(self.get_input("far_distance")),
                       float(self.get_input("scan_mount_x")), float(self.get_input("scan_mount_y")))
        if scan is not self._last_scan or config != self._last_config or path_inputs != self._path_inputs:
            self._last_scan, self._last_config, self._path_inputs = scan, config, path_inputs
            try:  # one validation and one REP 117 cleaning per scan, shared by the cones and the paths
                validate_scan(scan)
                clean = clean_validated(scan)
                self._sectors, self._error = sectors_from_clean(scan, clean, config), ""
                # no return anywhere (an LDS-01's all 0.0, an LDS-02's all NaN): a room wider than the LiDAR's
                # range reads like a dead or covered LiDAR, so no path is free (no maneuver fires on unknown
                # sectors either: the robot turns or stands rather than drive blind)
                blind = bool(clean.size) and bool(np.isnan(clean).all())
                self._paths = BLOCKED_PATHS if blind else free_paths_from_clean(
                    scan, clean, path_inputs[0], path_inputs[1], mount=path_inputs[2:])
                self._watch_returns(blind)
            except ScanError as exc:
                self._sectors, self._paths, self._error = UNKNOWN_SECTORS, BLOCKED_PATHS, f"malformed scan: {exc}"
        if self._error:
            return self._publish(False, self._error, UNKNOWN_SECTORS)
        age = self.clock() - self.get_input("scan_stamp")
        timeout = self.get_input("scan_timeout")
        if age > timeout:
            return self._publish(False, f"stale scan: none newer than {timeout:.2f} s", UNKNOWN_SECTORS)
        if age < -timeout:
            return self._publish(False, "scan stamped in the future (clock jumped back?)", UNKNOWN_SECTORS)
        return self._publish(True, "ok", self._sectors, self._paths)

    def _watch_returns(self, none: bool) -> None:
        """One line when the scans start to carry no return anywhere (their paths then count as blocked) and
        one when they carry returns again."""
        if none == self._no_returns:
            return
        if none:
            self.events.warning(f"{self.label}: no return in the whole scan (LiDAR blind, or nothing within its "
                                "range) — not driving on it")
        elif self._no_returns:
            self.events.info(f"{self.label}: returns again")
        self._no_returns = none

    def _watch_front(self, front: SectorReading) -> None:
        """One line when the front sector becomes unknown and one when it is known again: the homework's
        close branch then rotates in place and no maneuver fires, which would otherwise go unexplained."""
        if front.known == self._front_known:
            return
        if not front.known:
            self.events.warning(f"{self.label}: front sector unknown ({front.valid_beams} of {front.total_beams} "
                                "beams valid) — no reading ahead")
        elif self._front_known is False:
            self.events.info(f"{self.label}: front sector known again")
        self._front_known = front.known

    def _publish(self, ok: bool, status: str, sectors: Sectors, paths: FreePaths = BLOCKED_PATHS) -> Status:
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
        self._set_output("paths", paths)
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
    """Shared by the close / far questions: how far the robot's width can drive straight ahead.

    Unknown when the front cone is unknown (too few valid beams: the robot is blind ahead); otherwise
    close below ``close_distance`` of free path, far below ``far_distance``, none beyond.
    """

    INPUT_PORTS = {
        **SECTORS_PORT,
        **PATHS_PORT,
        "close_distance": port(float, default=0.3),
        "far_distance": port(float, default=0.7),
    }
    OUTPUT_PORTS = {}
    MATCH: frozenset[Proximity] = frozenset()

    def proximity(self) -> Proximity:
        """This tick's class of what lies ahead."""
        if not self.get_input("sectors").front.known:
            return Proximity.UNKNOWN
        ahead = self.get_input("paths").ahead
        if ahead < self.get_input("close_distance"):
            return Proximity.CLOSE
        return Proximity.FAR if ahead < self.get_input("far_distance") else Proximity.NONE

    def answer(self) -> bool:
        """Does this tick's class match?"""
        proximity = self.proximity()
        self.feedback_message = proximity.value
        return proximity in self.MATCH


class ObstacleClose(_FrontProximity):
    """An obstacle within ``close_distance`` of the robot's path, or the front is unknown."""

    MATCH = frozenset({Proximity.CLOSE, Proximity.UNKNOWN})


class ObstacleFar(_FrontProximity):
    """The robot's path is blocked between ``close_distance`` and ``far_distance``."""

    MATCH = frozenset({Proximity.FAR})
