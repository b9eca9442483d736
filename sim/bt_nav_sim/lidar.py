"""2D LiDAR model: exact ray casting against world segments and circles, vectorised with numpy.

A scan is one (obstacles x beams) broadcast: no Python loop over beams or obstacles, so a 360-beam scan of
stage_4 costs about 0.1 ms and the simulator can run many times faster than real time.

Reading conventions follow the TurtleBot3 LDS-01 driver as seen in sensor_msgs/LaserScan:
beam i is at robot-frame angle ``angle_min + i * angle_increment`` (CCW positive, 0 = straight ahead);
a hit beyond ``range_max`` (or no hit at all) reads +inf; a hit closer than ``range_min`` reads 0.0 (what
the LDS-01 reports for too-close targets); dropped beams read NaN.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from bt_nav_sim.world import World


@dataclass(frozen=True)
class LidarModel:
    """Beam geometry, range limits and error model of a planar LiDAR."""

    num_beams: int = 360
    angle_min: float = 0.0
    angle_increment: float = 2 * math.pi / 360
    range_min: float = 0.12
    range_max: float = 3.5
    noise_sigma: float = 0.01  # Gaussian range noise, m (LDS-01: +-10 mm at short range)
    rate_hz: float = 5.0
    dropout_prob: float = 0.0  # probability that a beam reads NaN (fault-injection tests)

    def __post_init__(self) -> None:
        if self.num_beams < 1:
            raise ValueError("num_beams must be >= 1")
        if not (0.0 <= self.range_min < self.range_max):
            raise ValueError("need 0 <= range_min < range_max")
        if self.noise_sigma < 0 or not (0.0 <= self.dropout_prob <= 1.0) or self.rate_hz <= 0:
            raise ValueError("need noise_sigma >= 0, 0 <= dropout_prob <= 1 and rate_hz > 0")

    @property
    def angle_max(self) -> float:
        """Angle of the last beam, as in LaserScan.angle_max."""
        return self.angle_min + (self.num_beams - 1) * self.angle_increment


# Tolerance on the segment parameter s in [0, 1] (fraction of the segment length).
_S_EPS = 1e-9

LDS01 = LidarModel()  # TurtleBot3 LDS-01 (360 beams, 0.12-3.5 m, 5 Hz)
HOMEWORK_LIDAR = LidarModel(range_max=10.0, rate_hz=10.0)  # the course homework's simulated profile


class RayCaster:
    """Casts scans of one LidarModel in one World, with everything pose-independent precomputed.

    Ray p + t*u against segment a + s*d: with w = a - p, t = cross(w, d) / cross(u, d) and
    s = cross(w, u) / cross(u, d). Only cross(u, d) and cross(w, u) depend on the beam, so the per-scan
    work is a handful of (obstacles, beams) products written into preallocated buffers.
    Ray against circle (centre c, radius r): with w = c - p, b = u.w, the near hit is
    t = b - sqrt(b^2 - |w|^2 + r^2).
    """

    def __init__(self, world: World, model: LidarModel = LDS01) -> None:
        self.world = world
        self.model = model
        nb = model.num_beams
        ang = model.angle_min + model.angle_increment * np.arange(nb, dtype=np.float64)
        # Beam directions in the robot frame; the scan rotates them by yaw (cheaper than nb trig calls).
        self._cos = np.cos(ang)
        self._sin = np.sin(ang)
        self._prepare()

    def _prepare(self) -> None:
        """Obstacle columns and work buffers of the world as it is now (again after an object appeared:
        ``World.version`` changed; a world without appearing objects is prepared once)."""
        world, nb = self.world, self.model.num_beams
        self._version = world.version
        # Obstacle data as (K, 1) columns: work arrays are (obstacles, beams) so the per-beam minimum is a
        # reduction over rows of contiguous memory (several times faster than reducing short rows).
        segs = world.segments
        self._ax = np.ascontiguousarray(segs[:, 0:1])
        self._ay = np.ascontiguousarray(segs[:, 1:2])
        self._dx = np.ascontiguousarray(segs[:, 2:3] - segs[:, 0:1])
        self._dy = np.ascontiguousarray(segs[:, 3:4] - segs[:, 1:2])
        circ = world.circles
        self._cx = np.ascontiguousarray(circ[:, 0:1])
        self._cy = np.ascontiguousarray(circ[:, 1:2])
        self._r2 = np.ascontiguousarray(circ[:, 2:3] ** 2)
        n, m = segs.shape[0], circ.shape[0]
        # Work buffers, reused by every scan (so one RayCaster must not be shared between threads).
        self._ux = np.empty(nb)
        self._uy = np.empty(nb)
        self._den = np.empty((n, nb))
        self._tmp = np.empty((n, nb))
        self._s = np.empty((n, nb))
        self._t = np.empty((n, nb))
        self._mask = np.empty((n, nb), dtype=bool)
        self._mask2 = np.empty((n, nb), dtype=bool)
        self._cb = np.empty((m, nb))
        self._ctmp = np.empty((m, nb))
        self._cmask = np.empty((m, nb), dtype=bool)
        self._best = np.empty(nb)
        self._cbest = np.empty(nb)

    def true_ranges(self, x: float, y: float, yaw: float, extra: np.ndarray | None = None) -> np.ndarray:
        """Exact distance to the first obstacle along every beam (float64, +inf if none).

        ``extra``: moving circles (K, 3: cx, cy, r) that are not part of the static world, such as the
        other robots of a multi-robot run; they are cast after the world's obstacles, so without them
        the result is exactly the single-robot one. Returns an internal buffer that the next call
        overwrites; copy it to keep it.
        """
        if self.world.version != self._version:
            self._prepare()
        cy, sy = math.cos(yaw), math.sin(yaw)
        ux, uy = self._ux, self._uy
        # World-frame beam directions: rotate the robot-frame ones by yaw.
        np.multiply(self._cos, cy, out=ux)
        ux -= self._sin * sy
        np.multiply(self._cos, sy, out=uy)
        uy += self._sin * cy
        best = self._best
        best.fill(np.inf)

        if self._ax.shape[0]:
            wx = self._ax - x
            wy = self._ay - y
            cwd = wx * self._dy - wy * self._dx  # cross(w, d), beam independent
            den, tmp, s, t = self._den, self._tmp, self._s, self._t
            np.multiply(self._dy, ux, out=den)
            np.multiply(self._dx, uy, out=tmp)
            den -= tmp  # cross(u, d)
            np.multiply(wx, uy, out=s)
            np.multiply(wy, ux, out=tmp)
            s -= tmp  # cross(w, u)
            # Parallel rays (den == 0) divide to inf/nan and are rejected by the range tests below.
            with np.errstate(divide="ignore", invalid="ignore"):
                np.divide(s, den, out=s)
                np.divide(cwd, den, out=t)
            mask, mask2 = self._mask, self._mask2
            # A small tolerance on s so a ray through the shared corner of two walls cannot slip between
            # them on round-off (s = 1 + 1e-16 on one wall and -1e-16 on the next).
            np.greater_equal(s, -_S_EPS, out=mask)
            np.less_equal(s, 1.0 + _S_EPS, out=mask2)
            mask &= mask2
            np.greater_equal(t, 0.0, out=mask2)
            mask &= mask2
            # Invert the mask in place and overwrite misses with inf, then take the nearest hit per beam.
            np.logical_not(mask, out=mask)
            np.copyto(t, np.inf, where=mask)
            np.minimum.reduce(t, axis=0, out=best)

        if self._cx.shape[0]:
            wx = self._cx - x
            wy = self._cy - y
            c2 = wx * wx + wy * wy - self._r2  # < 0: the sensor is inside the cylinder
            b, tmp, cmask = self._cb, self._ctmp, self._cmask
            np.multiply(wx, ux, out=b)
            np.multiply(wy, uy, out=tmp)
            b += tmp  # u . w
            np.multiply(b, b, out=tmp)
            tmp -= c2  # discriminant
            np.less(tmp, 0.0, out=cmask)  # ray misses the circle
            np.copyto(tmp, np.inf, where=cmask)
            np.sqrt(tmp, out=tmp)
            np.subtract(b, tmp, out=tmp)  # near intersection (-inf for misses)
            np.less(tmp, 0.0, out=cmask)  # behind the sensor (or missed)
            np.copyto(tmp, np.inf, where=cmask)
            tmp[c2[:, 0] < 0.0] = 0.0  # inside a cylinder: every beam is blocked at once
            np.minimum.reduce(tmp, axis=0, out=self._cbest)
            np.minimum(best, self._cbest, out=best)
        if extra is not None and len(extra):
            np.minimum(best, circle_ranges(x, y, ux, uy, np.asarray(extra, dtype=np.float64)), out=best)
        return best

    def cast(self, x: float, y: float, yaw: float, rng: np.random.Generator | None = None,
             extra: np.ndarray | None = None) -> np.ndarray:
        """One scan from pose (x, y, yaw): float32 ranges of length num_beams (see module docstring).

        Noise and dropouts are drawn only when ``rng`` is given, and always for every beam in the same
        order (noise, then dropout), so a seed reproduces the same scan regardless of what was hit.
        Noisy valid readings are clipped to [range_min, range_max] so a consumer's validity test agrees
        with the too-close (0.0) / out-of-range (inf) classification made on the true distance.
        ``extra``: moving circles seen besides the world (see :meth:`true_ranges`).
        """
        model = self.model
        true = self.true_ranges(float(x), float(y), float(yaw), extra)
        valid = true <= model.range_max
        near = true < model.range_min
        out = true.copy()
        if rng is not None and model.noise_sigma > 0.0:
            out += rng.normal(0.0, model.noise_sigma, size=out.shape)
            np.clip(out, model.range_min, model.range_max, out=out)
        out[~valid] = np.inf
        out[near] = 0.0
        if rng is not None and model.dropout_prob > 0.0:
            out[rng.random(out.shape) < model.dropout_prob] = np.nan
        return out.astype(np.float32)


def circle_ranges(x: float, y: float, ux: np.ndarray, uy: np.ndarray, circles: np.ndarray) -> np.ndarray:
    """Distance along each beam (unit directions ux, uy from (x, y)) to the nearest of ``circles``
    (K, 3), +inf where none is hit; 0 for every beam when the sensor is inside one.

    Few circles (the other robots), so plain allocating numpy is fine here, unlike the world's obstacles.
    """
    wx = circles[:, 0:1] - x
    wy = circles[:, 1:2] - y
    c2 = wx * wx + wy * wy - circles[:, 2:3] ** 2
    b = wx * ux + wy * uy
    disc = b * b - c2
    with np.errstate(invalid="ignore"):
        t = b - np.sqrt(np.where(disc < 0.0, np.inf, disc))
    t = np.where((disc < 0.0) | (t < 0.0), np.inf, t)
    t[c2[:, 0] < 0.0] = 0.0
    return t.min(axis=0)


# One caster per (world, model), dropped automatically when the world is garbage collected.
_CASTERS: weakref.WeakKeyDictionary[World, dict[LidarModel, RayCaster]] = weakref.WeakKeyDictionary()


def cast_rays(
    world: World,
    x: float,
    y: float,
    yaw: float,
    model: LidarModel = LDS01,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """One scan (float32, num_beams) of ``world`` from pose (x, y, yaw); see RayCaster.cast.

    Convenience wrapper that builds and caches a RayCaster per (world, model). The cached casters share
    work buffers, so call it from one thread at a time (or give each thread its own RayCaster).
    """
    per_world = _CASTERS.get(world)
    if per_world is None:
        per_world = {}
        _CASTERS[world] = per_world
    caster = per_world.get(model)
    if caster is None:
        caster = RayCaster(world, model)
        per_world[model] = caster
    return caster.cast(x, y, yaw, rng)
