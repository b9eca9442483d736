"""The right-node generator (``tests/nodegen``, issue 52) without DDS: every node it writes is a complete Python
file a student could hand in (it compiles, names its choice, declares ``safety_distance``), the seeds cover its
whole knob space, and each mutant differs from its right node in the one line of its mistake."""

from __future__ import annotations

import difflib
import re

import pytest

from tests.nodegen import EXPECT, MUTATIONS, VALUES, generate, mutants
from tests.nodegen.space import ODOM_MAX_RATE, STEP_ANGLE, TURN_RATE_RANGE

SEEDS = range(200)


@pytest.fixture(scope="module")
def specs() -> list:
    """The first 200 generated nodes (generated once for the module)."""
    return [generate(seed) for seed in SEEDS]


def test_every_generated_node_is_a_complete_lab_node(specs: list) -> None:
    for spec in specs:
        compile(spec.source, spec.name, "exec")
        assert f"# CHOICE: {spec.knobs.choice}\n" in spec.source, spec.name
        assert 'self.declare_parameter("safety_distance", 0.5)' in spec.source, spec.name
        assert '"toggle_navigation"' in spec.source and '"cmd_vel"' in spec.source, spec.name
        assert "qos_profile_sensor_data" in spec.source and "angle_increment" in spec.source, spec.name
        assert "# <" not in spec.source, spec.name  # no mutation marker left in a right node
        assert "bt_nav" not in spec.source.replace("tests/nodegen", ""), spec.name  # standalone


def test_the_same_seed_gives_the_same_node() -> None:
    assert generate(17).source == generate(17).source
    assert generate(17).source != generate(18).source


def test_the_seeds_cover_every_knob_value(specs: list) -> None:
    for name, values in VALUES.items():
        seen = {getattr(spec.knobs, name) for spec in specs}
        assert set(values) <= seen, (name, set(values) - seen)
    rates = [spec.knobs.turn_rate for spec in specs]
    assert min(rates) == TURN_RATE_RANGE[0] and max(rates) == TURN_RATE_RANGE[1]


def test_every_node_turns_within_its_tolerance_by_construction(specs: list) -> None:
    for spec in specs:
        k = spec.knobs
        assert TURN_RATE_RANGE[0] <= k.turn_rate <= TURN_RATE_RANGE[1], spec.name
        assert k.turn_rate * k.step_period() <= STEP_ANGLE + 1e-3, spec.name
        assert k.timing != "odom" or k.turn_rate <= ODOM_MAX_RATE, spec.name
        assert k.timing != "scan_stamp" or k.loop == "scan", spec.name
        if k.choice == "C":  # C's sides stay off the bow (they would see the obstacle it pivots from)
            assert k.side_centre - k.side_half >= 45, spec.name
        assert 30 <= k.side_centre - k.side_half and k.side_centre + k.side_half <= 140, spec.name


def test_each_mutant_compiles_and_differs_from_its_right_node_in_one_line(specs: list) -> None:
    made = set()
    for spec in specs[:30]:
        for name, source in mutants(spec).items():
            made.add((name, spec.knobs.choice))
            compile(source, f"{spec.name}__{name}", "exec")
            changed = [line for line in difflib.unified_diff(spec.source.splitlines(), source.splitlines(), n=0,
                                                              lineterm="") if re.match(r"[-+][^-+]", line)]
            # the docstring's mistake line and the mistake's own line
            assert len(changed) == 4, (spec.name, name, changed)
            assert MUTATIONS[name][2].split("  #")[0] in source, (spec.name, name)
    wanted = {(name, choice) for name, table in EXPECT.items() for choice in table}
    assert made == wanted, wanted ^ made


def test_every_mutant_has_an_expected_reason_that_is_a_regex() -> None:
    for name, table in EXPECT.items():
        assert name in MUTATIONS
        for choice, (pattern, cells) in table.items():
            assert choice in MUTATIONS[name][0]
            re.compile(pattern)
            assert cells is None or re.compile(cells)


def test_at_100_nodes_every_default_grid_cell_of_each_choice_gets_20_right_nodes() -> None:
    from tests.nodegen import suite

    dealt = suite.deal([generate(seed) for seed in range(100)])
    for choice in "ABC":
        cells = suite.choice_cells(choice)
        assert cells, choice
        for index in range(len(cells)):
            nodes = dealt[(choice, index)]
            assert len(nodes) >= suite.PER_CELL and all(n.knobs.choice == choice for n in nodes), (choice, index)


def _row(world: str, lidar: str, passed: bool, reason: str, params: dict | None = None) -> dict:
    return {"world": world, "maneuver": "C", "lidar": lidar, "seed": 0, "passed": passed, "reason": reason,
            "cell_params": params or {}}


def test_a_generated_mutant_is_judged_on_its_reason_its_cells_and_its_lidars() -> None:
    from tests.nodegen.suite import judged_mutant

    side = "failed: maneuver 1 turned 89 deg left; the Smart Pivot needs 90 +- 10 deg right (readings ...)"
    ok = judged_mutant("gen002_C__wrong_side", [_row("lab_slant", "lds01", False, side),
                                                _row("lab_dead_end", "lds01", True, "passed")])
    assert ok["outcome"] == "failed for its reason", ok
    missed = judged_mutant("gen002_C__wrong_side", [_row("lab_slant", "lds01", True, "passed")])
    assert missed["outcome"] == "wrong" and "PASSED" in missed["wrong"][0]
    other = judged_mutant("gen002_C__angle_45", [_row("lab_beside", "lds01", False, "failed: hit an obstacle")])
    assert other["outcome"] == "wrong"
    by_lidar = judged_mutant("gen002_C__hardcoded_indices", [
        _row("lab_beside", "lds01", True, "passed"),
        _row("lab_beside", "rplidar", False, "failed: performed no maneuver")])
    assert by_lidar["outcome"] == "failed for its reason", by_lidar
    assert judged_mutant("gen002_C__angle_45", [])["outcome"] == "not graded"
