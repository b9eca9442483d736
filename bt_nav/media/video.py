"""The mission video: one H.264 MP4 (yuv420p, plays in browsers and on phones) of a recorded mission.

Each frame shows the world, the trajectory so far coloured by the branch that drove it, the 1.5 m circle
around the start, the latest LiDAR scan, the robot's footprint and heading, a caption with sim time,
distance travelled and the active branch (tip and its feedback), a side panel with the tree coloured by
status (running path highlighted) and a console strip with the mission's log lines as they happened.

Why PIL and not matplotlib: a 55 s mission at 10 fps is 550 frames and the budget is 20 s on two cores,
so ~35 ms a frame including the encoder. Frames are drawn with PIL on a pre-rendered background; the
trajectory is drawn incrementally onto a persistent layer, and the tree panel and the console strip
are re-rendered only when their text changes. The encoder is ``imageio-ffmpeg``'s bundled ffmpeg
(libx264, no system ffmpeg). Measured numbers are in the README and ``make bench`` (bench/video.py).

A bag of several robots (:attr:`MissionRecord.robots`) is filmed by :class:`TracksRenderer`: every robot,
its scan, its 1.5 m circle and its path in its own colour (the picture's, :func:`bt_nav_sim.plot.robot_colour`),
a legend with each robot's name, distance and branch, each robot's running path of the tree and one console
of everyone's log lines. :func:`renderer_for` picks the renderer, so a one-robot bag is filmed as before.
"""

from __future__ import annotations

import bisect
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.media.bagread import MissionRecord
from bt_nav.media.treetext import active_path, parse_snapshot

WIDTH, HEIGHT = 1280, 720
MAP_W, MAP_H = 720, 560  # map panel (top left); the tree panel fills the rest of the top
CONSOLE_Y = MAP_H  # console strip: full width below
ROBOT_RADIUS = 0.105  # m: the Burger's footprint circumradius
MIN_DISTANCE = 1.5  # m: the homework's circle around the start
BG, INK, GRID, WALL = (250, 250, 247), (30, 30, 30), (228, 228, 222), (70, 70, 70)
PANEL_BG, CONSOLE_BG, CONSOLE_INK = (244, 244, 250), (22, 24, 28), (210, 215, 220)
STATUS_COLOURS = {"SUCCESS": (30, 140, 50), "FAILURE": (200, 40, 40), "RUNNING": (30, 90, 220),
                  "INVALID": (150, 150, 150)}


def _hex(colour: str) -> tuple[int, int, int]:
    return tuple(int(colour[i:i + 2], 16) for i in (1, 3, 5))  # type: ignore[return-value]


def _fonts() -> tuple[Any, Any]:
    """(regular, mono) TrueType fonts: DejaVu from the system or matplotlib, else PIL's default."""
    from PIL import ImageFont

    candidates = [Path("/usr/share/fonts/truetype/dejavu")]
    try:
        import matplotlib

        candidates.append(Path(matplotlib.get_data_path()) / "fonts" / "ttf")
    except ImportError:
        pass
    for folder in candidates:
        sans, mono = folder / "DejaVuSans.ttf", folder / "DejaVuSansMono.ttf"
        if sans.is_file() and mono.is_file():
            return ImageFont.truetype(str(sans), 15), ImageFont.truetype(str(mono), 13)
    return ImageFont.load_default(15), ImageFont.load_default(13)


@dataclass
class MapView:
    """Metres -> pixels of the map panel (y up, equal aspect, a margin around the bounds)."""

    xmin: float
    ymin: float
    scale: float  # px per metre
    ox: float
    oy: float

    @classmethod
    def fit(cls, bounds: tuple[float, float, float, float], margin: int = 16) -> MapView:
        xmin, ymin, xmax, ymax = bounds
        scale = min((MAP_W - 2 * margin) / max(xmax - xmin, 1e-6), (MAP_H - 2 * margin) / max(ymax - ymin, 1e-6))
        ox = (MAP_W - scale * (xmax - xmin)) / 2
        oy = (MAP_H - scale * (ymax - ymin)) / 2
        return cls(xmin, ymin, scale, ox, oy + scale * (ymax - ymin))

    def px(self, x: Any, y: Any) -> tuple[Any, Any]:
        """Pixel coordinates (arrays or scalars)."""
        return self.ox + (np.asarray(x) - self.xmin) * self.scale, self.oy - (np.asarray(y) - self.ymin) * self.scale


def _bounds(record: MissionRecord, world: Any) -> tuple[float, float, float, float]:
    if world is not None:
        return tuple(world.bounds)  # type: ignore[return-value]
    poses = [r.truth for r in record.robots.values()] or [record.truth]  # every robot must be in the picture
    xs = np.concatenate([p.x for p in poses])
    ys = np.concatenate([p.y for p in poses])
    if xs.size == 0:
        return (-2.0, -2.0, 2.0, 2.0)
    return (float(xs.min()) - 2, float(ys.min()) - 2, float(xs.max()) + 2, float(ys.max()) + 2)


def branches(record: MissionRecord) -> tuple[np.ndarray, list[str], list[str]]:
    """Per tree snapshot: times, branch labels and tip descriptions ("TurnAway: steering +10 deg")."""
    from bt_nav_sim.plot import branch_of_tip

    times, labels, tips = [], [], []
    for t, text in record.trees:
        rows = parse_snapshot(text)
        path = active_path(rows)
        tip = rows[path[-1]] if path else None
        times.append(t)
        labels.append(branch_of_tip(tip.name) if tip else "Stopped")
        tips.append(f"{tip.name}: {tip.feedback}" if tip and tip.feedback else (tip.name if tip else ""))
    return np.asarray(times, dtype=np.float64), labels, tips


class VideoRenderer:
    """Frames of one recorded mission (see the module docstring); ``frame(t)`` must be called with rising t."""

    def __init__(self, record: MissionRecord, world: Any = None) -> None:
        from PIL import Image, ImageDraw

        self._Image, self._Draw = Image, ImageDraw
        self.rec = record
        self.world = world
        self.view = MapView.fit(_bounds(record, world))
        self.font, self.mono = _fonts()
        self.tree_t, self.tree_branch, self.tree_tip = branches(record)
        truth = record.truth
        self.distance = truth.distance()
        idx = np.searchsorted(self.tree_t, truth.t, side="right") - 1
        self.sample_branch = [self.tree_branch[i] if i >= 0 else "Stopped" for i in idx]
        self.events = record.events
        self.event_t = [t for t, _ in record.events]
        self.layer = self._background()
        self._drawn = 1  # trajectory samples already on the layer (segments end at index _drawn)
        self._tree_cache: tuple[int, Any] = (-2, None)
        self._console_cache: tuple[int, Any] = (-1, None)

    # ------------------------------------------------------------------ static parts
    def _background(self) -> Any:
        img = self._Image.new("RGB", (WIDTH, HEIGHT), BG)
        d = self._Draw.Draw(img)
        v = self.view
        xmin, ymin, xmax, ymax = _bounds(self.rec, self.world)
        for gx in np.arange(np.ceil(xmin), xmax + 1e-9, 1.0):
            (px, _), (_, py0), (_, py1) = v.px(gx, 0), v.px(0, ymin), v.px(0, ymax)
            d.line([(float(px), float(py0)), (float(px), float(py1))], fill=GRID)
        for gy in np.arange(np.ceil(ymin), ymax + 1e-9, 1.0):
            (px0, py), (px1, _) = v.px(xmin, gy), v.px(xmax, gy)
            d.line([(float(px0), float(py)), (float(px1), float(py))], fill=GRID)
        if self.world is not None:
            self._draw_world(d)
        self._draw_start(d)
        d.rectangle([MAP_W, 0, WIDTH, MAP_H], fill=PANEL_BG)
        d.line([(MAP_W, 0), (MAP_W, MAP_H)], fill=(180, 180, 190), width=2)
        return img

    def _draw_start(self, d: Any, truth: Any = None, colour: tuple[int, int, int] = (31, 119, 180)) -> None:
        """The start point and the 1.5 m circle around it (of ``truth``, default the record's)."""
        truth = self.rec.truth if truth is None else truth
        if len(truth):
            cx, cy = self.view.px(truth.x[0], truth.y[0])
            r = MIN_DISTANCE * self.view.scale
            d.ellipse([cx - r, cy - r, cx + r, cy + r], outline=colour, width=2)
            d.ellipse([cx - 5, cy - 5, cx + 5, cy + 5], fill=colour)

    def _draw_world(self, d: Any) -> None:
        from bt_nav_sim.world import box_corners

        v = self.view
        for box in self.world.boxes:
            xs, ys = v.px(*np.asarray(box_corners(*box)).T)
            d.polygon(list(zip(xs.tolist(), ys.tolist(), strict=True)), fill=(110, 110, 110), outline=WALL)
        for x1, y1, x2, y2 in self.world.segments:
            (a, b), (c, e) = v.px(x1, y1), v.px(x2, y2)
            d.line([(float(a), float(b)), (float(c), float(e))], fill=WALL, width=3)
        for cx, cy, r in self.world.circles:
            px, py = v.px(cx, cy)
            rp = r * v.scale
            d.ellipse([px - rp, py - rp, px + rp, py + rp], fill=(110, 110, 110), outline=WALL)

    # ------------------------------------------------------------------ per frame
    def _extend_trail(self, upto: int) -> None:
        """Draw trajectory segments up to sample ``upto`` onto the persistent layer."""
        from bt_nav_sim.plot import BRANCH_COLOURS

        if upto <= self._drawn:
            return
        tr, d = self.rec.truth, self._Draw.Draw(self.layer)
        xs, ys = self.view.px(tr.x[self._drawn - 1:upto], tr.y[self._drawn - 1:upto])
        for k in range(len(xs) - 1):
            colour = _hex(BRANCH_COLOURS.get(self.sample_branch[self._drawn + k], "#000000"))
            d.line([(float(xs[k]), float(ys[k])), (float(xs[k + 1]), float(ys[k + 1]))], fill=colour, width=3)
        self._drawn = upto

    def _draw_scan(self, d: Any, t: float, x: float, y: float, yaw: float, scans: Any = None,
                   colour: tuple[int, int, int] = (230, 40, 40)) -> None:
        scans = self.rec.scans if scans is None else scans
        k = int(np.searchsorted(scans.t, t, side="right")) - 1
        if k < 0 or scans.ranges.size == 0:
            return
        r = scans.ranges[k]
        ok = np.isfinite(r) & (r < scans.range_max)
        a = scans.angles[ok] + yaw
        px, py = self.view.px(x + r[ok] * np.cos(a), y + r[ok] * np.sin(a))
        for u, w in zip(px.tolist(), py.tolist(), strict=True):
            d.rectangle([u - 1.5, w - 1.5, u + 1.5, w + 1.5], fill=colour)

    def _draw_robot(self, d: Any, x: float, y: float, yaw: float, fill: tuple[int, int, int] = (40, 40, 40)) -> None:
        px, py = self.view.px(x, y)
        r = ROBOT_RADIUS * self.view.scale
        d.ellipse([px - r, py - r, px + r, py + r], fill=fill, outline=(255, 255, 255), width=2)
        hx, hy = self.view.px(x + 2.2 * ROBOT_RADIUS * np.cos(yaw), y + 2.2 * ROBOT_RADIUS * np.sin(yaw))
        d.line([(float(px), float(py)), (float(hx), float(hy))], fill=(255, 200, 0), width=3)

    def frame(self, t: float) -> Any:
        """The frame at sim time ``t`` (a PIL RGB image of WIDTH x HEIGHT)."""
        tr = self.rec.truth
        i = int(np.searchsorted(tr.t, t, side="right")) - 1
        self._extend_trail(i + 1)
        img = self.layer.copy()
        d = self._Draw.Draw(img)
        k = int(np.searchsorted(self.tree_t, t, side="right")) - 1
        if i >= 0:
            self._draw_scan(d, t, tr.x[i], tr.y[i], tr.yaw[i])
            self._draw_robot(d, tr.x[i], tr.y[i], tr.yaw[i])
        branch = self.tree_branch[k] if k >= 0 else "Stopped"
        tip = self.tree_tip[k] if k >= 0 else ""
        travelled = self.distance[i] if i >= 0 else 0.0
        d.rectangle([0, 0, MAP_W, 46], fill=(255, 255, 255))
        d.text((10, 4), f"t = {t - self.rec.start:6.2f} s    travelled {travelled:5.2f} m    {branch}",
               font=self.font, fill=INK)
        d.text((10, 25), tip[:90], font=self.mono, fill=(70, 70, 90))
        img.paste(self._tree_panel(k), (MAP_W + 2, 0))
        img.paste(self._console(bisect.bisect_right(self.event_t, t)), (0, CONSOLE_Y))
        return img

    def _tree_panel(self, k: int) -> Any:
        """The tree of snapshot ``k`` coloured by status (cached while the snapshot is the same)."""
        if self._tree_cache[0] == k:
            return self._tree_cache[1]
        img = self._Image.new("RGB", (WIDTH - MAP_W - 2, MAP_H), PANEL_BG)
        d = self._Draw.Draw(img)
        d.text((8, 6), "behaviour tree", font=self.font, fill=INK)
        rows = parse_snapshot(self.rec.trees[k][1]) if k >= 0 else []
        on_path = set(active_path(rows))
        step = min(15, (MAP_H - 30) // max(len(rows), 1))
        for n, row in enumerate(rows):
            y = 28 + n * step
            colour = STATUS_COLOURS[row.status]
            if n in on_path:
                d.rectangle([2, y - 1, WIDTH - MAP_W - 6, y + step - 2], fill=(255, 243, 190))
            x = 8 + 14 * row.depth
            d.rectangle([x, y + 3, x + 7, y + 10], fill=colour)
            label = row.name + (f" - {row.feedback}" if row.feedback else "")
            d.text((x + 12, y), label[:70 - 2 * row.depth], font=self.mono, fill=colour)
        self._tree_cache = (k, img)
        return img

    def _console(self, n_events: int) -> Any:
        """The console strip with the first ``n_events`` log lines, newest at the bottom (cached)."""
        if self._console_cache[0] == n_events:
            return self._console_cache[1]
        img = self._Image.new("RGB", (WIDTH, HEIGHT - CONSOLE_Y), CONSOLE_BG)
        d = self._Draw.Draw(img)
        lines = self.events[:n_events][-9:]
        for n, (t, text) in enumerate(lines):
            ink = (255, 255, 255) if n == len(lines) - 1 else CONSOLE_INK
            d.text((10, 6 + 17 * n), f"[{t - self.rec.start:7.2f}] {text}"[:160], font=self.mono, fill=ink)
        self._console_cache = (n_events, img)
        return img


def renderer_for(record: MissionRecord, world: Any = None) -> VideoRenderer:
    """The renderer of this bag: :class:`TracksRenderer` when it holds robots in namespaces (each in its
    colour), else :class:`VideoRenderer` (one robot, its path coloured by branch)."""
    if record.robots:
        return TracksRenderer(record, world)
    return VideoRenderer(record, world)


def frame_times(record: MissionRecord, fps: float) -> np.ndarray:
    """Sim times of the frames: round(duration x fps) frames (at least one), from the bag's start."""
    n = max(1, round(record.duration * fps))
    return record.start + np.arange(n) / fps


@dataclass
class VideoStats:
    """What :func:`write_video` did."""

    path: Path
    frames: int
    fps: float
    seconds: float  # wall time to render and encode


def iter_frames(record: MissionRecord, fps: float, world: Any = None) -> Iterator[Any]:
    """The frames of the video, as PIL images."""
    renderer = renderer_for(record, world)
    for t in frame_times(record, fps):
        yield renderer.frame(float(t))


def write_video(record: MissionRecord, out: str | Path, fps: float = 10.0, world: Any = None) -> VideoStats:
    """Render ``record`` to an H.264 MP4 (yuv420p) at ``out``; returns the frame count and wall time."""
    import imageio_ffmpeg

    started = time.perf_counter()
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio_ffmpeg.write_frames(str(path), (WIDTH, HEIGHT), fps=fps, codec="libx264",
                                         pix_fmt_out="yuv420p", quality=None, bitrate=None,
                                         ffmpeg_log_level="error", macro_block_size=16,
                                         output_params=["-preset", "veryfast", "-crf", "23",
                                                        "-movflags", "+faststart"])
    writer.send(None)
    frames = 0
    try:
        for img in iter_frames(record, fps, world):
            writer.send(img.tobytes())
            frames += 1
    finally:
        writer.close()
    return VideoStats(path, frames, fps, time.perf_counter() - started)


def world_of(record: MissionRecord) -> Any:
    """The world the bag's /bt_nav/mission names (None when it names none or it cannot be loaded)."""
    from bt_nav_sim.world import load_world

    name = record.mission.get("world")
    if not name:
        return None
    try:
        return load_world(str(name), seed=int(record.mission.get("seed", 0) or 0))
    except (OSError, ValueError, KeyError):
        return None


def trajectory(record: MissionRecord) -> Any:
    """The bag's ground truth as a :class:`bt_nav_sim.plot.Trajectory`, each sample labelled with its branch."""
    from bt_nav_sim.plot import Trajectory

    tr = record.truth
    tree_t, labels, _ = branches(record)
    idx = np.searchsorted(tree_t, tr.t, side="right") - 1
    return Trajectory(tr.t, tr.x, tr.y, tr.yaw, np.array([labels[i] if i >= 0 else "Stopped" for i in idx],
                                                         dtype=object))


def plot_bag(record: MissionRecord, out: str | Path, world: Any = None) -> Path:
    """The trajectory picture (:func:`bt_nav_sim.plot.plot_run`) of a bag; the verdict from /bt_nav/mission."""
    from bt_nav_sim.plot import plot_run
    from bt_nav_sim.world import World

    world = world if world is not None else world_of(record)
    if world is None:
        bounds = _bounds(record, None)
        world = World(name=str(record.mission.get("world", record.path.name)), segments=np.zeros((0, 4)),
                      circles=np.zeros((0, 3)), spawn=(0.0, 0.0, 0.0), bounds=bounds)
    if record.robots:
        return _plot_robots_bag(record, out, world)
    dist = record.truth.distance()
    results = {"travelled": float(dist[-1]) if dist.size else 0.0, "collisions": len(record.collisions),
               "collision_events": [c for c in record.collisions if "x" in c and "y" in c]}
    if "passed" in record.mission:
        results["passed"] = bool(record.mission["passed"])
    return plot_run(world, trajectory(record), results, out, title=f"{world.name} (bag {record.path.name})")


def _plot_robots_bag(record: MissionRecord, out: str | Path, world: Any) -> Path:
    """The several-robot picture (:func:`bt_nav_sim.plot.plot_robots`) of a bag: one path per robot."""
    from bt_nav_sim.plot import plot_robots

    runs = []
    for name, rec in record.robots.items():
        dist = rec.truth.distance()
        passed = any(text == "verdict: PASSED" for _, text in rec.events)
        runs.append((name, trajectory(rec), {"travelled": float(dist[-1]) if dist.size else 0.0, "passed": passed,
                                             "collisions": len(rec.collisions)}))
    return plot_robots(world, runs, out, title=f"{world.name} (bag {record.path.name})")

# ---------------------------------------------------------------------- several robots: one track each
# Why a renderer subclass: with one robot the path is coloured by the branch that drove it, but two
# crossing paths coloured that way cannot be told apart. With several, as in the picture
# (:func:`bt_nav_sim.plot.plot_robots`), each robot has one colour (:func:`bt_nav_sim.plot.robot_colour`, in
# the bag's robot order) for its path, footprint, scan, start and 1.5 m circle; the caption is the legend
# (each robot's name in its colour with its distance and active branch), the side panel shows each robot's
# running path of its tree, and the console interleaves every robot's log lines, prefixed with its name.

@dataclass
class Track:
    """One robot of the film: its name, record and colour, and how much of its path is on the layer."""

    name: str
    rec: MissionRecord
    colour: tuple[int, int, int]
    drawn: int = 1  # trajectory samples already on the layer (segments end at index ``drawn``)
    distance: np.ndarray = field(init=False)
    tree: tuple[np.ndarray, list[str], list[str]] = field(init=False)

    def __post_init__(self) -> None:
        self.distance = self.rec.truth.distance()
        self.tree = branches(self.rec)

    def index(self, t: float) -> int:
        """The last ground-truth sample at or before ``t`` (-1: none yet)."""
        return int(np.searchsorted(self.rec.truth.t, t, side="right")) - 1

    def snapshot(self, t: float) -> int:
        """The last tree snapshot at or before ``t`` (-1: none yet)."""
        return int(np.searchsorted(self.tree[0], t, side="right")) - 1


def robot_colours(record: MissionRecord) -> dict[str, tuple[int, int, int]]:
    """Robot name -> RGB, the picture's palette in the bag's robot order (one home: bt_nav_sim.plot)."""
    from bt_nav_sim.plot import robot_colour

    return {name: _hex(robot_colour(i)) for i, name in enumerate(record.robots)}


class TracksRenderer(VideoRenderer):
    """Frames of a several-robot bag (see the module docstring); ``frame(t)`` must be called with rising t."""

    def __init__(self, record: MissionRecord, world: Any = None) -> None:
        self.tracks = [Track(name, rec, colour) for (name, rec), colour in
                       zip(record.robots.items(), robot_colours(record).values(), strict=True)]
        super().__init__(record, world)  # draws the background, so the tracks must exist before
        merged = sorted(((t, f"{tr.name}: {text}") for tr in self.tracks for t, text in tr.rec.events),
                        key=lambda e: e[0])
        self.events = merged
        self.event_t = [t for t, _ in merged]
        self._paths_cache: tuple[tuple[int, ...], Any] = ((), None)

    @property
    def colours(self) -> dict[str, tuple[int, int, int]]:
        """Robot name -> the RGB its path, footprint and legend entry are drawn in."""
        return {tr.name: tr.colour for tr in self.tracks}

    def _draw_start(self, d: Any, truth: Any = None, colour: tuple[int, int, int] = (0, 0, 0)) -> None:
        """Every robot's start and 1.5 m circle in its colour."""
        for tr in getattr(self, "tracks", ()):
            super()._draw_start(d, tr.rec.truth, tr.colour)

    def _extend_track(self, tr: Track, upto: int) -> None:
        """Draw ``tr``'s path up to sample ``upto`` onto the persistent layer, in its colour."""
        if upto <= tr.drawn:
            return
        truth = tr.rec.truth
        xs, ys = self.view.px(truth.x[tr.drawn - 1:upto], truth.y[tr.drawn - 1:upto])
        points = list(zip(xs.tolist(), ys.tolist(), strict=True))
        self._Draw.Draw(self.layer).line(points, fill=tr.colour, width=3, joint="curve")
        tr.drawn = upto

    def frame(self, t: float) -> Any:
        """The frame at sim time ``t`` (a PIL RGB image of WIDTH x HEIGHT)."""
        now = [(tr, tr.index(t), tr.snapshot(t)) for tr in self.tracks]
        for tr, i, _ in now:
            self._extend_track(tr, i + 1)
        img = self.layer.copy()
        d = self._Draw.Draw(img)
        for tr, i, _ in now:
            if i >= 0:
                truth = tr.rec.truth
                scan_ink = tuple(int(c + (255 - c) * 0.45) for c in tr.colour)  # lighter than the path
                self._draw_scan(d, t, truth.x[i], truth.y[i], truth.yaw[i], tr.rec.scans, scan_ink)
                self._draw_robot(d, truth.x[i], truth.y[i], truth.yaw[i], fill=tr.colour)
                px, py = self.view.px(truth.x[i], truth.y[i])
                d.text((float(px) + 9, float(py) - 22), tr.name, font=self.mono, fill=tr.colour)
        self._legend(d, t, now)
        img.paste(self._paths_panel(tuple(k for _, _, k in now)), (MAP_W + 2, 0))
        img.paste(self._console(int(np.searchsorted(self.event_t, t, side="right"))), (0, CONSOLE_Y))
        return img

    def _legend(self, d: Any, t: float, now: list[tuple[Track, int, int]]) -> None:
        """The caption: sim time, then per robot a swatch, its name, distance and branch in its colour."""
        d.rectangle([0, 0, MAP_W, 46], fill=(255, 255, 255))
        d.text((10, 4), f"t = {t - self.rec.start:6.2f} s    {len(self.tracks)} robots", font=self.font, fill=INK)
        width = (MAP_W - 10) // max(len(now), 1)
        for n, (tr, i, k) in enumerate(now):
            x = 10 + n * width
            d.rectangle([x, 29, x + 12, 39], fill=tr.colour)
            branch = tr.tree[1][k] if k >= 0 else "Stopped"
            travelled = tr.distance[i] if i >= 0 else 0.0
            label = f"{tr.name}  {travelled:5.2f} m  {branch}"
            d.text((x + 17, 26), label[:max(8, (width - 20) // 8)], font=self.mono, fill=tr.colour)

    def _paths_panel(self, ks: tuple[int, ...]) -> Any:
        """Each robot's running path of its tree (name in its colour, rows coloured by status); cached."""
        if self._paths_cache[0] == ks and self._paths_cache[1] is not None:
            return self._paths_cache[1]
        img = self._Image.new("RGB", (WIDTH - MAP_W - 2, MAP_H), PANEL_BG)
        d = self._Draw.Draw(img)
        d.text((8, 6), "behaviour trees: running path", font=self.font, fill=INK)
        y = 30
        for tr, k in zip(self.tracks, ks, strict=True):
            d.text((8, y), tr.name, font=self.font, fill=tr.colour)
            y += 20
            rows = parse_snapshot(tr.rec.trees[k][1]) if k >= 0 else []
            for row in (rows[n] for n in active_path(rows)):
                x = 8 + 10 * row.depth
                d.rectangle([x, y + 3, x + 7, y + 10], fill=STATUS_COLOURS[row.status])
                label = row.name + (f" - {row.feedback}" if row.feedback else "")
                d.text((x + 12, y), label[:66 - row.depth], font=self.mono, fill=STATUS_COLOURS[row.status])
                y += 15
            y += 10
        self._paths_cache = (ks, img)
        return img
