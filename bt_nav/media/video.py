"""The mission video: one H.264 MP4 (yuv420p, plays in browsers and on phones) of a recorded mission.

Each frame shows the world, the trajectory so far coloured by the branch that drove it, the 1.5 m circle
around the start, the latest LiDAR scan, the robot's footprint and heading, a caption with sim time,
distance travelled and the active branch (tip and its feedback), a side panel with the tree coloured by
status (running path highlighted) and a console strip with the mission's log lines as they happened.

What a frame says is computed apart from the drawing (:class:`FrameText`, :meth:`Track.text`) and is that
frame's own: one time base, sim seconds since the bag's first /clock (:data:`TIME_BASE`, written in the
caption; ``bt-nav video --still --at T`` is the frame whose clock reads T); feedback only of nodes ticked in
the snapshot at that instant, countdowns counted down to the frame (:func:`live_feedback`), a maneuver's turn
so far from ground truth; the scan placed from the pose at the scan's own stamp
(:meth:`~bt_nav.media.bagread.MissionRecord.scan_at`); the console filtered by one rule
(:data:`bt_nav.media.console.HIDDEN_PREFIXES`), or a hand-in's terminal (:class:`bt_nav.media.console.ConsoleScript`:
the command, the launch line it stands in for, the node's lines and the service calls, on the sim clock, which is
then the frame's time base). Every frame says it is a simulation (:data:`bt_nav.media.console.SIM_LABEL`), and
:func:`write_video` can record the console rows of every frame it drew (:class:`bt_nav.media.console.ConsoleLog`).

Why PIL and not matplotlib: a 55 s mission at 10 fps is 550 frames and the budget is 20 s on two cores,
so ~35 ms a frame including the encoder. Frames are drawn with PIL on a pre-rendered background; the
trajectory is drawn incrementally onto a persistent layer, and the tree panel and the console strip
are re-rendered only when their text changes. The encoder is ``imageio-ffmpeg``'s bundled ffmpeg
(libx264, no system ffmpeg). Measured numbers are in docs/benchmarks.md and ``make bench`` (bench/video.py).

A bag of several robots (:attr:`MissionRecord.robots`) is filmed by :class:`TracksRenderer`: every robot,
its scan, its 1.5 m circle and its path in its own colour (the picture's, :func:`bt_nav.media.plot.robot_colour`),
a legend with each robot's name, distance and branch, each robot's running path of the tree and one console
of everyone's log lines. :func:`renderer_for` picks the renderer, so a one-robot bag is filmed as before.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.media.bagread import MissionRecord
from bt_nav.media.console import (
    CONSOLE_ROWS,
    SIM_LABEL,
    ConsoleLog,
    ConsoleScript,
    command_at,
    console_lines,
    doing_text,
    motion_text,
    node_lines,
)
from bt_nav.mission.snapshot import DEADLINE, DEADLINE_LEFT, TO_GO, SnapshotNode, snapshot_nodes

WIDTH, HEIGHT = 1280, 720
MAP_W, MAP_H = 720, 560  # map panel (top left); the tree panel fills the rest of the top
CONSOLE_Y = MAP_H  # console strip: full width below
ROBOT_RADIUS = 0.105  # m: the Burger's footprint circumradius
BG, INK, GRID, WALL = (250, 250, 247), (30, 30, 30), (228, 228, 222), (70, 70, 70)
PANEL_BG, CONSOLE_BG, CONSOLE_INK = (244, 244, 250), (22, 24, 28), (210, 215, 220)
STATUS_COLOURS = {"SUCCESS": (30, 140, 50), "FAILURE": (200, 40, 40), "RUNNING": (30, 90, 220),
                  "INVALID": (150, 150, 150)}


def status_colour(status: str) -> tuple[int, int, int]:
    """A status's colour; a status this module does not know (a py_trees newer than the film) is drawn in ink."""
    return STATUS_COLOURS.get(status, INK)


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


# ---------------------------------------------------------------------- what a frame says
# Why a section of its own: every text of a frame (caption, tree panel, legend, console) must be that frame's
# own, on one time base, and a test compares it with the bag. The drawing code only draws these strings.

TIME_BASE = "since the bag's first /clock"  # the origin of every time a picture shows (MissionRecord.origin)

#: s: a tip's feedback older than this is shown with its time (snapshots come only when a status changes).
STALE_AFTER = 0.5
#: What a snapshot's deadline node says in the caption, by its state (:data:`DEADLINE` of its ``data``; counting: the
#: seconds left, :func:`live_feedback`; not armed yet: nothing).
_DEADLINE_WORDS = {"none": "no deadline", "reached": "deadline reached"}


def live_feedback(row: SnapshotNode, elapsed: float, turned: float) -> str:
    """A row's feedback as of the frame (:func:`shown_feedback`): ``elapsed`` s and ``turned`` deg after the snapshot.

    Why: the executive publishes its tree only when a status changes, so a snapshot's countdowns ("16.2 s
    left", "+158 deg to go") are as old as the snapshot. They are counted down by the sim time and by the
    ground-truth heading change since, from the figures the leaf put in the snapshot (its ``data``:
    :data:`DEADLINE_LEFT`, :data:`TO_GO`); any other feedback is shown as the snapshot says it.
    """
    feedback = shown_feedback(row)
    if not feedback or not is_countdown(row):
        return feedback
    if row.data.get(DEADLINE_LEFT) is not None:
        return f"{max(0.0, float(row.data[DEADLINE_LEFT]) - elapsed):.1f} s left"
    return f"{float(row.data[TO_GO]) - turned:+.0f} deg to go"


def is_countdown(row: SnapshotNode) -> bool:
    """Whether the row's feedback counts down (its leaf gave the figure): a frame shows it live, never as old."""
    return row.data.get(DEADLINE_LEFT) is not None or row.data.get(TO_GO) is not None


def shown_feedback(row: SnapshotNode) -> str:
    """A row's feedback if that node was ticked in the snapshot's tick (RUNNING, SUCCESS or FAILURE), else "".

    Why: py_trees keeps a node's last feedback after it stops being ticked ("+158 deg to go" of a finished
    turn, "creeping" of a branch no longer chosen); only the nodes of that tick speak for that moment.
    """
    return row.feedback if row.status != "INVALID" else ""


@dataclass(frozen=True)
class Snapshot:
    """One tree snapshot of the bag, read once: its rows, the running path, the branch and the tip."""

    t: float  # sim time of the snapshot (absolute, as in the bag)
    rows: list[SnapshotNode]
    path: list[int]
    branch: str  # the tree's branch: the child of the first selector on the running path ("Lab", "Disarmed")
    label: str  # the trajectory's colour label (:func:`bt_nav.media.plot.branch_of_tip`)
    running_since: float  # since when the tip has been running without a break (``t`` when it is not running)

    @property
    def tip(self) -> SnapshotNode | None:
        """The last node of the running path (None for a snapshot without one)."""
        return self.rows[self.path[-1]] if self.path else None


def snapshots(record: MissionRecord) -> list[Snapshot]:
    """The bag's tree snapshots (:mod:`bt_nav.mission.snapshot` documents), read (see :class:`Snapshot`)."""
    from bt_nav.media.plot import branch_of_tip

    out: list[Snapshot] = []
    for t, document in record.trees:
        rows = snapshot_nodes(document)
        path = [i for i in document.get("path", ()) if 0 <= i < len(rows)]
        tip = rows[path[-1]] if path else None
        chosen = next((path[n + 1] for n, i in enumerate(path[:-1]) if rows[i].kind == "selector"), None)
        branch = rows[chosen].name if chosen is not None else (tip.name if tip else "")
        since = t
        if tip is not None and tip.status == "RUNNING" and out:
            last = out[-1].tip
            if last is not None and last.name == tip.name and last.status == "RUNNING":
                since = out[-1].running_since
        out.append(Snapshot(t, rows, path, branch, branch_of_tip(tip.name) if tip else "Stopped", since))
    return out


def branches(record: MissionRecord) -> tuple[np.ndarray, list[str], list[str]]:
    """Per tree snapshot: times, trajectory labels and tips as the snapshot says them ("TurnAway: steering
    +10 deg"; the feedback only when the tip was ticked)."""
    snaps = snapshots(record)
    tips = []
    for snap in snaps:
        tip = snap.tip
        feedback = shown_feedback(tip) if tip else ""
        tips.append(f"{tip.name}: {feedback}" if feedback else (tip.name if tip else ""))
    return np.asarray([s.t for s in snaps], dtype=np.float64), [s.label for s in snaps], tips


@dataclass(frozen=True)
class FrameText:
    """Everything a frame says about one robot at one instant (the caption draws :meth:`lines`)."""

    clock: float  # s since :attr:`MissionRecord.origin` (:data:`TIME_BASE`)
    travelled: float  # m, ground truth
    branch: str  # the tree's branch at that instant ("Stopped" before the first snapshot)
    tip: str
    feedback: str  # the tip's feedback, live (:func:`live_feedback`), "" when the tip was not ticked
    deadline: str  # "no deadline", "12.3 s left", "deadline reached", "" (no such node in the tree)
    turned: float | None  # deg turned since the running maneuver began (ground truth); None when none runs
    snapshot: float | None  # the snapshot's time, s since the origin (None before the first)
    live: bool = False  # the feedback is a countdown counted to the frame (:func:`is_countdown`): never "as of"
    base: str = TIME_BASE  # the words of ``clock``'s origin (a hand-in's: the sim clock)

    def lines(self) -> tuple[str, str]:
        """The caption's two lines: time (and its base), distance and deadline; then branch, tip, the turn so far
        and the feedback (last: a stale feedback's "as of" may be cut at the frame's edge, the turn may not)."""
        head = f"t = {self.clock:.2f} s {self.base}    travelled {self.travelled:.2f} m"
        if self.deadline:
            head += f"    {self.deadline}"
        if not self.tip or self.tip == self.branch:
            detail = self.branch
        else:  # "ManeuverC_SmartPivot > SmartPivot" says the name twice: the tip alone says it
            detail = self.tip if self.branch.endswith(self.tip) else f"{self.branch} > {self.tip}"
        if self.turned is not None:
            detail += f" [turned {self.turned:+.0f} deg]"
        if self.feedback:
            detail += f": {self.feedback}"
            stale = self.snapshot is not None and self.clock - self.snapshot > STALE_AFTER
            if stale and not self.live:  # a countdown is live; other text says its age
                detail += f" (as of {self.snapshot:.2f} s)"
        return head, detail


def _deadline(snap: Snapshot, elapsed: float, turned: float) -> str:
    """The deadline as that snapshot's ticked deadline node says it (its ``data``), counted down to the frame ("" when
    none says: no such node, not ticked, or not armed yet)."""
    for row in snap.rows:
        state = row.data.get(DEADLINE)
        if state is None or not shown_feedback(row):
            continue
        if state == "counting":
            return live_feedback(row, elapsed, turned)
        if state in _DEADLINE_WORDS:
            return _DEADLINE_WORDS[state]
    return ""


@dataclass
class Track:
    """One robot of the film: its name, record and colour, its parsed snapshots, and how much of its path is on
    the layer. Both renderers ask a track what its robot says and where its scan lies at an instant."""

    name: str
    rec: MissionRecord
    colour: tuple[int, int, int]
    drawn: int = 1  # trajectory samples already on the layer (segments end at index ``drawn``)
    distance: np.ndarray = field(init=False)
    snaps: list[Snapshot] = field(init=False)
    snap_t: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.distance = self.rec.truth.distance()
        self.snaps = snapshots(self.rec)
        self.snap_t = np.asarray([s.t for s in self.snaps], dtype=np.float64)

    def index(self, t: float) -> int:
        """The last ground-truth sample at or before ``t`` (-1: none yet)."""
        return int(np.searchsorted(self.rec.truth.t, t, side="right")) - 1

    def snapshot(self, t: float) -> int:
        """The last tree snapshot at or before ``t`` (-1: none yet)."""
        return int(np.searchsorted(self.snap_t, t, side="right")) - 1

    def sample_labels(self) -> list[str]:
        """The branch label of each ground-truth sample (what drove it), for the path's colours."""
        idx = np.searchsorted(self.snap_t, self.rec.truth.t, side="right") - 1
        return [self.snaps[i].label if i >= 0 else "Stopped" for i in idx]

    def text(self, t: float, origin: float) -> FrameText:
        """What the frame at sim time ``t`` says about this robot (times counted from ``origin``)."""
        i, k = self.index(t), self.snapshot(t)
        travelled = float(self.distance[i]) if i >= 0 else 0.0
        if not self.snaps:  # not bt_nav's executive: no tree; say what the robot does
            return FrameText(t - origin, travelled, doing_text(self.rec, t), "", "", "", None, None)
        if k < 0:
            return FrameText(t - origin, travelled, "Stopped", "", "", "", None, None)
        snap, truth = self.snaps[k], self.rec.truth
        elapsed, since_snap = t - snap.t, truth.turned(snap.t, t)
        tip = snap.tip
        feedback = live_feedback(tip, elapsed, since_snap) if tip else ""
        turning = tip is not None and tip.status == "RUNNING" and snap.label == "Maneuver"
        turned = truth.turned(snap.running_since, t) if turning else None
        return FrameText(t - origin, travelled, snap.branch, tip.name if tip else "", feedback,
                         _deadline(snap, elapsed, since_snap), turned, snap.t - origin,
                         tip is not None and is_countdown(tip))

    def panel_rows(self, t: float) -> list[tuple[SnapshotNode, str, bool]]:
        """The tree at ``t``: each row with the feedback the frame shows and whether it is on the running path."""
        k = self.snapshot(t)
        if k < 0:
            return []
        snap = self.snaps[k]
        elapsed, turned = t - snap.t, self.rec.truth.turned(snap.t, t)
        on_path = set(snap.path)
        return [(row, live_feedback(row, elapsed, turned), n in on_path)
                for n, row in enumerate(snap.rows)]


class VideoRenderer:
    """Frames of one recorded mission (see the module docstring); ``frame(t)`` must be called with rising t."""

    def __init__(self, record: MissionRecord, world: Any = None, script: ConsoleScript | None = None) -> None:
        from PIL import Image, ImageDraw

        self._Image, self._Draw = Image, ImageDraw
        self.rec = record
        self.world = world
        self.view = MapView.fit(_bounds(record, world))
        self.font, self.mono = _fonts()
        self.script = script  # a hand-in's terminal in place of the bag's events (its origin: the sim clock)
        self.origin = record.origin if script is None else script.origin  # every time a frame shows counts from here
        self.time_base = TIME_BASE if script is None else script.time_base
        if not hasattr(self, "tracks"):  # one robot: one track, its path coloured by branch
            self.tracks = [Track("", record, (40, 40, 40))]
        self.track = self.tracks[0]
        self.sample_branch = self.track.sample_labels()
        self.events = console_lines(record.events)
        self.event_t = [t for t, _ in self.events]
        self._node_lines = node_lines(record.events)
        self._node_t = [t for t, _ in self._node_lines]
        self.layer = self._background()
        self._tree_cache: tuple[Any, Any] = (None, None)
        self._panel_base: tuple[int | None, Any] = (None, None)
        self._console_cache: tuple[Any, Any] = (None, None)

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
        """The start point and the homework's 1.5 m circle around it (of ``truth``, default the record's; the
        lab has no circle)."""
        truth = self.rec.truth if truth is None else truth
        if len(truth):
            cx, cy = self.view.px(truth.x[0], truth.y[0])
            from bt_nav.media.plot import start_circle

            radius = start_circle(self.rec.mission.get("profile"))
            if radius is not None:
                r = radius * self.view.scale
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
        from bt_nav.media.plot import BRANCH_COLOURS

        drawn = self.track.drawn
        if upto <= drawn:
            return
        tr, d = self.rec.truth, self._Draw.Draw(self.layer)
        xs, ys = self.view.px(tr.x[drawn - 1:upto], tr.y[drawn - 1:upto])
        for k in range(len(xs) - 1):
            colour = _hex(BRANCH_COLOURS.get(self.sample_branch[drawn + k], "#000000"))
            d.line([(float(xs[k]), float(ys[k])), (float(xs[k + 1]), float(ys[k + 1]))], fill=colour, width=3)
        self.track.drawn = upto

    def _draw_scan(self, d: Any, t: float, rec: MissionRecord | None = None,
                   colour: tuple[int, int, int] = (230, 40, 40)) -> None:
        """The latest scan at ``t`` of ``rec`` (default the record's), placed from the pose at its own stamp."""
        scan = (self.rec if rec is None else rec).scan_at(t)
        if scan is None:
            return
        px, py = self.view.px(scan[1], scan[2])
        for u, w in zip(px.tolist(), py.tolist(), strict=True):
            d.rectangle([u - 1.5, w - 1.5, u + 1.5, w + 1.5], fill=colour)

    def _draw_walkers(self, d: Any, t: float) -> None:
        """The people walking where the simulator last said they were (pink disks), if the bag has them."""
        circles = self.rec.walkers_at(t)
        for x, y, r in ([] if circles is None else circles.tolist()):
            px, py = self.view.px(x, y)
            s = r * self.view.scale
            d.ellipse([px - s, py - s, px + s, py + s], fill=(240, 170, 215), outline=(200, 60, 150), width=2)

    def _draw_robot(self, d: Any, x: float, y: float, yaw: float, fill: tuple[int, int, int] = (40, 40, 40)) -> None:
        px, py = self.view.px(x, y)
        r = ROBOT_RADIUS * self.view.scale
        d.ellipse([px - r, py - r, px + r, py + r], fill=fill, outline=(255, 255, 255), width=2)
        hx, hy = self.view.px(x + 2.2 * ROBOT_RADIUS * np.cos(yaw), y + 2.2 * ROBOT_RADIUS * np.sin(yaw))
        d.line([(float(px), float(py)), (float(hx), float(hy))], fill=(255, 200, 0), width=3)

    def text(self, t: float) -> FrameText:
        """What the frame at sim time ``t`` says (its caption is :meth:`FrameText.lines`, drawn as is)."""
        return dataclasses.replace(self.track.text(t, self.origin), base=self.time_base)

    def console_rows(self, t: float) -> list[str]:
        """The console's rows at sim time ``t``: the script's (a hand-in), else the newest shown log lines of the
        bag, each stamped on the frame's time base."""
        if self.script is not None:
            return self.script.rows(t)
        n = int(np.searchsorted(self.event_t, t, side="right"))
        return [f"[{lt - self.origin:7.2f}] {text}" for lt, text in self.events[:n][-CONSOLE_ROWS:]]

    def _draw_label(self, d: Any) -> None:
        """:data:`SIM_LABEL` in the map's lower left corner, on every frame."""
        box = d.textbbox((8, MAP_H - 22), SIM_LABEL, font=self.font)
        d.rectangle([box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2], fill=(255, 255, 255), outline=(150, 150, 160))
        d.text((8, MAP_H - 22), SIM_LABEL, font=self.font, fill=(90, 90, 110))

    def frame(self, t: float) -> Any:
        """The frame at sim time ``t`` (a PIL RGB image of WIDTH x HEIGHT)."""
        tr = self.rec.truth
        i = self.track.index(t)
        self._extend_trail(i + 1)
        img = self.layer.copy()
        d = self._Draw.Draw(img)
        pose = tr.at(t)
        self._draw_walkers(d, t)
        if pose is not None:
            self._draw_scan(d, t)
            self._draw_robot(d, *pose)
        head, detail = self.text(t).lines()
        d.rectangle([0, 0, MAP_W, 46], fill=(255, 255, 255))
        d.text((10, 4), head, font=self.font, fill=INK)
        d.text((10, 25), detail[:90], font=self.mono, fill=(70, 70, 90))
        img.paste(self._tree_panel(t), (MAP_W + 2, 0))
        img.paste(self._console(self.console_rows(t)), (0, CONSOLE_Y))
        self._draw_label(d)
        return img

    def _tree_panel(self, t: float) -> Any:
        """The tree at ``t`` coloured by status, feedback as :meth:`Track.panel_rows` gives it.

        Why two levels of cache: the snapshot's panel is drawn once; only rows whose feedback is live (a
        countdown, :func:`live_feedback`) are redrawn on a copy, and only when their text changed.
        """
        if not self.track.snaps:
            return self._node_panel(t)
        k = self.track.snapshot(t)
        rows = self.track.panel_rows(t)
        live = tuple((n, feedback) for n, (row, feedback, _) in enumerate(rows) if feedback != shown_feedback(row))
        if self._tree_cache[0] == (k, live):
            return self._tree_cache[1]
        if self._panel_base[0] != k:
            self._panel_base = (k, self._draw_panel(k, rows))
        img = self._panel_base[1]
        if live:
            img = img.copy()
            d = self._Draw.Draw(img)
            step = self._panel_step(len(rows))
            for n, feedback in live:
                row, _, on_path = rows[n]
                y = 28 + n * step
                d.rectangle([2, y, WIDTH - MAP_W - 6, y + step - 2], fill=(255, 243, 190) if on_path else PANEL_BG)
                self._panel_row(d, y, row, feedback)
        self._tree_cache = ((k, live), img)
        return img

    def _node_panel(self, t: float) -> Any:
        """The side panel of a robot node without a tree: its command, the robot's motion and the node's recent
        log lines (:func:`node_lines`), redrawn only when one of them changes."""
        cmd = command_at(self.rec, t)
        n_lines = int(np.searchsorted(self._node_t, t, side="right"))
        key = (cmd, doing_text(self.rec, t), n_lines)
        if self._tree_cache[0] == key:
            return self._tree_cache[1]
        img = self._Image.new("RGB", (WIDTH - MAP_W - 2, MAP_H), PANEL_BG)
        d = self._Draw.Draw(img)
        d.text((8, 6), "robot node (publishes no bt_nav tree)", font=self.font, fill=INK)
        linear = f"linear {cmd[0]:+.2f} m/s, angular {cmd[1]:+.2f} rad/s" if cmd else "no command yet"
        rows = [("cmd_vel", INK), (f"  {linear}", STATUS_COLOURS["RUNNING"]),
                (f"  {motion_text(*cmd) if cmd else ''}", STATUS_COLOURS["RUNNING"]),
                ("robot (ground truth)", INK), (f"  {key[1].split(';')[0].removeprefix('robot ')}", INK),
                ("", INK), ("node's log lines", INK)]
        width = (WIDTH - MAP_W - 20) // 8
        for lt, text in self._node_lines[:n_lines][-24:]:
            rows += [(line, CONSOLE_BG) for line in _wrap(f"[{lt - self.origin:6.2f}] {text}", width)]
        room = (MAP_H - 30) // 15 - 7  # rows left for log lines under the seven of the command and motion
        for n, (text, colour) in enumerate(rows[:7] + rows[7:][-room:]):
            d.text((8, 30 + 15 * n), text, font=self.mono, fill=colour)
        self._tree_cache = (key, img)
        return img

    @staticmethod
    def _panel_step(n_rows: int) -> int:
        return min(15, (MAP_H - 30) // max(n_rows, 1))

    def _draw_panel(self, k: int, rows: list[tuple[SnapshotNode, str, bool]]) -> Any:
        """The panel of snapshot ``k``: title with the snapshot's time, highlights of the running path, rows."""
        img = self._Image.new("RGB", (WIDTH - MAP_W - 2, MAP_H), PANEL_BG)
        d = self._Draw.Draw(img)
        title = f"behaviour tree (t = {self.track.snaps[k].t - self.origin:.2f} s)" if k >= 0 else "behaviour tree"
        d.text((8, 6), title, font=self.font, fill=INK)
        step = self._panel_step(len(rows))
        for n, (_, _, on_path) in enumerate(rows):  # highlights first: none may cover the text of the row above
            if on_path:
                d.rectangle([2, 28 + n * step - 1, WIDTH - MAP_W - 6, 28 + (n + 1) * step - 2], fill=(255, 243, 190))
        for n, (row, _, _) in enumerate(rows):
            self._panel_row(d, 28 + n * step, row, shown_feedback(row))
        return img

    def _panel_row(self, d: Any, y: int, row: SnapshotNode, feedback: str) -> None:
        colour = status_colour(row.status)
        x = 8 + 14 * row.depth
        d.rectangle([x, y + 3, x + 7, y + 10], fill=colour)
        label = row.name + (f" - {feedback}" if feedback else "")
        d.text((x + 12, y), label[:70 - 2 * row.depth], font=self.mono, fill=colour)

    def _console(self, rows: list[str]) -> Any:
        """The console strip with ``rows`` (:meth:`console_rows`), the newest (last) brightest; a script's pinned
        head in green, as a shell's prompt lines (cached while the rows are the same)."""
        key = tuple(rows)
        if self._console_cache[0] == key:
            return self._console_cache[1]
        img = self._Image.new("RGB", (WIDTH, HEIGHT - CONSOLE_Y), CONSOLE_BG)
        d = self._Draw.Draw(img)
        pinned = len(self.script.head) if self.script is not None else 0
        for n, text in enumerate(rows):
            ink = (140, 220, 140) if n < pinned else (255, 255, 255) if n == len(rows) - 1 else CONSOLE_INK
            d.text((10, 6 + 17 * n), text[:160], font=self.mono, fill=ink)
        self._console_cache = (key, img)
        return img


def _wrap(text: str, width: int) -> list[str]:
    """``text`` in lines of at most ``width`` characters (continuations indented)."""
    return [text[:width]] + [f"  {text[k:k + width - 2]}" for k in range(width, len(text), width - 2)]


def renderer_for(record: MissionRecord, world: Any = None, script: ConsoleScript | None = None) -> VideoRenderer:
    """The renderer of this bag: :class:`TracksRenderer` when it holds robots in namespaces (each in its
    colour), else :class:`VideoRenderer` (one robot, its path coloured by branch; ``script``: a hand-in's console)."""
    if record.robots:
        return TracksRenderer(record, world)
    return VideoRenderer(record, world, script)


def frame_times(record: MissionRecord, fps: float) -> np.ndarray:
    """Sim times of the frames: one every 1/fps s from the bag's origin (:attr:`MissionRecord.origin`, the time
    zero the frames show) to its end, at least one."""
    n = max(1, round(max(0.0, record.end - record.origin) * fps))
    return record.origin + np.arange(n) / fps


@dataclass
class VideoStats:
    """What :func:`write_video` did."""

    path: Path
    frames: int
    fps: float
    seconds: float  # wall time to render and encode


def iter_frames(record: MissionRecord, fps: float, world: Any = None,
                script: ConsoleScript | None = None) -> Iterator[tuple[float, Any, list[str]]]:
    """The frames of the video: (sim time, PIL image, the console rows drawn on it)."""
    renderer = renderer_for(record, world, script)
    for t in frame_times(record, fps):
        yield float(t), renderer.frame(float(t)), renderer.console_rows(float(t))


def open_mp4(path: Path, fps: float) -> Any:
    """An H.264 MP4 (yuv420p, fast start) writer at ``path`` for frames of the film's size, primed for frames
    (``send`` RGB bytes, ``close`` to finish): one encoding for the simulator's films and a robot's."""
    import imageio_ffmpeg

    path.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio_ffmpeg.write_frames(str(path), (WIDTH, HEIGHT), fps=fps, codec="libx264",
                                         pix_fmt_out="yuv420p", quality=None, bitrate=None,
                                         ffmpeg_log_level="error", macro_block_size=16,
                                         output_params=["-preset", "veryfast", "-crf", "23",
                                                        "-movflags", "+faststart"])
    writer.send(None)
    return writer


def write_video(record: MissionRecord, out: str | Path, fps: float = 10.0, world: Any = None,
                script: ConsoleScript | None = None, console_log: str | Path | None = None) -> VideoStats:
    """Render ``record`` to an H.264 MP4 (yuv420p) at ``out``; returns the frame count and wall time.

    ``script``: a hand-in's console (:class:`bt_nav.media.console.ConsoleScript`) in place of the bag's events;
    ``console_log``: also write there, per frame, the console rows drawn (:class:`bt_nav.media.console.ConsoleLog`).
    """
    started = time.perf_counter()
    path = Path(out)
    writer = open_mp4(path, fps)
    log = ConsoleLog(path, TIME_BASE if script is None else script.time_base) if console_log else None
    origin = record.origin if script is None else script.origin
    frames = 0
    try:
        for t, img, rows in iter_frames(record, fps, world, script):
            writer.send(img.tobytes())
            if log is not None:
                log.add(t - origin, rows)
            frames += 1
    finally:
        writer.close()
    if log is not None and console_log is not None:
        log.write(Path(console_log))
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
    """The bag's ground truth as a :class:`bt_nav.media.plot.Trajectory`, each sample labelled with its branch."""
    from bt_nav.media.plot import Trajectory

    tr = record.truth
    labels = Track("", record, (0, 0, 0)).sample_labels()
    return Trajectory(tr.t, tr.x, tr.y, tr.yaw, np.array(labels, dtype=object))


def plot_bag(record: MissionRecord, out: str | Path, world: Any = None) -> Path:
    """The trajectory picture (:func:`bt_nav.media.plot.plot_run`) of a bag; the verdict from /bt_nav/mission."""
    from bt_nav_sim.world import World

    from bt_nav.media.plot import plot_run, start_circle

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
    return plot_run(world, trajectory(record), results, out, title=f"{world.name} (bag {record.path.name})",
                    min_distance=start_circle(record.mission.get("profile")))


def _plot_robots_bag(record: MissionRecord, out: str | Path, world: Any) -> Path:
    """The several-robot picture (:func:`bt_nav.media.plot.plot_robots`) of a bag: one path per robot."""
    from bt_nav.media.plot import plot_robots

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
# (:func:`bt_nav.media.plot.plot_robots`), each robot has one colour (:func:`bt_nav.media.plot.robot_colour`, in
# the bag's robot order) for its path, footprint, scan, start and 1.5 m circle; the caption is the legend
# (each robot's name in its colour with its distance and active branch), the side panel shows each robot's
# running path of its tree, and the console interleaves every robot's log lines, prefixed with its name.

def robot_colours(record: MissionRecord) -> dict[str, tuple[int, int, int]]:
    """Robot name -> RGB, the picture's palette in the bag's robot order (one home: bt_nav.media.plot)."""
    from bt_nav.media.plot import robot_colour

    return {name: _hex(robot_colour(i)) for i, name in enumerate(record.robots)}


class TracksRenderer(VideoRenderer):
    """Frames of a several-robot bag (see the module docstring); ``frame(t)`` must be called with rising t."""

    def __init__(self, record: MissionRecord, world: Any = None) -> None:
        self.tracks = [Track(name, rec, colour) for (name, rec), colour in
                       zip(record.robots.items(), robot_colours(record).values(), strict=True)]
        super().__init__(record, world)  # draws the background, so the tracks must exist before
        merged = sorted((line for tr in self.tracks for line in console_lines(tr.rec.events, f"{tr.name}: ")),
                        key=lambda e: e[0])
        self.events = merged
        self.event_t = [t for t, _ in merged]
        self._paths_cache: tuple[Any, Any] = ((), None)

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
        for tr in self.tracks:
            self._extend_track(tr, tr.index(t) + 1)
        img = self.layer.copy()
        d = self._Draw.Draw(img)
        self._draw_walkers(d, t)
        for tr in self.tracks:
            pose = tr.rec.truth.at(t)
            if pose is not None:
                scan_ink = tuple(int(c + (255 - c) * 0.45) for c in tr.colour)  # lighter than the path
                self._draw_scan(d, t, tr.rec, scan_ink)
                self._draw_robot(d, *pose, fill=tr.colour)
                px, py = self.view.px(pose[0], pose[1])
                d.text((float(px) + 9, float(py) - 22), tr.name, font=self.mono, fill=tr.colour)
        self._legend(d, t)
        img.paste(self._paths_panel(t), (MAP_W + 2, 0))
        img.paste(self._console(self.console_rows(t)), (0, CONSOLE_Y))
        self._draw_label(d)
        return img

    def _legend(self, d: Any, t: float) -> None:
        """The caption: the time, then per robot a swatch, its name, distance and branch in its colour (each
        robot's :meth:`Track.text`, as the one-robot caption)."""
        d.rectangle([0, 0, MAP_W, 46], fill=(255, 255, 255))
        d.text((10, 4), f"t = {t - self.origin:.2f} s {TIME_BASE}    {len(self.tracks)} robots", font=self.font,
               fill=INK)
        width = (MAP_W - 10) // max(len(self.tracks), 1)
        for n, tr in enumerate(self.tracks):
            x = 10 + n * width
            d.rectangle([x, 29, x + 12, 39], fill=tr.colour)
            text = tr.text(t, self.origin)
            label = f"{tr.name}  {text.travelled:5.2f} m  {text.branch}"
            d.text((x + 17, 26), label[:max(8, (width - 20) // 8)], font=self.mono, fill=tr.colour)

    def _paths_panel(self, t: float) -> Any:
        """Each robot's running path of its tree (name in its colour, rows coloured by status, feedback as
        :meth:`Track.panel_rows` gives it); cached while the rows are the same."""
        panels = [[(row, feedback) for row, feedback, on_path in tr.panel_rows(t) if on_path] for tr in self.tracks]
        key = tuple(tuple((row.name, row.status, feedback) for row, feedback in rows) for rows in panels)
        if self._paths_cache[0] == key and self._paths_cache[1] is not None:
            return self._paths_cache[1]
        img = self._Image.new("RGB", (WIDTH - MAP_W - 2, MAP_H), PANEL_BG)
        d = self._Draw.Draw(img)
        d.text((8, 6), "behaviour trees: running path", font=self.font, fill=INK)
        y = 30
        for tr, rows in zip(self.tracks, panels, strict=True):
            d.text((8, y), tr.name, font=self.font, fill=tr.colour)
            y += 20
            for row, feedback in rows:
                x = 8 + 10 * row.depth
                d.rectangle([x, y + 3, x + 7, y + 10], fill=status_colour(row.status))
                label = row.name + (f" - {feedback}" if feedback else "")
                d.text((x + 12, y), label[:66 - row.depth], font=self.mono, fill=status_colour(row.status))
                y += 15
            y += 10
        self._paths_cache = (key, img)
        return img
