"""The tree file parses with the pinned py_trees parser, and its Groot2 model matches the leaves."""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import py_trees
import pytest

from bt_nav.media.treedot import nodes_model
from bt_nav.mission.behaviours import LEAF_CLASSES, REGISTRY
from bt_nav.mission.core import MissionCore, strip_ansi
from bt_nav.mission.resources import read_yaml, tree_file, written_whole
from bt_nav.mission.snapshot import render_art
from bt_nav.mission.tree import load_tree
from bt_nav.testing import TickHarness

GOLDEN = Path(__file__).parent / "golden"
UPDATE = os.environ.get("BT_NAV_UPDATE_GOLDEN") == "1"


def test_py_trees_is_the_pinned_version() -> None:
    """The XML parser is experimental upstream: a new py_trees must be a deliberate upgrade."""
    assert py_trees.version.__version__ == "2.6.0"


def test_tree_file_is_behaviortree_cpp_v4() -> None:
    root = ET.parse(tree_file()).getroot()
    assert root.tag == "root" and root.attrib["BTCPP_format"] == "4"
    assert root.attrib["main_tree_to_execute"] == "Mission"
    ids = {bt.attrib["ID"] for bt in root.findall("BehaviorTree")}
    assert ids == {"Mission", "ManeuverNone", "ManeuverA", "ManeuverB", "ManeuverC"}


@pytest.mark.parametrize(("maneuver", "leaf"), [("none", "NoManeuver"), ("A", "Randomizer"), ("B", "Retreat"),
                                                ("randomizer", "Randomizer"), ("smart_pivot", "SmartPivot")])
def test_each_maneuver_fills_the_slot(maneuver: str, leaf: str) -> None:
    root = load_tree(maneuver)
    names = [n.name for n in root.iterate()]
    assert leaf in names
    others = {"NoManeuver", "Randomizer", "Retreat", "SmartPivot"} - {leaf}
    assert not others & set(names), "exactly one maneuver in the tree"
    assert len(names) == len(set(names)), "node names are unique"
    priorities = next(n for n in root.iterate() if n.name == "Priorities")
    order = [c.name for c in priorities.children]
    assert order[:3] == ["MissionOver", "Disarmed", "ScanUnusable"]
    assert order[-3:] == ["Close", "Far", "FullSpeed"]


def test_reactive_composites_are_memoryless() -> None:
    root = load_tree("A")
    for node in root.iterate():
        if isinstance(node, py_trees.composites.Composite) and not isinstance(node, py_trees.composites.Parallel):
            assert node.memory is False, f"{node.name} must re-evaluate its guards every tick"


def test_ports_are_wired_to_the_shared_keys() -> None:
    root = load_tree("C")
    pivot = next(n for n in root.iterate() if n.name == "SmartPivot")
    assert pivot._get_blackboard_key("cmd_vel") == "/cmd_vel"
    assert pivot._get_blackboard_key("angular_speed") == "/maneuver_angular_speed"
    trigger = next(n for n in root.iterate() if n.name == "FrontTooClose?")
    assert trigger._get_blackboard_key("distance") == "/pivot_distance"


def test_unknown_maneuver_and_unknown_tags_are_clear_errors(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown maneuver"):
        load_tree("Z")
    bad = tmp_path / "bad.xml"
    bad.write_text(tree_file().read_text().replace("<DriveForward ", "<DriveBackward "))
    with pytest.raises(ValueError, match="DriveBackward"):
        load_tree("none", bad)


def test_groot_model_in_the_tree_file_matches_the_leaves() -> None:
    committed = ET.parse(tree_file()).getroot().find("TreeNodesModel")
    assert committed is not None

    def entries(model: ET.Element) -> list:
        return sorted((e.tag, e.attrib["ID"], [(p.tag, p.attrib["name"], p.attrib["type"]) for p in e]) for e in model)

    assert entries(committed) == entries(nodes_model()), "regenerate: bt-nav dump-tree --format groot-model"
    used = {e.tag for e in ET.parse(tree_file()).getroot().iter()} & set(LEAF_CLASSES)
    declared = {e.attrib["ID"] for e in committed}
    assert used <= declared
    assert set(LEAF_CLASSES) <= set(REGISTRY)


def golden(name: str, text: str, suffix: str = ".txt") -> None:
    path = GOLDEN / f"{name}{suffix}"
    if UPDATE or not path.exists():
        path.write_text(text, encoding="utf-8")
        if not UPDATE:
            pytest.fail(f"golden file {path.name} was missing and has been written; check it in")
    assert text == path.read_text(encoding="utf-8"), f"snapshot differs from {path} (BT_NAV_UPDATE_GOLDEN=1)"


def golden_snapshot(name: str, core: MissionCore) -> None:
    """The structured snapshot (``~/tree``'s document) and the art drawn from it, each against its golden file;
    the art is also what py_trees' own display prints for the live tree."""
    snapshot = core.snapshot()
    golden(name, json.dumps(snapshot, indent=1, ensure_ascii=False) + "\n", ".json")
    art = render_art(snapshot)
    golden(name, art)
    assert art == strip_ansi(py_trees.display.unicode_tree(core.root, show_status=True))


def test_golden_snapshots() -> None:
    h = TickHarness("A")
    h.tick()
    golden_snapshot("01_before_arming", h.core)
    h.arm()
    h.tick()
    golden_snapshot("02_full_speed", h.core)
    h.see((0.0, 0.45))
    h.tick(3)
    golden_snapshot("03_maneuver_a_running", h.core)
    h.see()
    h.clock.now = 60.0
    h.tick()
    golden_snapshot("04_mission_over", h.core)


def test_cached_type_hints_answer_as_py_trees_does() -> None:
    """The parser's type hints, asked once per class, are py_trees' own for every class of the registry, and each
    answer is a dict of its own (the parser may fill it in)."""
    from bt_nav.mission import tree

    assert py_trees.ports_utils.collect_type_hints is tree._cached_type_hints
    classes = set(REGISTRY.values())
    assert len(classes) > 5
    for cls in classes:
        first = tree._cached_type_hints(cls)
        assert first == tree._COLLECT_TYPE_HINTS(cls), cls
        first["changed"] = int
        assert "changed" not in tree._cached_type_hints(cls), "a shared dict would leak one call's changes"


def test_read_yaml_parses_each_version_once_and_hands_out_copies(tmp_path: Path) -> None:
    path = tmp_path / "w.yaml"
    path.write_text("boxes: [[1, 2]]\n")
    first = read_yaml(path)
    first["boxes"][0].append(3)
    assert read_yaml(path) == {"boxes": [[1, 2]]}, "a caller's change must not reach the next reader"
    path.write_text("boxes: [[5, 6, 7]]\n")  # another size: another version of the file
    assert read_yaml(path) == {"boxes": [[5, 6, 7]]}


def test_a_file_written_whole_appears_complete_or_not_at_all(tmp_path: Path) -> None:
    path = tmp_path / "verdict.json"
    with written_whole(path) as stream:
        stream.write("{}")
        assert not path.exists(), "nothing under the name before the block ends"
    assert path.read_text() == "{}" and (path.stat().st_mode & 0o777) == 0o644
    with pytest.raises(RuntimeError), written_whole(path) as stream:
        stream.write('{"half": ')
        raise RuntimeError("stopped half-way")
    assert path.read_text() == "{}", "a writer stopped half-way leaves the old file"
    assert [p.name for p in tmp_path.iterdir()] == ["verdict.json"], "no temporary file left"
