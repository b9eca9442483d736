"""Several robots in lock-step: one :class:`MultiSimCore`, one mission tree and one referee per robot.

Each robot is a :class:`bt_nav.cli.lockstep.LockstepMission` driving its own robot of the shared
:class:`bt_nav_sim.multi.MultiSimCore` (so the delivery order per instant, the tick and the referee steps
are the single-robot runner's), and the shared clock is stepped here: at each instant every robot gets its
outputs, then every referee steps, then every tree ticks, then all robots move one physics step under their
own commands. The robots see each other in their scans and a contact between two counts for both.

py_trees' blackboard is one per process (its storage lives on the ``Blackboard`` class), so each robot's
tree gets a blackboard of its own (:class:`Boards`), switched in before anything touches that robot's tree.

Each robot has its own referee (its own arming, 50 s, evaluation call and verdict); the run ends when every
referee has reported. Robot ``i`` > 0 gets maneuver A's random seed ``seed + i * ROBOT_SEED_STRIDE`` so two robots do
not make the same random choices.

With ``bag`` (``bt-nav lockstep --robots N --bag DIR [--video FILE.mp4]``) the run is one rosbag2 bag: each
robot writes through its own :meth:`bt_nav.media.bag.MissionBag.robot` sink (its topics under its namespace,
as the namespaced executives publish them over DDS) and the shared clock is written once per instant.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_nav_sim.core import SimConfig
from bt_nav_sim.multi import ROBOT_SEED_STRIDE, MultiSimCore, robot_names
from bt_nav_sim.plot import plot_robots
from bt_nav_sim.referee_core import RefereeConfig
from bt_nav_sim.world import World, load_world

from bt_nav.cli.lockstep import DEFAULT_JITTER, HARD_STOP, LockstepMission, MissionResult

if TYPE_CHECKING:
    import argparse

    from bt_nav.media.bag import MissionBag


@dataclass
class MultiResult:
    """Every robot's :class:`MissionResult`, by name, and the run's wall time."""

    names: list[str]
    results: list[MissionResult]
    wall_time: float

    @property
    def passed(self) -> bool:
        """Every robot passed."""
        return all(r.passed for r in self.results)

    def summary_line(self) -> str:
        """One line for all robots: ``summary: 2/2 robots PASSED (robot1 PASSED, robot2 PASSED)``."""
        good = sum(r.passed for r in self.results)
        each = ", ".join(f"{n} {'PASSED' if r.passed else 'FAILED'}" for n, r in zip(self.names, self.results,
                                                                                       strict=True))
        return f"summary: {good}/{len(self.results)} robots {'PASSED' if self.passed else 'FAILED'} ({each})"

    def report_lines(self) -> list[str]:
        """Each robot's verdict lines prefixed with its name, then the summary line."""
        lines = [f"{n}: {line}" for n, r in zip(self.names, self.results, strict=True) for line in r.report_lines]
        return [*lines, self.summary_line()]

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """JSON-able: per robot its :meth:`MissionResult.to_dict`, and the overall verdict."""
        return {"passed": self.passed, "summary": self.summary_line(), "wall_time": round(self.wall_time, 4),
                "robots": {n: r.to_dict(trajectory) for n, r in zip(self.names, self.results, strict=True)}}

    def plot(self, path: str | Path, title: str | None = None) -> Path:
        """Both (all) paths in one picture, each robot in its colour."""
        world = self.results[0].world_model
        runs = [(n, r.trajectory, r.results) for n, r in zip(self.names, self.results, strict=True)]
        return plot_robots(world, runs, path, title=title)


class Boards:
    """One py_trees blackboard per robot in one process: the contents of the ``Blackboard`` class's dicts,
    swapped in and out (the dict objects stay, as the leaves hold a reference to the storage dict).

    Why: :class:`bt_nav.mission.core.MissionCore` keeps its state on the process-wide blackboard (and
    clears it when created), so two trees in one process would read each other's scans and arming.
    """

    _FIELDS = ("storage", "metadata", "clients")

    def __init__(self) -> None:
        from py_trees.blackboard import Blackboard

        self._dicts = {name: getattr(Blackboard, name) for name in self._FIELDS}
        self._saved = {name: dict(d) for name, d in self._dicts.items()}  # the process's own, restored at the end
        self._slots: list[dict[str, dict]] = []
        self._current = -1

    def add(self) -> int:
        """A fresh, empty blackboard, made current; returns its index."""
        self._slots.append({name: {} for name in self._FIELDS})
        self._switch(len(self._slots) - 1)
        return self._current

    def _switch(self, index: int) -> None:
        if index == self._current:
            return
        for name, live in self._dicts.items():
            if self._current >= 0:
                self._slots[self._current][name] = dict(live)
            live.clear()
            live.update(self._slots[index][name])
        self._current = index

    @contextmanager
    def use(self, index: int) -> Iterator[None]:
        """Robot ``index``'s blackboard while the block runs."""
        self._switch(index)
        yield

    def restore(self) -> None:
        """The process's own blackboard again."""
        for name, live in self._dicts.items():
            live.clear()
            live.update(self._saved[name])
        self._current = -1


def run_multi_mission(world: str | World = "stage_4", maneuver: str = "none", seed: int = 0, robots: int = 2,
                      overrides: dict[str, Any] | None = None, profile: str = "homework", *,
                      names: tuple[str, ...] = (), starts: tuple[tuple[float, float, float], ...] = (),
                      kinematics: str = "", noise: bool = True,
                      jitter: tuple[float, float] | None = DEFAULT_JITTER,
                      referee_config: RefereeConfig | None = None, duration: float | None = None,
                      bag: MissionBag | None = None) -> MultiResult:
    """``robots`` homework missions in one world in lock-step; deterministic per arguments.

    ``bag``: write every robot's messages into it, each under its namespace (see the module docstring).
    """
    started = time.perf_counter()
    world_obj = world if isinstance(world, World) else load_world(world, seed=int(seed))
    jitter_m, jitter_deg = jitter or (0.0, 0.0)
    config = SimConfig(world=world_obj.name, profile=profile, seed=int(seed), noise=noise, kinematics=kinematics,
                       spawn_jitter_m=jitter_m, spawn_jitter_deg=jitter_deg)
    multi = MultiSimCore(config, robots, names, starts, world=world_obj)
    boards = Boards()
    try:
        missions = []
        for i, core in enumerate(multi.cores):
            boards.add()
            robot_overrides = {"random_seed": (int(seed) + i * ROBOT_SEED_STRIDE) % 2**31, **(overrides or {})}
            sink = bag.robot(multi.names[i]) if bag is not None else None
            missions.append(LockstepMission(world_obj, maneuver, seed, robot_overrides, profile,
                                            kinematics=kinematics, noise=noise, jitter=jitter,
                                            referee_config=referee_config, sim=core, sink=sink))
        _run(multi, missions, boards, duration, bag)
        wall = time.perf_counter() - started
        results = []
        for i, mission in enumerate(missions):
            with boards.use(i):
                results.append(mission.result(wall))
    finally:
        boards.restore()
    return MultiResult(multi.names, results, wall)


def _run(multi: MultiSimCore, missions: list[LockstepMission], boards: Boards, duration: float | None,
         bag: MissionBag | None = None) -> None:
    """Step the shared clock until every referee reported (or ``duration``); see the module docstring.

    ``bag`` gets /clock once per instant, after every robot's messages of that instant (as a robot's
    own sink writes it after its messages when it runs alone).
    """
    end_ns = round((duration if duration is not None else HARD_STOP) * 1e9)
    tick_ns, referee_ns = missions[0].tick_ns, missions[0].referee_ns
    next_tick = next_referee = 0
    for mission in missions:
        mission.referee.start(0.0)
    outs = multi.outputs()
    while multi.t_ns <= end_ns:
        referee_due, tick_due = multi.t_ns >= next_referee, multi.t_ns >= next_tick
        next_referee += referee_ns if referee_due else 0
        next_tick += tick_ns if tick_due else 0
        for i, (mission, out) in enumerate(zip(missions, outs, strict=True)):
            with boards.use(i):  # this robot's instant, in the single-robot runner's order
                mission.clock.now = multi.t
                mission.deliver(out)
                if referee_due:
                    mission.referee_step()
                if tick_due:
                    mission.tick()
        if bag is not None:
            bag.clock(multi.t)
        if referee_due and duration is None and all(m.referee.done for m in missions):
            break
        outs = multi.advance([(m.command.linear, m.command.angular) for m in missions])


def print_multi(result: MultiResult, plot: str | None, json_path: str | None) -> int:
    """``bt-nav lockstep --robots N``'s output: every robot's verdict, the summary, the files; exit code."""
    import json

    for line in result.report_lines():
        print(line)
    for name, r in zip(result.names, result.results, strict=True):
        print(f"{name}: {r.world}, maneuver {r.maneuver}, seed {r.seed}: {'PASSED' if r.passed else 'FAILED'}; "
              f"travelled {r.travelled:.2f} m, {r.collisions} collisions, {r.maneuvers} maneuvers")
    print(f"{len(result.names)} robots, {result.results[0].sim_time:.1f} s simulated in {result.wall_time:.3f} s")
    if plot:
        r0 = result.results[0]
        result.plot(plot, title=f"{r0.world}, maneuver {r0.maneuver}, seed {r0.seed}, {len(result.names)} robots")
        print(f"picture: {plot}")
    if json_path:
        path = Path(json_path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result.to_dict(trajectory=True), indent=1))
        print(f"results: {json_path}")
    return 0 if result.passed else 1


def main_multi(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``bt-nav lockstep --robots N [--bag DIR] [--video FILE.mp4]``: the run, its bag and its film; exit code.

    As with one robot, ``--video`` without ``--bag`` writes the bag next to the video (``FILE_bag``): the
    film is always made from a bag, so what it shows is what ``ros2 bag play`` would replay.
    """
    from bt_nav.cli.lockstep import _film, parse_assignments
    from bt_nav.media.bag import BagError, MissionBag

    if args.trace:
        parser.error("--trace records one robot: not with --robots > 1 (--bag records them all)")
    bag_dir = args.bag or (str(Path(args.video).with_suffix("")) + "_bag" if args.video else None)
    kwargs: dict[str, Any] = {"jitter": None if args.no_jitter else DEFAULT_JITTER, "kinematics": args.kinematics,
                              "noise": not args.no_noise, "duration": args.duration}
    try:
        info = {"world": args.world, "maneuver": args.maneuver, "seed": args.seed, "profile": args.profile,
                "robots": robot_names(args.robots)}
        bag = MissionBag(bag_dir, mission=info) if bag_dir else None
        with bag if bag is not None else nullcontext():
            result = run_multi_mission(args.world, args.maneuver, args.seed, args.robots,
                                       parse_assignments(args.overrides), args.profile, bag=bag, **kwargs)
            for name, r in zip(result.names, result.results, strict=True):
                if bag is not None:
                    bag.robot(name).event(r.sim_time, f"verdict: {'PASSED' if r.passed else 'FAILED'}")
    except (ValueError, FileNotFoundError, BagError) as exc:
        parser.error(str(exc))
    code = print_multi(result, args.plot, args.json)
    if bag_dir:
        print(f"bag: {bag_dir}")
    if args.video:
        _film(bag_dir, args.video, args.fps)
    return code
