"""2D LiDAR model: exact ray casting against world segments and circles, vectorised with numpy.

A scan is one (obstacles x beams) broadcast: no Python loop over beams or obstacles, so a 360-beam scan of
stage_4 costs about 0.1 ms and the simulator can run many times faster than real time.

Reading conventions as seen in sensor_msgs/LaserScan: beam i is at sensor-frame angle ``angle_min + i *
angle_increment`` (CCW positive, 0 = straight ahead; a negative increment sweeps clockwise), cast from the
sensor's mount on the robot. The profiles' own models read +inf beyond ``range_max``, 0.0 closer than
``range_min`` and NaN for a dropped beam; the named real sensors of :data:`LIDARS` read what their drivers
publish (the LDS-01's 0.0 for no return, the LDS-02's NaN and varying beam count, the RPLIDAR's -pi..pi and
+inf, a 270 deg Hokuyo mounted off-centre).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from bt_nav_sim.world import World


@dataclass(frozen=True)
class ScanLayout:
    """Where one scan's beams point (the LaserScan fields that say so): beam i at ``angle_min + i *
    angle_increment`` in the sensor frame."""

    angle_min: float
    angle_increment: float
    num_beams: int

    @property
    def angle_max(self) -> float:
        """Angle of the last beam, as in LaserScan.angle_max."""
        return self.angle_min + (self.num_beams - 1) * self.angle_increment

    def angles(self) -> np.ndarray:
        """Every beam's angle (rad, sensor frame)."""
        return self.angle_min + self.angle_increment * np.arange(self.num_beams, dtype=np.float64)


@dataclass(frozen=True)
class LidarModel:
    """Beam geometry, range limits, mounting and error model of a planar LiDAR.

    The defaults are the idealised LDS-01 the profiles have always used (+inf for nothing in range); the named
    real sensors of :data:`LIDARS` say what their drivers publish instead.
    """

    num_beams: int = 360
    angle_min: float = 0.0
    angle_increment: float = 2 * math.pi / 360
    range_min: float = 0.12
    range_max: float = 3.5
    noise_sigma: float = 0.01  # Gaussian range noise, m (LDS-01: +-10 mm at short range)
    rate_hz: float = 5.0
    dropout_prob: float = 0.0  # probability that a beam reads ``dropout_value`` (a lost return)
    name: str = ""  # the registry's name (``lidar`` parameter); empty: a profile's own model
    label: str = ""  # what a report calls it
    frame_id: str = "base_scan"
    mount_x: float = 0.0  # m: the sensor's position in the robot's frame (forward, left)
    mount_y: float = 0.0
    no_return: float = math.inf  # what a beam with nothing within range_max reads
    too_close: float = 0.0  # what a beam closer than range_min reads
    dropout_value: float = math.nan  # what a lost return reads
    speed_spread: float = 0.0  # relative spread of the spin rate per scan: the beam count and start vary (LDS-02)
    published_range: tuple[float, float] | None = None  # (range_min, range_max) the driver publishes, if not the above

    def __post_init__(self) -> None:
        if self.num_beams < 1:
            raise ValueError("num_beams must be >= 1")
        if not (0.0 <= self.range_min < self.range_max):
            raise ValueError("need 0 <= range_min < range_max")
        if self.noise_sigma < 0 or not (0.0 <= self.dropout_prob <= 1.0) or self.rate_hz <= 0:
            raise ValueError("need noise_sigma >= 0, 0 <= dropout_prob <= 1 and rate_hz > 0")
        if not 0.0 <= self.speed_spread < 0.5:
            raise ValueError("need 0 <= speed_spread < 0.5")

    @property
    def angle_max(self) -> float:
        """Angle of the last beam, as in LaserScan.angle_max."""
        return self.angle_min + (self.num_beams - 1) * self.angle_increment

    @property
    def layout(self) -> ScanLayout:
        """The nominal layout (every scan's, unless ``speed_spread`` varies it)."""
        return ScanLayout(self.angle_min, self.angle_increment, self.num_beams)

    @property
    def message_range(self) -> tuple[float, float]:
        """The (range_min, range_max) a LaserScan of this sensor carries."""
        return self.published_range or (self.range_min, self.range_max)

    def next_layout(self, rng: np.random.Generator | None) -> ScanLayout:
        """The layout of the next scan: the nominal one, or for a sensor whose spin rate wanders (LDS-02) a beam
        spacing of ``angle_increment * (1 + u * speed_spread)`` and a first beam somewhere in the first spacing,
        so the beam count differs from scan to scan as the driver's does. Deterministic for the stream ``rng``."""
        if not self.speed_spread or rng is None:
            return self.layout
        increment = self.angle_increment * (1.0 + self.speed_spread * float(rng.uniform(-1.0, 1.0)))
        start = self.angle_min + abs(increment) * float(rng.uniform(0.0, 1.0))
        span = 2 * math.pi - abs(increment)
        count = int(math.floor((span - (start - self.angle_min)) / abs(increment))) + 1
        return ScanLayout(start, increment, max(1, count))

    def mount_params(self) -> dict[str, float]:
        """The executive's parameters that tell it where this LiDAR sits (what TF's base_link -> scan frame says
        on a robot); none for a sensor at the centre, so a profile's own LiDAR changes nothing."""
        if not (self.mount_x or self.mount_y):
            return {}
        return {"scan_mount_x": self.mount_x, "scan_mount_y": self.mount_y}

    def describe(self) -> dict[str, object]:
        """What a run's files and bags record about the sensor."""
        lo, hi = self.message_range
        return {"name": self.name or "profile default", "label": self.label or "idealised LDS-01 layout",
                "frame_id": self.frame_id, "mount": [self.mount_x, self.mount_y], "rate_hz": self.rate_hz,
                "beams": self.num_beams, "angle_min": self.angle_min, "angle_increment": self.angle_increment,
                "range": [lo, hi], "variable_beams": bool(self.speed_spread)}


# Tolerance on the segment parameter s in [0, 1] (fraction of the segment length).
_S_EPS = 1e-9

LDS01 = LidarModel()  # TurtleBot3 LDS-01 (360 beams, 0.12-3.5 m, 5 Hz), idealised: +inf for nothing in range
HOMEWORK_LIDAR = LidarModel(range_max=10.0, rate_hz=10.0)  # the course homework's simulated profile

#: The real LiDARs a course robot carries, as their ROS 2 drivers publish them (``lidar`` parameter, ``--lidars``).
#: A node that computes its indices from ``angle_min`` and ``angle_increment`` reads them all alike; one that
#: hard-codes ``ranges[0]`` as the front or 360 beams does not.
LIDARS: dict[str, LidarModel] = {
    # ROBOTIS-GIT/hls_lfcd_lds_driver src/hlds_laser_publisher.cpp: angle_min 0, angle_increment 2pi/360, 360
    # ranges of range/1000 (a raw 0, no return, reads 0.0), range 0.12-3.5 m; 300 rpm = 5 Hz. Mounted as
    # turtlebot3_description's burger base_scan joint: x -0.032 m. Dark or glancing surfaces lose returns (0.0).
    "lds01": LidarModel(name="lds01", label="TurtleBot3 LDS-01 (0..2pi, 0.0 = no return)", mount_x=-0.032,
                        no_return=0.0, too_close=0.0, dropout_prob=0.005, dropout_value=0.0),
    # The same driver with chronological_order true: angle_min 0, angle_increment -pi/180 (clockwise).
    "lds01_cw": LidarModel(name="lds01_cw", label="TurtleBot3 LDS-01, chronological order (clockwise)",
                           angle_increment=-2 * math.pi / 360, mount_x=-0.032, no_return=0.0, too_close=0.0,
                           dropout_prob=0.005, dropout_value=0.0),
    # ROBOTIS-GIT/ld08_driver src/lipkg.cpp ToLaserscan: angle_min/max are the first and last points' angles,
    # angle_increment = spin speed / 2300 samples/s, beam_size = ceil((max - min) / increment): a different count
    # every scan; every beam starts NaN and only returns are filled in; the message says range 0-100 m. The
    # LD08 sees 0.16-8 m; ~1800 deg/s (5 Hz).
    "lds02": LidarModel(name="lds02", label="TurtleBot3 LDS-02 (beam count varies, NaN = no return)",
                        num_beams=460, angle_increment=math.radians(1800.0 / 2300.0), range_min=0.16,
                        range_max=8.0, mount_x=-0.032, no_return=math.nan, too_close=math.nan,
                        dropout_prob=0.005, speed_spread=0.02, published_range=(0.0, 100.0)),
    # Slamtec/rplidar_ros src/rplidar_node.cpp publish_scan: with angle compensation the 0..360 deg of the device
    # become angle_min = pi - 2pi = -pi, angle_increment = 2pi / (node_count - 1); a 0 reading is +inf; range
    # 0.15 m to max_distance (A1: 12 m). TurtleBot4's A1M8 in boost mode: 720 beams at 10 Hz.
    "rplidar": LidarModel(name="rplidar", label="TurtleBot4 RPLIDAR A1 (-pi..pi, inf = no return)", num_beams=720,
                          angle_min=-math.pi, angle_increment=2 * math.pi / 719, range_min=0.15, range_max=12.0,
                          rate_hz=10.0, frame_id="rplidar_link", no_return=math.inf, too_close=math.inf),
    # ros-drivers/urg_node (urg_c_wrapper.cpp) on a Hokuyo UST-10LX: -135..+135 deg in 0.25 deg steps (1081
    # beams), 0.06-10 m, 40 Hz; the device's readings pass through, a lost echo as an error code of a few mm
    # (below range_min). Mounted on a bracket ahead of and beside the robot's centre.
    "ust10": LidarModel(name="ust10", label="Hokuyo UST-10LX 270 deg, mounted off-centre (+0.08, +0.03 m)",
                        num_beams=1081, angle_min=math.radians(-135.0), angle_increment=math.radians(0.25),
                        range_min=0.06, range_max=10.0, rate_hz=40.0, frame_id="laser", mount_x=0.08, mount_y=0.03,
                        no_return=0.001, too_close=0.001, dropout_prob=0.002, dropout_value=0.001),
}


def lidar_model(name: str) -> LidarModel:
    """The registry's model called ``name`` (ValueError listing the names otherwise)."""
    try:
        return LIDARS[name]
    except KeyError:
        raise ValueError(f"unknown lidar {name!r}; choose one of {', '.join(LIDARS)}") from None


def closed_quads(segs: np.ndarray) -> np.ndarray:
    """Row indices (Q, 4) of the runs of four consecutive segments that close a convex counter-clockwise
    quadrilateral, each ending exactly where the next begins (the boxes of a world: ``box_segments``)."""
    quads = []
    i, n = 0, segs.shape[0]
    while i + 4 <= n:
        four = segs[i:i + 4]
        closed = bool(np.array_equal(four[:, 2:4], np.roll(four[:, 0:2], -1, axis=0)))
        d = four[:, 2:4] - four[:, 0:2]
        turns = d[:, 0] * np.roll(d[:, 1], -1) - d[:, 1] * np.roll(d[:, 0], -1)
        if closed and bool(np.all(turns > 0.0)):
            quads.append(range(i, i + 4))
            i += 4
        else:
            i += 1
    return np.asarray(quads, dtype=np.intp).reshape(-1, 4)


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
        self.layout = model.layout
        self._set_angles(self.layout)
        self._prepare()

    def _set_angles(self, layout: ScanLayout) -> None:
        """Beam directions in the sensor frame; the scan rotates them by yaw (cheaper than nb trig calls)."""
        ang = layout.angles()
        self._cos = np.cos(ang)
        self._sin = np.sin(ang)
        self._still: tuple[tuple[float, ...], np.ndarray, np.ndarray, np.ndarray] | None = None  # _classified

    def use_layout(self, layout: ScanLayout) -> None:
        """Cast the next scans with ``layout`` (a sensor whose beam count varies: LDS-02)."""
        if layout == self.layout:
            return
        resize = layout.num_beams != self.layout.num_beams
        self.layout = layout
        self._set_angles(layout)
        if resize:
            self._prepare()

    def sensor_pose(self, x: float, y: float, yaw: float) -> tuple[float, float]:
        """Where the sensor is when the robot's centre is at (x, y) heading ``yaw`` (its mount offset)."""
        mx, my = self.model.mount_x, self.model.mount_y
        if not (mx or my):
            return x, y
        c, s = math.cos(yaw), math.sin(yaw)
        return x + mx * c - my * s, y + mx * s + my * c

    def _prepare(self) -> None:
        """Obstacle columns and work buffers of the world as it is now (again after an object appeared:
        ``World.version`` changed; a world without appearing objects is prepared once)."""
        world, nb = self.world, self.layout.num_beams
        self._version = world.version
        self._still = None
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
        self._quads = closed_quads(segs)
        self._front: tuple[np.ndarray, tuple[np.ndarray, ...]] | None = None  # the last _facing choice
        self._front_back = np.zeros(0, dtype=bool)
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

    def _facing(self, cwd: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]] | None:
        """The segments a ray from the sensor can hit first, and their (a_x, a_y, d_x, d_y) columns (None: all).

        The faces of a closed box (:func:`closed_quads`) whose inner side the sensor is on (``cwd`` > 0: the
        interior is on each face's left) are hidden behind the box's front faces: a ray from outside a convex
        polygon enters it through a face turned towards the ray, so leaving the far faces out changes no range
        and halves the work a box costs. A sensor inside a box (every face turned away) keeps all four. The
        choice changes only when the sensor crosses a face's line, so it is kept until the pattern changes.
        """
        quads = self._quads
        if not quads.shape[0]:
            return None
        back = cwd[:, 0] > 0.0
        if self._front is not None and np.array_equal(back, self._front_back):
            return self._front
        hidden = back[quads]
        hidden &= ~hidden.all(axis=1, keepdims=True)
        keep = np.ones(cwd.shape[0], dtype=bool)
        keep[quads[hidden]] = False
        front = np.flatnonzero(keep)
        self._front_back = back
        self._front = (front, tuple(a[front] for a in (self._ax, self._ay, self._dx, self._dy)))
        return self._front

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
            ax, ay, dx, dy = self._ax, self._ay, self._dx, self._dy
            wx = ax - x
            wy = ay - y
            cwd = wx * dy - wy * dx  # cross(w, d), beam independent; > 0: the sensor is on the segment's left
            facing = self._facing(cwd)
            if facing is not None:
                front, (ax, ay, dx, dy) = facing
                wx, wy, cwd = wx[front], wy[front], cwd[front]
            k = ax.shape[0]
            den, tmp, s, t = self._den[:k], self._tmp[:k], self._s[:k], self._t[:k]
            np.multiply(dy, ux, out=den)
            np.multiply(dx, uy, out=tmp)
            den -= tmp  # cross(u, d)
            np.multiply(wx, uy, out=s)
            np.multiply(wy, ux, out=tmp)
            s -= tmp  # cross(w, u)
            # Parallel rays (den == 0) divide to inf/nan and are rejected by the range tests below.
            with np.errstate(divide="ignore", invalid="ignore"):
                np.divide(s, den, out=s)
                np.divide(cwd, den, out=t)
            mask, mask2 = self._mask[:k], self._mask2[:k]
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
            if k:
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
        sx, sy = self.sensor_pose(float(x), float(y), float(yaw))
        true, invalid, near = self._classified(sx, sy, float(yaw), extra)
        if rng is not None and model.noise_sigma > 0.0:
            out = rng.normal(0.0, model.noise_sigma, size=true.shape)
            out += true
            np.clip(out, model.range_min, model.range_max, out=out)
        else:
            out = true.copy()
        out[invalid] = model.no_return
        out[near] = model.too_close
        if rng is not None and model.dropout_prob > 0.0:
            out[rng.random(out.shape) < model.dropout_prob] = model.dropout_value
        return out.astype(np.float32)

    def _classified(self, x: float, y: float, yaw: float,
                    extra: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The true ranges from the sensor at (x, y, yaw), beyond ``range_max`` (or NaN) and closer than
        ``range_min``: kept while the sensor stands still in an unchanged world.

        Why: a robot waiting to be armed, after its deadline or stopped by a guard casts scan after scan
        from the very same pose (a third of a lock-step homework mission's scans); their geometry is the
        same to the bit, only the noise drawn on top differs. Moving circles (``extra``) end the reuse.
        """
        key = (x, y, yaw, float(self.world.version))  # a new layout clears the entry (_set_angles)
        still = self._still
        if still is not None and still[0] == key and (extra is None or not len(extra)):
            return still[1], still[2], still[3]
        true = self.true_ranges(x, y, yaw, extra)
        model = self.model
        entry = (key, true.copy(), ~(true <= model.range_max), true < model.range_min)
        self._still = entry if extra is None or not len(extra) else None
        return entry[1], entry[2], entry[3]


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
