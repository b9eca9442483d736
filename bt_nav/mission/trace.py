"""Per-tick traces: one JSON object per line, enough to replay what the tree decided and why.

Each line holds the tick number, the mission-clock time, every node's status (and feedback message
where it changed), the tip, the blackboard values that changed since the previous line, the
commanded twist, and (``events``, only when there were some) the leaves' announcements since the previous line as
``~/events`` carries them (:mod:`bt_nav.mission.snapshot`: a maneuver's start with its side and angle, its end,
the emergency brake). Both the ROS executive and the lock-step runner write the same format;
``bt-nav replay`` reads it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import IO, Any

from bt_nav.mission.core import OUTPUT_KEYS, MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.snapshot import jsonable

__all__ = ["TRACED_KEYS", "TraceRecorder", "jsonable", "read_trace"]

TRACED_KEYS = (*OUTPUT_KEYS, "scan_stamp")


class TraceRecorder:
    """Appends one JSON line per tick to ``path`` (or an open text stream)."""

    def __init__(self, core: MissionCore, path: str | Path | IO[str]) -> None:
        self.core = core
        self._own = not hasattr(path, "write")
        if self._own:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
        self._out: IO[str] = open(path, "w", encoding="utf-8") if self._own else path  # noqa: SIM115
        self._last_values: dict[str, Any] = {}
        self._last_feedback: dict[str, str] = {}
        self.lines = 0
        core.traced_announcements = []  # the leaves' events from now on, for the next line's "events"
        self._write({"header": {"tree": core.root.name, "maneuver": core.params["maneuver"],
                                "params": {k: jsonable(v) for k, v in core.params.items()}}})

    def _write(self, obj: dict[str, Any]) -> None:
        self._out.write(json.dumps(obj, separators=(",", ":")) + "\n")
        self.lines += 1

    def record(self, command: Command, extra: dict[str, Any] | None = None) -> dict[str, Any]:
        """Write the line for the tick that just happened (call right after ``core.tick()``)."""
        values = {key: jsonable(self.core.value(key)) for key in TRACED_KEYS}
        changed = {k: v for k, v in values.items() if self._last_values.get(k, object()) != v}
        self._last_values = values
        feedback = {}
        for node in self.core.nodes:
            if node.feedback_message and self._last_feedback.get(node.name) != node.feedback_message:
                feedback[node.name] = node.feedback_message
                self._last_feedback[node.name] = node.feedback_message
        line = {
            "tick": self.core.ticks,
            "time": round(self.core.clock(), 6),
            "tip": self.core.tip,
            "statuses": self.core.statuses(),
            "feedback": feedback,
            "changed": changed,
            "cmd": jsonable(command),
        }
        if self.core.traced_announcements:
            line["events"], self.core.traced_announcements = self.core.traced_announcements, []
        if extra:
            line.update(extra)
        self._write(line)
        return line

    def close(self) -> None:
        """Flush, and close the file if this recorder opened it."""
        self._out.flush()
        if self._own:
            self._out.close()


def read_trace(path: str | Path) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(header, tick lines) of a trace file."""
    header: dict[str, Any] = {}
    ticks: list[dict[str, Any]] = []
    with open(path, encoding="utf-8") as stream:
        for number, raw in enumerate(stream, 1):
            raw = raw.strip()
            if not raw:
                continue
            try:
                obj = json.loads(raw)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path}:{number}: not a JSON line ({exc})") from None
            if "header" in obj:
                header = obj["header"]
            else:
                ticks.append(obj)
    return header, ticks
