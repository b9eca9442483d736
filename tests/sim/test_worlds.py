"""Every bundled world is a fair test: it loads, the robot fits at its start, it cannot leave, it can move.

The referee grades the executive in worlds we have never seen, so our own worlds must be realistic, and a
world that is broken (spawn wedged, a door narrower than the robot, a hole in the outer wall) would make a
grade meaningless. These checks run on a 4 cm occupancy grid: a cell is free when the robot's disk fits
there (clearance >= its radius, and not inside a solid box); a 4-connected flood fill from the spawn gives
the space the robot can reach. Closed = that space never touches the edge of a grid laid 0.5 m beyond the
world's plotting bounds. Per world, named checkpoints (each room, each aisle, the far end...) must be
reachable through passages at least as wide as the world file promises.
"""

from __future__ import annotations

import math
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from bt_nav_sim import World, list_worlds, load_world
from bt_nav_sim.world import WORLDS_DIR, world_from_dict

from bt_nav.run.settings import DEFAULT_JITTER
from tests.judge.truthkit import truth_judge

ROBOT_RADIUS = 0.12  # TurtleBot3 Burger collision disk
RES = 0.04  # grid resolution, m
GRID_SLACK = RES  # a grid cell can sit this far off a passage's centre line
BORDER = 0.5  # the grid extends this far beyond the world's bounds

# New worlds must not be easy variations of the old ones: these are the ones the issue asks for.
NEW_WORLDS = {"office", "forest", "maze", "hall", "long_corridor", "warehouse"}

# Per world: points that must be reachable from the spawn, and the narrowest passage (m) on the way to
# them that the world file documents (doors, aisles, gaps). Every bundled world must be listed here, so
# adding a world means saying what the robot must be able to get to.
CHECKPOINTS: dict[str, tuple[float, list[tuple[float, float]]]] = {
    "stage_4": (0.7, [(-2.0, 2.0), (2.0, -2.0), (1.9, 1.0), (-1.0, -2.0)]),
    "empty_room": (1.0, [(-1.8, -1.8), (1.8, 1.8)]),
    "corridor": (0.6, [(4.0, 2.0), (0.9, -0.7), (2.7, 0.7)]),  # dead end and both pockets
    "cluttered": (0.35, [(-2.1, -2.1), (2.1, 2.1), (-2.1, 2.1), (2.1, -2.1)]),  # room corners
    # S1 (spawn room), S2, S3, hallway east end, N1, N2 east of the desks, N1|N2 door; 0.8-1.0 m doors but
    # furniture leaves 0.5 m in places (doors: test_office_doors_are_door_sized)
    "office": (0.5, [(2.5, 2.0), (4.0, 2.5), (8.5, 2.0), (9.0, 3.9), (1.0, 6.5), (9.5, 5.0), (5.5, 6.8)]),
    "forest": (0.4, [(-3.7, -2.7), (3.7, 2.7), (-3.7, 2.7), (3.7, -2.7)]),  # fence corners
    "maze": (1.0, []),  # every cell centre, added by _maze_cells()
    "hall": (0.5, [(0.4, 0.4), (9.6, 7.6), (0.4, 7.6), (9.0, 0.8), (5.0, 3.0), (5.0, 7.7)]),
    # both ends of every leg, the far dead end, past both fittings
    "long_corridor": (0.8, [(-0.2, 0.0), (7.0, 0.0), (7.0, 2.5), (2.0, 2.5), (2.0, 4.6), (6.2, 4.6),
                            (3.4, 0.0), (4.5, 2.4)]),
    # the far end of every aisle, both ends of the main lane, between the mid-lane pallet and the wall
    # every corner of the lobby, behind the bench, between the pillars (the people do not block a grid)
    "lobby": (0.7, [(0.4, 0.4), (7.6, 0.4), (0.4, 5.6), (6.8, 5.0), (5.2, 3.0), (3.0, 3.05)]),
    "warehouse": (1.1, [(0.75, 0.4), (3.0, 0.4), (5.1, 0.4), (7.2, 0.4), (9.3, 0.4), (11.4, 1.2),
                        (0.4, 7.6), (11.6, 7.6), (8.0, 7.5)]),
}


def _raw(name: str) -> dict:
    with open(WORLDS_DIR / f"{name}.yaml", encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _generator(name: str) -> dict | None:
    return _raw(name).get("generator")


def _seeds(name: str) -> list[int | None]:
    """The YAML's own seed and, for generated worlds, a few more: a bad draw must not hide."""
    return [None, 0, 1, 2, 5] if _generator(name) else [None]


WORLD_SEEDS = [(name, seed) for name in list_worlds() for seed in _seeds(name)]


class Grid:
    """Free/reachable cells of a world on a regular grid around its bounds."""

    def __init__(self, world: World, radius: float = ROBOT_RADIUS) -> None:
        xmin, ymin, xmax, ymax = world.bounds
        self.xs = np.arange(xmin - BORDER, xmax + BORDER + 1e-9, RES)
        self.ys = np.arange(ymin - BORDER, ymax + BORDER + 1e-9, RES)
        self.px, self.py = np.meshgrid(self.xs, self.ys, indexing="ij")
        self.clear = _clearance(world, self.px, self.py)
        self.free = (self.clear >= radius) & ~_inside_boxes(world, self.px, self.py)
        self.reach = self.flood(self.cell(world.spawn[0], world.spawn[1]))

    def cell(self, x: float, y: float) -> tuple[int, int]:
        return int(round((x - self.xs[0]) / RES)), int(round((y - self.ys[0]) / RES))

    def flood(self, start: tuple[int, int], free: np.ndarray | None = None) -> np.ndarray:
        """4-connected flood fill over ``free`` (default: the robot-sized free cells) from ``start``."""
        free = self.free if free is None else free
        seen = np.zeros_like(free)
        if not free[start]:
            return seen
        seen[start] = True
        todo = deque([start])
        nx, ny = free.shape
        while todo:
            i, j = todo.popleft()
            for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
                if 0 <= a < nx and 0 <= b < ny and free[a, b] and not seen[a, b]:
                    seen[a, b] = True
                    todo.append((a, b))
        return seen


def _clearance(world: World, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """World.clearance over a whole grid at once (one obstacle at a time, vectorised over cells)."""
    best = np.full(px.shape, np.inf)
    for x1, y1, x2, y2 in world.segments:
        dx, dy = x2 - x1, y2 - y1
        len2 = dx * dx + dy * dy
        t = np.clip(((px - x1) * dx + (py - y1) * dy) / len2, 0.0, 1.0) if len2 > 0 else 0.0
        np.minimum(best, np.hypot(px - x1 - t * dx, py - y1 - t * dy), out=best)
    for cx, cy, r in world.circles:
        np.minimum(best, np.hypot(px - cx, py - cy) - r, out=best)
    return best


def _inside_boxes(world: World, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Cells inside a solid box: walls are bare segments, so a thick box's middle has clearance too."""
    inside = np.zeros(px.shape, dtype=bool)
    for bx, by, length, th, yaw in world.boxes:
        along = (px - bx) * math.cos(yaw) + (py - by) * math.sin(yaw)
        across = -(px - bx) * math.sin(yaw) + (py - by) * math.cos(yaw)
        inside |= (np.abs(along) <= length / 2) & (np.abs(across) <= th / 2)
    return inside


def _maze_cells(name: str) -> list[tuple[float, float]]:
    gen = _generator(name) or {}
    x0, y0 = gen.get("origin", [0.0, 0.0])
    cell = float(gen["cell"])
    return [(x0 + (i + 0.5) * cell, y0 + (j + 0.5) * cell) for i in range(gen["cols"]) for j in range(gen["rows"])]


def test_bundled_worlds_include_the_new_ones() -> None:
    names = set(list_worlds())
    assert NEW_WORLDS <= names
    assert len(names) >= 9
    assert set(CHECKPOINTS) == names, "every bundled world needs its checkpoints here"


@pytest.mark.parametrize("name", sorted(NEW_WORLDS))
def test_new_world_files_document_start_pose_and_purpose(name: str) -> None:
    text = (WORLDS_DIR / f"{name}.yaml").read_text(encoding="utf-8")
    header = text.split("\nname:")[0]
    assert "Start pose:" in header and "What it tests:" in header
    assert _raw(name)["name"] == name == Path(WORLDS_DIR / f"{name}.yaml").stem


@pytest.mark.parametrize(("name", "seed"), WORLD_SEEDS)
def test_spawn_has_clearance_even_when_jittered(name: str, seed: int | None) -> None:
    w = load_world(name, seed=seed)
    x, y, _ = w.spawn
    jitter_m = DEFAULT_JITTER[0] * math.sqrt(2)  # lock-step/grade move the spawn up to this far
    assert w.clearance(x, y) - jitter_m > ROBOT_RADIUS + 0.1
    xmin, ymin, xmax, ymax = w.bounds
    assert xmin < x < xmax and ymin < y < ymax


@pytest.mark.parametrize(("name", "seed"), WORLD_SEEDS)
def test_world_is_closed_and_roomy_enough(name: str, seed: int | None) -> None:
    w = load_world(name, seed=seed)
    g = Grid(w)
    assert g.reach.any(), "spawn cell is not free"
    # Closed: the reachable space never gets to the edge of a grid laid 0.5 m beyond the bounds...
    assert not (g.reach[0, :].any() or g.reach[-1, :].any() or g.reach[:, 0].any() or g.reach[:, -1].any())
    # ...nor outside the plotting bounds themselves.
    xmin, ymin, xmax, ymax = w.bounds
    rx, ry = g.px[g.reach], g.py[g.reach]
    assert rx.min() > xmin and rx.max() < xmax and ry.min() > ymin and ry.max() < ymax
    # The mission needs >= 1.5 m from the start: there must be room to get 2 m away, and some area.
    sx, sy, _ = w.spawn
    assert float(np.max(np.hypot(rx - sx, ry - sy))) >= 2.0
    assert g.reach.sum() * RES * RES >= 2.0


@pytest.mark.parametrize(("name", "seed"), WORLD_SEEDS)
def test_checkpoints_reachable_through_documented_passages(name: str, seed: int | None) -> None:
    """Each checkpoint is reachable by the robot, and a disk as wide as the narrowest documented gap gets
    within its own radius of it (a checkpoint may sit closer to a wall than that disk fits).

    Fails if a door, aisle or post gap is narrower than the world file says (or than the robot).
    """
    passage, points = CHECKPOINTS[name]
    points = points + (_maze_cells(name) if name == "maze" else [])
    w = load_world(name, seed=seed)
    g = Grid(w)
    fat_r = max(ROBOT_RADIUS, passage / 2 - GRID_SLACK)
    fat = g.flood(g.cell(*w.spawn[:2]), (g.clear >= fat_r) & g.free)
    fx, fy = g.px[fat], g.py[fat]
    for x, y in points:
        assert w.clearance(x, y) >= ROBOT_RADIUS, f"checkpoint {(x, y)} itself is not free"
        assert g.reach[g.cell(x, y)], f"{name}: {(x, y)} unreachable for the robot"
        near = float(np.min(np.hypot(fx - x, fy - y)))
        assert near <= fat_r + GRID_SLACK, f"{name}: {(x, y)} only reachable through a gap narrower than {passage} m"


@pytest.mark.parametrize(("name", "seed"), [(n, s) for n in ("cluttered", "forest") for s in (None, 0, 1, 7)])
def test_generated_room_has_no_pockets(name: str, seed: int | None) -> None:
    """Every cell of the generator's room where the robot fits is reachable from the spawn: the min_gap
    guarantee (obstacles are disjoint islands once inflated by the robot) holds in the result."""
    gen = _generator(name) or {}
    (w_, h_), (cx, cy) = gen["room"], gen.get("center", [0.0, 0.0])
    g = Grid(load_world(name, seed=seed))
    room = (np.abs(g.px - cx) < w_ / 2) & (np.abs(g.py - cy) < h_ / 2)
    assert np.array_equal(g.reach & room, g.free & room)


def test_office_doors_are_door_sized() -> None:
    """The 0.8-1.0 m doorways: a 1.1 m wide robot could not leave the spawn room, a 0.7 m one can."""
    w = load_world("office")
    g = Grid(w)
    start = g.cell(*w.spawn[:2])
    hallway = g.cell(8.0, 3.75)
    assert g.flood(start, g.clear >= 0.35 - GRID_SLACK / 2)[hallway]
    assert not g.flood(start, g.clear >= 0.55)[hallway]


def test_long_corridor_is_narrow_everywhere() -> None:
    """No place in the corridor is wider than 0.9 m: off the corner squares (clearance up to 0.45 * sqrt 2
    towards the inner corner) every reachable cell is within 0.45 m of a wall."""
    w = load_world("long_corridor")
    g = Grid(w)
    clear = g.clear[g.reach]
    assert float(clear.max()) <= 0.45 * math.sqrt(2)
    assert float(np.mean(clear > 0.45 + 1e-9)) < 0.02
    # ...and the fittings pinch it to 0.8 m (0.4 on the centre line there).
    assert w.clearance(3.4, 0.05) == pytest.approx(0.4)
    assert w.clearance(4.5, 2.45) == pytest.approx(0.4)


def test_hall_is_large_and_open() -> None:
    """At least 60 m^2 of reachable floor, and from the spawn a quarter of the LDS-01 beams see nothing."""
    from bt_nav_sim import LDS01, cast_rays

    w = load_world("hall")
    assert Grid(w).reach.sum() * RES * RES >= 60.0
    scan = cast_rays(w, *w.spawn, LDS01)
    assert np.isinf(scan).mean() > 0.25


# ----- generators: forest and maze -------------------------------------------------------------------


def test_forest_deterministic_per_seed_and_sized_by_density() -> None:
    a, b, c = load_world("forest", seed=3), load_world("forest", seed=3), load_world("forest", seed=4)
    np.testing.assert_array_equal(a.circles, b.circles)
    assert not np.array_equal(a.circles, c.circles)
    np.testing.assert_array_equal(load_world("forest").circles, load_world("forest", seed=11).circles)
    gen = _generator("forest")
    assert len(a.circles) == round(gen["density"] * gen["room"][0] * gen["room"][1])
    assert len(a.boxes) == 4  # the fence only: a forest has no boxes


@pytest.mark.parametrize("seed", range(6))
def test_forest_posts_keep_gaps(seed: int) -> None:
    w = load_world("forest", seed=seed)
    c = w.circles
    assert np.all((c[:, 2] >= 0.05) & (c[:, 2] <= 0.15))
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1]) - c[:, None, 2] - c[None, :, 2]
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 0.4 - 1e-9  # min_gap between posts
    assert np.all(np.abs(c[:, 0]) + c[:, 2] + 0.4 <= 4.0 + 1e-9)  # ... and to the fence
    assert np.all(np.abs(c[:, 1]) + c[:, 2] + 0.4 <= 3.0 + 1e-9)
    assert np.min(np.hypot(c[:, 0], c[:, 1]) - c[:, 2]) >= 0.5  # keep_clear around the spawn


def test_forest_count_overrides_density() -> None:
    d = {"name": "f", "generator": {"kind": "forest", "room": [3, 3], "count": 4, "density": 9, "seed": 1}}
    w = world_from_dict(d)
    assert len(w.circles) == 4 and not w.boxes
    with pytest.raises(ValueError, match="density"):
        world_from_dict({"name": "f", "generator": {"kind": "forest", "density": -1}})


def _maze(seed: int, loops: float = 0.0, cols: int = 7, rows: int = 6) -> World:
    gen = {"kind": "maze", "cols": cols, "rows": rows, "cell": 1.1, "wall": 0.1, "loops": loops, "seed": seed}
    return world_from_dict({"name": "m", "spawn": {"x": 0.55, "y": 0.55}, "generator": gen})


@pytest.mark.parametrize("seed", range(4))
def test_maze_is_a_perfect_maze_with_dead_ends(seed: int) -> None:
    """loops 0: a spanning tree of the cells, so walls = inner edges - (cells - 1), and it has dead ends."""
    cols, rows = 7, 6
    w = _maze(seed)
    inner_edges = (cols - 1) * rows + cols * (rows - 1)
    assert len(w.boxes) == inner_edges - (cols * rows - 1) + 4  # + the 4 outer walls
    # A cell is a dead end when 3 of its 4 sides are walls: probe just inside each side.
    dead_ends = 0
    for i in range(cols):
        for j in range(rows):
            x, y = 0.55 + 1.1 * i, 0.55 + 1.1 * j
            sides = [w.clearance(x + dx, y + dy) < 0.1 for dx, dy in ((0.5, 0), (-0.5, 0), (0, 0.5), (0, -0.5))]
            dead_ends += sum(sides) == 3
            assert w.clearance(x, y) == pytest.approx(0.5)  # corridors 1.0 m wide whatever the seed
    assert dead_ends >= 3


def test_maze_loops_remove_walls_and_seeds_differ() -> None:
    assert len(_maze(1, loops=0.5).boxes) < len(_maze(1).boxes)
    a, b = _maze(1), _maze(2)
    assert not np.array_equal(a.segments, b.segments)
    np.testing.assert_array_equal(_maze(1).segments, a.segments)
    with pytest.raises(ValueError, match="wall < cell"):
        world_from_dict({"name": "m", "generator": {"kind": "maze", "cell": 0.5, "wall": 0.6}})
    with pytest.raises(ValueError, match="known: cluttered, forest, maze"):
        world_from_dict({"name": "m", "generator": {"kind": "volcano"}})


# ---------------------------------------------------------------------------------------------- lab arenas
# The lab's check-off arenas (lab_*) are small on purpose: list_worlds() leaves them out of the homework's
# worlds (and so out of the feasibility checks above: >= 2 m from the start, the checkpoints); here they
# get the generic checks (documented, spawn clear even jittered, closed) and their own: what each header
# promises to check off lies straight ahead within 1.5 m of creeping.
LAB_WORLDS = list_worlds("lab")
#: Arenas that start the robot beside a wall on purpose (a side reading < 0.3 m at the arming), and the clearance
#: they keep from it at the worst spawn jitter instead of 0.1 m.
NEAR_START = {"lab_beside": 0.03}


def test_lab_arenas_are_listed_apart() -> None:
    assert set(LAB_WORLDS) == {"lab_object", "lab_dead_end", "lab_narrow_gap", "lab_cluttered", "lab_appearing",
                               "lab_passerby", "lab_side", "lab_beside", "lab_hallway", "lab_slant"}
    assert not set(LAB_WORLDS) & set(list_worlds())
    assert sorted(list_worlds() + LAB_WORLDS) == list_worlds("all")


@pytest.mark.parametrize("name", LAB_WORLDS)
def test_lab_arena_is_documented_closed_and_clear(name: str) -> None:
    text = (WORLDS_DIR / f"{name}.yaml").read_text(encoding="utf-8")
    header = text.split("\nname:")[0]
    assert "Start pose:" in header and "What it tests:" in header
    w = load_world(name)
    # every object counts for the spawn, appearing ones too (they must never appear on the robot)
    full = world_from_dict({**_raw(name), "boxes": [{k: v for k, v in b.items() if k != "appear_within"}
                                                     for b in _raw(name).get("boxes", [])]})
    x, y, _ = w.spawn
    margin = NEAR_START.get(name, 0.1)
    assert full.clearance(x, y) - DEFAULT_JITTER[0] * math.sqrt(2) > ROBOT_RADIUS + margin
    g = Grid(w)
    assert g.reach.any()
    assert not (g.reach[0, :].any() or g.reach[-1, :].any() or g.reach[:, 0].any() or g.reach[:, -1].any())
    xmin, ymin, xmax, ymax = w.bounds
    assert 3.0 <= xmax - xmin <= 5.5 and 3.0 <= ymax - ymin <= 5.5


def _creep(name: str) -> dict[str, float]:
    """Creep straight ahead from the spawn at 0.05 m/s (noise-free) and note, per maneuver, the distance
    crept when its trigger first holds on noise-free ground truth, read over the sectors the arenas' headers
    describe (front +-30 deg, sides 90 +-30 deg: one member of the judge's family of readings)."""
    from bt_nav_sim.core import SimConfig, SimCore

    from bt_nav.judge.checkoff_core import CheckoffConfig

    core = SimCore(SimConfig(world=name, noise=False, profile="lab"))
    classic = CheckoffConfig(front_min_half_deg=30.0, side_centre_min_deg=90.0, side_centre_max_deg=90.0,
                             side_min_half_deg=30.0)
    judge = truth_judge(classic, core.world, update_world=False)
    x0, y0 = core.state.x, core.state.y
    first: dict[str, float] = {}
    while core.collisions == 0 and core.t < 40.0:
        core.advance(0.05, 0.0, 10)
        s = core.state
        r = judge.readings.read(s.x, s.y, s.yaw)
        crept = math.hypot(s.x - x0, s.y - y0)
        for key, held in (("A", r.front < 0.5), ("B", r.left < 0.5 and r.right < 0.5), ("C", r.front < 0.3)):
            first.setdefault(key, crept) if held else None
    return first


@pytest.mark.parametrize("name", LAB_WORLDS)
def test_lab_arena_triggers_what_it_checks_off_within_reach(name: str) -> None:
    w = load_world(name)
    assert w.checkoff_maneuvers, "a lab arena lists the maneuvers it can check off"
    first = _creep(name)
    for maneuver in w.checkoff_maneuvers:
        assert first.get(maneuver, math.inf) <= 1.5, f"{name}: {maneuver}'s trigger not reached ({first})"
    if "B" not in w.checkoff_maneuvers:
        assert "B" not in first  # the header says B cannot be checked off: nothing squeezes both sides


def _reading_at_spawn(name: str, dx: float, dy: float, dyaw: float) -> Any:
    """The check-off judge's readings at the spawn moved by (dx, dy, dyaw deg)."""
    from bt_nav.judge.checkoff_core import CheckoffConfig

    w = load_world(name)
    x, y, yaw = w.spawn
    judge = truth_judge(CheckoffConfig(), w, update_world=False)
    return judge.readings.read(x + dx, y + dy, yaw + math.radians(dyaw))


@pytest.mark.parametrize(("name", "side", "b_graded"), [("lab_beside", 0.3, False), ("lab_hallway", 0.5, True)])
def test_the_wall_beside_the_start_is_near_one_side_and_no_front_sees_it(name: str, side: float,
                                                                         b_graded: bool) -> None:
    """At every corner of the spawn jitter: the left within ``side`` (C's 0.3 m, B's 0.5 m) and the widest front
    beyond 0.75 m (A's safety_distance 0.7 and its margin), and where B is graded the right beyond 0.75 m too, so a
    node that fires on a side or the whole scan there is judged "its trigger did not hold" at either distance."""
    m, deg = DEFAULT_JITTER
    for dx in (-m, m):
        for dy in (-m, m):
            for dyaw in (-deg, deg):
                r = _reading_at_spawn(name, dx, dy, dyaw)
                assert r.left_abeam < side and r.front > 0.75, (dx, dy, dyaw, r)
                assert r.right > 0.75 or not b_graded, (dx, dy, dyaw, r)
