"""One homework mission in lock-step: the real mission tree and the simulator core in one process, no DDS.

The simulator is :class:`bt_nav_sim.core.SimCore`, the very object the ROS simulator node steps, with the
same profile, kinematics, noise and odometry slip; the tree is :class:`bt_nav.mission.core.MissionCore`,
the very object the executive ticks; the referee is :class:`bt_nav_sim.referee_core.Referee`, the ROS
referee node's core. Only the transport differs: each physics step (100 Hz of sim time) is followed, in a
fixed order, by what the ROS graph would do at that instant:

1. the step's outputs (physics steps between two events are merged, see :meth:`SimCore.advance`):
   odometry (30 Hz) to the tree (with its slip, as the executive sees ``odom``) and ground truth to the
   referee; a LiDAR scan (the profile's rate) to the tree; a collision event to the
   referee;
2. the referee's 2 Hz step, its activate calls applied through ``core.request_arm``;
3. the tree tick (``tick_rate_hz`` of sim time); its command drives the physics from the next step on, as
   the simulator node applies a command that arrived during a step at the next one. The tree's evaluation
   call is answered in the same tick by the referee (``LocalTriggerClient``).

So a lock-step run predicts a DDS run of the same world, profile, kinematics and seed
(``tests/ros/test_sim_agreement.py`` measures how closely). Everything random comes from ``seed``: LiDAR
noise, odometry slip, the spawn perturbation (so seeds explore different paths, as Gazebo's own jitter
does) and maneuver A's random choices.
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from bt_nav_sim.core import SimConfig, SimCore, profile
from bt_nav_sim.physics import KINEMATICS
from bt_nav_sim.plot import Trajectory, branch_of_tip, plot_run
from bt_nav_sim.referee_core import Referee, RefereeConfig
from bt_nav_sim.world import World, load_world

from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command
from bt_nav.mission.local_services import LocalTriggerClient, TriggerRequest, TriggerResponse
from bt_nav.mission.params import SPECS, normalise_maneuver, parse_assignments
from bt_nav.mission.profiles import PROFILE_FILES
from bt_nav.mission.profiles import profile_parameters as profile_file_parameters
from bt_nav.mission.scan import Scan
from bt_nav.mission.trace import TraceRecorder

REFEREE_HZ = 2.0
HARD_STOP = 60.0  # s after t0: the run ends even if the referee has not reported
#: Spawn perturbation: uniform within +-metres and +-degrees (None/0 for the exact spawn).
DEFAULT_JITTER = (0.05, 10.0)


def profile_parameters(profile_name: str) -> dict[str, Any]:
    """The tree parameters of the profile's params files, without its maneuver: lock-step runs what
    ``bt-nav demo`` and the launch files run."""
    values = profile_file_parameters(profile_name)
    return {k: v for k, v in values.items() if k in SPECS and SPECS[k].in_tree and k != "maneuver"}


class MissionSink(Protocol):
    """Receives what a DDS recorder would see on the graph (e.g. a rosbag2 writer); times are sim seconds."""

    def clock(self, t: float) -> None: ...  # noqa: D102
    def scan(self, t: float, scan: Scan) -> None: ...  # noqa: D102
    def odom(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None: ...  # noqa: D102
    def ground_truth(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None: ...  # noqa: D102
    def cmd(self, t: float, v: float, w: float) -> None: ...  # noqa: D102
    def tree(self, t: float, snapshot: str) -> None: ...  # noqa: D102
    def event(self, t: float, text: str) -> None: ...  # noqa: D102


@dataclass
class MissionResult:
    """Everything one lock-step mission produced."""

    world: str
    maneuver: str
    seed: int
    profile: str
    kinematics: str
    results: dict[str, Any]  # the referee's results()
    passed: bool
    travelled: float
    efficiency: float  # travelled / (max_linear_speed * active_time)
    active_time: float  # s the robot was armed before the deadline stop
    collisions: int
    wall_time: float  # s of real time the run took
    sim_time: float  # s of simulated time
    branch_ticks: dict[str, int]  # ticks per branch label (FullSpeed, TurnAway, ...) while armed
    maneuvers: int  # maneuver starts
    report_lines: list[str]
    trajectory: Trajectory = field(repr=False)
    faults: int = 0  # ticks that raised inside a leaf
    world_model: World | None = field(default=None, repr=False)  # the world as simulated (for plots)
    events: list[tuple[float, str, str]] = field(default_factory=list, repr=False)  # (t, level, line)

    @property
    def failed_checks(self) -> list[str]:
        """Names of the referee checks that failed."""
        return [c["name"] for c in self.results.get("checks", ()) if not c["passed"]]

    def summary(self) -> dict[str, Any]:
        """JSON-able summary without the trajectory."""
        return {
            "world": self.world, "maneuver": self.maneuver, "seed": self.seed, "profile": self.profile,
            "kinematics": self.kinematics,
            "passed": self.passed, "travelled": round(self.travelled, 4), "efficiency": round(self.efficiency, 4),
            "active_time": round(self.active_time, 3), "collisions": self.collisions,
            "max_distance_from_start": self.results.get("max_distance_from_start"),
            "failed_checks": self.failed_checks, "wall_time": round(self.wall_time, 4),
            "sim_time": round(self.sim_time, 4), "branch_ticks": dict(self.branch_ticks),
            "maneuvers": self.maneuvers, "faults": self.faults,
        }

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """Summary, the referee's full results and (optionally) the trajectory."""
        out = {**self.summary(), "results": self.results, "report": self.report_lines}
        if trajectory:
            out["trajectory"] = self.trajectory.to_dict()
        return out


class _Clock:
    """The simulated mission clock the tree and the local evaluation client read."""

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


class LockstepMission:
    """One mission: SimCore, MissionCore and Referee stepped together (see the module docstring)."""

    def __init__(self, world: str | World = "stage_4", maneuver: str = "none", seed: int = 0,
                 overrides: dict[str, Any] | None = None, profile_name: str = "homework", *,
                 kinematics: str = "", noise: bool = True, jitter: tuple[float, float] | None = DEFAULT_JITTER,
                 referee_config: RefereeConfig | None = None, sink: MissionSink | None = None,
                 merge_steps: bool = True, sim: SimCore | None = None) -> None:
        """``sim``: a robot of a :class:`bt_nav_sim.multi.MultiSimCore` to drive instead of a core of its own
        (the multi-robot runner steps the shared clock, :mod:`bt_nav.cli.lockstep_multi`)."""
        profile(profile_name)  # ValueError for an unknown profile, before any work
        self.profile = profile_name
        self.maneuver = normalise_maneuver(maneuver)
        self.seed = int(seed)
        world_obj = world if isinstance(world, World) else load_world(world, seed=self.seed)
        jitter_m, jitter_deg = jitter or (0.0, 0.0)
        self.sim = sim if sim is not None else SimCore(
            SimConfig(world=world_obj.name, profile=profile_name, seed=self.seed, noise=noise, kinematics=kinematics,
                      spawn_jitter_m=jitter_m, spawn_jitter_deg=jitter_deg), world=world_obj)
        self.clock = _Clock()
        self.referee = Referee(referee_config or RefereeConfig())
        self.events = _QuietEvents(self.clock, sink)
        settings = {**profile_parameters(profile_name), "random_seed": self.seed % 2**31, **(overrides or {}),
                    "maneuver": self.maneuver}
        client = LocalTriggerClient(default=self._evaluate, clock=self.clock)
        self.core = MissionCore(settings, clock=self.clock, evaluation_client=client, events=self.events)
        self.sink = sink
        self.merge_steps = merge_steps
        self.samples = _Samples()
        self.branch = "Stopped"
        self.branch_ticks: Counter[str] = Counter()
        self.maneuvers = 0
        self.active_ticks = 0
        self.command = Command(0.0, 0.0)
        self.tick_ns = round(1e9 / float(self.core.params["tick_rate_hz"]))
        self.referee_ns = round(1e9 / REFEREE_HZ)

    def _evaluate(self, _request: TriggerRequest) -> TriggerResponse:
        ok, message = self.referee.on_evaluate(self.clock.now)
        self.events.info(f"referee: evaluate_mission -> {message}")
        return TriggerResponse(ok, message)

    def run(self, duration: float | None = None, trace_path: str | Path | None = None) -> None:
        """Step until the referee reports (or ``duration`` sim seconds have passed)."""
        recorder = TraceRecorder(self.core, trace_path) if trace_path is not None else None
        end_ns = round((duration if duration is not None else HARD_STOP) * 1e9)
        sim = self.sim
        next_tick = next_referee = 0
        out = sim.outputs()
        self.referee.start(0.0)
        try:
            while sim.t_ns <= end_ns:
                self.clock.now = sim.t
                self.deliver(out)
                if sim.t_ns >= next_referee:
                    next_referee += self.referee_ns
                    self.referee_step()
                    if self.referee.done and duration is None:
                        break
                if sim.t_ns >= next_tick:
                    next_tick += self.tick_ns
                    self.tick(recorder)
                steps = sim.steps_until(min(next_tick, next_referee)) if self.merge_steps else 1
                out = sim.advance(self.command.linear, self.command.angular, steps)
        finally:
            if recorder is not None:
                recorder.close()

    def deliver(self, out: Any) -> None:
        """Odometry and ground truth, a scan and a collision event, as the simulator node publishes them."""
        sim, t, s = self.sim, self.sim.t, self.sim.state
        if out.collision:
            self.referee.on_collision(t, s.x, s.y)
            self.events.warning(f"collision at ({s.x:.2f}, {s.y:.2f})")
        if out.odom:
            self.referee.observe(t, s.x, s.y, s.yaw)
            self.core.feed_odom(sim.odom_yaw, t, x=sim.odom_x, y=sim.odom_y)
            for name, value in (("t", t), ("x", s.x), ("y", s.y), ("yaw", s.yaw), ("branch", self.branch)):
                getattr(self.samples, name).append(value)
            if self.sink is not None:
                self.sink.odom(t, sim.odom_x, sim.odom_y, sim.odom_yaw, s.v, s.w)
                self.sink.ground_truth(t, s.x, s.y, s.yaw, s.v, s.w)
        if out.scan is not None:
            m = sim.model
            scan = Scan(m.angle_min, m.angle_max, m.angle_increment, m.range_min, m.range_max, out.scan)
            self.core.feed_scan(scan, t)
            if self.sink is not None:
                self.sink.scan(t, scan)
        if self.sink is not None:
            self.sink.clock(t)

    def referee_step(self) -> None:
        """The referee's step at the current instant; its activate calls go to the tree."""
        t = self.clock.now
        for action in self.referee.step(t):
            ok, message = self.core.request_arm(action.data)
            self.referee.on_activate_result(t, action.data, ok)
            self.events.info(f"referee: activate({str(action.data).lower()}) -> {ok}: {message}")

    def tick(self, recorder: TraceRecorder | None = None) -> None:
        """One tree tick; its command drives the physics from the next step on."""
        command = self.core.tick()
        t, s = self.clock.now, self.sim.state
        if recorder is not None:
            recorder.record(command, extra={"pose": [round(s.x, 4), round(s.y, 4), round(s.yaw, 4)]})
        branch = branch_of_tip(self.core.tip)
        if bool(self.core.value("armed", False)) and not self.core.mission_over:
            self.active_ticks += 1
            self.branch_ticks[branch] += 1
        if branch == "Maneuver" and self.branch != "Maneuver":
            self.maneuvers += 1
        self.branch = branch
        if self.sink is not None:
            self.sink.cmd(t, command.linear, command.angular)
            self.sink.tree(t, self.core.snapshot(show_status=True))
        self.command = command

    def result(self, wall_time: float) -> MissionResult:
        """The referee's verdict and the run's measurements."""
        results = self.referee.results()
        active_time = self.active_ticks * self.tick_ns * 1e-9
        v_max = float(self.core.params["max_linear_speed"])
        travelled = float(results["travelled"])
        efficiency = travelled / (v_max * active_time) if active_time > 0 and v_max > 0 else 0.0
        results = {**results, "efficiency": round(efficiency, 4), "active_time": round(active_time, 3)}
        return MissionResult(
            world=self.sim.world.name, maneuver=self.maneuver, seed=self.seed, profile=self.profile,
            kinematics=self.sim.params.kinematics, results=results, passed=self.referee.passed,
            travelled=travelled, efficiency=efficiency, active_time=active_time,
            collisions=int(results["collisions"]), wall_time=wall_time, sim_time=self.clock.now,
            branch_ticks=dict(self.branch_ticks), maneuvers=self.maneuvers,
            report_lines=self.referee.report_lines(), trajectory=self.samples.trajectory(),
            faults=self.core.faults, world_model=self.sim.world, events=list(self.events.lines),
        )


def run_mission(world: str | World = "stage_4", maneuver: str = "none", seed: int = 0,
                overrides: dict[str, Any] | None = None, profile: str = "homework",
                trace_path: str | Path | None = None, duration: float | None = None,
                jitter: tuple[float, float] | None = DEFAULT_JITTER, *, kinematics: str = "",
                noise: bool = True, referee_config: RefereeConfig | None = None,
                sink: MissionSink | None = None, merge_steps: bool = True) -> MissionResult:
    """Run one homework mission in lock-step; deterministic per (world, maneuver, seed, settings).

    Args:
        world: a bundled world name, a YAML path, or a loaded World (generated worlds use ``seed``).
        maneuver: none, A, B or C (any spelling :func:`bt_nav.mission.params.normalise_maneuver` accepts).
        seed: LiDAR noise, odometry slip, spawn perturbation and maneuver A's randomness.
        overrides: parameter values over the profile's (``random_seed`` defaults to ``seed``).
        profile: homework, lab or turtlebot3: the params files (:mod:`bt_nav.mission.profiles`) and the
            simulated robot (:data:`bt_nav_sim.core.PROFILES`).
        trace_path: write the per-tick JSONL trace here.
        duration: end after this many simulated seconds instead of when the referee reports.
        jitter: spawn perturbation (metres, degrees); None for the exact spawn.
        kinematics: ideal or burger (empty: the profile's).
        noise: LiDAR noise and odometry slip.
        referee_config: the referee's schedule and thresholds (the homework's by default).
        sink: receives every message a recorder on the DDS graph would see.
        merge_steps: integrate the physics steps between two events in one go (exact for a constant
            command; False steps every 10 ms like the simulator node).
    """
    started = time.perf_counter()
    mission = LockstepMission(world, maneuver, seed, overrides, profile, kinematics=kinematics, noise=noise,
                              jitter=jitter, referee_config=referee_config, sink=sink, merge_steps=merge_steps)
    mission.run(duration, trace_path)
    return mission.result(time.perf_counter() - started)


class _QuietEvents:
    """Event sink for batch runs: the leaves' one-line messages are kept with their sim time, not printed."""

    def __init__(self, clock: _Clock | None = None, sink: MissionSink | None = None) -> None:
        self.lines: list[tuple[float, str, str]] = []
        self._clock = clock
        self._sink = sink

    def _add(self, level: str, msg: str) -> None:
        t = self._clock.now if self._clock is not None else 0.0
        self.lines.append((t, level, msg))
        if self._sink is not None:
            self._sink.event(t, f"[{level.upper()}] {msg}")

    def info(self, msg: str) -> None:  # noqa: D102
        self._add("info", msg)

    def warning(self, msg: str) -> None:  # noqa: D102
        self._add("warning", msg)

    def error(self, msg: str) -> None:  # noqa: D102
        self._add("error", msg)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="bt-nav lockstep", description=__doc__.splitlines()[0])
    parser.add_argument("--world", default="stage_4", help="bundled world name or YAML path")
    parser.add_argument("--maneuver", default="none", help="none, A, B or C")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--profile", default="homework", choices=sorted(PROFILE_FILES),
                        help="params files and simulated robot (homework, lab, turtlebot3)")
    parser.add_argument("--kinematics", default="", choices=("", *KINEMATICS),
                        help="ideal or burger (per-wheel limits); default: the profile's")
    parser.add_argument("--no-noise", action="store_true", help="no LiDAR noise and no odometry slip")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter override (repeatable)")
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds (default: until report)")
    parser.add_argument("--no-jitter", action="store_true", help="start exactly at the world's spawn")
    parser.add_argument("--trace", default=None, help="write the per-tick JSONL trace here")
    parser.add_argument("--plot", default=None, help="write the trajectory picture here (.png/.svg)")
    parser.add_argument("--json", default=None, help="write results (with trajectory) as JSON here")
    parser.add_argument("--bag", default=None, metavar="DIR", help="write the mission as a rosbag2 (MCAP) bag here")
    parser.add_argument("--video", default=None, metavar="FILE.mp4", help="film the mission (needs --bag or "
                        "writes a bag next to the video)")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per second of --video")
    parser.add_argument("--robots", type=int, default=1, help="robots in the world, each with its own tree and "
                        "referee (robot1, robot2, ...; default 1)")
    return parser


def _run(args: argparse.Namespace) -> MissionResult:
    """The mission, written to a bag while it runs when one is asked for."""
    overrides = parse_assignments(args.overrides)
    kwargs = {"jitter": None if args.no_jitter else DEFAULT_JITTER, "kinematics": args.kinematics,
              "noise": not args.no_noise}
    bag_dir = args.bag or (str(Path(args.video).with_suffix("")) + "_bag" if args.video else None)
    if bag_dir is None:
        return run_mission(args.world, args.maneuver, args.seed, overrides, args.profile, args.trace,
                           args.duration, **kwargs)
    from bt_nav.media.bag import MissionBag

    mission = {"world": args.world, "maneuver": args.maneuver, "seed": args.seed, "profile": args.profile}
    with MissionBag(bag_dir, mission=mission) as bag:
        result = run_mission(args.world, args.maneuver, args.seed, overrides, args.profile, args.trace,
                             args.duration, sink=bag, **kwargs)
        bag.event(result.sim_time, f"verdict: {'PASSED' if result.passed else 'FAILED'}")
    args.bag = bag_dir
    return result


def _film(bag_dir: str, out: str, fps: float) -> None:
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.video import world_of, write_video

    record = read_bag(bag_dir)
    stats = write_video(record, out, fps, world_of(record))
    print(f"video: {out} ({stats.frames} frames at {fps:g} fps, rendered in {stats.seconds:.1f} s)")


def _main_multi(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``bt-nav lockstep --robots N``: N robots in one world (:mod:`bt_nav.cli.lockstep_multi`)."""
    from bt_nav.cli.lockstep_multi import main_multi

    return main_multi(parser, args)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav lockstep``: one mission; prints the referee's report; exit 0 only if it passed."""
    parser = _parser()
    args = parser.parse_args(argv)
    if args.robots != 1:
        return _main_multi(parser, args)
    try:
        result = _run(args)
    except (ValueError, FileNotFoundError) as exc:
        parser.error(str(exc))
    for line in result.report_lines:
        print(line)
    ticks = ", ".join(f"{name} {n}" for name, n in sorted(result.branch_ticks.items(), key=lambda kv: -kv[1]))
    print(f"{result.world}, maneuver {result.maneuver}, seed {result.seed} ({result.profile}, "
          f"{result.kinematics} kinematics): "
          f"{'PASSED' if result.passed else 'FAILED'}; travelled {result.travelled:.2f} m, "
          f"efficiency {result.efficiency:.3f} over {result.active_time:.1f} s armed, "
          f"{result.collisions} collisions, {result.maneuvers} maneuvers; ticks: {ticks}; "
          f"{result.sim_time:.1f} s simulated in {result.wall_time:.3f} s")
    if args.plot:
        plot_run(result.world_model, result.trajectory, result.results, args.plot,
                 title=f"{result.world}, maneuver {result.maneuver}, seed {result.seed}")
        print(f"picture: {args.plot}")
    if args.json:
        path = Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result.to_dict(trajectory=True), indent=1))
        print(f"results: {args.json}")
    for name in ("trace", "bag"):
        if getattr(args, name):
            print(f"{name}: {getattr(args, name)}")
    if args.video:
        _film(args.bag, args.video, args.fps)
    return 0 if result.passed else 1
