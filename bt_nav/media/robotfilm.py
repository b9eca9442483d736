"""The film of a robot's run (``bt-nav video BAG`` of a bag with no ground truth): an H.264 MP4 drawn from what the
robot itself recorded (:class:`bt_nav.media.robotrun.RobotRun`), for a TA to show.

Each frame: the room as the scans saw it, laid out in the odometry frame (grey: every return up to now, red: the
latest scan; once the robot was moved by hand or carried the odometry no longer places a scan, so the room stops
growing there and says so), the odometry path (blue; orange where the robot was stuck, magenta where it was moved by
hand or carried), the robot with its heading and its current command (an arrow for the speed, an arc for the turn
rate), a caption with the time, the pose and the command (``no command for 2.1 s`` when the node sent none for more
than :data:`bt_nav.media.robotrun.COMMAND_STALE` s), a banner while an interval the judge set apart happens (a topic
silent, stuck, moved by hand, carried: the judge's words), a scale bar; on the right the check-off's lines as the
judge decided them (each maneuver's when its turn settled, each data line when its interval ended); below, the
node's /rosout lines at INFO and above, repeats folded (:class:`bt_nav.media.console.FoldedLines`); in the map's
corner where the data came from (:attr:`RobotRun.source`). The film ends on the verdict card (:func:`card_layout`:
every line of the verdict, whole, the overall verdict first and last) held for :data:`CARD_HOLD` s.

The film never judges: every word of the panel, the banners and the card is the judge's
(:func:`bt_nav.judge.recorded.judge_recording`, read once by :func:`bt_nav.media.robotrun.load_robot_run`).

:func:`write_robot_video` also writes, per frame, every text drawn on it (``<video>.console.json``,
:class:`bt_nav.media.console.ConsoleLog`): label, caption, banners, notes, scale, check-off lines, console rows, card.

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

from bt_nav.media.console import INFO, ConsoleLog, FoldedLines
from bt_nav.media.robotrun import HANDLED, ROBOT_TIME_BASE, Mark, RobotRun
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
#: The colour of each kind of interval the judge sets apart (path and banner).
MARK_COLOURS = {"stuck": (230, 130, 0), "moved by hand": (200, 0, 160), "carried": (200, 0, 160),
                "gap": (110, 60, 180)}
#: How far outside the path the picture reaches (m): a LiDAR's far returns would shrink the robot to a dot.
VIEW_REACH = 3.0
#: s the verdict card is held at the film's end (a TA pauses on it; 3 s at the least).
CARD_HOLD = 4.0
#: The check-off panel: characters a row, text lines that fit (18 px each from y=10 to the map's bottom).
PANEL_CHARS, PANEL_LINES = 62, 28
#: Lengths a scale bar may take (m): the one drawn is 60-160 px long.
SCALE_STEPS = (0.1, 0.2, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0)


def bounds(run: RobotRun) -> tuple[float, float, float, float]:
    """The map's extent: the path, and the room's returns (:func:`room_scans`) within :data:`VIEW_REACH` of it."""
    path = run.path_xy()
    xs, ys = [path[:, 1]], [path[:, 2]]
    lo_x, hi_x = float(path[:, 1].min()) - VIEW_REACH, float(path[:, 1].max()) + VIEW_REACH
    lo_y, hi_y = float(path[:, 2].min()) - VIEW_REACH, float(path[:, 2].max()) + VIEW_REACH
    for k in range(room_scans(run)):
        _, x, y = run.scan_points(k)
        keep = (x > lo_x) & (x < hi_x) & (y > lo_y) & (y < hi_y)
        xs.append(x[keep])
        ys.append(y[keep])
    x, y = np.concatenate(xs), np.concatenate(ys)
    pad = 0.3
    return float(x.min()) - pad, float(y.min()) - pad, float(x.max()) + pad, float(y.max()) + pad


def room_scans(run: RobotRun) -> int:
    """How many of the scans make the picture of the room: those before the robot was first moved by hand or carried
    (:attr:`RobotRun.room_until`); after that its odometry no longer says where a scan was taken."""
    until = run.room_until
    if until is None:
        return len(run.rec.scans)
    return int(np.searchsorted(np.asarray([t for t, _ in run.rec.scans]), until, side="right"))


def scale_bar(px_per_m: float) -> tuple[float, float]:
    """The scale bar: (metres, pixels), the first of :data:`SCALE_STEPS` at least 60 px long (else the longest)."""
    for metres in SCALE_STEPS:
        if metres * px_per_m >= 60:
            return metres, metres * px_per_m
    return SCALE_STEPS[-1], SCALE_STEPS[-1] * px_per_m


def fit_panel(head: str, rows: list[str], chars: int = PANEL_CHARS, lines: int = PANEL_LINES) -> list[str]:
    """The panel's rows as drawn: the heading, then ``rows`` whose wrapped lines fit in ``lines``; when they do not,
    the oldest data lines give way first, then the other lines but the maneuvers' and the overall verdict (which stay
    on screen), then the oldest rows, and a row says how many (the card at the end shows every one)."""
    kept = list(rows)

    def need(keep: list[str]) -> int:
        return sum(len(_wrap(row, chars)) for row in keep) + (1 if len(keep) < len(rows) else 0)

    def last_to_go(row: str) -> bool:  # the maneuvers' verdicts, their count and the overall verdict
        return any(f"] {word}" in row or row.startswith(word) for word in ("maneuver", "overall:"))

    while kept and need(kept) > lines - 1:
        data = next((k for k, row in enumerate(kept) if "] data: " in row or row.startswith("data: ")), None)
        other = next((k for k, row in enumerate(kept) if not last_to_go(row)), 0)
        kept.pop(data if data is not None else other)
    dropped = len(rows) - len(kept)
    return [head, *([f"({dropped} line{'s' if dropped > 1 else ''} not shown here: all in the verdict at the end)"]
                    if dropped else []), *kept]


def line_colour(text: str) -> tuple[int, int, int]:
    """A check-off line's colour by its verdict word."""
    if "NOT JUDGED" in text:
        return NOT_JUDGED
    return FAILED if text.endswith("FAILED") else PASSED if text.endswith("PASSED") else INK


@dataclass(frozen=True)
class CardRow:
    """One drawn row of the verdict card: its text, colour, whether in the large font, and its top (px)."""

    text: str
    colour: tuple[int, int, int]
    big: bool
    y: int


#: The verdict card's margin (px), its mono sizes tried from the largest, the title's line height.
CARD_MARGIN, CARD_SIZES, CARD_TITLE_H = 20, (13, 12, 11, 10), 26


def card_lines(run: RobotRun) -> list[str]:
    """The verdict as the card says it: the title with the overall verdict, where the data came from and the time
    zero, then every line of the judge's report (the overall verdict last)."""
    report = run.report or [line.text for line in run.lines]
    overall = next((line for line in report if line.startswith("overall:")), "overall: not judged")
    feed = (run.verdict or {}).get("feed", {})
    window = feed.get("window", [0.0, run.end - run.origin])
    title = f"check-off of maneuver {run.maneuver} from {run.path.name}: {overall}"
    about = (f"{run.source}; t=0: {feed.get('time_zero', 'the first message')}; window t={window[0]:.1f}-"
             f"{window[1]:.1f} s; armed: {feed.get('arming', 'not known')}")
    return [title, about, *report, *([] if report else run.notes)]


def card_layout(run: RobotRun, mono_width: Any) -> tuple[list[CardRow], int]:
    """The card's rows and the mono size they fit at (``mono_width(size)``: a character's width in px at that size).
    Every line wrapped to the frame's width, the largest size that fits; at the smallest, the last data lines that do
    not fit are counted in one row, never the overall verdict (in the title and the last row)."""
    lines = card_lines(run)
    title, body = lines[0], lines[1:]
    rows: list[CardRow] = []
    for size in CARD_SIZES:
        rows = _card_rows(title, body, size, mono_width(size), run.source)
        if _fits(rows, size):
            return rows, size
    size = CARD_SIZES[-1]
    data = [k for k, text in enumerate(body) if text.startswith("data: ")]
    dropped = 0
    while data:
        body.pop(data.pop())
        dropped += 1
        trial = [*body[:-1], f"... and {dropped} more data line(s): in the terminal's report", body[-1]]
        rows = _card_rows(title, trial, size, mono_width(size), run.source)
        if _fits(rows, size):
            break
    return rows, size


def _fits(rows: list[CardRow], size: int) -> bool:
    return rows[-1].y + size + 4 <= HEIGHT - CARD_MARGIN


def _card_rows(title: str, body: list[str], size: int, char_width: float, source: str) -> list[CardRow]:
    """The card's rows at one mono size: the title, then each line wrapped to the frame's width."""
    chars = int((WIDTH - 2 * CARD_MARGIN) // char_width)
    rows, y = [CardRow(title, line_colour(title), True, CARD_MARGIN)], CARD_MARGIN + CARD_TITLE_H
    for text in body:
        colour = INK if text.startswith(source) else line_colour(text)
        for piece in _wrap(text, chars):
            rows.append(CardRow(piece, colour, False, y))
            y += size + 4
    return rows


class RobotFilmRenderer:
    """Frames of a robot's run; ``frame(t)`` must be called with rising t (absolute, on the recording's clock)."""

    def __init__(self, run: RobotRun) -> None:
        from PIL import Image, ImageDraw

        self._Image, self._Draw = Image, ImageDraw
        self.run = run
        self.view = MapView.fit(bounds(run))
        self.font, self.mono = _fonts()
        variant = getattr(self.font, "font_variant", None)
        self._title = variant(size=19) if variant is not None else self.font  # the card's title
        self.layer = self._background()
        self._scans_drawn = 0
        self._room = room_scans(run)
        self._path_drawn = 0
        self._scan_t = np.asarray([t for t, _ in run.rec.scans])
        self._path = run.path_xy()
        shown = [(t, f"[{logger}]: {line}") for t, level, logger, line in run.rec.log if level >= INFO]
        self.console = FoldedLines(shown)

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
        """The room (every scan up to ``t`` that the odometry still places) and the path, drawn once onto the
        persistent layer; the path in a mark's colour where the judge set it apart."""
        d = self._Draw.Draw(self.layer)
        upto = min(int(np.searchsorted(self._scan_t, t, side="right")), self._room)
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
            for k in range(len(seg) - 1):
                marks = self.run.marks_at(float(seg[k + 1, 0]))
                colour = MARK_COLOURS.get(marks[0].kind, PATH) if marks else PATH
                d.line([(float(px[k]), float(py[k])), (float(px[k + 1]), float(py[k + 1]))], fill=colour, width=3)
            self._path_drawn = n

    def caption(self, t: float) -> str:
        """The frame's caption: time, odometry pose and the current command (or how long none has come)."""
        pose = self.run.pose_at(t)
        where = f"odom x {pose[0]:+.2f} m  y {pose[1]:+.2f} m  yaw {math.degrees(pose[2]):+.0f} deg" if pose else \
            "no odometry yet"
        return f"t = {t - self.run.origin:6.2f} {ROBOT_TIME_BASE}\n{where}   {self.run.command_words(t)}"

    def banners(self, t: float) -> list[tuple[Mark, str]]:
        """What is set apart as it happens (the judge's words), one banner each."""
        return [(m, f"{m.kind.upper()}: {m.text}") for m in self.run.marks_at(t)]

    def map_notes(self, t: float) -> list[str]:
        """The map's notes: the scale, and once the room stopped growing, since when and why."""
        metres, _ = scale_bar(self.view.scale)
        notes = [f"scale: {metres:g} m"]
        until = self.run.room_until
        if until is not None and t >= until:
            kind = next(m.kind for m in self.run.marks if m.kind in HANDLED and m.start == until)
            notes.append(f"room drawn from the scans up to t={until - self.run.origin:.1f} s (then {kind})")
        return notes

    def console_rows(self, t: float) -> list[str]:
        """The node's /rosout lines up to ``t`` at INFO and above, repeats folded, each on the film's time base."""
        return self.console.rows(t, self.run.origin)

    def texts(self, t: float, card: bool = False) -> list[str]:
        """Every text the frame at ``t`` shows: the source label, the caption, banners, map notes, the check-off
        panel and the console; on the card (``card``), the card's rows (it covers the rest)."""
        if card:  # it covers the frame: its rows are all the frame shows (the source is in its second line)
            return [row.text for row in card_layout(self.run, self._char_width)[0]]
        shown = [self.run.source, self.caption(t), *(text for _, text in self.banners(t)), *self.map_notes(t)]
        return [*shown, *self.panel_rows(t), *self.console_rows(t)]

    def panel_rows(self, t: float) -> list[str]:
        """The check-off panel as drawn: its heading, then the newest lines decided by ``t`` that fit (or why there
        are none)."""
        head = f"check-off of maneuver {self.run.maneuver}" if self.run.maneuver else "check-off: not judged"
        return fit_panel(head, [*self.run.lines_at(t), *([] if self.run.lines else self.run.notes)])

    def frame(self, t: float, card: bool = False) -> Any:
        """The frame at ``t`` (a PIL RGB image, WIDTH x HEIGHT); ``card``: the verdict card over it."""
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
            self._robot(d, *pose, self.run.current_command(t))
        d.rectangle([0, 0, MAP_W, 44], fill=(255, 255, 255))
        for k, text in enumerate(self.caption(t).split("\n")):
            d.text((8, 4 + 19 * k), text[:96], font=self.mono, fill=INK)
        self._banners(d, t)
        self._scale_and_notes(d, t)
        self._panel(d, t)
        self._console(d, t)
        self._label(d)
        if card:
            self._card(d)
        return img

    def _char_width(self, size: int) -> float:
        """A character's width (px) in the mono font at ``size`` (a monospaced font: every one alike)."""
        return float(self._mono(size).getlength("M"))

    def _mono(self, size: int) -> Any:
        variant = getattr(self.mono, "font_variant", None)
        return variant(size=size) if variant is not None else self.mono

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

    def _banners(self, d: Any, t: float) -> None:
        """A coloured banner under the caption for each interval set apart that is happening."""
        y = 50
        for mark, text in self.banners(t):
            for piece in _wrap(text, 92):
                box = d.textbbox((10, y), piece, font=self.mono)
                d.rectangle([4, box[1] - 3, MAP_W - 4, box[3] + 3], fill=MARK_COLOURS.get(mark.kind, FAILED))
                d.text((10, y), piece, font=self.mono, fill=(255, 255, 255))
                y += 19
            y += 4

    def _scale_and_notes(self, d: Any, t: float) -> None:
        """The scale bar in the map's bottom right corner, the room's note above the source label."""
        metres, length = scale_bar(self.view.scale)
        x1, y = MAP_W - 16, MAP_H - 14
        x0 = x1 - length
        d.line([(x0, y), (x1, y)], fill=INK, width=3)
        for x in (x0, x1):
            d.line([(x, y - 6), (x, y + 2)], fill=INK, width=2)
        label = f"{metres:g} m"
        d.text(((x0 + x1) / 2 - d.textlength(label, font=self.font) / 2, y - 24), label, font=self.font, fill=INK)
        for k, note in enumerate(self.map_notes(t)[1:]):
            d.text((8, MAP_H - 46 - 18 * k), note[:92], font=self.mono, fill=(90, 90, 110))

    def _panel(self, d: Any, t: float) -> None:
        y = 10
        for k, row in enumerate(self.panel_rows(t)):
            colour = INK if k == 0 else line_colour(row)
            for piece in _wrap(row, PANEL_CHARS):
                if y > MAP_H - 20:
                    return
                d.text((MAP_W + 12, y), piece, font=self.mono if k else self.font, fill=colour)
                y += 18
            y += 4 if k == 0 else 0

    def _console(self, d: Any, t: float) -> None:
        d.rectangle([0, CONSOLE_Y, WIDTH, HEIGHT], fill=CONSOLE_BG)
        for k, row in enumerate(self.console_rows(t)):
            d.text((10, CONSOLE_Y + 8 + 17 * k), row, font=self.mono, fill=CONSOLE_INK)

    def _label(self, d: Any) -> None:
        box = d.textbbox((8, MAP_H - 22), self.run.source, font=self.font)
        d.rectangle([box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2], fill=(255, 255, 255), outline=(150, 150, 160))
        d.text((8, MAP_H - 22), self.run.source, font=self.font, fill=(90, 90, 110))

    def _card(self, d: Any) -> None:
        """The verdict card over the whole frame (:func:`card_layout`)."""
        rows, size = card_layout(self.run, self._char_width)
        mono = self._mono(size)
        d.rectangle([6, 6, WIDTH - 6, HEIGHT - 6], fill=(255, 255, 255), outline=line_colour(rows[0].text), width=4)
        for row in rows:
            d.text((CARD_MARGIN, row.y), row.text, font=self._title if row.big else mono, fill=row.colour)


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
    """Absolute times of the frames of the run: every 1/fps s from the recording's start, the last one at its end
    (where the verdict is decided); the card's frames follow (:func:`card_frames`)."""
    n = max(1, math.ceil(max(0.0, run.end - run.origin) * fps - 1e-9) + 1)
    return np.minimum(run.origin + np.arange(n) / fps, run.end)


def card_frames(fps: float) -> int:
    """How many frames hold the verdict card at the end (:data:`CARD_HOLD` s)."""
    return math.ceil(CARD_HOLD * fps)


def film_frames(run: RobotRun, fps: float) -> list[tuple[float, bool]]:
    """Every frame of the film: (absolute time, whether it is the verdict card), the run's frames then, when the run
    was judged, the card held at its end."""
    frames = [(float(t), False) for t in frame_times(run, fps)]
    return frames + [(run.end, True)] * (card_frames(fps) if run.lines else 0)


def write_robot_video(run: RobotRun, out: str | Path, fps: float = 10.0,
                      sidecar: str | Path | None = None) -> RobotVideoStats:
    """Render ``run`` to an H.264 MP4 (yuv420p) at ``out``, the verdict card held at its end when the run was
    judged; ``sidecar``: also write every frame's texts there."""
    started = time.perf_counter()
    path = Path(out)
    writer = open_mp4(path, fps)
    renderer = RobotFilmRenderer(run)
    log = ConsoleLog(path, ROBOT_TIME_BASE) if sidecar else None
    frames = film_frames(run, fps)
    try:
        for t, card in frames:
            writer.send(renderer.frame(t, card).tobytes())
            if log is not None:
                log.add(t - run.origin, renderer.texts(t, card))
    finally:
        writer.close()
    if log is not None and sidecar is not None:
        log.write(Path(sidecar))
    return RobotVideoStats(path, len(frames), fps, time.perf_counter() - started, Path(sidecar) if sidecar else None)
