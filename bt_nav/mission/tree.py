"""Build the mission tree from ``trees/mission.xml`` with py_trees' BehaviorTree.CPP parser.

The shape of the tree lives only in the XML. The ``maneuver`` parameter selects which maneuver
subtree fills the slot named ``Maneuver`` (its ``subtree`` in :mod:`bt_nav.mission.maneuver_spec`): the
loader rewrites that ``<SubTree ID=...>`` before parsing (the upstream parser has no way to pick a subtree
at run time), so the chosen maneuver shows in the tree's name, its display and its trace. A maneuver whose
subtree the XML lacks (one added to the spec alone) gets one generated from its spec
(:func:`maneuver_subtree`): the shape every maneuver shares, its trigger leaf at its distance, its leaf.

py_trees' parser is experimental and pinned (py_trees==2.6.0); ``tests/test_tree_parse.py`` guards it.
"""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import py_trees
import py_trees.ports_utils
from py_trees.parsers.behaviour_tree_xml import parse_behaviour_tree_xml

from bt_nav.mission.behaviours import REGISTRY, maneuver_leaf
from bt_nav.mission.maneuver_spec import NONE, ManeuverSpec, maneuver_spec, subtrees
from bt_nav.mission.params import MANEUVER_TITLES, normalise_maneuver
from bt_nav.mission.resources import tree_file

MANEUVER_SLOT = "Maneuver"
#: The trigger ports a generated subtree passes on from the slot (the edge trigger's, ``triggers._EdgeTrigger``).
_TRIGGER_PORTS = ("sectors", "hysteresis", "repeat", "clear_away", "rearm_distance", "odom", "odom_timeout",
                  "cmd_vel", "arm_count", "fire_at_arming")


@cache
def _class_type_hints(constructor: Callable) -> dict[str, Any]:
    return _COLLECT_TYPE_HINTS(constructor)


def _cached_type_hints(constructor: Callable) -> dict[str, Any]:
    """py_trees' ``collect_type_hints``, once per constructor (a copy each call, as the original returns).

    Why: the parser asks for every node's constructor hints, walking the class's MRO with ``inspect.signature``
    each time: 60 % of the 15 ms a tree took to load, and a lock-step mission loads one. The hints are a
    function of the class alone, so the cached answer is the same one.
    """
    return dict(_class_type_hints(constructor))


_COLLECT_TYPE_HINTS = py_trees.ports_utils.collect_type_hints
py_trees.ports_utils.collect_type_hints = _cached_type_hints


def select_maneuver(root: ET.Element, maneuver: str) -> None:
    """Point the ``Maneuver`` SubTree slot at the chosen maneuver's subtree (in place); generate that subtree
    from the maneuver's spec when the tree file has none of that ID."""
    choice = normalise_maneuver(maneuver)
    slots = [e for e in root.iter("SubTree") if e.attrib.get("name") == MANEUVER_SLOT]
    if len(slots) != 1:
        raise ValueError(f"the tree file needs exactly one <SubTree name='{MANEUVER_SLOT}'>, found {len(slots)}")
    subtree = subtrees()[choice]
    slots[0].attrib["ID"] = subtree
    if not any(e.attrib.get("ID") == subtree for e in root.iter("BehaviorTree")):
        root.insert(len(root) - 1 if root.find("TreeNodesModel") is not None else len(root),
                    maneuver_subtree(maneuver_spec(choice)))


def maneuver_subtree(spec: ManeuverSpec) -> ET.Element:
    """The ``<BehaviorTree>`` of a maneuver the tree file does not hold, from its spec: (in progress OR its
    trigger, at the trigger's distance) -> its leaf, every leaf port wired to the slot's key of the same name
    (what the file's own maneuver subtrees do)."""
    tree = ET.Element("BehaviorTree", ID=spec.subtree)
    sequence = ET.SubElement(tree, "ReactiveSequence", name=f"{spec.subtree}_{spec.tip}")
    engaged = ET.SubElement(sequence, "ReactiveFallback", name="Engaged?")
    ET.SubElement(engaged, "ManeuverActive", name="InProgress?", active="{active}")
    ET.SubElement(engaged, spec.trigger.leaf, name="Triggered?", distance=f"{{{spec.trigger.distance}}}",
                  **{p: f"{{{p}}}" for p in _TRIGGER_PORTS})
    leaf = maneuver_leaf(spec.leaf)
    ET.SubElement(sequence, spec.leaf, name=spec.tip,
                  **{p: f"{{{p}}}" for p in (*leaf.input_ports(), *leaf.output_ports())})
    return tree


def load_tree(maneuver: str = "none", path: str | os.PathLike[str] | None = None) -> py_trees.behaviour.Behaviour:
    """Parse the mission tree with the chosen maneuver; returns the root behaviour.

    Node names are shortened to the names written in the XML (the parser prefixes every parent's
    name, which makes the display unreadable); they stay unique within this tree.
    """
    source = Path(path) if path is not None else tree_file()
    document = ET.parse(source)
    select_maneuver(document.getroot(), maneuver)
    with tempfile.TemporaryDirectory(prefix="bt_nav_tree_") as tmp:
        selected = Path(tmp) / source.name
        document.write(selected, encoding="unicode")
        choice = normalise_maneuver(maneuver)
        leaf = None if choice == NONE else maneuver_spec(choice).leaf  # bt_nav's, or one defined elsewhere
        leaves = {} if leaf is None else {leaf: maneuver_leaf(leaf)}
        root = parse_behaviour_tree_xml(str(selected), node_registry={**REGISTRY, **leaves})
    for node in root.iterate():
        node.name = node.name.rsplit(".", 1)[-1]
    root.name = f"{root.name} [maneuver {MANEUVER_TITLES[normalise_maneuver(maneuver)]}]"
    return root
