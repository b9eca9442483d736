"""The simulator's truth feed: the check-off's trigger readings at its ground-truth samples, cast in the world, what
the robot could have read when it decided.

A reading (:class:`bt_nav.judge.readings.Reading`: front, left and right sector minima and the distance to the first
obstacle in the robot's swept path) is cast noise-free from the true pose with unlimited range, along the robot's
LiDAR beams from its mount, the people walking where they were at the pose's time (the latest ``walkers`` sample at
or before it). It is the feed (:class:`bt_nav.judge.feeds.TriggerFeed`) the judge reads in the simulator; a real
robot's is its recorded scans (:class:`bt_nav.judge.feeds.SourceReadings`). The judge owns no world: the ROS node and
the lock-step runner hand it this feed.

When: the check-off keeps one entry per ground-truth sample, a reading while the robot is armed. In a world that cannot
change (no appearing objects) it is cast when first asked for, not as the sample comes: an episode reads a few
seconds of samples before its turn, and casting all of them was the hosted check-off's largest cost (measured: ~1700
casts a lab run, ~80 us each on a quiet core). A world with appearing objects is cast at every armed sample, as it
was then (an object that appears later must not count).

Appearing objects (``appear_within`` in a world file): the ray caster sees an object once it has appeared.
``update_world=True`` (default) reveals them from the poses the judge observes; that is what a judge with a world of
its own needs (over DDS), and it is harmless on a world the simulator shares (appearance is a monotone function of the
robot's positions, and every observed pose is one the simulator has already checked). ``update_world=False`` leaves
the world to the simulator that shares it.
"""

from __future__ import annotations

import bisect
import math
from typing import Any

import numpy as np

from bt_nav.judge.readings import Reading, SectorFamily, SectorReader
from bt_nav_sim.lidar import LDS01, RayCaster, lidar_model
from bt_nav_sim.world import World


class _Pose:
    """A sample whose reading is not cast yet: its pose, time, whether the robot was armed then and, if it was, the
    people walking as they were then (the samples that come later must not move them)."""

    __slots__ = ("armed", "t", "walkers", "x", "y", "yaw")

    def __init__(self, x: float, y: float, yaw: float, t: float, walkers: np.ndarray | None, armed: bool) -> None:
        self.x, self.y, self.yaw, self.t, self.walkers, self.armed = x, y, yaw, t, walkers, armed


class TruthReadings:
    """The readings of one check-off's samples, by sample index (:meth:`add` in order, :meth:`at` and :meth:`cast`):
    a :class:`bt_nav.judge.feeds.TriggerFeed` cast in ``world`` (``lidar``: the LiDAR model's name whose beams are
    cast, else the world's, else the LDS-01; ``family``: the sectors; ``half_width``: the swept path's;
    ``update_world``: reveal appearing objects from the observed poses, see the module's docstring)."""

    def __init__(self, world: World, lidar: str | None, family: SectorFamily, half_width: float, *,
                 update_world: bool = True) -> None:
        self.world, self.update_world, self.half_width = world, update_world, half_width
        name = lidar or world.lidar
        self.caster = RayCaster(world, lidar_model(name) if name else LDS01)
        angles = self.caster.layout.angles()
        self._mount = (self.caster.model.mount_x, self.caster.model.mount_y)
        self._sectors = SectorReader(angles, family)
        self._cos, self._sin = np.cos(angles), np.sin(angles)
        self._deferred = not world.appearing
        self._samples: list[Reading | _Pose | None] = []
        self._walkers: list[tuple[float, np.ndarray]] = []  # (t, circles (K, 3)) as the simulator reported them

    def on_walkers(self, t: float, circles: Any) -> None:
        """Where the people walking were at ``t`` (circles (K, 3): x, y, r); out-of-order samples are dropped."""
        if self._walkers and t <= self._walkers[-1][0]:
            return
        self._walkers.append((float(t), np.asarray(circles, dtype=np.float64).reshape(-1, 3)))

    def walkers_at(self, t: float) -> np.ndarray | None:
        """The walkers of the last sample at or before ``t`` (else the first one; None without walkers)."""
        if not self._walkers:
            return None
        i = bisect.bisect_right(self._walkers, t + 1e-9, key=lambda s: s[0]) - 1
        return self._walkers[max(0, i)][1]

    def add(self, x: float, y: float, yaw: float, t: float, armed: bool) -> None:
        """The next ground-truth sample; its reading is read now or deferred (see the module's docstring). An
        appearing object is revealed from the pose first (``update_world``)."""
        if self.update_world and self.world.appearing:
            self.world.update([(x, y)])
        if not armed:  # cast only if an episode asks (:meth:`cast`), with the people walking known by then
            self._samples.append(_Pose(x, y, yaw, t, None, False))
        elif self._deferred:
            self._samples.append(_Pose(x, y, yaw, t, self.walkers_at(t), True))
        else:
            self._samples.append(self.read(x, y, yaw, self.walkers_at(t), t))

    def at(self, k: int) -> Reading | None:
        """Sample ``k``'s reading while armed (None: not armed then, or no reading), cast now if it was deferred."""
        entry = self._samples[k]
        if isinstance(entry, _Pose):
            if not entry.armed:
                return None
            entry = self._samples[k] = self.read(entry.x, entry.y, entry.yaw, entry.walkers, entry.t)
        return entry

    def cast(self, k: int) -> Reading | None:
        """Sample ``k``'s reading though the robot was not armed then (an episode that starts at the arming may have
        been decided on a scan from just before it)."""
        entry = self._samples[k]
        if isinstance(entry, _Pose) and not entry.armed:  # the people walking as they are known now
            return self.read(entry.x, entry.y, entry.yaw, self.walkers_at(entry.t), entry.t)
        return self.at(k)

    def read(self, x: float, y: float, yaw: float, walkers: np.ndarray | None = None,
             t: float = math.nan) -> Reading | None:
        """Sector minima and the swept-path distance from the true pose (noise-free, unlimited range), the people
        walking included (``t``: unused, the protocol's time of the pose)."""
        sx, sy = self.caster.sensor_pose(float(x), float(y), float(yaw))
        r = self.caster.true_ranges(sx, sy, float(yaw), walkers)
        along, across = r * self._cos + self._mount[0], np.abs(r * self._sin + self._mount[1])  # from the centre
        in_path = (along > 0.0) & (across <= self.half_width)
        return self._sectors.read(r, float(along[in_path].min()) if in_path.any() else math.inf)


def truth_feed(config: Any, world: World, *, update_world: bool = True) -> TruthReadings:
    """The truth feed of a check-off judge's ``config`` (its ``lidar``, sector ``family()`` and ``half_width``: a
    :class:`bt_nav.judge.checkoff_core.CheckoffConfig`) in ``world``."""
    return TruthReadings(world, config.lidar, config.family(), config.half_width, update_world=update_world)
