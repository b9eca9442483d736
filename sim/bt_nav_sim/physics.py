"""Unicycle (differential-drive) kinematics for a TurtleBot3 Burger with acceleration limits and walls.

The simulator is kinematic, not dynamic: the base follows the commanded twist up to its speed and
acceleration limits and stops dead at obstacles. That is what a reactive navigator can observe on the real
robot (the Burger's motors track cmd_vel closely), and it keeps every step exact and cheap.

Command semantics: ``step`` applies ``(cmd_v, cmd_w)`` for ``dt`` seconds. Like the real base, the last
cmd_vel persists until a new one arrives; holding that last command and passing it on every step is the
caller's job (the ROS node / scenario runner), this module keeps no hidden command state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from bt_nav.mission.geometry import wrap_angle  # one home for the angle helpers (pure, no ROS)
from bt_nav_sim.world import World

# Largest centre displacement between two collision checks. 0.02 m is far below the thinnest wall the
# checks must stop (a zero-thickness segment needs a jump of >= 2 * radius = 0.24 m to be crossed), so no
# speed/dt combination can tunnel, and it keeps the sub-step count small (0.22 m/s * 0.1 s = 1 sub-step).
MAX_SUBSTEP = 0.02
# Contact is located by bisection to this precision (m) so a blocked robot ends up touching the wall.
_CONTACT_TOL = 1e-7
# A disk whose clearance is within this of its radius counts as touching (collided=True).
_TOUCH_TOL = 1e-6
# Below this |w| (rad/s) the arc is integrated as a straight line.
_W_EPS = 1e-9


#: Kinematics modes of :class:`RobotParams` (see :func:`wheel_limited`).
KINEMATICS = ("ideal", "burger")


@dataclass(frozen=True)
class RobotParams:
    """TurtleBot3 Burger limits (ROBOTIS e-manual / turtlebot3_teleop constants) and the kinematics mode.

    ``ideal`` clamps v and w separately, like an ideal unicycle (and Gazebo's diff drive plugin with its
    default limits): full speed and a fast turn at once. ``burger`` converts the command to wheel speeds
    and clamps each wheel to ``max_wheel_speed``, as the Burger's motor controller does, so a fast turn
    costs forward speed (see :func:`wheel_limited`).
    """

    max_linear: float = 0.22  # m/s, Burger maximum translational velocity
    max_angular: float = 2.84  # rad/s, Burger maximum rotational velocity
    # The Burger's Dynamixels reach full speed in ~0.1 s: 0.22 m/s / 0.088 s = 2.5 m/s^2.
    max_linear_accel: float = 2.5  # m/s^2
    # Full turn rate in ~0.3 s: the wheels are the same motors but a spin also has to overcome the caster
    # scrub, so it ramps a little slower than translation; 10 rad/s^2 keeps turns crisp but not instant.
    max_angular_accel: float = 10.0  # rad/s^2
    radius: float = 0.12  # m, collision disk (Burger footprint is 0.138 x 0.178 m; ~0.105 m circumradius)
    kinematics: str = "ideal"
    wheel_separation: float = 0.160  # m, Burger
    # Per-wheel speed limit: the published 2.84 rad/s spin needs each wheel at 2.84 * 0.160 / 2 = 0.2272
    # m/s, and the 0.22 m/s top speed sits just below it, so one limit explains both published figures.
    max_wheel_speed: float = 0.2272  # m/s

    def __post_init__(self) -> None:
        if self.kinematics not in KINEMATICS:
            raise ValueError(f"kinematics must be one of {', '.join(KINEMATICS)}, got {self.kinematics!r}")
        if not (self.wheel_separation > 0 and self.max_wheel_speed > 0):
            raise ValueError("wheel_separation and max_wheel_speed must be > 0")


def wheel_limited(v: float, w: float, params: RobotParams) -> tuple[float, float]:
    """The twist a differential drive actually follows for the (already body-clamped) command (v, w).

    ``ideal``: unchanged. ``burger``: wheel speeds v -/+ w * b / 2, each clamped to +-max_wheel_speed on
    its own (the motor controller saturates each wheel; the curvature is not preserved), and back to
    (v, w). Example: v = 0.22, w = 2.5 on the Burger gives wheels 0.02 and 0.42 -> 0.02 and 0.2272, so
    the robot really drives 0.124 m/s and turns 1.29 rad/s.
    """
    if params.kinematics == "ideal":
        return v, w
    half = 0.5 * params.wheel_separation
    limit = params.max_wheel_speed
    left = _clamp(v - w * half, limit)
    right = _clamp(v + w * half, limit)
    return 0.5 * (left + right), (right - left) / params.wheel_separation


@dataclass
class RobotState:
    """Pose and current (acceleration-limited) twist of the robot."""

    x: float
    y: float
    yaw: float
    v: float = 0.0  # current linear velocity (after accel limits), m/s
    w: float = 0.0  # current angular velocity, rad/s
    colliding: bool = False  # the disk touched an obstacle during the last step


def _finite(v: float) -> float:
    """Bad input (NaN/inf/non-numbers) reads as 0: a glitching controller must stop the robot, not crash."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return 0.0
    return f if math.isfinite(f) else 0.0


def _clamp(v: float, lim: float) -> float:
    return max(-lim, min(lim, v))


def _arc(x: float, y: float, yaw: float, v: float, w: float, t: float) -> tuple[float, float, float]:
    """Exact unicycle motion for constant (v, w) over time t.

    Uses the chord form (length v*t*sinc(w*t/2) along the mean heading), which equals the textbook
    (v/w)(sin - sin) arc formula but has no cancellation for small w.
    """
    dth = w * t
    if abs(w) > _W_EPS:
        half = 0.5 * dth
        chord = v * t * (math.sin(half) / half) if half != 0.0 else v * t
        heading = yaw + half
    else:
        chord = v * t
        heading = yaw
    return x + chord * math.cos(heading), y + chord * math.sin(heading), yaw + dth


#: target_twist's last question and answer: (cmd_v, cmd_w, params, twist).
_last_target: tuple[Any, Any, RobotParams, tuple[float, float]] | None = None


def target_twist(cmd_v: float, cmd_w: float, params: RobotParams) -> tuple[float, float]:
    """The twist the base settles at under a command: sanitised, clamped, wheel-limited.

    The simulator asks it of one command at every physics step until the next arrives, so the last answer
    is kept for the very same number objects and the same (frozen) params: a hit is the same answer.
    """
    global _last_target
    last = _last_target
    if last is not None and last[0] is cmd_v and last[1] is cmd_w and last[2] is params:
        return last[3]
    twist = wheel_limited(_clamp(_finite(cmd_v), params.max_linear), _clamp(_finite(cmd_w), params.max_angular),
                          params)
    _last_target = (cmd_v, cmd_w, params, twist)
    return twist


def _velocity_pieces(
    v0: float, w0: float, v1: float, w1: float, dt: float, params: RobotParams
) -> list[tuple[float, float, float]]:
    """Split dt into pieces in which both velocities are linear; return (mean v, mean w, duration) each.

    Each velocity ramps towards its target at its acceleration limit and then holds, so the profile has at
    most one kink per velocity. Integrating each piece with its mean velocities makes distance and heading
    change exact (e.g. a straight ramp covers exactly v*T - v^2/(2a)); only the path shape inside a ramp
    piece is approximated by an arc, and ramps last <= 0.3 s.
    """
    if v0 == v1 and w0 == w1:  # settled: what the general case below gives, exactly (0.5 * (b + b) == b)
        return [(v1, w1, dt)]
    tv = abs(v1 - v0) / params.max_linear_accel if params.max_linear_accel > 0 else 0.0
    tw = abs(w1 - w0) / params.max_angular_accel if params.max_angular_accel > 0 else 0.0
    cuts = sorted({0.0, min(tv, dt), min(tw, dt), dt})

    def vel(t: float, a: float, b: float, tr: float) -> float:
        return b if t >= tr else a + (b - a) * (t / tr)

    pieces = []
    for t0, t1 in zip(cuts[:-1], cuts[1:], strict=False):
        if t1 <= t0:
            continue
        vm = 0.5 * (vel(t0, v0, v1, tv) + vel(t1, v0, v1, tv))
        wm = 0.5 * (vel(t0, w0, w1, tw) + vel(t1, w0, w1, tw))
        pieces.append((vm, wm, t1 - t0))
    return pieces


def step(
    state: RobotState,
    cmd_v: float,
    cmd_w: float,
    dt: float,
    world: World,
    params: RobotParams = RobotParams(),  # noqa: B008 - frozen, immutable default is safe
    memo: ClearanceMemo | None = None,
) -> tuple[RobotState, bool]:
    """Advance the robot by dt under (cmd_v, cmd_w); return (new state, collided).

    Order: sanitise (non-finite -> 0) and clamp the command (per wheel under ``burger`` kinematics), ramp the
    current twist towards it under the acceleration limits, integrate the exact unicycle arc in sub-steps of <=
    MAX_SUBSTEP metres, and stop at the first sub-step whose disk would overlap an obstacle. A blocked robot
    keeps the position where it touched (found by bisection on the blocked sub-step, so it never penetrates),
    still gets the full rotation (a robot against a wall can turn away), and has v set to 0. ``collided`` is
    True when the step was blocked or the disk ends up touching an obstacle. The input state is not modified.
    ``memo``: the caller's :class:`ClearanceMemo` for this robot and ``world`` (consecutive steps), which spares
    the exact clearance query at the start of a step where nothing is near; the result is the same without it.
    """
    dt = _finite(dt)
    radius = params.radius
    if dt <= 0.0:
        touching = world.clearance(state.x, state.y) <= radius + _TOUCH_TOL
        return replace(state, colliding=touching), touching

    v_target, w_target = target_twist(cmd_v, cmd_w, params)
    v0, w0 = _finite(state.v), _finite(state.w)
    dv_max = params.max_linear_accel * dt
    dw_max = params.max_angular_accel * dt
    v1 = v0 + _clamp(v_target - v0, dv_max)
    w1 = w0 + _clamp(w_target - w0, dw_max)

    x, y, yaw = float(state.x), float(state.y), float(state.yaw)
    clear = _Clearance(world, x, y, radius + _TOUCH_TOL, memo)
    start_clear = clear.exact
    blocked = False
    for vm, wm, tau in _velocity_pieces(v0, w0, v1, w1, dt, params):
        if blocked:
            yaw += wm * tau  # position frozen, rotation continues
            continue
        n = max(1, math.ceil(abs(vm) * tau / MAX_SUBSTEP))
        h = tau / n
        for i in range(n):
            nx, ny, nyaw = _arc(x, y, yaw, vm, wm, h)
            c = clear.at(nx, ny)
            # Moves that increase clearance are always allowed, so a robot spawned overlapping an
            # obstacle can back out instead of being stuck forever.
            if c < radius and c < start_clear:
                x, y = _bisect_contact(world, x, y, yaw, vm, wm, h, radius)
                yaw = nyaw + wm * h * (n - 1 - i)
                blocked = True
                break
            x, y, yaw = nx, ny, nyaw
            start_clear = c

    collided = blocked or clear.at(x, y) <= radius + _TOUCH_TOL
    new = RobotState(
        x=x,
        y=y,
        yaw=wrap_angle(yaw),
        # the ramp arithmetic can land a rounding error past the limit (0.22000000000000003)
        v=0.0 if blocked else _clamp(v1, params.max_linear),
        w=_clamp(w1, params.max_angular),
        colliding=collided,
    )
    if memo is not None:
        memo.keep(world, clear.x0, clear.y0, clear.c0)
    return new, collided


class ClearanceMemo:
    """The last exact clearance one robot's steps computed, carried from step to step (see :class:`_Clearance`).

    Why: at 0.22 m/s a robot moves 2 mm a step, so a clearance of 0.5 m measured a few steps ago still bounds
    the present one from below well above the radius; the exact query (every obstacle, each step) is then
    needed only near something. It answers only for the world object and version it was measured in: an
    object appearing, or a world with moving parts (other robots), invalidates it.
    """

    def __init__(self) -> None:
        self._key: tuple[int, int] | None = None
        self._value: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @staticmethod
    def _key_of(world: Any) -> tuple[int, int] | None:
        version = getattr(world, "version", None)  # a World; a world with moving robots has none
        return None if version is None else (id(world), int(version))

    def recall(self, world: Any) -> tuple[float, float, float] | None:
        """(x0, y0, c0) measured in this very ``world`` (object and version), else None."""
        key = self._key_of(world)
        return self._value if key is not None and key == self._key else None

    def keep(self, world: Any, x0: float, y0: float, c0: float) -> None:
        """Remember the exact clearance ``c0`` at (x0, y0) in ``world``."""
        self._key = self._key_of(world)
        self._value = (x0, y0, c0)


class _Clearance:
    """One step's clearance queries, exact only where the answer can matter.

    Clearance is 1-Lipschitz in the position: ``clearance(p) >= c0 - |p - p0|`` for the last exact value c0 at
    p0. Every use in :func:`step` compares a clearance with the radius (plus a touch tolerance ``floor``), so
    where that lower bound is above the floor the bound itself is returned: the comparisons come out exactly as
    with the true value (a bound above the floor never blocks, and a true value that does block, being below
    the radius, is below any such bound as well). A robot far from everything then costs one exact query a
    step instead of three or more.
    """

    def __init__(self, world: World, x: float, y: float, floor: float, memo: ClearanceMemo | None = None) -> None:
        self.world, self.floor = world, floor
        known = memo.recall(world) if memo is not None else None
        if known is not None:
            self.x0, self.y0, self.c0 = known
            bound = self.c0 - math.hypot(x - self.x0, y - self.y0)
            if bound > floor:  # the start's clearance is only compared where the bound decides alike
                self.exact = bound
                return
        self.x0, self.y0 = x, y
        self.exact = self.c0 = world.clearance(x, y)

    def at(self, x: float, y: float) -> float:
        """The clearance at (x, y), or a lower bound of it that is above ``floor``."""
        bound = self.c0 - math.hypot(x - self.x0, y - self.y0)
        if bound > self.floor:
            return bound
        self.x0, self.y0 = x, y
        self.c0 = self.world.clearance(x, y)
        return self.c0


def _bisect_contact(
    world: World, x: float, y: float, yaw: float, v: float, w: float, h: float, radius: float
) -> tuple[float, float]:
    """Furthest collision-free point along the blocked sub-step (to _CONTACT_TOL), so the robot touches.

    Stopping at the previous sub-step instead would leave a random 0-2 cm gap that depends on dt.
    """
    lo, hi = 0.0, h
    best = (x, y)
    while (hi - lo) * abs(v) > _CONTACT_TOL:
        mid = 0.5 * (lo + hi)
        mx, my, _ = _arc(x, y, yaw, v, w, mid)
        if world.clearance(mx, my) >= radius:
            lo, best = mid, (mx, my)
        else:
            hi = mid
    return best
