"""``bt-nav view --bag BAG`` of a robot's bag (no ground truth, no world file): the browser page plays it back as
the film shows it (:mod:`bt_nav.media.robotfilm`), from what the robot recorded.

The page's "world" is the room as the whole run's scans saw it, laid out in the odometry frame
(:class:`ScannedRoom`: every return, thinned to one per :data:`CELL` m square, drawn as a dot); the robot is at its
odometry pose, its path is the odometry's, the scan is the latest one placed from the pose at its own time; the
log lines are where the data came from (first, always), the node's /rosout lines and the check-off's lines at
the times they were decided.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bt_nav.media.robotfilm import bounds
from bt_nav.media.robotrun import RobotRun
from bt_nav.media.view import EVENT_LINES, BagScene

#: m: the room's returns are thinned to one per square of this side.
CELL = 0.02
#: m: each of the room's returns is drawn as a dot of this radius.
DOT = 0.008


@dataclass
class ScannedRoom:
    """What :func:`bt_nav.media.view.world_json` reads of a world, for a room known only from its scans."""

    name: str
    segments: np.ndarray
    circles: np.ndarray
    bounds: tuple[float, float, float, float]


def scanned_room(run: RobotRun) -> ScannedRoom:
    """Every scan's returns in the odometry frame, one per :data:`CELL` square, as dots."""
    xs, ys = [], []
    for k in range(len(run.rec.scans)):
        _, x, y = run.scan_points(k)
        xs.append(x)
        ys.append(y)
    x, y = (np.concatenate(xs), np.concatenate(ys)) if xs else (np.zeros(0), np.zeros(0))
    cells = np.unique(np.column_stack([np.round(x / CELL), np.round(y / CELL)]), axis=0) * CELL
    circles = np.column_stack([cells, np.full(len(cells), DOT)]) if len(cells) else np.zeros((0, 3))
    return ScannedRoom(f"the room as scanned ({run.source})", np.zeros((0, 4)), circles, bounds(run))


class RobotScene(BagScene):
    """Playback of a robot's run (see the module docstring); the playhead is on the recording's clock."""

    def __init__(self, run: RobotRun) -> None:
        self.run = run
        self._path = run.path_xy()
        self._scan_t = np.asarray([t for t, _ in run.rec.scans])
        super().__init__(run.rec, scanned_room(run))  # type: ignore[arg-type] - start and end are all it reads

    def lines(self, t: float) -> list[str]:
        """The log lines at ``t``: the data's source, then the node's and the check-off's, newest last."""
        origin = self.run.origin
        logs = [(lt, f"[{lt - origin:7.2f}] [{logger}]: {text}") for lt, logger, text in self.run.rec.announcements]
        logs += [(line.t, f"[{line.t - origin:7.2f}] check-off: {line.text}") for line in self.run.lines]
        shown = [text for lt, text in sorted(logs) if lt <= t]
        return [self.run.source, *shown[-(EVENT_LINES - 1):]]

    def state(self) -> dict[str, Any]:
        run, t = self.run, self.t
        pose = run.pose_at(t)
        n = int(np.searchsorted(self._path[:, 0], t, side="right"))
        step = max(1, n // 1500)
        trail = np.round(self._path[:n:step, 1:3], 3).tolist()
        k = int(np.searchsorted(self._scan_t, t, side="right")) - 1
        scan = np.round(np.column_stack(run.scan_points(k)[1:]), 3).tolist() if k >= 0 else []
        cmd = run.command_at(t)
        return {"mode": "bag", "t": round(t, 3), "start": run.origin, "end": run.end,
                "playing": self.playing, "pose": list(pose) if pose else None, "trail": trail, "scan": scan,
                "tree": [], "events": self.lines(t), "cmd": list(cmd) if cmd else [0.0, 0.0], "walkers": [],
                "circle": False, "source": run.source, "version": self.version}
