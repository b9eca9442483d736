"""Build the mission tree from ``trees/mission.xml`` with py_trees' BehaviorTree.CPP parser.

The shape of the tree lives only in the XML. The ``maneuver`` parameter selects which maneuver
subtree fills the slot named ``Maneuver``: the loader rewrites that ``<SubTree ID=...>`` before
parsing (the upstream parser has no way to pick a subtree at run time), so the chosen maneuver shows
in the tree's name, its display and its trace.

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

from bt_nav.mission.behaviours import REGISTRY
from bt_nav.mission.params import MANEUVER_TITLES, normalise_maneuver
from bt_nav.mission.resources import tree_file

MANEUVER_SLOT = "Maneuver"
SUBTREE_FOR = {"none": "ManeuverNone", "A": "ManeuverA", "B": "ManeuverB", "C": "ManeuverC"}


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
    """Point the ``Maneuver`` SubTree slot at the chosen maneuver's subtree (in place)."""
    choice = normalise_maneuver(maneuver)
    slots = [e for e in root.iter("SubTree") if e.attrib.get("name") == MANEUVER_SLOT]
    if len(slots) != 1:
        raise ValueError(f"the tree file needs exactly one <SubTree name='{MANEUVER_SLOT}'>, found {len(slots)}")
    slots[0].attrib["ID"] = SUBTREE_FOR[choice]


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
        root = parse_behaviour_tree_xml(str(selected), node_registry=dict(REGISTRY))
    for node in root.iterate():
        node.name = node.name.rsplit(".", 1)[-1]
    root.name = f"{root.name} [maneuver {MANEUVER_TITLES[normalise_maneuver(maneuver)]}]"
    return root
