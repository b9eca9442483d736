"""People walking: cylinders that pace a polyline back and forth, for worlds that are not static.

A real robot shares its floor with people, and a reactive executive must handle an obstacle that moves
into its path or stands in its way for a while. A walker is the simplest honest model of that:

- it walks its ``path`` (a polyline) at ``speed`` to the last point, stands ``pause`` s, walks back to the
  first point, stands ``pause`` s, and so on; where it is at time 0 (``phase``, s into that cycle) is
  drawn from the world's seed unless the world file fixes it, so each seed meets the people elsewhere;
- it **gives way**: it does not take a step that would bring it closer than :data:`GIVE_WAY` to a robot's
  disk (it stands until the robot has moved or turned away). A contact is therefore always the robot's
  doing (it drove into a person), never a person walking into a robot that stood still, so "no collision"
  stays a fair check of the executive.

To the robots a walker is a circle like another robot (:attr:`bt_nav_sim.core.SimCore.crowd`): the LiDAR
sees it and the physics stops a robot at contact, which counts as a collision. The state lives in
:class:`Walkers`, owned by :class:`bt_nav_sim.multi.MultiSimCore` (one per run), so the lock-step and the
ROS simulator move the people identically for a seed.

World YAML (see :mod:`bt_nav_sim.world`)::

    walkers:
      - {path: [[1, 0], [1, 4]], r: 0.2, speed: 1.0, pause: 1.0}   # phase: 2.5 to fix the start
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

#: Gap a walker keeps to a robot's disk (m): it stands rather than step closer.
GIVE_WAY = 0.1
#: Closest a walker's path may come to the world's spawn (m, beyond both radii): no run starts in a contact.
SPAWN_CLEARANCE = 0.2


@dataclass(frozen=True, eq=False)
class WalkerSpec:
    """One person as the world file describes it (validated by :func:`walker_from_dict`)."""

    path: np.ndarray  # (K, 2), K >= 2, the polyline walked there and back
    radius: float = 0.2  # m, a person seen at LiDAR height (legs and hips) as one disk
    speed: float = 1.0  # m/s, a calm walking pace
    pause: float = 1.0  # s standing at each end
    phase: float | None = None  # s into the cycle at time 0; None: drawn from the seed

    # Derived once (a walker steps every physics step): each piece of the path and the whole length.
    _pieces: np.ndarray = field(init=False, repr=False)
    _piece_lengths: np.ndarray = field(init=False, repr=False)
    length: float = field(init=False)  # m, the path's length

    def __post_init__(self) -> None:
        pieces = np.diff(self.path, axis=0)
        lengths = np.hypot(pieces[:, 0], pieces[:, 1])
        object.__setattr__(self, "_pieces", pieces)
        object.__setattr__(self, "_piece_lengths", lengths)
        object.__setattr__(self, "length", float(lengths.sum()))

    @property
    def cycle(self) -> float:
        """Duration of one there-and-back walk with both pauses (s)."""
        return 2.0 * self.length / self.speed + 2.0 * self.pause

    def point_at(self, along: float) -> tuple[float, float]:
        """The point ``along`` metres along the path (clamped to its ends)."""
        along = min(max(along, 0.0), self.length)
        for (x, y), (dx, dy), length in zip(self.path[:-1], self._pieces, self._piece_lengths, strict=True):
            if along <= length and length > 0:
                f = along / length
                return float(x + f * dx), float(y + f * dy)
            along -= length
        return float(self.path[-1, 0]), float(self.path[-1, 1])


def walkers_message(t: float, circles: np.ndarray) -> str:
    """The ``walkers`` message's text (std_msgs/String): JSON ``{"t": sim s, "circles": [[x, y, r], ...]}``, as
    the simulator node publishes it and bags record it."""
    return json.dumps({"t": round(float(t), 6), "circles": np.round(circles, 4).tolist()})


def read_walkers_message(text: str) -> tuple[float, np.ndarray]:
    """(t, circles (K, 3)) of a ``walkers`` message's text; ValueError when it is not one."""
    try:
        sample = json.loads(text)
        return float(sample["t"]), np.asarray(sample["circles"], dtype=np.float64).reshape(-1, 3)
    except (KeyError, TypeError, ValueError) as exc:  # json.JSONDecodeError is a ValueError
        raise ValueError(f"not a walkers message: {text[:80]!r}") from exc


def walker_from_dict(entry: dict, where: str) -> WalkerSpec:
    """A ``walkers`` entry of a world file, with errors that say which one is wrong."""
    if not isinstance(entry, dict):
        raise ValueError(f"{where}: expected a mapping with path, r, speed, pause, got {entry!r}")
    try:
        path = np.asarray(entry.get("path"), dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: path must be [[x, y], ...]") from exc
    if path.ndim != 2 or path.shape[1] != 2 or len(path) < 2 or not np.all(np.isfinite(path)):
        raise ValueError(f"{where}: path must be at least two finite points [[x, y], ...]")
    values = {}
    for key, default, low in (("r", 0.2, 0.0), ("speed", 1.0, 0.0), ("pause", 1.0, -1e-12)):
        try:
            values[key] = float(entry.get(key, default))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: {key} must be a number, got {entry.get(key)!r}") from exc
        if not (math.isfinite(values[key]) and values[key] > low):
            raise ValueError(f"{where}: {key} must be {'>= 0' if key == 'pause' else '> 0'}, got {values[key]}")
    phase = entry.get("phase")
    spec = WalkerSpec(path=path, radius=values["r"], speed=values["speed"], pause=values["pause"],
                      phase=None if phase is None else float(phase))
    if spec.length <= 0:
        raise ValueError(f"{where}: path has zero length")
    return spec


class Walkers:
    """The people of one run: where each is, and one step of their walk (see the module docstring)."""

    def __init__(self, specs: Sequence[WalkerSpec], seed: int | None) -> None:
        self.specs = tuple(specs)
        rng = np.random.default_rng(None if seed is None else [max(0, seed), 17])
        self.along = np.zeros(len(self.specs))  # m along the path
        self.heading = np.ones(len(self.specs))  # +1 towards the last point, -1 back
        self.standing = np.zeros(len(self.specs))  # s of the current end pause left
        for i, spec in enumerate(self.specs):
            phase = float(rng.uniform(0.0, spec.cycle)) if spec.phase is None else spec.phase % spec.cycle
            self._start(i, phase)
        self.xy = np.array([spec.point_at(a) for spec, a in zip(self.specs, self.along, strict=True)],
                           dtype=np.float64).reshape(-1, 2)
        self.radii = np.array([s.radius for s in self.specs], dtype=np.float64)

    def __len__(self) -> int:
        return len(self.specs)

    def _start(self, i: int, phase: float) -> None:
        """Walker ``i``'s state ``phase`` s into its cycle (out, pause, back, pause)."""
        spec = self.specs[i]
        walk = spec.length / spec.speed
        for heading, start in ((1.0, 0.0), (-1.0, spec.length)):
            if phase < walk:
                self.along[i], self.heading[i] = start + heading * phase * spec.speed, heading
                return
            phase -= walk
            if phase < spec.pause:
                self.along[i], self.heading[i], self.standing[i] = start + heading * spec.length, -heading, \
                    spec.pause - phase
                return
            phase -= spec.pause
        self.along[i], self.heading[i] = 0.0, 1.0

    def circles(self) -> np.ndarray:
        """Every walker as a circle (x, y, radius), (N, 3)."""
        return np.column_stack([self.xy, self.radii]) if len(self.specs) else np.zeros((0, 3))

    def step(self, dt: float, robots: np.ndarray) -> None:
        """Walk ``dt`` s; ``robots`` (R, 3) are the robots' disks, given way to (see :data:`GIVE_WAY`)."""
        for i, spec in enumerate(self.specs):
            if self.standing[i] > 0.0:
                self.standing[i] = max(0.0, self.standing[i] - dt)
                continue
            along = self.along[i] + self.heading[i] * spec.speed * dt
            end = along >= spec.length if self.heading[i] > 0 else along <= 0.0
            along = min(max(along, 0.0), spec.length)
            x, y = spec.point_at(along)
            if len(robots) and self._blocked(i, x, y, robots):
                continue
            self.along[i], self.xy[i] = along, (x, y)
            if end:
                self.heading[i], self.standing[i] = -self.heading[i], spec.pause

    def _blocked(self, i: int, x: float, y: float, robots: np.ndarray) -> bool:
        """Whether stepping to (x, y) brings walker ``i`` within the give-way gap of a robot it nears."""
        r = self.radii[i] + robots[:, 2] + GIVE_WAY
        new = np.hypot(robots[:, 0] - x, robots[:, 1] - y)
        old = np.hypot(robots[:, 0] - self.xy[i, 0], robots[:, 1] - self.xy[i, 1])
        return bool(np.any((new < r) & (new < old)))
