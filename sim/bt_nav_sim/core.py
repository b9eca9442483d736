"""The one simulation core: sim time, physics, sensor schedules, odometry and noise, with no ROS.

Every driver of the simulator steps this class, so they cannot drift apart: the ROS simulator node
(:mod:`bt_nav.ros.nodes.simulator`) publishes what :meth:`SimCore.advance` says is due, and the lock-step
runner (:mod:`bt_nav.run.lockstep`) hands the same scans and odometry to the mission tree in-process. The
same world, profile, kinematics and seed therefore give the same trajectory on both paths (the only
difference is when a command reaches the physics, which the ROS path leaves to DDS).

Time is kept in integer nanoseconds so that 100 Hz steps land exactly on the 10 Hz scan grid for hours
(a float accumulator drifts off it and scans start jittering by one step).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from bt_nav.mission.assignments import PROFILES as ASSIGNMENT_PROFILES  # the one table of profiles (pure, no ROS)
from bt_nav_sim.lidar import HOMEWORK_LIDAR, LDS01, LidarModel, RayCaster, ScanLayout, lidar_model
from bt_nav_sim.physics import KINEMATICS, ClearanceMemo, RobotParams, RobotState, step, target_twist, wrap_angle
from bt_nav_sim.world import World, load_world


@dataclass(frozen=True)
class SimProfile:
    """What a simulated robot looks like to a controller: its LiDAR and its default kinematics."""

    lidar: LidarModel
    kinematics: str
    description: str


#: The idealised LiDARs a profile's simulated robot carries, by the name its record gives
#: (:attr:`bt_nav.mission.assignments.Profile.lidar`).
PROFILE_LIDARS: dict[str, LidarModel] = {"homework": HOMEWORK_LIDAR, "lds01": LDS01}
#: The simulator's side of every profile (``--profile`` everywhere a profile is chosen), read from the one table of
#: profiles, :data:`bt_nav.mission.assignments.PROFILES`.
PROFILES: dict[str, SimProfile] = {name: SimProfile(PROFILE_LIDARS[spec.lidar], spec.kinematics, spec.description)
                                   for name, spec in ASSIGNMENT_PROFILES.items()}

# Light wheel-odometry error (relative, per step) when noise is on: odometry drifts a little, the way
# wheel slip makes it drift on the real base, while ground truth stays exact.
ODOM_SLIP_SIGMA = 0.01
#: Largest accepted actuation latency (s): beyond it a run is a broken link, not a slow base.
MAX_LATENCY = 2.0


def profile(name: str) -> SimProfile:
    """The profile called ``name`` (ValueError listing the choices otherwise)."""
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILES)}") from None


@dataclass(frozen=True)
class SimConfig:
    """Everything that shapes one simulation run (all defaults are the homework setup)."""

    world: str = "stage_4"
    profile: str = "homework"
    seed: int = 0  # -1: random (noise from OS entropy, generated worlds from their YAML seed)
    physics_rate_hz: float = 100.0
    odom_rate_hz: float = 30.0
    radius: float = 0.12
    noise: bool = True  # LiDAR range noise and odometry slip
    dropout_prob: float = 0.0
    spawn_x: float = math.nan  # NaN: the world's spawn
    spawn_y: float = math.nan
    spawn_yaw: float = math.nan  # rad
    # Per-seed perturbation of the spawn (uniform within +-metres, +-degrees), so seeds explore different
    # paths as Gazebo's own jitter does; 0 for the exact spawn.
    spawn_jitter_m: float = 0.0
    spawn_jitter_deg: float = 0.0
    cmd_vel_timeout: float = 0.0  # sim s; 0: the last command persists (Gazebo diff drive behaviour)
    kinematics: str = ""  # ideal | burger; empty: the profile's
    max_wheel_speed: float = RobotParams.max_wheel_speed  # m/s, burger kinematics
    wheel_separation: float = RobotParams.wheel_separation  # m
    # Sim s between a command and the wheels (a real base's serial link and motor controller; 0.1-0.15 s
    # on real TurtleBot3s): a command given at t drives the physics from t + latency on (see SimCore.move).
    actuation_latency: float = 0.0
    # A real base's wheel odometry in a pivot (TurtleBot3 bags): it reads every turn this much too far (1.015:
    # 1.5 % over) and drifts sideways this many metres per radian turned, while ground truth stays exact.
    odom_yaw_scale: float = 1.0
    odom_turn_drift: float = 0.0
    # A real LiDAR of bt_nav_sim.lidar.LIDARS by name (lds01, lds02, rplidar, ...); empty: the world file's
    # ``lidar``, else the profile's own.
    lidar: str = ""

    def lidar_model(self, world_lidar: str = "") -> LidarModel:
        """The LiDAR of this run (this config's ``lidar``, else the world's, else the profile's) with this run's
        noise setting; a named sensor keeps its own dropouts unless ``dropout_prob`` asks for more."""
        name = self.lidar or world_lidar
        if not name:
            model = profile(self.profile).lidar
            return replace(model, noise_sigma=model.noise_sigma if self.noise else 0.0,
                           dropout_prob=self.dropout_prob)
        model = lidar_model(name)
        return replace(model, noise_sigma=model.noise_sigma if self.noise else 0.0,
                       dropout_prob=max(self.dropout_prob, model.dropout_prob if self.noise else 0.0))

    def robot(self) -> RobotParams:
        """The robot's limits and kinematics for this run."""
        return RobotParams(radius=self.radius, kinematics=self.kinematics or profile(self.profile).kinematics,
                           max_wheel_speed=self.max_wheel_speed, wheel_separation=self.wheel_separation)

    def check(self) -> None:
        """Refuse values that would make the loop meaningless (raises ValueError naming the field)."""
        for name in ("physics_rate_hz", "odom_rate_hz", "radius", "max_wheel_speed", "wheel_separation"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be > 0, got {value}")
        if not 0.0 <= self.dropout_prob <= 1.0:
            raise ValueError(f"dropout_prob must be in [0, 1], got {self.dropout_prob}")
        if self.cmd_vel_timeout < 0 or not math.isfinite(self.cmd_vel_timeout):
            raise ValueError(f"cmd_vel_timeout must be >= 0, got {self.cmd_vel_timeout}")
        if not (math.isfinite(self.actuation_latency) and 0.0 <= self.actuation_latency <= MAX_LATENCY):
            raise ValueError(f"actuation_latency must be in [0, {MAX_LATENCY}] s, got {self.actuation_latency}")
        if not (0.5 <= self.odom_yaw_scale <= 1.5 and 0.0 <= self.odom_turn_drift <= 0.1):
            raise ValueError(f"odom_yaw_scale must be in [0.5, 1.5] and odom_turn_drift in [0, 0.1] m/rad, got "
                             f"{self.odom_yaw_scale} and {self.odom_turn_drift}")
        if self.kinematics and self.kinematics not in KINEMATICS:
            raise ValueError(f"kinematics must be one of {', '.join(KINEMATICS)}, got {self.kinematics!r}")
        self.lidar_model()


@dataclass
class StepOutput:
    """What became due at one instant of sim time (the node turns it into messages)."""

    t_ns: int
    scan: np.ndarray | None = None  # float32 ranges when a scan is due
    odom: bool = False  # odometry and ground truth are due
    collision: bool = False  # a collision event started at this step


def spawn_pose(world: World, config: SimConfig) -> tuple[float, float, float]:
    """The configured spawn (the world's where NaN), perturbed per seed within the configured jitter."""
    sx, sy, syaw = world.spawn
    x = sx if math.isnan(config.spawn_x) else config.spawn_x
    y = sy if math.isnan(config.spawn_y) else config.spawn_y
    yaw = syaw if math.isnan(config.spawn_yaw) else config.spawn_yaw
    if config.spawn_jitter_m <= 0 and config.spawn_jitter_deg <= 0:
        return x, y, yaw
    rng = np.random.default_rng([max(0, int(config.seed)), 1])
    dx, dy = rng.uniform(-config.spawn_jitter_m, config.spawn_jitter_m, size=2)
    dyaw = math.radians(rng.uniform(-config.spawn_jitter_deg, config.spawn_jitter_deg))
    return x + float(dx), y + float(dy), math.remainder(yaw + dyaw, 2 * math.pi)


class CrowdedWorld:
    """The static world plus other robots as circles, for the physics' contact checks (its only use of a
    world is ``clearance``): a robot is stopped by another robot the way it is stopped by a wall."""

    def __init__(self, world: World, crowd: np.ndarray) -> None:
        self.world = world
        self.crowd = crowd

    def clearance(self, x: float, y: float) -> float:
        """Distance from (x, y) to the nearest wall, obstacle or other robot's disk."""
        crowd = self.crowd
        others = np.hypot(x - crowd[:, 0], y - crowd[:, 1]) - crowd[:, 2]
        return min(self.world.clearance(x, y), float(others.min()) if len(others) else math.inf)


class SimCore:
    """Sim time, physics, sensor schedules and odometry: deterministic for a seed and command sequence."""

    def __init__(self, config: SimConfig, world: World | None = None, *, index: int = 0,
                 spawn: tuple[float, float, float] | None = None) -> None:
        """``index`` > 0 and ``spawn``: the further robots of a :class:`bt_nav_sim.multi.MultiSimCore`
        (noise streams of their own, their own start pose); robot 0 is exactly the single-robot core."""
        config.check()
        self.config = config
        seed = None if config.seed < 0 else int(config.seed)
        self.world = world if world is not None else load_world(config.world, seed=seed)
        self.model = config.lidar_model(self.world.lidar)
        self.caster = RayCaster(self.world, self.model)
        self.layout: ScanLayout = self.model.layout  # the last scan's (a varying sensor's changes every scan)
        self.params = config.robot()
        # Two independent streams so that turning LiDAR noise off does not change the odometry drift.
        self.lidar_rng = np.random.default_rng(seed if index == 0 or seed is None else [seed, index, 0])
        self.odom_rng = np.random.default_rng(None if seed is None else seed + 1 if index == 0 else [seed, index, 1])
        self.spawn = spawn_pose(self.world, config) if spawn is None else spawn
        # The other robots as circles (K, 3), set by MultiSimCore before each step; None: alone.
        self.crowd: np.ndarray | None = None
        self.state = RobotState(*self.spawn)
        self.step_ns = max(1, round(1e9 / config.physics_rate_hz))
        self.scan_period_ns = max(1, round(1e9 / self.model.rate_hz))
        self.odom_period_ns = max(1, round(1e9 / config.odom_rate_hz))
        self.t_ns = 0
        self._next_scan_ns = 0
        self._next_odom_ns = 0
        # Odometry: the pose in the odom frame (origin = start pose), dead-reckoned from true motion.
        self.odom_x = 0.0
        self.odom_y = 0.0
        self.odom_yaw = 0.0
        self._odom_anchor = self.state  # true pose at the last odometry sample
        self.collisions = 0
        self.steps = 0
        self.scans = 0
        # Actuation latency: commands given but not yet at the wheels as (effective t_ns, v, w), oldest
        # first; the command the wheels follow now; the last command given (only a change is queued).
        self.latency_ns = round(config.actuation_latency * 1e9)
        self._pending: deque[tuple[int, float, float]] = deque()
        self.in_force: tuple[float, float] = (0.0, 0.0)
        self._given: tuple[float, float] = (0.0, 0.0)
        # Appearing objects (world.update) are checked after every move; a world without any skips that.
        self._appearing = bool(self.world.appearing)
        if self._appearing:
            self.world.update([self.spawn[:2]])
        self._was_colliding = self.world.clearance(self.spawn[0], self.spawn[1]) <= config.radius
        self._clearance = ClearanceMemo()  # the physics' last exact clearance, step to step

    @property
    def t(self) -> float:
        """Sim time in seconds."""
        return self.t_ns * 1e-9

    def outputs(self) -> StepOutput:
        """What is due at the current time (scan, odometry); advances the schedules past it."""
        out = StepOutput(self.t_ns)
        if self.t_ns >= self._next_scan_ns:
            out.scan = self.scan()
            self.scans += 1
            while self._next_scan_ns <= self.t_ns:
                self._next_scan_ns += self.scan_period_ns
        if self.t_ns >= self._next_odom_ns:
            out.odom = True
            while self._next_odom_ns <= self.t_ns:
                self._next_odom_ns += self.odom_period_ns
        return out

    def scan_after_ns(self, t_ns: int) -> int:
        """When the first scan after sim ``t_ns`` is due (scans fall on the grid of :attr:`scan_period_ns`)."""
        return (int(t_ns) // self.scan_period_ns + 1) * self.scan_period_ns

    def scan(self) -> np.ndarray:
        """A scan from the current true pose (noise and dropouts from the seeded stream)."""
        s = self.state
        rng = self.lidar_rng if (self.model.noise_sigma > 0 or self.model.dropout_prob > 0) else None
        if self.model.speed_spread:  # its own layout every scan, from the same seeded stream
            self.layout = self.model.next_layout(self.lidar_rng)
            self.caster.use_layout(self.layout)
        return self.caster.cast(s.x, s.y, s.yaw, rng, self.crowd)

    def advance(self, cmd_v: float, cmd_w: float, steps: int = 1) -> StepOutput:
        """``steps`` physics steps under (cmd_v, cmd_w), then whatever became due (see :meth:`outputs`).

        Several steps under one command are integrated in one go once the twist has settled at the
        command: the physics is exact for a constant twist (closed-form arcs; contacts are found to
        1e-7 m), so a caller that knows nothing falls due in between (lock-step) gets the same trajectory
        as stepping one at a time (tests/run/test_lockstep.py). A robot at rest under a zero command cannot
        move, so the physics is skipped then (before arming and after the deadline).
        """
        steps = max(1, int(steps))
        return self.finish_step(self.move(cmd_v, cmd_w, steps), steps)

    def move(self, cmd_v: float, cmd_w: float, steps: int = 1) -> bool:
        """The physics half of :meth:`advance` (no time, no outputs); returns whether the robot collided.

        Among other robots (``crowd`` set) a robot at rest is stepped too: another robot may touch it.

        With ``actuation_latency`` L > 0 the command is *given* now (sim time t) and drives the wheels from
        the first physics step starting at or after t + L; until then the command in force (the one given
        before) does. Only a change of command is queued, so a caller that repeats the same command every
        step (the ROS node) and one that gives it once for merged steps (lock-step) queue the same thing.
        The steps are split at every queued command's effective time, so a merged call never integrates
        across one. With L = 0 this is exactly the old path (no queue at all).
        """
        if self._appearing:
            before = self.state
            collided = self._move_latent(cmd_v, cmd_w, steps)
            self.world.update(((before.x, before.y), (self.state.x, self.state.y)))
            return collided
        return self._move_latent(cmd_v, cmd_w, steps)

    def _move_latent(self, cmd_v: float, cmd_w: float, steps: int) -> bool:
        """:meth:`move` without the appearing objects' update: the latency queue, then the physics."""
        if not self.latency_ns:
            self.in_force = (cmd_v, cmd_w)
            return self._move_under(cmd_v, cmd_w, steps)
        cmd = (cmd_v, cmd_w)
        if cmd != self._given:
            self._given = cmd
            self._pending.append((self.t_ns + self.latency_ns, cmd_v, cmd_w))
        t_ns, collided = self.t_ns, False
        while steps > 0:
            while self._pending and self._pending[0][0] <= t_ns:
                _, v, w = self._pending.popleft()
                self.in_force = (v, w)
            n = steps
            if self._pending:
                n = min(n, max(1, -(-(self._pending[0][0] - t_ns) // self.step_ns)))
            collided = self._move_under(*self.in_force, n) or collided
            steps -= n
            t_ns += n * self.step_ns
        return collided

    def _move_under(self, cmd_v: float, cmd_w: float, steps: int) -> bool:
        """``steps`` physics steps with (cmd_v, cmd_w) at the wheels (skipped at rest when alone)."""
        before = self.state
        resting = before.v == 0.0 and before.w == 0.0 and cmd_v == 0.0 and cmd_w == 0.0
        if resting and self.crowd is None:
            return self._was_colliding
        return self._integrate(cmd_v, cmd_w, steps)

    def finish_step(self, collided: bool, steps: int = 1) -> StepOutput:
        """The bookkeeping half of :meth:`advance`: time, outputs, odometry and the collision edge."""
        self.t_ns += steps * self.step_ns
        self.steps += steps
        out = self.outputs()
        if out.odom:
            self._integrate_odom(self._odom_anchor, self.state)
            self._odom_anchor = self.state
        if collided and not self._was_colliding:
            out.collision = True
            self.collisions += 1
        self._was_colliding = collided
        return out

    def _integrate(self, cmd_v: float, cmd_w: float, steps: int) -> bool:
        """Physics over ``steps`` steps: one at a time while the twist ramps towards the command (a ramp
        inside a merged step would be followed along one mean arc), the rest in one exact arc."""
        target = target_twist(cmd_v, cmd_w, self.params)
        dt = self.step_ns * 1e-9
        collided = False
        world = self.world if self.crowd is None else CrowdedWorld(self.world, self.crowd)
        while steps > 0:
            settled = (self.state.v, self.state.w) == target
            n = steps if settled else 1
            self.state, hit = step(self.state, cmd_v, cmd_w, n * dt, world, self.params, self._clearance)
            collided = collided or hit
            steps -= n
        return collided

    def steps_until(self, t_ns: int) -> int:
        """Physics steps from now until ``t_ns`` or until the next scan or odometry sample, whichever is
        first (at least one): what a caller may merge into one :meth:`advance`. A queued command's
        effective time (actuation latency) ends a merge too, so merged steps never straddle one."""
        due = min(t_ns, self._next_scan_ns, self._next_odom_ns)
        for effective, _, _ in self._pending:
            if effective > self.t_ns:
                due = min(due, effective)
                break
        return max(1, -(-(due - self.t_ns) // self.step_ns))

    def _integrate_odom(self, before: RobotState, after: RobotState) -> None:
        """Wheel odometry: the true displacement since the last sample in the robot frame, lightly scaled
        by slip noise (one draw per odometry sample, so merged physics steps draw the same noise)."""
        dx, dy = after.x - before.x, after.y - before.y
        c, s = math.cos(before.yaw), math.sin(before.yaw)
        forward, lateral = c * dx + s * dy, -s * dx + c * dy
        dyaw = wrap_angle(after.yaw - before.yaw)
        if self.config.noise and (forward or dyaw):
            slip_s, slip_yaw = self.odom_rng.normal(0.0, ODOM_SLIP_SIGMA, 2)
            forward *= 1.0 + slip_s
            dyaw *= 1.0 + slip_yaw
        if dyaw:  # the real-robot pivot effects (1.0 and 0.0 by default: none)
            lateral += self.config.odom_turn_drift * abs(dyaw)
            dyaw *= self.config.odom_yaw_scale
        oc, os_ = math.cos(self.odom_yaw), math.sin(self.odom_yaw)
        self.odom_x += oc * forward - os_ * lateral
        self.odom_y += os_ * forward + oc * lateral
        self.odom_yaw = wrap_angle(self.odom_yaw + dyaw)
