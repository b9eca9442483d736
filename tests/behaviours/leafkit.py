"""Tick one leaf alone: a small blackboard holding just its ports, a fake clock, a recording event log.

Each leaf is built as the tree file builds it, with every port on the blackboard key of the same name,
so a test writes the inputs it cares about (:meth:`Board.set`) and reads the outputs back.
"""

from __future__ import annotations

from typing import Any

import py_trees

from bt_nav.testing import FakeClock

Status = py_trees.common.Status


class Events:
    """An event logger that keeps ``(level, message)`` lines."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def info(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("info", msg))

    def warning(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("warning", msg))

    def error(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("error", msg))

    def text(self) -> str:
        """Every message, one per line."""
        return "\n".join(msg for _, msg in self.lines)

    def count(self, level: str, text: str = "") -> int:
        """How many lines of ``level`` contain ``text``."""
        return sum(1 for lv, msg in self.lines if lv == level and text in msg)


class Board:
    """A fresh blackboard (the global one, cleared) with write access to any key."""

    def __init__(self) -> None:
        py_trees.blackboard.Blackboard.clear()
        self.client = py_trees.blackboard.Client(name="leafkit")

    def set(self, **values: Any) -> None:
        """Write ``key=value`` pairs (keys registered on first use)."""
        for key, value in values.items():
            if not self.client.is_registered(key=key):
                self.client.register_key(key=key, access=py_trees.common.Access.WRITE)
            self.client.set(key, value)

    def get(self, key: str, default: Any = None) -> Any:
        """A value (``default`` when the key holds nothing)."""
        storage = py_trees.blackboard.Blackboard.storage
        return storage.get(f"/{key}", default)


def make(cls: type, name: str = "Leaf", *, clock: FakeClock | None = None, events: Events | None = None,
         **kwargs: Any) -> Any:
    """``cls`` with every port on the key of its name, set up with a fake clock and a recording log."""
    leaf = cls(name, **kwargs)
    ports = {**{p: f"/{p}" for p in leaf.input_ports()}, **{p: f"/{p}" for p in leaf.output_ports()}}
    leaf.setup_ports(ports)
    leaf.setup(clock=clock or FakeClock(1.0), events=events or Events())
    return leaf


def tick(leaf: Any) -> Status:
    """One tick of the leaf alone; its status."""
    leaf.tick_once()
    return leaf.status
