"""The static mission tree rendered: text (ascii, unicode), graphviz (dot; svg and png through the ``dot`` binary),
the selected tree file (xml), json, and the Groot2 node model; and any tree's graph coloured by status.

``bt-nav dump-tree`` prints these, ``bt-nav replay --svg`` colours a recorded tick with :func:`tree_to_dot`, and
``bt-nav demo`` writes the run's ``tree.svg`` with :func:`render`.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import xml.etree.ElementTree as ET
from typing import Any

import py_trees

from bt_nav.mission.behaviours import LEAF_CLASSES
from bt_nav.mission.behaviours.base import Condition
from bt_nav.mission.core import strip_ansi
from bt_nav.mission.params import MANEUVER_TITLES, normalise_maneuver
from bt_nav.mission.resources import tree_file
from bt_nav.mission.tree import load_tree, select_maneuver

FORMATS = ("ascii", "unicode", "dot", "svg", "png", "xml", "json", "groot-model")

STATUS_FILL = {"SUCCESS": "#9be39b", "FAILURE": "#f4a3a3", "RUNNING": "#9cc7f4", "INVALID": "#e6e6e6"}


class GraphvizMissingError(RuntimeError):
    """svg/png were asked for but graphviz's ``dot`` is not installed."""


def kind(node: py_trees.behaviour.Behaviour) -> str:
    """sequence | fallback | decorator | condition | action."""
    if isinstance(node, py_trees.composites.Sequence):
        return "sequence"
    if isinstance(node, py_trees.composites.Selector):
        return "fallback"
    if isinstance(node, py_trees.decorators.Decorator):
        return "decorator"
    return "condition" if isinstance(node, Condition) else "action"


def ports(node: py_trees.behaviour.Behaviour) -> dict[str, str]:
    """Port name -> blackboard key the port is wired to (constants show as their value)."""
    if not hasattr(node, "input_ports"):
        return {}
    wired: dict[str, str] = {}
    for port in [*node.input_ports(), *node.output_ports()]:
        key = node._get_blackboard_key(port)  # noqa: SLF001 - py_trees exposes no public accessor
        wired[port] = key
    return wired


def to_dict(node: py_trees.behaviour.Behaviour) -> dict[str, Any]:
    """The tree as nested dicts (for json)."""
    out: dict[str, Any] = {"name": node.name, "class": type(node).__name__, "kind": kind(node)}
    wired = ports(node)
    if wired:
        out["ports"] = wired
    if node.children:
        out["children"] = [to_dict(child) for child in node.children]
    return out


def _dot_id(index: int) -> str:
    return f"n{index}"


def tree_to_dot(root: py_trees.behaviour.Behaviour, statuses: dict[str, str] | None = None,
                title: str = "") -> str:
    """Graphviz dot text; with ``statuses`` nodes are filled by status (replay), else by kind."""
    shapes = {"sequence": ("box", "→"), "fallback": ("octagon", "?"), "decorator": ("diamond", ""),
              "condition": ("ellipse", ""), "action": ("box", "")}
    kind_fill = {"sequence": "#fff2cc", "fallback": "#dae8fc", "decorator": "#eeeeee",
                 "condition": "#d5e8d4", "action": "#ffffff"}
    lines = ["digraph mission {", '  graph [rankdir=TB, fontname="Helvetica", ordering=out'
             + (f', label="{title}", labelloc=t' if title else "") + "];",
             '  node [fontname="Helvetica", fontsize=11, style="filled,rounded"];']
    ids: dict[int, str] = {}
    for index, node in enumerate(root.iterate()):
        ids[id(node)] = _dot_id(index)
        shape, prefix = shapes[kind(node)]
        label = f"{prefix} {node.name}".strip()
        fill = STATUS_FILL.get(statuses.get(node.name, "INVALID")) if statuses is not None else kind_fill[kind(node)]
        style = "filled" if shape in ("ellipse", "octagon", "diamond") else "filled,rounded"
        lines.append(f'  {ids[id(node)]} [label="{label}", shape={shape}, fillcolor="{fill}", style="{style}"];')
    for node in root.iterate():
        for child in node.children:
            lines.append(f"  {ids[id(node)]} -> {ids[id(child)]};")
    lines.append("}")
    return "\n".join(lines) + "\n"


def graphviz(dot_text: str, fmt: str) -> bytes:
    """Render dot text with graphviz's ``dot`` binary."""
    binary = shutil.which("dot")
    if binary is None:
        raise GraphvizMissingError(f"rendering {fmt} needs graphviz's `dot` binary: install it with "
                              "`sudo apt-get install graphviz` (or use --format dot)")
    return subprocess.run([binary, f"-T{fmt}"], input=dot_text.encode(), capture_output=True,
                          check=True).stdout


def selected_xml(maneuver: str) -> str:
    """The tree file with the maneuver slot pointing at the chosen maneuver."""
    document = ET.parse(tree_file())
    select_maneuver(document.getroot(), maneuver)
    return ET.tostring(document.getroot(), encoding="unicode")


def nodes_model() -> ET.Element:
    """Groot2's ``TreeNodesModel`` for bt_nav's leaves, generated from their port declarations."""
    model = ET.Element("TreeNodesModel")
    for name, cls in sorted(LEAF_CLASSES.items()):
        element = ET.SubElement(model, "Condition" if issubclass(cls, Condition) else "Action", ID=name)
        for port, info in cls.INPUT_PORTS.items():
            ET.SubElement(element, "input_port", name=port, type=getattr(info.data_type, "__name__", "any"))
        for port, info in cls.OUTPUT_PORTS.items():
            ET.SubElement(element, "output_port", name=port, type=getattr(info.data_type, "__name__", "any"))
        for attribute in getattr(cls, "ATTRIBUTES", ()):
            ET.SubElement(element, "input_port", name=attribute, type="str")
    for name in ("ForceSuccess",):
        ET.SubElement(model, "Decorator", ID=name)
    return model


def render(maneuver: str = "none", fmt: str = "unicode") -> str | bytes:
    """The static tree in ``fmt`` (one of :data:`FORMATS`)."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; choose from {', '.join(FORMATS)}")
    if fmt == "xml":
        return selected_xml(maneuver)
    if fmt == "groot-model":
        element = nodes_model()
        ET.indent(element, space="  ", level=1)
        return "  " + ET.tostring(element, encoding="unicode") + "\n"
    root = load_tree(maneuver)
    if fmt == "ascii":
        return py_trees.display.ascii_tree(root)
    if fmt == "unicode":
        return strip_ansi(py_trees.display.unicode_tree(root))
    if fmt == "json":
        return json.dumps(to_dict(root), indent=2) + "\n"
    title = f"bt_nav mission tree — maneuver {MANEUVER_TITLES[normalise_maneuver(maneuver)]}"
    dot_text = tree_to_dot(root, title=title)
    return dot_text if fmt == "dot" else graphviz(dot_text, fmt)
