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
``path`` lists the indices from the root to the tip (the nodes the last tick ended on). A leaf whose feedback is a
figure the readers count on also gives it as ``data`` (:data:`DEADLINE_LEFT`: the deadline leaf's seconds left;
:data:`TO_GO`: a turning maneuver's degrees to go; :data:`DEADLINE`: the deadline's state), so a video counts
down from the number, never from the feedback's words.

An event (``format`` :data:`EVENT_FORMAT`), one per announcement of a leaf (:meth:`~bt_nav.mission.behaviours.base.
Leaf.announce`); a maneuver's::

    {"format": "bt_nav.event/1", "event": "maneuver", "t": 12.3, "leaf": "Randomizer", "maneuver": "A",
     "side": "right", "angle_deg": 143.0, "readings": {"front": 0.49, "left": 1.2, "right": null}}

``angle_deg`` is the announced angle in whole degrees (as the log line says it), ``side`` left or right; the
readings are the sectors' nearest returns (m, null when unknown) when the maneuver started. Every event a leaf
announces beside a log line (:meth:`~bt_nav.mission.behaviours.base.Leaf.tell`) also carries that line as
``text`` with its ``level`` (``INFO``, ``WARN``): the lab's terminal shows it as it is, without reading the log.
The leaves' events: ``maneuver`` (a maneuver starts), ``maneuver_end`` (``status`` SUCCESS or FAILURE,
``turned_deg``), ``maneuver_preempted``, ``open_loop`` (a maneuver lost its odometry), ``brake`` (the emergency
brake stops, ``ahead_m``), ``brake_turn`` (it turns away, ``side``), ``brake_clear`` (the path is clear,
``ahead_m``).

A judge's events (:class:`bt_nav.ros.nodes.judging.JudgeNode` on its ``~/events``, :func:`call_event`) say what it
asked of the robot and what came back, at the judge's sim time::

    {"format": "bt_nav.event/1", "event": "call", "t": 9.0, "call": "toggle_navigation", "data": true}
    {"format": "bt_nav.event/1", "event": "reply", "t": 9.01, "call": "toggle_navigation", "data": true,
     "answered": true, "success": true, "message": "armed at 9.01 s"}

(``unanswered``: the request was given up after ``attempts`` sends.) Pure: py_trees only.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import py_trees

from bt_nav.mission.datatypes import Command

SNAPSHOT_FORMAT = "bt_nav.tree/1"
EVENT_FORMAT = "bt_nav.event/1"
#: A node's ``data`` keys: the deadline's state (``none``, ``unarmed``, ``counting``, ``reached``), its seconds left
#: while counting, and a turning maneuver's signed degrees to go.
DEADLINE, DEADLINE_LEFT, TO_GO = "deadline", "deadline_left_s", "to_go_deg"
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
        data = getattr(node, "snapshot_data", None)  # a bt_nav leaf's (Leaf.snapshot_data)
        if data:
            entry["data"] = {key: jsonable(value) for key, value in data.items()}
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


def snapshot_time(snapshot: Mapping[str, Any]) -> float | None:
    """When the snapshot was taken: its ``t`` (the tick's time on the executive's clock, sim time in simulation);
    None when it has no finite number there. Why a reader takes it rather than the time the message arrived: at
    10-20x real time a reader's queue of ground truth lags seconds of sim time behind the rare snapshots, and a
    branch timed by arrival colours the wrong stretch of the path (:mod:`bt_nav.run.recorder`,
    :func:`bt_nav.media.bagread.read_bag`)."""
    t = snapshot.get("t")
    if isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t):
        return None
    return float(t)


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
    data: Mapping[str, Any] = field(default_factory=dict, hash=False, compare=False)  # the leaf's figures


def snapshot_nodes(snapshot: dict[str, Any]) -> list[SnapshotNode]:
    """The nodes of a snapshot in display order (unknown fields are ignored, missing ones get neutral values)."""
    return [SnapshotNode(str(n.get("name", "")), str(n.get("kind", "leaf")), str(n.get("status", "INVALID")),
                         str(n.get("feedback", "")), int(n.get("depth", 0)), int(n.get("parent", -1)),
                         dict(n["data"]) if isinstance(n.get("data"), dict) else {})
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


def event_line(record: dict[str, Any]) -> str:
    """An event as one line for a human (``bt-nav replay``): its own line (``text``) when it has one, else its kind,
    source and fields."""
    if record.get("text"):
        return f"[{record.get('level', 'INFO')}] {record['text']}"
    fields = ", ".join(f"{k}={v}" for k, v in record.items() if k not in ("format", "event", "t", "leaf", "call"))
    source = record.get("leaf") or record.get("call", "")
    return f"{source}: {record.get('event', '')}" + (f" ({fields})" if fields else "")


def call_event(kind: str, t: float, call: str, data: bool, **fields: Any) -> dict[str, Any]:
    """A judge's event about its service call ``call`` (``call``, ``reply`` or ``unanswered``; see the module
    docstring): what it asked (``data``) at sim time ``t``, and with a reply what came back."""
    return {"format": EVENT_FORMAT, "event": kind, "t": t, "call": call, "data": data, **fields}
