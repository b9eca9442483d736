"""Lock-step runs: the real mission trees and the simulator core in one process, no DDS; one loop for any
number of robots (one robot is a list of one).

The simulator is :class:`bt_nav_sim.multi.MultiSimCore` (with one robot it *is* the
:class:`bt_nav_sim.core.SimCore` the ROS simulator node steps, bit for bit), each robot's tree is a
:class:`bt_nav.mission.core.MissionCore` (the object the executive ticks, with a blackboard of its own) and
each robot's referee is by default :class:`bt_nav.judge.referee_core.Referee` (the ROS referee node's core);
any object with the referee's driver protocol will do (:class:`RefereeLike`; the lab's check-off judge
is one). Only the transport differs: each physics step (100 Hz of sim time) is followed, in a fixed order,
by what the ROS graph would do at that instant:

1. every robot's outputs (physics steps between two events are merged when one robot runs, see
   :meth:`SimCore.advance`): odometry (30 Hz) to its tree (with its slip, as the executive sees ``odom``)
   and ground truth to its referee; a LiDAR scan (the profile's rate) to its tree; a collision event to
   its referee; then ``/clock`` to the run's sink;
2. every referee's 2 Hz step, its activate calls applied through ``core.request_arm``; the run ends here
   once every referee has reported;
3. every tree's tick (``tick_rate_hz`` of sim time); its command drives the physics from the next step on,
   as the simulator node applies a command that arrived during a step at the next one (and goes to the
   referee's ``on_command`` when it has one). A tree's evaluation call is answered in the same tick by its
   referee (``LocalTriggerClient``).

So a lock-step run predicts a DDS run of the same world, profile, kinematics and seed
(``tests/ros/test_sim_agreement.py`` measures how closely). Everything random comes from ``seed``: LiDAR
noise, odometry slip, the spawn perturbation and maneuver A's random choices (robot ``i`` > 0 gets
``seed + i * ROBOT_SEED_STRIDE`` so two robots do not make the same choices). Time base: sim seconds from
the run's start, for the trees, the referees (t0 = 0) and every event.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from bt_nav_sim.core import SimConfig, profile
from bt_nav_sim.multi import ROBOT_SEED_STRIDE, MultiSimCore
from bt_nav_sim.world import World, load_world

from bt_nav.judge.referee_core import Referee, RefereeConfig
from bt_nav.media.plot import Trajectory, branch_of_tip
from bt_nav.mission.assignments import LAB, assignment_of
from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.local_services import LocalTriggerClient, TriggerRequest, TriggerResponse
from bt_nav.mission.params import coerce
from bt_nav.mission.scan import Scan
from bt_nav.mission.trace import TraceRecorder
from bt_nav.run.lab import lab_judge
from bt_nav.run.result import MissionResult, RunResult
from bt_nav.run.settings import DEFAULT_JITTER, effective_parameters, profile_maneuver, tree_settings
from bt_nav.run.sinks import MissionSink, RunSink, SimEventLog

REFEREE_HZ = 2.0
HARD_STOP = 60.0  # s after t0: the run ends even if the referees have not reported (a referee may say
#                   when it will have reported: its ``hard_stop``, the lab's check-off runs longer)


class RefereeLike(Protocol):
    """The driver protocol of :class:`bt_nav.judge.referee_core.Referee`, which the engine drives.

    Optional: ``on_command(t, v, w)``, called with every command a tree publishes (after its tick, at the
    tick's sim time), and ``on_walkers(t, circles)``, called before each ground-truth pose in a world with
    people walking, when the object has them."""

    done: bool
    passed: bool

    def start(self, t0: float) -> None: ...  # noqa: D102
    def step(self, t: float) -> list[Any]: ...  # noqa: D102
    def on_activate_result(self, t: float, data: bool, ok: bool, answer: str = ..., message: str = ...) -> None: ...  # noqa: D102, E501
    def observe(self, t: float, x: float, y: float, yaw: float) -> None: ...  # noqa: D102
    def on_collision(self, t: float, x: float, y: float) -> None: ...  # noqa: D102
    def on_evaluate(self, t: float) -> tuple[bool, str]: ...  # noqa: D102
    def results(self) -> dict[str, Any]: ...  # noqa: D102
    def report_lines(self) -> list[str]: ...  # noqa: D102


#: Makes robot ``index``'s referee (named ``name``).
RefereeFactory = Callable[[int, str], RefereeLike]


def homework_referee(config: RefereeConfig | None = None) -> RefereeFactory:
    """A factory of the homework referee (:class:`Referee`) with ``config`` (the homework's by default)."""
    return lambda _index, _name: Referee(config or RefereeConfig())


class SimClock:
    """The simulated clock the trees and the local evaluation clients read (sim seconds)."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@dataclass
class _Samples:
    """Ground-truth samples (at odometry times) and the branch the tree was in."""

    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    yaw: list[float] = field(default_factory=list)
    branch: list[str] = field(default_factory=list)

    def trajectory(self) -> Trajectory:
        return Trajectory(np.array(self.t), np.array(self.x), np.array(self.y), np.array(self.yaw),
                          np.array(self.branch, dtype=object))


class Robot:
    """One robot of a lock-step run: its simulated body, its tree, its referee and what they produced."""

    def __init__(self, name: str, sim: Any, settings: dict[str, Any], referee: RefereeLike, clock: SimClock,
                 sink: MissionSink | None = None) -> None:
        self.name = name
        self.sim = sim
        self.clock = clock
        self.referee = referee
        self._on_command = getattr(referee, "on_command", None)
        self._on_walkers = getattr(referee, "on_walkers", None)
        self._on_announcement = getattr(referee, "on_announcement", None)  # the check-off's: the lines it logs
        self.sink = sink
        self.events = SimEventLog(clock, sink)
        client = LocalTriggerClient(default=self._evaluate, clock=clock)
        self.core = MissionCore(settings, clock=clock, evaluation_client=client, events=self.events)
        self.samples = _Samples()
        self.branch = "Stopped"
        self.branch_ticks: Counter[str] = Counter()
        self.maneuvers = 0
        self.active_ticks = 0
        self.command = Command(0.0, 0.0)
        self.recorder: TraceRecorder | None = None
        self.announcements: list[dict[str, Any]] = []  # the tree's events (:mod:`bt_nav.mission.snapshot`)

    def _evaluate(self, _request: TriggerRequest) -> TriggerResponse:
        ok, message = self.referee.on_evaluate(self.clock.now)
        self.events.info(f"referee: evaluate_mission -> {message}")
        return TriggerResponse(ok, message)

    def deliver(self, out: Any, walkers: np.ndarray | None = None) -> None:
        """Odometry and ground truth, a scan and a collision event, as the simulator node publishes them;
        ``walkers``: where the people walking are (the simulator's ``walkers`` message), None if none."""
        sim, t, s, sink = self.sim, self.clock.now, self.sim.state, self.sink
        if out.collision:
            self.referee.on_collision(t, s.x, s.y)
            self.events.warning(f"collision at ({s.x:.2f}, {s.y:.2f})")
        if out.odom:
            if walkers is not None and self._on_walkers is not None:
                self._on_walkers(t, walkers)
            if walkers is not None and sink is not None:
                sink.walkers(t, walkers)
            self.referee.observe(t, s.x, s.y, s.yaw)
            self.core.feed_odom(sim.odom_yaw, t, x=sim.odom_x, y=sim.odom_y)
            samples = self.samples
            samples.t.append(t)
            samples.x.append(s.x)
            samples.y.append(s.y)
            samples.yaw.append(s.yaw)
            samples.branch.append(self.branch)
            if sink is not None:
                sink.odom(t, sim.odom_x, sim.odom_y, sim.odom_yaw, s.v, s.w)
                sink.ground_truth(t, s.x, s.y, s.yaw, s.v, s.w)
        if out.scan is not None:
            layout, (range_min, range_max) = sim.layout, sim.model.message_range  # as the node publishes it
            scan = Scan(layout.angle_min, layout.angle_max, layout.angle_increment, range_min, range_max, out.scan)
            self.core.feed_scan(scan, t)
            if sink is not None:
                sink.scan(t, scan)

    def referee_step(self) -> None:
        """The referee's step at the current instant; its activate calls go to the tree."""
        t = self.clock.now
        for action in self.referee.step(t):
            ok, message = self.core.request_arm(action.data)
            self.referee.on_activate_result(t, action.data, ok, message=message)
            self.events.info(f"referee: activate({str(action.data).lower()}) -> {ok}: {message}")

    def tick(self) -> None:
        """One tree tick; its command drives the physics from the next step on."""
        command = self.core.tick()
        t, s = self.clock.now, self.sim.state
        if self.recorder is not None:
            self.recorder.record(command, extra={"pose": [round(s.x, 4), round(s.y, 4), round(s.yaw, 4)]})
        branch = branch_of_tip(self.core.tip)
        if bool(self.core.value("armed", False)) and not self.core.mission_over:
            self.active_ticks += 1
            self.branch_ticks[branch] += 1
        if branch == "Maneuver" and self.branch != "Maneuver":
            self.maneuvers += 1
        self.branch = branch
        announced = self.core.take_announcements()
        self.announcements += announced
        if self._on_announcement is not None:  # each event's log line, as the judge reads /rosout over DDS
            for record in announced:
                if record.get("text"):
                    self._on_announcement(t, "bt_nav_executive", str(record["text"]))
        if self.sink is not None:  # what the executive publishes after a tick: cmd_vel, ~/events, ~/tree on change
            self.sink.cmd(t, command.linear, command.angular)
            for record in announced:
                self.sink.announce(t, record)
            snapshot = self.core.changed_snapshot()
            if snapshot is not None:
                self.sink.tree(t, snapshot)
        if self._on_command is not None:
            self._on_command(t, command.linear, command.angular)
        self.command = command

    def result(self, run: Lockstep, wall_time: float) -> MissionResult:
        """The referee's verdict and this robot's measurements."""
        results = self.referee.results()
        active_time = self.active_ticks * run.tick_ns * 1e-9
        v_max = float(self.core.params["max_linear_speed"])
        travelled = float(results.get("travelled", 0.0))
        efficiency = travelled / (v_max * active_time) if active_time > 0 and v_max > 0 else 0.0
        results = {**results, "efficiency": round(efficiency, 4), "active_time": round(active_time, 3)}
        return MissionResult(
            world=self.sim.world.name, maneuver=run.maneuver, seed=run.seed,
            profile=run.profile, kinematics=self.sim.params.kinematics, results=results,
            passed=bool(self.referee.passed), travelled=travelled, efficiency=efficiency, active_time=active_time,
            collisions=int(results.get("collisions", 0)), wall_time=wall_time, sim_time=self.clock.now,
            branch_ticks=dict(self.branch_ticks), maneuvers=self.maneuvers,
            report_lines=list(self.referee.report_lines()), trajectory=self.samples.trajectory(),
            faults=self.core.faults, world_model=self.sim.world, events=list(self.events.lines),
            announcements=list(self.announcements),
            parameters=effective_parameters(dict(self.core.params)), robot=self.name,
        )


class Lockstep:
    """A lock-step run of ``robots`` robots in one world (see the module docstring).

    Args:
        world: a bundled world name, a YAML path, or a loaded World (generated worlds use ``seed``).
        maneuver: none, A, B or C (any spelling :func:`bt_nav.mission.params.normalise_maneuver` accepts);
            None: the profile's (``config/homework.yaml`` says C).
        seed: LiDAR noise, odometry slip, spawn perturbation and maneuver A's randomness.
        overrides: parameter values over the profile's (``random_seed`` defaults to ``seed``).
        profile_name: homework, lab or turtlebot3 (:data:`bt_nav.mission.assignments.PROFILES`): the params
            files, the simulated robot and the judge (the assignment's: the referee, or the lab's check-off).
        robots: how many robots (robot1, robot2, ...), or ``names``; ``starts``: their poses (x, y, yaw).
        kinematics: ideal or burger (empty: the profile's). ``noise``: LiDAR noise and odometry slip.
        jitter: spawn perturbation (metres, degrees); None for the exact spawn.
        referee: makes each robot's referee (index, name) -> a :class:`RefereeLike`; default the homework's
            :class:`Referee` with ``referee_config``.
        sink: receives every message a recorder on the DDS graph would see (one robot: its topics at the
            root; several: each robot's under its namespace through ``sink.robot(name)``).
        merge_steps: integrate the physics steps between two events in one go when one robot runs (exact
            for a constant command; False steps every 10 ms like the simulator node).
    """

    def __init__(self, world: str | World = "stage_4", maneuver: str | None = None, seed: int = 0,
                 overrides: dict[str, Any] | None = None, profile_name: str = "homework", *, robots: int = 1,
                 names: Sequence[str] = (), starts: Sequence[tuple[float, float, float]] = (),
                 kinematics: str = "", noise: bool = True,
                 jitter: tuple[float, float] | None = DEFAULT_JITTER, referee: RefereeFactory | None = None,
                 referee_config: RefereeConfig | None = None, sink: RunSink | MissionSink | None = None,
                 merge_steps: bool = True, sim_params: dict[str, Any] | None = None) -> None:
        profile(profile_name)  # ValueError for an unknown profile, before any work
        self.profile = profile_name
        self.maneuver = profile_maneuver(profile_name, maneuver)
        self.seed = int(seed)
        world_obj = world if isinstance(world, World) else load_world(world, seed=self.seed)
        jitter_m, jitter_deg = jitter or (0.0, 0.0)
        config = sim_config(SimConfig(world=world_obj.name, profile=profile_name, seed=self.seed, noise=noise,
                                      kinematics=kinematics, spawn_jitter_m=jitter_m,
                                      spawn_jitter_deg=jitter_deg), sim_params)
        self.sim = MultiSimCore(config, robots, names, starts, world=world_obj)
        self.clock = SimClock()
        self.sink = sink
        self.merge_steps = merge_steps
        checkoff = assignment_of(profile_name).judge == LAB.judge  # the assignment's judge: the lab's, or the referee
        make_referee = referee or (lab_judge(self.maneuver, self.sim.world, lidar=config.lidar) if checkoff
                                   else homework_referee(referee_config))
        self.robots: list[Robot] = []
        for i, (name, body) in enumerate(zip(self.sim.names, self.sim.cores, strict=True)):
            robot_sink = sink if sink is None or len(self.sim.names) == 1 else sink.robot(name)  # type: ignore[union-attr]
            settings = tree_settings(profile_name, self.maneuver, self.seed + i * ROBOT_SEED_STRIDE,
                                     {**body.model.mount_params(), **(overrides or {})})
            self.robots.append(Robot(name, body, settings, make_referee(i, name), self.clock, robot_sink))
        self.tick_ns = round(1e9 / float(self.robots[0].core.params["tick_rate_hz"]))
        self.referee_ns = round(1e9 / REFEREE_HZ)

    @property
    def names(self) -> list[str]:
        """The robots' names (namespaces)."""
        return list(self.sim.names)

    def run(self, duration: float | None = None, trace_paths: Sequence[str | Path | None] = ()) -> None:
        """Step until every referee has reported (or ``duration`` sim seconds have passed); ``trace_paths``:
        per robot, where to write its per-tick JSONL trace (None: none)."""
        for robot, path in zip(self.robots, trace_paths, strict=False):
            robot.recorder = TraceRecorder(robot.core, path) if path is not None else None
        try:
            self._loop(duration)
        finally:
            for robot in self.robots:
                if robot.recorder is not None:
                    robot.recorder.close()
                    robot.recorder = None

    def _loop(self, duration: float | None) -> None:
        """The one loop (see the module docstring for the order within an instant)."""
        sim, robots, sink = self.sim, self.robots, self.sink
        next_tick = next_referee = 0
        outs = sim.outputs()
        for robot in robots:
            robot.referee.start(0.0)
        hard_stop = max(getattr(robot.referee, "hard_stop", HARD_STOP) for robot in robots)
        end_ns = round((duration if duration is not None else hard_stop) * 1e9)
        while sim.t_ns <= end_ns:
            self.clock.now = sim.t
            walkers = sim.walkers.circles() if len(sim.walkers) else None
            for robot, out in zip(robots, outs, strict=True):
                robot.deliver(out, walkers)
            if sink is not None:
                sink.clock(sim.t)
            if sim.t_ns >= next_referee:
                next_referee += self.referee_ns
                for robot in robots:
                    robot.referee_step()
                if duration is None and all(robot.referee.done for robot in robots):
                    break
            if sim.t_ns >= next_tick:
                next_tick += self.tick_ns
                for robot in robots:
                    robot.tick()
            steps = sim.steps_until(min(next_tick, next_referee)) if self.merge_steps else 1
            outs = sim.advance([(r.command.linear, r.command.angular) for r in robots], steps)

    def result(self, wall_time: float) -> RunResult:
        """Every robot's verdict and measurements."""
        return RunResult(self.names, [robot.result(self, wall_time) for robot in self.robots], wall_time)


def sim_config(config: SimConfig, sim_params: dict[str, Any] | None) -> SimConfig:
    """``config`` with the simulator settings ``sim_params`` (``--sim-param NAME=VALUE``: the simulator node's
    parameter names, e.g. ``actuation_latency``, ``odom_rate_hz``); ValueError names an unknown one."""
    if not sim_params:
        return config
    known = {f.name for f in fields(SimConfig)}
    unknown = sorted(set(sim_params) - known)
    if unknown:
        raise ValueError(f"unknown simulator parameter {unknown[0]!r}; known: {', '.join(sorted(known))}")
    values = {name: coerce(getattr(config, name), value) for name, value in sim_params.items()}
    updated = replace(config, **values)
    updated.check()
    return updated


def run_robots(world: str | World = "stage_4", maneuver: str | None = None, seed: int = 0,
               overrides: dict[str, Any] | None = None, profile: str = "homework", *,
               duration: float | None = None, trace_paths: Sequence[str | Path | None] = (),
               **options: Any) -> RunResult:
    """One lock-step run (any number of robots, :class:`Lockstep`'s ``options``); deterministic per arguments."""
    started = time.perf_counter()
    run = Lockstep(world, maneuver, seed, overrides, profile, **options)
    run.run(duration, trace_paths)
    return run.result(time.perf_counter() - started)


def run_mission(world: str | World = "stage_4", maneuver: str | None = None, seed: int = 0,
                overrides: dict[str, Any] | None = None, profile: str = "homework",
                trace_path: str | Path | None = None, duration: float | None = None,
                jitter: tuple[float, float] | None = DEFAULT_JITTER, **options: Any) -> MissionResult:
    """One robot's lock-step mission (:func:`run_robots` with one robot); its :class:`MissionResult`."""
    return run_robots(world, maneuver, seed, overrides, profile, duration=duration, trace_paths=[trace_path],
                      jitter=jitter, **options).results[0]
