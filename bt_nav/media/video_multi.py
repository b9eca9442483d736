"""The video of several robots in one world (a bag of ``bt-nav lockstep --robots N --bag``).

Why a renderer of its own: with one robot the path is coloured by the branch that drove it, but two
crossing paths coloured that way cannot be told apart. Here, as in the picture
(:func:`bt_nav_sim.plot.plot_robots`), each robot has one colour (:func:`bt_nav_sim.plot.robot_colour`, in the
bag's robot order) for its path, footprint, scan, start and 1.5 m circle; the caption is the legend (each
robot's name in its colour with its distance and active branch), the side panel shows each robot's running
path of its tree, and the console interleaves every robot's log lines, each prefixed with its name.

It reuses :class:`bt_nav.media.video.VideoRenderer`'s background, world, scan and robot drawing; only what
differs per robot is here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bt_nav.media.bagread import MissionRecord
from bt_nav.media.treetext import active_path, parse_snapshot
from bt_nav.media.video import (
    CONSOLE_Y,
    INK,
    MAP_H,
    MAP_W,
    PANEL_BG,
    STATUS_COLOURS,
    WIDTH,
    VideoRenderer,
    _hex,
    branches,
)


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


class MultiVideoRenderer(VideoRenderer):
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
