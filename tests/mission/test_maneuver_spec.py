"""The maneuver spec is the one home of the lab's maneuvers: every table elsewhere derives from it, and a maneuver
added to the spec alone (a throw-away D here) runs through the tree, a lock-step mission, the check-off judge and
the docs' reference, judged by its own rules."""

from __future__ import annotations

import math
import sys
import tokenize
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from bt_nav_sim.world import list_worlds, load_world, world_file

from bt_nav.grading.exe.grid import choice_line
from bt_nav.judge.checkoff_core import MANEUVER_NAMES, CheckoffConfig, maneuver_problems
from bt_nav.media.plot import branch_of_tip
from bt_nav.mission import maneuver_spec as S
from bt_nav.mission import params as P
from bt_nav.mission.behaviours import REGISTRY, RotationManeuver, maneuver_leaf
from bt_nav.mission.resources import read_yaml, tree_file
from bt_nav.mission.scan import Sectors, clearer_side
from bt_nav.mission.tree import load_tree
from bt_nav.ros.bringup import CHECKOFF_WORLDS
from bt_nav.run.lockstep import run_mission
from bt_nav.testing import TickHarness
from tests.judge.truthkit import truth_judge

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import bt_nav_reference  # noqa: E402 - the docs' generator lives with the docs


class WiggleManeuver(RotationManeuver):
    """D, the throw-away Wiggle: 45 deg towards the clearer side (defined here only; py_trees registers it)."""

    def choose_rotation(self, sectors: Sectors) -> float:
        """An eighth of a turn."""
        return clearer_side(sectors) * math.radians(45.0)


WIGGLE = S.ManeuverSpec("D", "Wiggle", ("wiggle",), "WiggleManeuver", "Wiggle", "ManeuverD",
                        S.Trigger("front", "safety_distance"), S.AngleRule(45.0, 45.0), ("lab_object",))


@pytest.fixture
def maneuver_d(monkeypatch: pytest.MonkeyPatch) -> S.ManeuverSpec:
    """D registered in the spec, and nowhere else, for one test."""
    monkeypatch.setitem(S.MANEUVER_SPECS, "D", WIGGLE)
    return WIGGLE


# ---------------------------------------------------------------- a maneuver added to the spec alone
def test_d_is_a_value_of_the_maneuver_parameter(maneuver_d: S.ManeuverSpec) -> None:
    assert P.normalise_maneuver("wiggle") == P.normalise_maneuver("d") == "D"
    assert "D" in P.LAB_MANEUVERS and P.MANEUVERS[-1] == "D" and P.MANEUVER_TITLES["D"] == "D Wiggle"
    assert CHECKOFF_WORLDS["D"] == "lab_object" and load_world("lab_object").checkoff_maneuvers == ("A", "C", "D")
    assert branch_of_tip("Wiggle") == "Maneuver"
    assert choice_line().search("# CHOICE: D\n").group(1) == "D"


def test_d_runs_in_the_tree_from_its_trigger_to_its_end(maneuver_d: S.ManeuverSpec) -> None:
    assert load_tree("wiggle").name.endswith("[maneuver D Wiggle]")
    h = TickHarness("D")
    h.tick()
    assert h.arm()[0]
    h.tick()
    h.see((10.0, 0.4), (-30.0, 2.0))  # the front within safety_distance, the right clearer
    first = h.tick()
    assert first.tip == "Wiggle", first.tip
    leaf = next(n for n in h.core.root.iterate() if n.name == "Wiggle")
    assert isinstance(leaf, WiggleManeuver) and leaf.rotation == pytest.approx(-math.pi / 4)
    h.see()
    record = h.run_until(lambda r: r.statuses["Wiggle"] != "RUNNING", limit=200)
    assert record.statuses["Wiggle"] == "SUCCESS"
    assert all(r.command.linear == 0.0 for r in h.records[-5:])


def test_d_runs_a_lock_step_check_off_judged_by_its_own_rules(maneuver_d: S.ManeuverSpec) -> None:
    result = run_mission("lab_object", "D", 0, profile="lab")
    judged = result.results["maneuvers"]
    assert result.maneuvers >= 1 and judged, result.report_lines
    assert result.results["maneuver"] == "D"
    assert all(m["rule"].startswith("45 +- 10 deg") for m in judged if not m["interrupted"]), judged
    first = judged[0]
    assert abs(abs(first["angle_deg"]) - 45.0) <= 10.0 and first["angle_ok"], first
    assert result.passed, result.report_lines


def test_the_judge_holds_d_to_45_deg_not_to_cs_90(maneuver_d: S.ManeuverSpec) -> None:
    judge = truth_judge(CheckoffConfig(maneuver="D"), load_world("lab_object"))
    assert judge._angle_rule(44.0, None)[0] and not judge._angle_rule(90.0, None)[0]
    assert judge._within_max(50.0) and not judge._within_max(90.0)
    assert judge.config.limits() == (0.5, 0.5)
    assert judge.config.trigger_rule().startswith("held: front < 0.5 m (+0.05 m sensor-noise tolerance)")
    assert MANEUVER_NAMES["D"] == "the Wiggle"
    event = {"trigger": True, "angle_ok": False, "angle_deg": 90.0, "side": "left", "rule": "45 +- 10 deg either side",
             "forward_ok": True, "moved_on": True}
    assert maneuver_problems("D", event) == ["turned 90 deg left; the Wiggle needs 45 +- 10 deg either side"]


def test_the_docs_reference_has_a_section_for_d(maneuver_d: S.ManeuverSpec) -> None:
    page = bt_nav_reference.checks_page()
    assert "### D: the Wiggle" in page
    assert "the Wiggle needs 45 +- 10 deg either side" in page


# ---------------------------------------------------------------- every derived table agrees with the spec
def test_an_unknown_maneuver_is_an_error_never_judged_as_another() -> None:
    with pytest.raises(ValueError, match="maneuver must be one of A, B, C, got 'D'"):
        CheckoffConfig(maneuver="D")
    with pytest.raises(ValueError, match=r"unknown maneuver 'D': the lab's maneuvers are A, B or C"):
        S.maneuver_spec("D")


def test_a_judge_whose_maneuver_left_the_spec_refuses_to_judge(monkeypatch: pytest.MonkeyPatch) -> None:
    """The rules are looked up on every use: a maneuver gone from the spec is an error, never C's rules."""
    monkeypatch.setitem(S.MANEUVER_SPECS, "D", WIGGLE)
    judge = truth_judge(CheckoffConfig(maneuver="D"), load_world("lab_object"))
    monkeypatch.delitem(S.MANEUVER_SPECS, "D")
    for rule in (lambda: judge._angle_rule(90.0, None), lambda: judge._within_max(90.0), judge.config.limits):
        with pytest.raises(ValueError, match="unknown maneuver 'D'"):
            rule()


def test_the_derived_tables_agree_with_the_spec() -> None:
    specs = S.MANEUVER_SPECS.values()
    assert tuple(P.LAB_MANEUVERS) == tuple(S.MANEUVER_SPECS) and tuple(P.MANEUVERS) == ("none", *S.MANEUVER_SPECS)
    for spec in specs:
        assert P.normalise_maneuver(spec.letter.lower()) == spec.letter
        assert all(P.normalise_maneuver(alias) == spec.letter for alias in spec.aliases)
        assert P.MANEUVER_TITLES[spec.letter] == f"{spec.letter} {spec.title}"
        assert REGISTRY[spec.leaf] is maneuver_leaf(spec.leaf)
        assert CHECKOFF_WORLDS[spec.letter] == spec.arenas[0]
        assert MANEUVER_NAMES[spec.letter] == f"the {spec.title}"
        assert branch_of_tip(spec.tip) == "Maneuver"
        assert choice_line().search(f"# CHOICE: {spec.letter}").group(1) == spec.letter
        assert load_tree(spec.letter).name.endswith(f"[maneuver {spec.full_title}]")
    description = next(p.description for p in P.PARAMS if p.name == "maneuver")
    assert all(f"{s.letter} ({s.title})" in description for s in specs)


def test_the_tree_files_maneuver_subtrees_are_the_specs() -> None:
    """Each subtree in ``trees/mission.xml`` holds the spec's leaf under its tip name, after the spec's trigger
    leaf at the spec's distance parameter (the file's hand-written subtrees may add to that, never differ)."""
    trees = {t.attrib["ID"]: t for t in ET.parse(tree_file()).getroot().iter("BehaviorTree")}
    for spec in S.MANEUVER_SPECS.values():
        tree = trees[spec.subtree]
        leaves = [e for e in tree.iter() if e.tag == spec.leaf]
        assert [e.attrib["name"] for e in leaves] == [spec.tip]
        engaged = next(e for e in tree.iter("ReactiveFallback") if e.attrib["name"] == "Engaged?")
        trigger = [e for e in engaged if e.tag in {leaf for _, leaf in S.TRIGGER_READS.values()}][0]
        assert trigger.tag == spec.trigger.leaf and trigger.attrib["distance"] == f"{{{spec.trigger.distance}}}"


def test_the_bundled_arenas_are_the_specs() -> None:
    """A bundled world's ``checkoff_maneuvers`` may repeat what the spec's arenas say, never add to it; every arena a
    spec names is a bundled lab world."""
    for name in list_worlds("all"):
        written = read_yaml(world_file(name)).get("checkoff_maneuvers") or []
        assert set(written) <= set(S.checked_off_in(name)), name
        assert load_world(name).checkoff_maneuvers == S.checked_off_in(name)
    assert {a for spec in S.MANEUVER_SPECS.values() for a in spec.arenas} <= set(list_worlds("lab"))


def test_no_letter_is_spelled_as_data_outside_the_spec() -> None:
    """A maneuver letter as a string literal (``"A"``), or a ``[ABC]`` class in a regex, only in the spec (prose in
    docstrings and comments may name them)."""
    spec_file = ROOT / "bt_nav" / "mission" / "maneuver_spec.py"
    found = []
    for path in sorted([*(ROOT / "bt_nav").rglob("*.py"), *(ROOT / "sim" / "bt_nav_sim").rglob("*.py")]):
        if path == spec_file:
            continue
        with path.open("rb") as stream:
            for token in tokenize.tokenize(stream.readline):
                literal = token.type == tokenize.STRING and token.string.strip("rbfRBF") in ('"A"', '"B"', '"C"',
                                                                                              "'A'", "'B'", "'C'")
                if literal or (token.type != tokenize.COMMENT and "[ABC]" in token.string):
                    found.append(f"{path.relative_to(ROOT)}:{token.start[0]}: {token.line.strip()}")
    assert not found, found
