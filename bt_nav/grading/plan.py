"""A grid's plan from the grading options: worlds, seeds, maneuvers and LiDARs, with the defaults each kind of
grid gets (bt_nav's tree in lock-step; any node over DDS, one or a class of them).

Why the defaults differ: a lock-step mission costs a fraction of a second, so bt_nav's own grids cover every world
and 20 seeds; a node over DDS costs ~17 s of wall time, so its default grid is what a class can afford (the
profile's representative worlds, the node's own maneuver, 2 seeds) and varies the LiDAR, which is what catches a
node reading the scan by fixed indices.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from bt_nav_sim.world import list_worlds, load_world, world_file

from bt_nav.grading.exe.grid import declared_choice, node_file
from bt_nav.grading.grid import Job, checkoff_jobs, make_jobs, parse_lidars
from bt_nav.mission.assignments import ASSIGNMENTS, Cell, Grid, assignment_of
from bt_nav.mission.maneuver_spec import letters_text
from bt_nav.mission.params import normalise_maneuver, parse_assignments
from bt_nav.run.settings import DEFAULT_JITTER

#: The LiDARs an ``--exe`` grid varies by default: the LDS-01 (0..2pi, 360 beams), the LDS-02 (a different beam
#: count every scan) and the RPLIDAR (-pi..pi): fixed indices are right for at most the first.
EXE_LIDARS = ("lds01", "lds02", "rplidar")
#: The ``--exe`` grid's default worlds, per assignment (:attr:`bt_nav.mission.assignments.Assignment.exe_grid`).
EXE_WORLDS = {name: a.exe_grid.worlds for name, a in ASSIGNMENTS.items()}


def check_worlds(worlds: Sequence[str]) -> None:
    """Refuse a world that is neither bundled nor a world file before any run starts: a typo would otherwise cost
    every run of the grid a simulator that refuses to start. ValueError names the bundled worlds."""
    for world in worlds:
        try:
            world_file(world)
        except FileNotFoundError as exc:
            raise ValueError(str(exc)) from None


def grid_axes(args: argparse.Namespace) -> tuple[list[str], list[int]]:
    """The grid's worlds and seeds (defaults: a lock-step grid all the profile's 20 seeds; a node over DDS, the
    profile's representative worlds and 2 seeds, a size a class can afford). ValueError: an unknown world."""
    assignment = assignment_of(args.profile)
    grid = assignment.exe_grid if args.exe is not None or getattr(args, "klass", None) is not None else assignment.grid
    worlds = [w.strip() for w in (args.worlds or grid.worlds).split(",") if w.strip()]
    if worlds == ["all"]:
        worlds = list_worlds(assignment.world_kind)
    check_worlds(worlds)
    count = args.seeds if args.seeds is not None else grid.seeds
    return worlds, list(range(args.first_seed, args.first_seed + count))


def grid_maneuvers(args: argparse.Namespace, lab: bool) -> str:
    """The grid's maneuvers: ``--maneuvers``; else for a node of one's own (``--exe``) in the lab the one its file
    declares as the lab's template asks (``# CHOICE: X``), else for the homework none; for bt_nav's tree all.

    Raises:
        ValueError: a lab ``--exe`` grid without ``--maneuvers`` whose command names no file with a choice.
    """
    if args.maneuvers:
        return args.maneuvers
    if args.exe is None:
        return ",".join(ASSIGNMENTS["lab" if lab else "homework"].maneuvers)
    if not lab:
        return "none"  # a foreign homework node has no maneuvers of bt_nav's
    return lab_maneuver(args.exe, None, "--maneuvers")[0]


def no_choice(option: str) -> str:
    """What a lab node that declares no maneuver is told (``grade`` and ``demo`` alike; ``option`` is theirs)."""
    return (f"which maneuver does the node perform? give {option} {letters_text()} (or write the lab template's "
            "'# CHOICE: X' comment in the node's file)")


def lab_maneuver(command: str, given: str | None, option: str) -> tuple[str, str]:
    """The maneuver(s) a lab node is run on: ``given`` (the command line's ``option``) when there is one, else the
    ``# CHOICE: X`` its file declares (:func:`~bt_nav.grading.exe.grid.declared_choice`), and a line to say when
    the two differ (empty when they agree or the file declares none): a node is judged on one maneuver, so the
    one that wins must be said.

    Raises:
        ValueError: neither ``given`` nor a declared choice (:func:`no_choice`), or an unknown maneuver.
    """
    declared = declared_choice(command)
    if not given:
        if declared is None:
            raise ValueError(no_choice(option))
        return declared, ""
    wanted = [normalise_maneuver(m.strip()) for m in given.split(",") if m.strip()]
    if declared is None or declared in wanted:
        return given, ""
    return given, f"{option} {given} wins over the '# CHOICE: {declared}' in {node_file(command)}"


def default_cells(args: argparse.Namespace) -> Grid | None:
    """The assignment's default ``--exe`` grid when it is made of cells (:class:`~bt_nav.mission.assignments.Cell`)
    and the options leave the worlds to it (no ``--worlds``), else None: the plain product of worlds and maneuvers."""
    if args.worlds or (args.exe is None and getattr(args, "klass", None) is None):
        return None
    grid = assignment_of(args.profile).exe_grid
    return grid if grid.cells else None


def checked_cells(grid: Grid, maneuver: str) -> list[Cell]:
    """The cells of ``grid`` that grade ``maneuver`` (:meth:`~bt_nav.mission.assignments.Grid.cells_of`), kept
    where the arena can check it off (its ``checkoff_maneuvers``): what a grade runs and the rules page lists."""
    return [cell for cell in grid.cells_of(maneuver) if maneuver in load_world(cell.world).checkoff_maneuvers]


def build_jobs(args: argparse.Namespace, worlds: Sequence[str], seeds: Sequence[int],
               left_out: set[str] | None = None) -> list[Job]:
    """The grid of the options: worlds x maneuvers x LiDARs x seeds (the lab's arenas only where they can check
    the maneuver off; says on stderr which pairs it leaves out, or adds them to ``left_out``, for a class to say
    once). ValueError: options that do not fit."""
    lab, exe = args.profile == "lab", args.exe is not None
    maneuvers = [normalise_maneuver(m.strip()) for m in grid_maneuvers(args, lab).split(",") if m.strip()]
    lidars = parse_lidars(args.lidars if args.lidars is not None else ",".join(EXE_LIDARS) if exe else None)
    sim_params = parse_assignments(args.sim_param) or None
    if sim_params and "lidar" in sim_params and len(lidars) > 1:
        raise ValueError("--sim-param lidar=... and --lidars with several LiDARs: choose one way")
    options = (parse_assignments(args.overrides) or None, args.profile, None if args.no_jitter else DEFAULT_JITTER,
               args.kinematics, sim_params, lidars)
    cells = default_cells(args)
    if cells is None:
        jobs = make_jobs(worlds, maneuvers, seeds, *options)
    else:  # the default grid's cells: each choice where its mistakes show
        given = set(parse_assignments(getattr(args, "node_param", None) or []))
        jobs = list(dict.fromkeys(job for m in maneuvers for cell in checked_cells(cells, m)
                                  for job in make_jobs([cell.world], [m], seeds, *options,
                                                       tuple((k, v) for k, v in cell.params if k not in given))))
    if not lab:
        return jobs
    kept, skipped = checkoff_jobs(jobs)
    if skipped and left_out is not None:
        left_out.update(f"{w} {m}" for w, m in skipped)
    elif skipped:
        print("not checked off there: " + ", ".join(f"{w} {m}" for w, m in skipped), file=sys.stderr)
    return kept
