"""The compiled ticker (bt_nav.mission.behaviours.control.compile_tick) against py_trees' own tick.

The ticker replaces py_trees' generators on every tick of the mission, so it must leave exactly the same
trail: the same ``initialise``/``update``/``terminate`` calls in the same order, the same statuses and
``current_child`` after every tick. Random trees of every kind the mission uses (memory-less sequences
and selectors, the Inverter and ForceSuccess decorators, leaves) plus kinds it hands back to py_trees
(a sequence with memory, a Parallel) are built twice, one ticked by py_trees and one by the ticker, with
leaves that answer from the same random script; the two trails must be equal tick by tick.

Also here: the one-pass scan processing (cones and free paths from one cleaning) against the plain
formulas, bit for bit, and the leaves' direct output writes against py_trees' own.
"""

from __future__ import annotations

import math
import random
from typing import Any

import numpy as np
import py_trees
import pytest

from bt_nav.mission.behaviours.control import ForceSuccess, ReactiveFallback, ReactiveSequence, compile_tick
from bt_nav.mission.paths import HEADINGS, FreePaths, free_paths, free_paths_from_clean
from bt_nav.mission.scan import (
    Scan,
    SectorConfig,
    beam_angles,
    clean_ranges,
    clean_validated,
    sector_minima,
    sectors_from_clean,
    validate_scan,
)

Status = py_trees.common.Status
STATUSES = (Status.SUCCESS, Status.FAILURE, Status.RUNNING)


class Quiet(py_trees.behaviour.Behaviour):
    """A leaf whose ``update`` answers from a seeded random script and logs every call; py_trees' own (empty)
    ``initialise`` and ``terminate``, which the ticker skips."""

    def __init__(self, name: str, seed: int, log: list[tuple[str, ...]]) -> None:
        super().__init__(name=name)
        self.rng = random.Random(seed)
        self.log = log

    def update(self) -> Status:  # noqa: D102
        status = self.rng.choice(STATUSES)
        self.log.append(("update", self.name, status.name))
        return status


class Scripted(Quiet):
    """A scripted leaf that logs its ``initialise`` and ``terminate`` calls too."""

    def initialise(self) -> None:  # noqa: D102
        self.log.append(("initialise", self.name))

    def terminate(self, new_status: Status) -> None:  # noqa: D102
        self.log.append(("terminate", self.name, new_status.name))


def build(rng: random.Random, log: list[tuple[str, ...]], depth: int = 0) -> py_trees.behaviour.Behaviour:
    """A random tree; the same ``rng`` state gives the same tree (names, kinds, leaf scripts)."""
    name = f"n{rng.randrange(10**9)}"
    kind = rng.random() if depth < 4 else 1.0
    if kind < 0.3:
        return ReactiveSequence(name, children=[build(rng, log, depth + 1) for _ in range(rng.randint(1, 4))])
    if kind < 0.55:
        return ReactiveFallback(name, children=[build(rng, log, depth + 1) for _ in range(rng.randint(1, 4))])
    if kind < 0.62:
        return py_trees.decorators.Inverter(name, child=build(rng, log, depth + 1))
    if kind < 0.69:
        return ForceSuccess(name, child=build(rng, log, depth + 1))
    if kind < 0.72:
        return py_trees.composites.Sequence(name, memory=True, children=[build(rng, log, depth + 1)
                                                                          for _ in range(rng.randint(1, 3))])
    if kind < 0.74:
        return py_trees.composites.Parallel(name, policy=py_trees.common.ParallelPolicy.SuccessOnAll(),
                                            children=[build(rng, log, depth + 1) for _ in range(2)])
    if kind < 0.8:
        return Quiet(name, rng.randrange(10**9), log)
    return Scripted(name, rng.randrange(10**9), log)


def trail(root: py_trees.behaviour.Behaviour) -> list[tuple[Any, ...]]:
    """Every node's status and current child (composites) after a tick."""
    return [(node.name, node.status.name, getattr(getattr(node, "current_child", None), "name", None))
            for node in root.iterate()]


@pytest.mark.parametrize("seed", range(300))
def test_the_compiled_ticker_leaves_the_same_trail_as_py_trees(seed: int) -> None:
    logs: list[list[tuple[str, ...]]] = [[], []]
    roots = [ReactiveSequence("root", children=[build(random.Random(seed), logs[i])]) for i in range(2)]
    tree = py_trees.trees.BehaviourTree(roots[0])
    fast = compile_tick(roots[1])
    for tick in range(25):
        tree.tick()
        fast()
        assert logs[1] == logs[0], f"seed {seed}, tick {tick}: calls differ"
        assert trail(roots[1]) == trail(roots[0]), f"seed {seed}, tick {tick}: statuses differ"
        if tick == 12:  # an interruption from outside, as MissionCore does after an exception
            for root in roots:
                root.stop(Status.INVALID)


def test_the_compiled_ticker_calls_an_update_wrapped_on_the_instance_later() -> None:
    log: list[tuple[str, ...]] = []
    leaf = Scripted("leaf", 0, log)
    fast = compile_tick(ReactiveSequence("root", children=[leaf]))
    leaf.update = lambda: Status.FAILURE  # as the fault injection wraps a leaf after the tree is built
    fast()
    assert leaf.status is Status.FAILURE


def test_an_invalid_status_becomes_invalid_as_in_py_trees() -> None:
    leaf = Scripted("leaf", 0, [])
    leaf.update = lambda: "nonsense"
    root = ReactiveSequence("root", children=[leaf])
    compile_tick(root)()
    assert leaf.status is Status.INVALID and root.status is Status.INVALID


# ------------------------------------------------------------------------------------------ scans
def plain_free_paths(scan: Scan, half_width: float, horizon: float) -> np.ndarray:
    """The module docstring's formula, written plainly (the implementation before the one-pass version)."""
    ranges, angles = clean_ranges(scan), beam_angles(scan)
    near = np.isfinite(ranges) & (ranges < horizon + half_width)
    r, theta = ranges[near], angles[near]
    if r.size == 0:
        return np.full(HEADINGS.shape, float(horizon))
    x, y = r * np.cos(theta), r * np.sin(theta)
    cos_h, sin_h = np.cos(HEADINGS)[:, None], np.sin(HEADINGS)[:, None]
    along = x[None, :] * cos_h + y[None, :] * sin_h
    lateral = y[None, :] * cos_h - x[None, :] * sin_h
    inside = (np.abs(lateral) < half_width) & (along > 0.0)
    reach = along - np.sqrt(np.maximum(half_width * half_width - lateral * lateral, 0.0))
    return np.clip(np.where(inside, reach, math.inf).min(axis=1), 0.0, float(horizon))


def random_scan(rng: np.random.Generator) -> Scan:
    """A scan of a random layout with NaN, +-inf, zeros and out-of-range readings mixed in."""
    n = int(rng.choice([1, 5, 90, 360, 361, 1440, 4096]))
    angle_min = float(rng.choice([0.0, -math.pi, rng.uniform(-3.0, 3.0)]))
    inc = float(rng.choice([1.0, -1.0])) * 2 * math.pi / n if n > 1 else 0.01
    ranges = rng.uniform(0.0, 4.0, n)
    k = rng.random(n)
    ranges[k < 0.05] = np.nan
    ranges[(k >= 0.05) & (k < 0.08)] = np.inf
    ranges[(k >= 0.08) & (k < 0.1)] = -np.inf
    ranges[(k >= 0.1) & (k < 0.12)] = 0.0
    if rng.random() < 0.3:
        ranges = ranges.astype(np.float32)
    return Scan(angle_min, angle_min + (n - 1) * inc, inc, float(rng.choice([0.0, 0.12])),
                float(rng.choice([1.0, 3.5])), ranges)


@pytest.mark.parametrize("seed", range(5))
def test_one_cleaning_gives_the_same_cones_and_paths_bit_for_bit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(300):
        scan = random_scan(rng)
        half_width, horizon = float(rng.choice([0.1, 0.18])), float(rng.choice([0.5, 1.05, 2.0]))
        config = SectorConfig.from_degrees(float(rng.choice([20.0, 90.0])), 15.0, 15.0, int(rng.choice([1, 3, 10])))
        validate_scan(scan)
        clean = clean_validated(scan)
        expected = plain_free_paths(scan, half_width, horizon)
        assert np.array_equal(free_paths_from_clean(scan, clean, half_width, horizon).free, expected)
        assert np.array_equal(free_paths(scan, half_width, horizon).free, expected)
        assert repr(sectors_from_clean(scan, clean, config)) == repr(sector_minima(scan, config))


def test_free_paths_with_other_headings_still_work() -> None:
    scan = Scan(-math.pi, math.pi - 0.01, 2 * math.pi / 629, 0.1, 3.5, np.full(629, 0.5))
    headings = np.radians([-10.0, 0.0, 10.0])
    paths = free_paths(scan, 0.18, 1.0, headings)
    assert isinstance(paths, FreePaths) and paths.free.shape == (3,) and (paths.free < 0.5).all()


# ------------------------------------------------------------------------------------------ ports
def test_direct_output_writes_land_where_py_trees_writes_them() -> None:
    from bt_nav.testing import TickHarness

    h = TickHarness("C")
    h.tick()
    h.arm()
    for _ in range(3):
        h.tick()
    storage = py_trees.blackboard.Blackboard.storage
    for node in h.core.nodes:
        for port_name, (key, _type) in getattr(node, "_output_keys", {}).items():
            assert key == node._get_blackboard_key(port_name)
            assert storage[key] is node.get_last_output(port_name)


def test_a_wrongly_typed_output_write_still_raises() -> None:
    from bt_nav.testing import TickHarness

    h = TickHarness("C")
    h.tick()
    leaf = next(node for node in h.core.nodes if node.name == "ProcessScan")
    assert "scan_ok" in leaf._output_keys  # written once already: the direct path is in use
    with pytest.raises(TypeError):
        leaf._set_output("scan_ok", "yes")
