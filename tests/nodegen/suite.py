"""Generated right nodes and their mutants as the grader suite's classes (``tests/grader_suite.py --generated N``).

Every default-grid cell of each choice must see many right nodes nobody wrote by hand: each generated node is
graded on a sample of its choice's cells, dealt round-robin so that every cell gets at least :data:`PER_CELL` nodes
when there are enough (N >= 100: each choice's ~33 nodes take two of its cells), each node-cell with one LiDAR,
dealt round-robin. A cell and LiDAR is graded as its own class (``--maneuvers X --worlds W --lidars L`` and the
cell's parameters as ``--node-param``, which the judge triggers at too); each node's one mutant
(:func:`one_mutant`) is graded where its mistake shows and must fail there for the reason of
:data:`tests.nodegen.EXPECT`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from bt_nav_sim.world import load_world

from bt_nav.grading.grid import cell_label
from bt_nav.mission.assignments import LAB, Cell
from tests.nodegen import BY_LIDAR, EXPECT, NodeSpec, generate, mutants

#: The fewest right nodes each default-grid cell of a choice gets when the choice has that many nodes.
PER_CELL = 20
#: Class names: ``gen_right_<choice>_<cell>`` and ``gen_mutants_<choice>``.
RIGHT, MUTANTS = "gen_right", "gen_mutants"


def choice_cells(choice: str) -> list[Cell]:
    """The choice's cells of the lab's default grid (those whose world checks the choice off)."""
    return [c for c in LAB.exe_grid.cells_of(choice) if choice in load_world(c.world).checkoff_maneuvers]


def deal(specs: list[NodeSpec], per_cell: int = PER_CELL) -> dict[tuple[str, int], list[NodeSpec]]:
    """(choice, cell index) -> the nodes graded there: each node on k of its choice's cells, round-robin, k the
    fewest that give every cell ``per_cell`` nodes (all the cells when the choice has too few nodes)."""
    out: dict[tuple[str, int], list[NodeSpec]] = {}
    for choice in "ABC":
        nodes = [s for s in specs if s.knobs.choice == choice]
        cells = choice_cells(choice)
        if not nodes or not cells:
            continue
        k = min(len(cells), math.ceil(per_cell * len(cells) / len(nodes)))
        for i, spec in enumerate(nodes):
            for j in range(k):
                out.setdefault((choice, (i * k + j) % len(cells)), []).append(spec)
    return out


def cell_grid(choice: str, cell: Cell) -> tuple[str, ...]:
    """The grade options of one cell: its world, the choice, and the cell's parameters given to the node."""
    params = [word for name, value in cell.params for word in ("--node-param", f"{name}={value:g}")]
    return ("--maneuvers", choice, "--worlds", cell.world, *params)


def cell_name(cell: Cell) -> str:
    """A cell as a class-name part: ``lab_beside_safety_distance_0.7``."""
    return "_".join([cell.world, *(f"{k}_{v:g}" for k, v in cell.params)])


#: The default grid's LiDARs, dealt one per (node, cell): every cell sees every LiDAR, each run one of them.
LIDARS = ("lds01", "lds02", "rplidar")


def classes(count: int, folder: Path, python: str, with_mutants: bool = True) -> dict[str, dict[str, Any]]:
    """Write nodes 0..count-1 (and their mutants) under ``folder``; the classes that grade them: each right node on
    its share of its choice's cells (:func:`deal`) with one LiDAR a cell, dealt round-robin (a class per cell and
    LiDAR); each node's one mutant (:func:`one_mutant`) on the cell where its mistake shows, with the LiDAR it must
    fail with."""
    folder.mkdir(parents=True, exist_ok=True)
    specs = [generate(seed) for seed in range(count)]
    out: dict[str, dict[str, Any]] = {}
    for spec in specs:
        (folder / f"{spec.name}.py").write_text(spec.source)
    for (choice, index), nodes in sorted(deal(specs).items()):
        cell = choice_cells(choice)[index]
        for k, spec in enumerate(nodes):
            lidar = LIDARS[(k + index) % len(LIDARS)]
            group = out.setdefault(f"{RIGHT}_{choice}_{cell_name(cell)}_{lidar}",
                                   {"grid": (*cell_grid(choice, cell), "--lidars", lidar), "students": {}})
            group["students"][spec.name] = f"{python} {folder / (spec.name + '.py')}"
    for spec in specs if with_mutants else []:
        mistake, source, cell, lidar = one_mutant(spec)
        path = folder / f"{spec.name}__{mistake}.py"
        path.write_text(source)
        group = out.setdefault(f"{MUTANTS}_{spec.knobs.choice}_{cell_name(cell)}_{lidar}",
                               {"grid": (*cell_grid(spec.knobs.choice, cell), "--lidars", lidar), "students": {}})
        group["students"][path.stem] = f"{python} {path}"
    return out


#: deg: a B node whose side sectors begin nearer the bow than this reads the hallway's narrowing walls ahead of its
#: flanks: at 0.5 m it fires about where a node reading its flanks fires at 0.7 m, so its ignoring a 0.7 m
#: safety_distance is one of the sheet's reasonable readings there (the judge's "every reading held" late rule).
FLANK_FROM_DEG = 60


def catchable(mistake: str, spec: NodeSpec) -> bool:
    """Whether the grader can tell this node's mutant from a right node at all (not: a B reading ahead of its flanks
    that ignores safety_distance, :data:`FLANK_FROM_DEG`)."""
    knobs = spec.knobs
    if mistake == "hardcoded_indices" and knobs.choice == "B":
        # B reads only its two flanks: on the RPLIDAR (-pi..pi) ranges[90] is its right flank and ranges[270] its
        # left, the same squeeze; on the simulated LDS-02 its beams are near enough 360. Graded at 1x, 13 such
        # mutants passed every run on both (2026-11-28): the sheet's rule shows in the code, not in these runs
        return False
    return not (mistake == "ignores_safety_distance" and knobs.choice == "B"
                and knobs.side_centre - knobs.side_half < FLANK_FROM_DEG)


def one_mutant(spec: NodeSpec) -> tuple[str, str, Cell, str]:
    """The node's one mutant (its choice's mistakes taken in turn by seed), the cell its mistake shows in (the first
    of the choice's cells its expectation names) and the LiDAR it must fail with (any, dealt by seed, unless only
    one shows it)."""
    made = sorted((name, source) for name, source in mutants(spec).items() if catchable(name, spec))
    mistake, source = made[spec.seed // 3 % len(made)]
    cells = EXPECT[mistake][spec.knobs.choice][1]
    cell = next(c for c in choice_cells(spec.knobs.choice) if cells is None or re.search(cells, cell_label(
        {"world": c.world, "maneuver": spec.knobs.choice, "lidar": "", "cell_params": dict(c.params)})))
    lidar = BY_LIDAR[mistake][1] if mistake in BY_LIDAR else LIDARS[spec.seed % len(LIDARS)]
    return mistake, source, cell, lidar


def judged_mutant(student: str, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """A generated mutant's line of the matrix (``gen007_C__angle_45``): it must fail every run in the cells where
    its mistake shows, for its reason (with the LiDAR it reads right, when only some show it: pass there)."""
    # a cell's parameters came as --node-param (the class grades one world): its label names them as the grid's does
    runs = [{"cell": cell_label({**r, "cell_params": r.get("cell_params") or r.get("node_params")}),
             "lidar": r.get("lidar") or "", "seed": r.get("seed"), "passed": bool(r["passed"]), "reason": r["reason"],
             "not_graded": bool(r.get("not_graded"))} for r in rows]
    line = {"student": student, "kind": "mistake", "runs": runs}
    if not runs:
        return {**line, "outcome": "not graded", "wrong": ["no runs"]}
    if all(r["not_graded"] for r in runs):  # a machine too busy for a 1x run, twice: no verdict either way
        return {**line, "outcome": "not graded", "wrong": [f"{r['cell']}: {r['reason']}" for r in runs]}
    name, mistake = student.split("__", 1)
    pattern, cells = EXPECT[mistake][name[-1]]
    good = BY_LIDAR.get(mistake, (None, None))[0]
    wrong, counted = [], 0
    for r in runs:
        if cells is not None and not re.search(cells, r["cell"]):
            continue
        counted += 1
        if r["lidar"] == good and not r["passed"]:
            wrong.append(f"{r['cell']}: failed with the LiDAR it reads right ({r['reason']})")
        elif r["lidar"] != good and (r["passed"] or not re.search(pattern, r["reason"])):
            wrong.append(f"{r['cell']}: {'PASSED' if r['passed'] else r['reason']}")
    if not counted:
        wrong.append(f"no run in the cells it must fail in ({cells})")
    return {**line, "outcome": "wrong" if wrong else "failed for its reason", "wrong": wrong}
