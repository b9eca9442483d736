"""The film of a robot's run (``bt-nav video BAG`` of a bag with no ground truth): an H.264 MP4 drawn from what the
robot itself recorded (:class:`bt_nav.media.robotrun.RobotRun`).

Each frame: the room as the scans so far saw it, laid out in the odometry frame (grey: every return up to now,
red: the latest scan), the odometry path (blue), the robot with its heading, its command (an arrow for the speed,
an arc for the turn rate, and the numbers), a caption with the time and the pose; on the right the check-off's lines
as the judge decided them (each maneuver's line when its turn settled, the verdict at the end); below, the node's
/rosout lines; and in the map's corner where the data came from (:attr:`RobotRun.source`).

:func:`write_robot_video` also writes, per frame, every text drawn on it (``<video>.console.json``,
:class:`bt_nav.media.console.ConsoleLog`): label, caption, check-off lines and console rows.

Same canvas and encoder settings as the simulator's film (:mod:`bt_nav.media.video`); PIL, layers drawn
incrementally (the room and the path only grow).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.media.console import CONSOLE_ROWS, ConsoleLog
from bt_nav.media.robotrun import ROBOT_TIME_BASE, RobotRun
from bt_nav.media.video import (
    BG,
    CONSOLE_BG,
    CONSOLE_INK,
    CONSOLE_Y,
    GRID,
    HEIGHT,
    INK,
    MAP_H,
    MAP_W,
    PANEL_BG,
    ROBOT_RADIUS,
    WIDTH,
    MapView,
    _fonts,
    open_mp4,
)

ROOM, SCAN, PATH, ROBOT = (150, 150, 150), (230, 40, 40), (31, 119, 180), (40, 40, 40)
COMMAND = (20, 150, 60)
PASSED, FAILED, NOT_JUDGED = (30, 140, 50), (200, 40, 40), (150, 110, 20)
#: How far outside the path the picture reaches (m): a LiDAR's far returns would shrink the robot to a dot.
VIEW_REACH = 3.0


def bounds(run: RobotRun) -> tuple[float, float, float, float]:
    """The map's extent: the path, and the scans' returns within :data:`VIEW_REACH` of it."""
    path = run.path_xy()
    xs, ys = [path[:, 1]], [path[:, 2]]
    lo_x, hi_x = float(path[:, 1].min()) - VIEW_REACH, float(path[:, 1].max()) + VIEW_REACH
    lo_y, hi_y = float(path[:, 2].min()) - VIEW_REACH, float(path[:, 2].max()) + VIEW_REACH
    for k in range(len(run.rec.scans)):
        _, x, y = run.scan_points(k)
        keep = (x > lo_x) & (x < hi_x) & (y > lo_y) & (y < hi_y)
        xs.append(x[keep])
        ys.append(y[keep])
    x, y = np.concatenate(xs), np.concatenate(ys)
    pad = 0.3
    return float(x.min()) - pad, float(y.min()) - pad, float(x.max()) + pad, float(y.max()) + pad


def line_colour(text: str) -> tuple[int, int, int]:
    """A check-off line's colour by its verdict word."""
    if "NOT JUDGED" in text:
        return NOT_JUDGED
    return FAILED if text.endswith("FAILED") else PASSED if text.endswith("PASSED") else INK


class RobotFilmRenderer:
    """Frames of a robot's run; ``frame(t)`` must be called with rising t (absolute, on the recording's clock)."""

    def __init__(self, run: RobotRun) -> None:
        from PIL import Image, ImageDraw

        self._Image, self._Draw = Image, ImageDraw
        self.run = run
        self.view = MapView.fit(bounds(run))
        self.font, self.mono = _fonts()
        self.layer = self._background()
        self._scans_drawn = 0
        self._path_drawn = 0
        self._scan_t = np.asarray([t for t, _ in run.rec.scans])
        self._path = run.path_xy()
        self._logs = [(t, f"[{logger}]: {line}") for t, logger, line in run.rec.announcements]

    def _background(self) -> Any:
        """The grid and the panels' ground (metres grid lines every 1 m)."""
        img = self._Image.new("RGB", (WIDTH, HEIGHT), BG)
        d = self._Draw.Draw(img)
        xmin, ymin, xmax, ymax = bounds(self.run)
        v = self.view
        for gx in np.arange(math.ceil(xmin), xmax + 1e-9, 1.0):
            (px, py0), (_, py1) = v.px(gx, ymin), v.px(gx, ymax)
            d.line([(float(px), float(py0)), (float(px), float(py1))], fill=GRID)
        for gy in np.arange(math.ceil(ymin), ymax + 1e-9, 1.0):
            (px0, py), (px1, _) = v.px(xmin, gy), v.px(xmax, gy)
            d.line([(float(px0), float(py)), (float(px1), float(py))], fill=GRID)
        d.rectangle([MAP_W, 0, WIDTH, MAP_H], fill=PANEL_BG)
        d.line([(MAP_W, 0), (MAP_W, MAP_H)], fill=(180, 180, 190), width=2)
        return img

    def _grow(self, t: float) -> None:
        """The room (every scan up to ``t``) and the path, drawn once onto the persistent layer."""
        d = self._Draw.Draw(self.layer)
        upto = int(np.searchsorted(self._scan_t, t, side="right"))
        for k in range(self._scans_drawn, upto):
            _, x, y = self.run.scan_points(k)
            px, py = self.view.px(x, y)
            for u, w in zip(px.tolist(), py.tolist(), strict=True):
                if 0 <= u < MAP_W and 0 <= w < MAP_H:
                    d.point((u, w), fill=ROOM)
        self._scans_drawn = max(self._scans_drawn, upto)
        n = int(np.searchsorted(self._path[:, 0], t, side="right"))
        if n > self._path_drawn + 1:
            seg = self._path[max(0, self._path_drawn - 1):n]
            px, py = self.view.px(seg[:, 1], seg[:, 2])
            d.line(list(zip(px.tolist(), py.tolist(), strict=True)), fill=PATH, width=3)
            self._path_drawn = n

    def caption(self, t: float) -> str:
        """The frame's caption: time, odometry pose and command."""
        pose, cmd = self.run.pose_at(t), self.run.command_at(t)
        where = f"odom x {pose[0]:+.2f} m  y {pose[1]:+.2f} m  yaw {math.degrees(pose[2]):+.0f} deg" if pose else \
            "no odometry yet"
        command = f"cmd v {cmd[0]:+.2f} m/s  w {cmd[1]:+.2f} rad/s" if cmd else "no command yet"
        return f"t = {t - self.run.origin:6.2f} {ROBOT_TIME_BASE}\n{where}   {command}"

    def console_rows(self, t: float) -> list[str]:
        """The node's /rosout lines up to ``t`` (the newest), each on the film's time base."""
        shown = [f"[{lt - self.run.origin:7.2f}] {text}" for lt, text in self._logs if lt <= t]
        return shown[-CONSOLE_ROWS:]

    def texts(self, t: float) -> list[str]:
        """Every text the frame at ``t`` shows: the source label, the caption, the check-off lines, the console."""
        return [self.run.source, self.caption(t), *self.panel_rows(t), *self.console_rows(t)]

    def panel_rows(self, t: float) -> list[str]:
        """The check-off panel: its heading, then the lines decided by ``t`` (or why there are none)."""
        head = f"check-off of maneuver {self.run.maneuver}" if self.run.maneuver else "check-off: not judged"
        return [head, *self.run.lines_at(t), *([] if self.run.lines else self.run.notes)]

    def frame(self, t: float) -> Any:
        """The frame at ``t`` (a PIL RGB image, WIDTH x HEIGHT)."""
        self._grow(t)
        img = self.layer.copy()
        d = self._Draw.Draw(img)
        k = int(np.searchsorted(self._scan_t, t, side="right")) - 1
        if k >= 0:
            _, x, y = self.run.scan_points(k)
            px, py = self.view.px(x, y)
            for u, w in zip(px.tolist(), py.tolist(), strict=True):
                if 0 <= u < MAP_W and 0 <= w < MAP_H:
                    d.rectangle([u - 1.5, w - 1.5, u + 1.5, w + 1.5], fill=SCAN)
        pose = self.run.pose_at(t)
        if pose is not None:
            self._robot(d, *pose, self.run.command_at(t))
        d.rectangle([0, 0, MAP_W, 44], fill=(255, 255, 255))
        for k, text in enumerate(self.caption(t).split("\n")):
            d.text((8, 4 + 19 * k), text[:88], font=self.mono, fill=INK)
        self._panel(d, t)
        self._console(d, t)
        self._label(d)
        return img

    def _robot(self, d: Any, x: float, y: float, yaw: float, cmd: tuple[float, float] | None) -> None:
        v = self.view
        px, py = v.px(x, y)
        r = max(ROBOT_RADIUS * v.scale, 4.0)
        d.ellipse([px - r, py - r, px + r, py + r], fill=ROBOT, outline=(255, 255, 255), width=2)
        hx, hy = v.px(x + 2.2 * ROBOT_RADIUS * math.cos(yaw), y + 2.2 * ROBOT_RADIUS * math.sin(yaw))
        d.line([(float(px), float(py)), (float(hx), float(hy))], fill=(255, 200, 0), width=3)
        if cmd is None:
            return
        speed, turn = cmd
        if abs(speed) > 1e-3:  # an arrow as long as 2 s of driving (at least 0.15 m)
            reach = math.copysign(max(abs(speed) * 2.0, 0.15), speed)
            ax, ay = v.px(x + reach * math.cos(yaw), y + reach * math.sin(yaw))
            d.line([(float(px), float(py)), (float(ax), float(ay))], fill=COMMAND, width=4)
        if abs(turn) > 1e-3:  # an arc around the robot, as far as 1 s of turning, counter-clockwise = left
            rr = r + 8
            start = -math.degrees(yaw)
            sweep = -math.degrees(turn)
            lo, hi = sorted((start, start + sweep))
            d.arc([px - rr, py - rr, px + rr, py + rr], lo, hi, fill=COMMAND, width=4)

    def _panel(self, d: Any, t: float) -> None:
        y = 10
        for k, row in enumerate(self.panel_rows(t)):
            colour = INK if k == 0 else line_colour(row)
            for piece in _wrap(row, 62):
                if y > MAP_H - 20:
                    return
                d.text((MAP_W + 12, y), piece, font=self.mono if k else self.font, fill=colour)
                y += 18
            y += 4

    def _console(self, d: Any, t: float) -> None:
        d.rectangle([0, CONSOLE_Y, WIDTH, HEIGHT], fill=CONSOLE_BG)
        for k, row in enumerate(self.console_rows(t)):
            d.text((10, CONSOLE_Y + 8 + 17 * k), row[:150], font=self.mono, fill=CONSOLE_INK)

    def _label(self, d: Any) -> None:
        box = d.textbbox((8, MAP_H - 22), self.run.source, font=self.font)
        d.rectangle([box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2], fill=(255, 255, 255), outline=(150, 150, 160))
        d.text((8, MAP_H - 22), self.run.source, font=self.font, fill=(90, 90, 110))


def _wrap(text: str, width: int) -> list[str]:
    """``text`` in pieces of at most ``width`` characters, broken at spaces where it can be."""
    out, rest = [], text
    while len(rest) > width:
        cut = rest.rfind(" ", 0, width)
        cut = cut if cut > width // 2 else width
        out.append(rest[:cut])
        rest = "    " + rest[cut:].lstrip()
    return [*out, rest]


@dataclass
class RobotVideoStats:
    """What :func:`write_robot_video` did."""

    path: Path
    frames: int
    fps: float
    seconds: float
    sidecar: Path | None


def frame_times(run: RobotRun, fps: float) -> np.ndarray:
    """Absolute times of the frames: every 1/fps s from the recording's start, the last one at its end (so the
    film's last frame shows the verdict, decided there)."""
    n = max(1, math.ceil(max(0.0, run.end - run.origin) * fps - 1e-9) + 1)
    return np.minimum(run.origin + np.arange(n) / fps, run.end)


def write_robot_video(run: RobotRun, out: str | Path, fps: float = 10.0,
                      sidecar: str | Path | None = None) -> RobotVideoStats:
    """Render ``run`` to an H.264 MP4 (yuv420p) at ``out``; ``sidecar``: also write every frame's texts there."""
    started = time.perf_counter()
    path = Path(out)
    writer = open_mp4(path, fps)
    renderer = RobotFilmRenderer(run)
    log = ConsoleLog(path, ROBOT_TIME_BASE) if sidecar else None
    frames = 0
    try:
        for t in frame_times(run, fps):
            writer.send(renderer.frame(float(t)).tobytes())
            if log is not None:
                log.add(float(t) - run.origin, renderer.texts(float(t)))
            frames += 1
    finally:
        writer.close()
    if log is not None and sidecar is not None:
        log.write(Path(sidecar))
    return RobotVideoStats(path, frames, fps, time.perf_counter() - started, Path(sidecar) if sidecar else None)
