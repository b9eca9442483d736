"""One picture of one run: the world, the path coloured by the branch that drove it, and the verdict.

Shared by the lock-step runner (trajectory sampled from the simulator) and the ROS demo (trajectory
recorded from topics), so the input is deliberately plain: a :class:`Trajectory` of numpy arrays and
the referee's results dict. matplotlib is imported inside :func:`plot_run` (Agg backend, no display)
so importing this module costs nothing for runs that never plot.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim.world import World, box_corners

from bt_nav.judge.referee_core import RefereeConfig
from bt_nav.mission.maneuver_spec import tips as maneuver_tips
from bt_nav.mission.resources import written_whole

#: Branch labels, in legend order.
BRANCHES = ("FullSpeed", "TurnAway", "RotateInPlace", "Creep", "AEB", "Maneuver", "Stopped")
BRANCH_COLOURS = {
    "FullSpeed": "#2ca02c",
    "TurnAway": "#ff7f0e",
    "RotateInPlace": "#d62728",
    "Creep": "#1f77b4",  # lab mode: the slow straight creep
    "AEB": "#e377c2",  # lab mode: the emergency stop and its way out
    "Maneuver": "#9467bd",
    "Stopped": "#7f7f7f",
}


def frame_axes(ax: Any, world: World) -> None:
    """The world's bounds at equal scale, a light grid and metre labels (every picture of a world)."""
    xmin, ymin, xmax, ymax = world.bounds
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def save_figure(fig: Any, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` (format from the suffix), creating the folder; the path written.

    Written whole or not at all (a temporary name, then renamed): a drawing process stopped half-way (the grade's
    starved :class:`~bt_nav.grading.media.Drawer`) leaves no half a picture that a report would take as drawn."""
    out = Path(path)
    fmt = out.suffix.lstrip(".").lower()
    if not fmt:  # as matplotlib does: its default format, and that suffix on the name
        fmt = fig.canvas.get_default_filetype()
        out = out.with_name(f"{out.name.rstrip('.')}.{fmt}")
    out.parent.mkdir(parents=True, exist_ok=True)
    with written_whole(out, "wb") as stream:  # a stream: no format writes the temporary name into the file
        fig.savefig(stream, format=fmt, bbox_inches="tight")
    return out


def branch_of_tip(tip: str) -> str:
    """The branch label of a tree tip name (what the executive's trace and ``~/tree`` show).

    Anything that is not a driving leaf (Stop*, EvaluateMission, an empty tip) counts as stopped.
    """
    name = tip.rsplit(".", 1)[-1]
    if name in ("FullSpeed", "TurnAway", "RotateInPlace", "Creep", "AEB"):
        return name
    if name in maneuver_tips() or name.startswith("Maneuver"):  # the maneuvers' leaves, by the maneuver spec
        return "Maneuver"
    return "Stopped"


@dataclass
class Trajectory:
    """Ground-truth samples of one run; every array has one entry per sample.

    ``branch`` holds labels from :data:`BRANCHES` (use :func:`branch_of_tip` on tree tips).
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    branch: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=object))

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        self.x = np.asarray(self.x, dtype=np.float64)
        self.y = np.asarray(self.y, dtype=np.float64)
        self.yaw = np.asarray(self.yaw, dtype=np.float64)
        branch = np.asarray(self.branch, dtype=object)
        if branch.size == 0:
            branch = np.full(self.t.shape, "Stopped", dtype=object)
        self.branch = branch
        n = self.t.shape[0]
        if not (self.x.shape == self.y.shape == self.yaw.shape == self.branch.shape == (n,)):
            raise ValueError("trajectory arrays must be 1-D and of equal length")

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Trajectory:
        """From ``{"t": [...], "x": [...], "y": [...], "yaw": [...], "branch": [...]}`` (branch optional)."""
        return cls(data["t"], data["x"], data["y"], data["yaw"], data.get("branch", ()))

    def to_dict(self) -> dict[str, list]:
        """JSON-able lists."""
        return {"t": self.t.tolist(), "x": self.x.tolist(), "y": self.y.tolist(), "yaw": self.yaw.tolist(),
                "branch": [str(b) for b in self.branch]}

    def segments_of(self, label: str) -> list[tuple[int, int]]:
        """Index ranges ``[start, end)`` of consecutive samples with this branch label."""
        mask = self.branch == label
        edges = np.flatnonzero(np.diff(np.concatenate(([False], mask, [False])).astype(np.int8)))
        return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _draw_world(ax: Any, world: World) -> None:
    from matplotlib.patches import Circle, Polygon

    drawn_as_box = set()
    for box in world.boxes:
        corners = box_corners(*box)
        ax.add_patch(Polygon(corners, closed=True, facecolor="#555555", edgecolor="#222222", lw=0.5, zorder=2))
        for i in range(4):
            a, b = corners[i], corners[(i + 1) % 4]
            drawn_as_box.add((round(a[0], 6), round(a[1], 6), round(b[0], 6), round(b[1], 6)))
    for x1, y1, x2, y2 in world.segments:
        if (round(x1, 6), round(y1, 6), round(x2, 6), round(y2, 6)) in drawn_as_box:
            continue
        ax.plot([x1, x2], [y1, y2], color="#222222", lw=2.0, solid_capstyle="round", zorder=2)
    for cx, cy, r in world.circles:
        ax.add_patch(Circle((cx, cy), r, facecolor="#555555", edgecolor="#222222", lw=0.5, zorder=2))
    for walker in world.walkers:  # people walking: the lane they pace, as wide as they are
        ax.plot(walker.path[:, 0], walker.path[:, 1], color="#e377c2", lw=2.0, alpha=0.35,
                solid_capstyle="round", zorder=1.5)
        ax.plot(walker.path[:, 0], walker.path[:, 1], color="#e377c2", lw=0.8, ls=":", zorder=1.6)


def start_circle(profile: str | None) -> float | None:
    """Radius of the circle a picture of a run draws around its start: the homework's "minimum distance from
    start" (1.5 m); None for the lab, which has no such check."""
    return None if profile == "lab" else RefereeConfig().min_distance_from_start


def plot_run(world: World, trajectory: Trajectory | Mapping[str, Any], results: Mapping[str, Any],
             path: str | Path, title: str | None = None, min_distance: float | None = 1.5) -> Path:
    """Draw one run to ``path`` (format from the suffix, e.g. .png or .svg); returns the path.

    ``results`` is the referee's results dict (``passed``, ``travelled``, ``max_distance_from_start``,
    ``collisions``, ``collision_events``); missing keys are simply not shown. ``title`` replaces the
    first title line (e.g. "stage_4, maneuver A, seed 3").
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle

    traj = trajectory if isinstance(trajectory, Trajectory) else Trajectory.from_dict(trajectory)
    fig, ax = plt.subplots(figsize=(7.5, 7.5), dpi=110)
    try:
        _draw_world(ax, world)
        sx, sy = (float(traj.x[0]), float(traj.y[0])) if len(traj) else world.spawn[:2]
        if min_distance is not None:  # the homework's circle (the lab has none)
            ax.add_patch(Circle((sx, sy), min_distance, fill=False, ls="--", lw=1.0, color="#1f77b4", zorder=3))
        if len(traj) > 1:
            points = np.column_stack([traj.x, traj.y])
            segs = np.stack([points[:-1], points[1:]], axis=1)
            colours = [BRANCH_COLOURS.get(str(b), "#000000") for b in traj.branch[1:]]
            ax.add_collection(LineCollection(segs, colors=colours, linewidths=2.0, zorder=4))
        for start, _ in traj.segments_of("Maneuver"):
            ax.plot(traj.x[start], traj.y[start], marker="D", ms=6, mfc="none", mec=BRANCH_COLOURS["Maneuver"],
                    mew=1.5, zorder=6)
        ax.plot(sx, sy, marker="o", ms=9, color="#1f77b4", zorder=7)
        if len(traj):
            ax.plot(traj.x[-1], traj.y[-1], marker="s", ms=8, color="black", zorder=7)
        for event in results.get("collision_events", ()):
            ax.plot(event["x"], event["y"], marker="X", ms=13, color="red", mec="black", zorder=8)

        present = set(map(str, traj.branch))
        handles = [Line2D([], [], color=BRANCH_COLOURS[b], lw=3, label=b) for b in BRANCHES if b in present]
        handles += [
            Line2D([], [], marker="o", ls="", color="#1f77b4", label="start"),
            Line2D([], [], marker="s", ls="", color="black", label="end"),
        ]
        if min_distance is not None:
            handles.append(Line2D([], [], ls="--", color="#1f77b4", label=f"{min_distance} m from start"))
        if traj.segments_of("Maneuver"):
            handles.append(Line2D([], [], marker="D", ls="", mfc="none", mec=BRANCH_COLOURS["Maneuver"],
                                  label="maneuver start"))
        if results.get("collision_events"):
            handles.append(Line2D([], [], marker="X", ls="", color="red", mec="black", label="collision"))
        ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)

        frame_axes(ax, world)
        verdict = "PASSED" if results.get("passed") else "FAILED"
        numbers = []
        if "travelled" in results:
            numbers.append(f"travelled {results['travelled']:.2f} m")
        if "max_distance_from_start" in results:
            numbers.append(f"max {results['max_distance_from_start']:.2f} m from start")
        if "efficiency" in results:
            numbers.append(f"efficiency {results['efficiency']:.2f}")
        if "collisions" in results:
            numbers.append(f"{results['collisions']} collision{'s' if results['collisions'] != 1 else ''}")
        failed = [c["name"] for c in results.get("checks", ()) if not c.get("passed")]
        head = title or world.name
        lines = [f"{head}: {verdict}", ", ".join(numbers)]
        if failed:
            lines.append("failed: " + ", ".join(failed))
        ax.set_title("\n".join(lines), fontsize=10, color="#006400" if verdict == "PASSED" else "#b00000")
        return save_figure(fig, path)
    finally:
        plt.close(fig)


#: One colour per robot of a multi-robot picture (and video), in robot order; reused cyclically.
ROBOT_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b")


def robot_colour(index: int) -> str:
    """The colour of robot ``index`` (0-based) in pictures and videos."""
    return ROBOT_COLOURS[index % len(ROBOT_COLOURS)]


def plot_robots(world: World, runs: list[tuple[str, Trajectory | Mapping[str, Any], Mapping[str, Any]]],
                path: str | Path, title: str | None = None) -> Path:
    """Several robots of one world in one picture, each path in its robot's colour (a branch colouring
    would make two crossing paths unreadable); ``runs`` is (name, trajectory, referee results) per robot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, ax = plt.subplots(figsize=(7.5, 7.5), dpi=110)
    try:
        _draw_world(ax, world)
        handles, lines = [], [title or world.name]
        for i, (name, trajectory, results) in enumerate(runs):
            traj = trajectory if isinstance(trajectory, Trajectory) else Trajectory.from_dict(trajectory)
            colour = robot_colour(i)
            if len(traj):
                ax.plot(traj.x, traj.y, color=colour, lw=2.0, zorder=4)
                ax.plot(traj.x[0], traj.y[0], marker="o", ms=9, color=colour, zorder=7)
                ax.plot(traj.x[-1], traj.y[-1], marker="s", ms=8, color=colour, mec="black", zorder=7)
            for start, _ in traj.segments_of("Maneuver"):
                ax.plot(traj.x[start], traj.y[start], marker="D", ms=6, mfc="none", mec=colour, mew=1.5, zorder=6)
            for event in results.get("collision_events", ()):
                ax.plot(event["x"], event["y"], marker="X", ms=13, color=colour, mec="black", zorder=8)
            verdict = "PASSED" if results.get("passed") else "FAILED"
            handles.append(Line2D([], [], color=colour, lw=3, label=f"{name}: {verdict}"))
            lines.append(f"{name}: {verdict}, travelled {results.get('travelled', 0.0):.2f} m, "
                         f"{results.get('collisions', 0)} collisions")
        handles += [Line2D([], [], marker="o", ls="", color="black", label="start"),
                    Line2D([], [], marker="s", ls="", color="black", label="end")]
        ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
        frame_axes(ax, world)
        ax.set_title("\n".join(lines), fontsize=10)
        return save_figure(fig, path)
    finally:
        plt.close(fig)


__all__ = ["BRANCHES", "BRANCH_COLOURS", "ROBOT_COLOURS", "Trajectory", "branch_of_tip", "plot_robots", "plot_run",
           "robot_colour"]
