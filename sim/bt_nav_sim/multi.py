"""Several robots in one world: per-robot :class:`SimCore` objects sharing the world and the clock.

Why compose rather than fork the core: every robot keeps the single-robot physics, sensor schedules,
odometry and noise unchanged (robot 0 *is* the single-robot core for the same seed), and the only thing
a multi-robot world adds is that each robot is an obstacle for the others. That enters in exactly two
places, both through :attr:`SimCore.crowd` (the other robots as circles of their radius):

- the LiDAR ray cast (:meth:`bt_nav_sim.lidar.RayCaster.cast` ``extra``), and
- the contact check of the physics (:class:`bt_nav_sim.core.CrowdedWorld`): a robot driving into another
  stops at contact, like at a wall, and a contact counts as a collision for *both* robots (the one that
  stood still too, which the physics alone would not notice).

Robots move one after the other within a step, each against the others' current poses, so two robots
can never overlap. One physics step at a time (no merged steps): the others move meanwhile.

People walking (:mod:`bt_nav_sim.walkers`, a world's ``walkers``) enter the same way: each step they walk
first (giving way to the robots where they stand), then the robots move against them and the others; a
robot's crowd is the other robots and the walkers. A world with walkers is stepped one step at a time even
with one robot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from bt_nav_sim.core import SimConfig, SimCore, StepOutput, spawn_pose
from bt_nav_sim.walkers import Walkers
from bt_nav_sim.world import World, load_world

#: Offset between the robots' maneuver-A seeds (robot i > 0: seed + i * stride; a prime, so the seeds of
#: neighbouring runs do not collide); lock-step and the ROS bringup use the same.
ROBOT_SEED_STRIDE = 1_000_003
#: Contact tolerance between two robots' disks (m), as the physics' wall contact tolerance.
_TOUCH_TOL = 1e-6
#: Free space wanted around an automatically placed start: the robot plus a margin (m).
_START_CLEARANCE = 0.3
#: Centre distance wanted between two automatically placed robots (m).
_START_SEPARATION = 0.6


def robot_names(count: int, names: Sequence[str] = ()) -> list[str]:
    """The robots' namespaces: ``names`` when given (their count wins), else robot1, robot2, ..."""
    given = [n.strip().strip("/") for n in names if n.strip().strip("/")]
    if given:
        if len(set(given)) != len(given):
            raise ValueError(f"robot names must differ: {', '.join(given)}")
        return given
    if count < 1:
        raise ValueError(f"robots must be >= 1, got {count}")
    return [f"robot{i + 1}" for i in range(count)]


def parse_starts(text: str) -> list[tuple[float, float, float]]:
    """``"x,y,yaw_deg; x,y,yaw_deg"`` -> poses (yaw in rad); empty text: none (automatic placement)."""
    poses = []
    for part in filter(None, (p.strip() for p in text.split(";"))):
        try:
            x, y, yaw_deg = (float(v) for v in part.split(","))
        except ValueError:
            raise ValueError(f"start pose {part!r}: expected x,y,yaw_deg") from None
        poses.append((x, y, math.radians(yaw_deg)))
    return poses


def auto_starts(world: World, first: tuple[float, float, float], count: int, radius: float
                ) -> list[tuple[float, float, float]]:
    """Start poses for ``count`` robots: the first at ``first``, the others at the nearest free points
    around it (rings of growing radius, same heading), deterministic for a world.

    Why not random: a seed must give the same placement in lock-step and over DDS, and a start next to
    the world's spawn keeps the world's documented spawn clearance meaningful.
    """
    poses = [first]
    x0, y0, yaw = first
    clearance = max(_START_CLEARANCE, radius + 0.15)
    ring = _START_SEPARATION
    while len(poses) < count and ring < 20.0:
        n = max(8, int(2 * math.pi * ring / 0.2))
        for k in range(n):
            angle = yaw + math.pi / 2 + 2 * math.pi * k / n  # beside the first robot first
            x, y = x0 + ring * math.cos(angle), y0 + ring * math.sin(angle)
            if world.clearance(x, y) < clearance:
                continue
            if all(math.hypot(x - px, y - py) >= _START_SEPARATION for px, py, _ in poses):
                poses.append((x, y, yaw))
                if len(poses) == count:
                    break
        ring += 0.1
    if len(poses) < count:
        raise ValueError(f"no room for {count} robots in world {world.name!r}")
    return poses


class MultiSimCore:
    """N robots in one world on one clock; see the module docstring. With one robot it is its
    :class:`SimCore` (same calls, bit-identical results)."""

    def __init__(self, config: SimConfig, count: int = 1, names: Sequence[str] = (),
                 starts: Sequence[tuple[float, float, float]] = (), world: World | None = None,
                 latencies: Sequence[float] = ()) -> None:
        """``latencies``: each robot's ``actuation_latency`` (s) when they differ (one per robot); empty:
        every robot has ``config``'s. Each robot queues its own commands (:meth:`SimCore.move`)."""
        self.names = robot_names(count, names)
        seed = None if config.seed < 0 else int(config.seed)
        self.world = world if world is not None else load_world(config.world, seed=seed)
        n = len(self.names)
        if starts and len(starts) != n:
            raise ValueError(f"{len(starts)} start poses for {n} robots")
        poses = list(starts) or auto_starts(self.world, spawn_pose(self.world, config), n, config.radius)
        if latencies and len(latencies) != n:
            raise ValueError(f"{len(latencies)} actuation latencies for {n} robots")
        configs = [replace(config, actuation_latency=float(lat)) for lat in latencies] or [config] * n
        self.cores = [SimCore(configs[i], self.world, index=i, spawn=None if i == 0 and not starts else poses[i])
                      for i in range(n)]
        self.walkers = Walkers(self.world.walkers, seed)
        self._alone = n == 1 and not len(self.walkers)  # the single-robot core's own (merged) stepping
        self._check_apart()
        self._update_crowds()

    def _check_apart(self) -> None:
        """Refuse start poses that overlap another robot (a world that starts in a collision)."""
        for i, a in enumerate(self.cores):
            for b in self.cores[i + 1:]:
                gap = math.hypot(a.state.x - b.state.x, a.state.y - b.state.y)
                if gap <= a.params.radius + b.params.radius:
                    raise ValueError(f"robots start overlapping ({gap:.2f} m apart): give other start poses")

    # ------------------------------------------------------------------ what the drivers read
    @property
    def t_ns(self) -> int:
        """Sim time in nanoseconds (one clock for all)."""
        return self.cores[0].t_ns

    @property
    def t(self) -> float:
        """Sim time in seconds."""
        return self.cores[0].t

    @property
    def step_ns(self) -> int:
        """One physics step in nanoseconds."""
        return self.cores[0].step_ns

    @property
    def steps(self) -> int:
        """Physics steps so far."""
        return self.cores[0].steps

    @property
    def scans(self) -> int:
        """Scans cast so far, over all robots."""
        return sum(c.scans for c in self.cores)

    @property
    def collisions(self) -> int:
        """Collision events so far, over all robots."""
        return sum(c.collisions for c in self.cores)

    def __len__(self) -> int:
        return len(self.cores)

    # ------------------------------------------------------------------ stepping
    def outputs(self) -> list[StepOutput]:
        """What is due now for each robot (see :meth:`SimCore.outputs`), the others in each one's scan."""
        self._update_crowds()
        return [core.outputs() for core in self.cores]

    def advance(self, commands: Sequence[tuple[float, float]], steps: int = 1) -> list[StepOutput]:
        """``steps`` physics steps, each robot under its own (v, w); then what became due for each.

        One robot: exactly :meth:`SimCore.advance` (merged steps allowed). Several, or people walking: one
        step at a time, the walkers first, then the robots in order against each other's current poses.
        """
        if len(commands) != len(self.cores):
            raise ValueError(f"{len(commands)} commands for {len(self.cores)} robots")
        if self._alone:
            return [self.cores[0].advance(commands[0][0], commands[0][1], steps)]
        outs: list[StepOutput] = []
        for _ in range(max(1, int(steps))):
            outs = self._step_all(commands)
        return outs

    def steps_until(self, t_ns: int) -> int:
        """Steps a caller may merge: :meth:`SimCore.steps_until` alone, one step among several robots or
        walkers."""
        return self.cores[0].steps_until(t_ns) if self._alone else 1

    def _step_all(self, commands: Sequence[tuple[float, float]]) -> list[StepOutput]:
        """One physics step of the walkers and of every robot, contacts between robots, then each robot's
        outputs."""
        if len(self.walkers):
            self.walkers.step(self.step_ns * 1e-9, self._robots())
        hits = []
        for i, core in enumerate(self.cores):
            core.crowd = self._others(i)
            hits.append(core.move(commands[i][0], commands[i][1], 1))
        touching = self._touching()
        self._update_crowds()  # the scans see the others where they are now
        return [core.finish_step(hit or touch, 1) for core, hit, touch in zip(self.cores, hits, touching, strict=True)]

    def _robots(self) -> np.ndarray:
        """Every robot as a circle (x, y, radius), at its current pose."""
        return np.array([(c.state.x, c.state.y, c.params.radius) for c in self.cores],
                        dtype=np.float64).reshape(-1, 3)

    def _others(self, i: int) -> np.ndarray:
        """What robot ``i`` may meet: every other robot and every walker as a circle (x, y, radius)."""
        robots = np.delete(self._robots(), i, axis=0)
        return np.vstack([robots, self.walkers.circles()]) if len(self.walkers) else robots

    def _update_crowds(self) -> None:
        if not self._alone:
            for i, core in enumerate(self.cores):
                core.crowd = self._others(i)

    def _touching(self) -> list[bool]:
        """Per robot: its disk touches another robot's (a contact counts for both)."""
        out = [False] * len(self.cores)
        for i, a in enumerate(self.cores):
            for j in range(i + 1, len(self.cores)):
                b = self.cores[j]
                if math.hypot(a.state.x - b.state.x, a.state.y - b.state.y) <= \
                        a.params.radius + b.params.radius + _TOUCH_TOL:
                    out[i] = out[j] = True
        return out
