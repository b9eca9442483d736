"""What a recorder of a lock-step run receives, and the run's event log.

Why a protocol here: the engine (:mod:`bt_nav.run.lockstep`) feeds any sink; the rosbag2 writer
(:class:`bt_nav.media.bag.MissionBag`) is one, without the engine importing media or media importing the
engine. Times are sim seconds throughout (the one time base of a lock-step run).
"""

from __future__ import annotations

from typing import Any, Protocol

from bt_nav.mission.scan import Scan


class MissionSink(Protocol):
    """Receives what a DDS recorder would see on the graph for one robot (a rosbag2 writer, say).

    ``clock`` is written once per instant by the run's own sink (the bag), not per robot."""

    def clock(self, t: float) -> None: ...  # noqa: D102
    def scan(self, t: float, scan: Scan) -> None: ...  # noqa: D102
    def odom(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None: ...  # noqa: D102
    def ground_truth(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None: ...  # noqa: D102
    def cmd(self, t: float, v: float, w: float) -> None: ...  # noqa: D102
    def tree(self, t: float, snapshot: dict[str, Any]) -> None: ...  # noqa: D102
    def announce(self, t: float, record: dict[str, Any]) -> None: ...  # noqa: D102
    def event(self, t: float, text: str) -> None: ...  # noqa: D102
    def walkers(self, t: float, circles: Any) -> None: ...  # noqa: D102


class RunSink(MissionSink, Protocol):
    """The sink of a whole run: the robots' sinks (each robot's topics under its namespace when several)."""

    def robot(self, name: str) -> MissionSink: ...  # noqa: D102


class SimEventLog:
    """The leaves' one-line messages of one robot in a lock-step run, kept with their sim time (not printed), and
    passed on to the robot's sink as ``[LEVEL] message``; over ROS the same :class:`EventLogger` is
    :class:`bt_nav.ros.rosutil.RclpyEventLog`."""

    def __init__(self, clock: object | None = None, sink: MissionSink | None = None) -> None:
        self.lines: list[tuple[float, str, str]] = []
        self._clock = clock
        self._sink = sink

    def _add(self, level: str, msg: str) -> None:
        t = self._clock() if callable(self._clock) else 0.0
        self.lines.append((t, level, msg))
        if self._sink is not None:
            self._sink.event(t, f"[{level.upper()}] {msg}")

    def info(self, msg: str) -> None:  # noqa: D102
        self._add("info", msg)

    def warning(self, msg: str) -> None:  # noqa: D102
        self._add("warning", msg)

    def error(self, msg: str) -> None:  # noqa: D102
        self._add("error", msg)
