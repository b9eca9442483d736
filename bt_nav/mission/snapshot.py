"""The tree's state and the maneuvers' announcements as structured data: what ``~/tree`` and ``~/events`` carry.

Why structured: the executive used to publish py_trees' unicode art and every reader (bag, video, browser view,
replay, recorder) parsed it back by regex, and the lab read a maneuver's angle back from a log line; a renamed
leaf or a new status broke them silently. Now the one producer, :func:`tree_snapshot` (called by
:meth:`bt_nav.mission.core.MissionCore.snapshot`, which the ROS executive and the lock-step engine both use), writes
a JSON document, and readers take fields from it (:func:`read_snapshot`, :func:`snapshot_nodes`); the art a human
reads is rendered from the document (:func:`render_art`, as ``bt-nav watch`` and ``bt-nav replay`` print it).

A snapshot (``format`` :data:`SNAPSHOT_FORMAT`)::

    {"format": "bt_nav.tree/1", "tick": 12, "t": 3.25, "maneuver": "A", "tip": "Randomizer", "path": [0, 4, 18, 23],
     "nodes": [{"name": "Mission", "kind": "sequence", "class": "ReactiveSequence", "status": "RUNNING",
                "feedback": "", "depth": 0, "parent": -1}, ...],
     "blackboard": {"armed": true, "mission_over": false, "maneuver_active": true, "cmd_vel": {...}, ...}}

``nodes`` are in display order (pre-order: a node, then its children); ``kind`` is ``sequence``, ``selector``,
``parallel``, ``decorator`` or ``leaf`` (composites also say ``memory``); ``status`` is py_trees' status name;
``path`` lists the indices from the root to the tip (the nodes the last tick ended on).

An event (``format`` :data:`EVENT_FORMAT`), one per announcement of a leaf (:meth:`~bt_nav.mission.behaviours.base.
Leaf.announce`); a maneuver's::

    {"format": "bt_nav.event/1", "event": "maneuver", "t": 12.3, "leaf": "Randomizer", "maneuver": "A",
     "side": "right", "angle_deg": 143.0, "readings": {"front": 0.49, "left": 1.2, "right": null}}

``angle_deg`` is the announced angle in whole degrees (as the log line says it), ``side`` left or right; the
readings are the sectors' nearest returns (m, null when unknown) when the maneuver started. Pure: py_trees only.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import py_trees

from bt_nav.mission.datatypes import Command

SNAPSHOT_FORMAT = "bt_nav.tree/1"
EVENT_FORMAT = "bt_nav.event/1"
#: The blackboard keys a snapshot carries: the command and the mission's and the maneuver's state.
SNAPSHOT_KEYS = ("armed", "mission_over", "scan_ok", "scan_status", "maneuver_active", "cmd_vel", "evaluation_result")
#: py_trees' status names (``Status.value``).
STATUSES = tuple(status.value for status in py_trees.common.Status)
#: How py_trees' unicode display marks each kind (``py_trees.display.unicode_symbols``, colour-free).
_MARKERS = {"parallel": "/_/", "decorator": "-^-", "leaf": "-->", ("sequence", False): "[-]",
            ("sequence", True): "{-}", ("selector", False): "[o]", ("selector", True): "{o}"}
#: And each status (check mark, multiplication x, star, dash).
_STATUS_MARKS = {"SUCCESS": "\u2713", "FAILURE": "\u2715", "RUNNING": "*", "INVALID": "-"}


def jsonable(value: Any) -> Any:
    """A JSON-friendly form of a blackboard value (numbers stay numbers; NaN/inf become strings)."""
    if isinstance(value, bool) or value is None or isinstance(value, int | str):
        return value
    if isinstance(value, float):
        return round(value, 6) if math.isfinite(value) else str(value)
    if isinstance(value, Command):
        return {"linear": jsonable(value.linear), "angular": jsonable(value.angular), "source": value.source}
    return repr(value)


def node_kind(node: py_trees.behaviour.Behaviour) -> str:
    """The node's family, as py_trees' display tells them apart (a parallel before a composite)."""
    if isinstance(node, py_trees.composites.Parallel):
        return "parallel"
    if isinstance(node, py_trees.decorators.Decorator):
        return "decorator"
    if isinstance(node, py_trees.composites.Sequence):
        return "sequence"
    if isinstance(node, py_trees.composites.Selector):
        return "selector"
    return "leaf"


def tree_snapshot(root: py_trees.behaviour.Behaviour, *, tick: int, t: float, maneuver: str,
                  board: dict[str, Any]) -> dict[str, Any]:
    """The snapshot of ``root`` after a tick (see the module docstring); ``board``: JSON-able values of
    :data:`SNAPSHOT_KEYS`."""
    nodes: list[dict[str, Any]] = []
    index: dict[int, int] = {}
    stack: list[tuple[py_trees.behaviour.Behaviour, int, int]] = [(root, 0, -1)]
    while stack:
        node, depth, parent = stack.pop()
        index[id(node)] = len(nodes)
        kind = node_kind(node)
        entry = {"name": node.name, "kind": kind, "class": type(node).__name__, "status": node.status.value,
                 "feedback": node.feedback_message or "", "depth": depth, "parent": parent}
        if kind in ("sequence", "selector"):
            entry["memory"] = bool(getattr(node, "memory", False))
        nodes.append(entry)
        stack.extend((child, depth + 1, index[id(node)]) for child in reversed(node.children))
    tip = root.tip()
    path: list[int] = []
    walker = tip
    while walker is not None and id(walker) in index:
        path.append(index[id(walker)])
        walker = walker.parent
    return {"format": SNAPSHOT_FORMAT, "tick": tick, "t": t, "maneuver": maneuver,
            "tip": tip.name if tip is not None else "", "path": path[::-1], "nodes": nodes, "blackboard": board}


def snapshot_json(snapshot: dict[str, Any]) -> str:
    """The wire form of a snapshot or an event (compact JSON, unicode kept)."""
    return json.dumps(snapshot, separators=(",", ":"), ensure_ascii=False)


def _read(text: str, form: str) -> dict[str, Any] | None:
    try:
        value = json.loads(text)
    except ValueError:
        return None
    return value if isinstance(value, dict) and value.get("format") == form else None


def read_snapshot(text: str) -> dict[str, Any] | None:
    """A snapshot from its wire form; None for anything else (e.g. the unicode art older bags hold)."""
    return _read(text, SNAPSHOT_FORMAT)


def read_event(text: str) -> dict[str, Any] | None:
    """An event from its wire form; None for anything else."""
    return _read(text, EVENT_FORMAT)


@dataclass(frozen=True)
class SnapshotNode:
    """One node of a snapshot, as the readers draw it."""

    name: str
    kind: str  # sequence, selector, parallel, decorator or leaf
    status: str  # SUCCESS, FAILURE, RUNNING or INVALID
    feedback: str
    depth: int
    parent: int  # index of the parent node, -1 for the root


def snapshot_nodes(snapshot: dict[str, Any]) -> list[SnapshotNode]:
    """The nodes of a snapshot in display order (unknown fields are ignored, missing ones get neutral values)."""
    return [SnapshotNode(str(n.get("name", "")), str(n.get("kind", "leaf")), str(n.get("status", "INVALID")),
                         str(n.get("feedback", "")), int(n.get("depth", 0)), int(n.get("parent", -1)))
            for n in snapshot.get("nodes", ())]


def render_art(snapshot: dict[str, Any]) -> str:
    """The snapshot as py_trees' unicode tree with statuses, without colours: what
    ``py_trees.display.unicode_tree(root, show_status=True)`` printed for the tree it was taken of."""
    lines = []
    for node in snapshot.get("nodes", ()):
        kind = node.get("kind", "leaf")
        marker = _MARKERS.get((kind, bool(node.get("memory"))), _MARKERS.get(kind, "-->"))
        feedback = node.get("feedback") or ""
        lines.append(f"{'    ' * int(node.get('depth', 0))}{marker} {str(node.get('name', '')).replace(chr(10), ' ')} "
                     f"[{_STATUS_MARKS.get(node.get('status'), '?')}]" + (f" -- {feedback}" if feedback else ""))
    return "\n".join(lines) + "\n"


def event(kind: str, t: float, leaf: str, **fields: Any) -> dict[str, Any]:
    """An event record (see the module docstring)."""
    return {"format": EVENT_FORMAT, "event": kind, "t": t, "leaf": leaf, **fields}
