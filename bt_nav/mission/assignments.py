"""The course's two assignments, each one record: the homework (reactive driving, judged by the referee) and the
lab (a maneuver, checked off by the check-off judge); and the profiles that run them (``--profile``).

Why one record: an assignment used to be four tables keyed by the same names (the params files, the simulated
robot, the service remaps of a graded node, the judge of a run), and a judge's defaults repeated the parameter
table's. Here each fact is written once and every consumer reads it: the params files
(:mod:`bt_nav.mission.profiles`), the simulated robot (:data:`bt_nav_sim.core.PROFILES`), the node graphs and the
remaps of a graded node (:mod:`bt_nav.ros.bringup`, :mod:`bt_nav.grading.exe.run`), which judge a run gets
(:mod:`bt_nav.run.lockstep`), the grids' defaults (:mod:`bt_nav.grading.plan`). The distances a judge judges the
robot by are the executive's parameters: their defaults are :data:`bt_nav.mission.params.SPECS`', never copies.

A *profile* is an assignment on a robot: ``homework`` and ``lab`` on the course's simulated robots, ``turtlebot3``
the homework on a real (or Gazebo) TurtleBot3 Burger.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from bt_nav.mission.maneuver_spec import maneuver_spec
from bt_nav.mission.params import LAB_MANEUVERS, MANEUVERS, SPECS


@dataclass(frozen=True)
class Judge:
    """Who judges an assignment's run, and what of the executive's it judges by."""

    executable: str  # its console script and ``bt-nav`` command: referee | checkoff
    node_name: str  # its ROS node name
    #: the executive parameters the judge reads the robot's triggers by; its defaults are the table's
    shared: tuple[str, ...] = ()
    #: those of :attr:`shared` a TA's launch file gives a robot node and its judge alike (``--node-param``)
    launch_shared: tuple[str, ...] = ()

    def defaults(self) -> dict[str, Any]:
        """The judge's values of :attr:`shared` when the robot's are not given: the parameter table's defaults."""
        return {name: SPECS[name].default for name in self.shared}

    def given(self, parameters: Mapping[str, Any], names: tuple[str, ...] | None = None) -> dict[str, float]:
        """The ``names`` (default :attr:`shared`) among ``parameters`` (what the robot was given), as the judge
        takes them: the trigger the robot was given is the one it is judged by."""
        return {name: float(parameters[name]) for name in (self.shared if names is None else names)
                if name in parameters}


@dataclass(frozen=True)
class Cell:
    """One cell of a default grid: a world and the parameters the graded node is started with there
    (``-p NAME:=VALUE``; its judge is given the same). A cell with parameters grades the maneuvers whose trigger
    distance is one of them (it proves the node applies it) in place of the world's plain cell; the plain cell grades
    the world's other maneuvers. Which maneuvers a world checks off at all is its own (``checkoff_maneuvers``)."""

    world: str
    params: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class Grid:
    """A grid's default axes (``bt-nav grade`` without ``--worlds``/``--seeds``)."""

    worlds: str  # comma-separated world names, or ``all`` (the assignment's bundled worlds)
    seeds: int
    #: when given, the default grid is these cells (their worlds are :attr:`worlds`), each choice graded where its
    #: mistakes show; ``--worlds`` replaces them by the plain product of worlds and maneuvers
    cells: tuple[Cell, ...] = ()

    def cells_of(self, maneuver: str) -> list[Cell]:
        """The cells that grade ``maneuver``: per world, the cells whose parameters hold its trigger distance, else
        the world's plain cell (see :class:`Cell`)."""
        distance = maneuver_spec(maneuver).trigger.distance
        out = []
        for world in dict.fromkeys(cell.world for cell in self.cells):
            own = [c for c in self.cells if c.world == world]
            out += [c for c in own if distance in dict(c.params)] or [c for c in own if not c.params]
        return out


@dataclass(frozen=True)
class Assignment:
    """One assignment (see the module docstring)."""

    name: str
    files: tuple[str, ...]  # params files under config/, applied in order
    arm_service: str  # the name bt_nav's ``arm`` service is served under (SetBool)
    evaluate_service: str | None  # the name bt_nav's ``evaluate_mission`` client calls (Trigger); None: none
    judge: Judge
    graph: str  # the node graph with its judge (bt_nav.ros.bringup): eval | checkoff
    world_kind: str  # which bundled worlds are the assignment's (bt_nav_sim.world.list_worlds)
    maneuvers: tuple[str, ...]  # the maneuvers a grid of bt_nav's tree covers
    grid: Grid  # bt_nav's tree in lock-step
    exe_grid: Grid  # a node of one's own over DDS (bt-nav grade --exe, --class)

    def remaps(self, namespace: bool = False, absolute: bool = False) -> tuple[tuple[str, str], ...]:
        """bt_nav's own service names (``arm``, ``evaluate_mission``) onto the assignment's: as the assignment
        writes them; ``namespace``: relative (inside a robot's namespace they are the namespace's); ``absolute``:
        every one from the root (a graded node's: whatever namespace it runs in, the judge calls the root's)."""
        pairs = [("arm", self.arm_service)]
        if self.evaluate_service is not None:
            pairs.append(("evaluate_mission", self.evaluate_service))
        if absolute:
            return tuple((src, "/" + dst.lstrip("/")) for src, dst in pairs)
        return tuple((src, dst.lstrip("/") if namespace else dst) for src, dst in pairs)


@dataclass(frozen=True)
class Profile:
    """An assignment on a robot: its params files and the simulated robot (LiDAR, kinematics)."""

    name: str
    assignment: Assignment
    files: tuple[str, ...]  # params files under config/, applied in order (later files win)
    lidar: str  # the simulator's profile LiDAR (bt_nav_sim.core.PROFILE_LIDARS)
    kinematics: str  # ideal | burger
    description: str


HOMEWORK = Assignment(
    name="homework", files=("homework.yaml",),
    arm_service="/reactive_control/activate", evaluate_service="/reactive_control/evaluate_mission",
    judge=Judge("referee", "bt_nav_referee"), graph="eval", world_kind="homework", maneuvers=MANEUVERS,
    grid=Grid("stage_4", 20), exe_grid=Grid("stage_4", 2))
LAB = Assignment(
    name="lab", files=("lab.yaml",), arm_service="toggle_navigation", evaluate_service=None,
    judge=Judge("checkoff", "bt_nav_checkoff", ("safety_distance", "pivot_distance"), ("safety_distance",)),
    graph="checkoff", world_kind="lab", maneuvers=LAB_MANEUVERS, grid=Grid("all", 20),
    # A node over DDS: per choice two cells (A, C: three) x 3 LiDARs x 2 seeds = 12 (18) runs, each choice where its
    # mistakes show. lab_dead_end checks all three off at the sheet's 0.5 m. lab_beside starts the robot beside a
    # wall 0.23 m to its left that no front sector sees: a whole-scan or side reading taken for "front" fires there
    # (A, C); A is graded there with safety_distance 0.7 (the check-off's `ros2 param list` step: the parameter
    # applied), where a node that keeps 0.5 m turns 0.2 m late. lab_hallway starts B beside a wall on its left only
    # (left OR right fires) and narrows evenly, with safety_distance 0.7: a node that keeps 0.5 m turns late.
    # lab_slant is C's clearer side where every reasonable reading of the sides agrees (lab_beside's box corners fall
    # in a 30-150 deg side sector, where either side passes since issue 52): a node turning toward the closer side
    # fails there. lab_object is the check-off itself (a static object ahead in an open room), A's at the sheet's
    # 0.5 m (the parameter given: only a choice triggering on safety_distance is graded there): a Randomizer that
    # spins until its front clears turns 40-60 deg there, while in lab_dead_end and lab_beside "clear" comes at
    # 130-150 deg, within A's 90-180, and at 1x it passed every run of A's other cells.
    exe_grid=Grid("lab_beside,lab_dead_end,lab_hallway,lab_slant,lab_object", 2, cells=(
        Cell("lab_beside"), Cell("lab_beside", (("safety_distance", 0.7),)), Cell("lab_dead_end"),
        Cell("lab_hallway", (("safety_distance", 0.7),)), Cell("lab_slant"),
        Cell("lab_object", (("safety_distance", 0.5),)))))

#: The assignments, by name.
ASSIGNMENTS: dict[str, Assignment] = {a.name: a for a in (HOMEWORK, LAB)}

#: The profiles (``--profile``), by name.
PROFILES: dict[str, Profile] = {p.name: p for p in (
    Profile("homework", HOMEWORK, HOMEWORK.files, "homework", "ideal",
            "the course homework's simulator: 360-beam LiDAR to 10 m at 10 Hz, ideal unicycle"),
    Profile("lab", LAB, LAB.files, "lds01", "ideal", "the lab's LDS-01 LiDAR (3.5 m, 5 Hz), ideal unicycle"),
    Profile("turtlebot3", HOMEWORK, (*HOMEWORK.files, "turtlebot3.yaml"), "lds01", "burger",
            "a real TurtleBot3 Burger: LDS-01 LiDAR (3.5 m, 5 Hz), per-wheel speed limits"),
)}


def profile_spec(name: str) -> Profile:
    """The profile called ``name`` (ValueError listing the choices otherwise)."""
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILES)}") from None


def assignment_of(profile: str) -> Assignment:
    """The assignment a profile runs (ValueError for an unknown profile)."""
    return profile_spec(profile).assignment
