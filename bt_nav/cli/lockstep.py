"""One homework mission in lock-step: the real mission tree and the 2D simulator in one process, no DDS.

Every rate of the ROS setup is reproduced on the simulated clock, on a fixed base grid (``1 / lcm`` of
the integer rates: 1/60 s for the 20 Hz tree, 30 Hz odometry and ground truth, 10 Hz homework LiDAR
(5 Hz lab LiDAR) and the 2 Hz referee), so every event lands exactly on a grid point and the schedule
is counted in integers with no drift. Within one instant the order is fixed:

1. physics up to now (the last cmd_vel persists, as with Gazebo's diff drive);
2. ground truth to the referee and odometry yaw to the tree (30 Hz);
3. a LiDAR scan with seeded noise (at the LiDAR's rate);
4. the referee's 2 Hz step, its activate calls applied through ``core.request_arm``;
5. the tree tick (20 Hz); the command it returns holds from now until the next tick. The tree's
   evaluation call is answered in the same tick by the referee (``LocalTriggerClient``).

Physics step: the integrator (:func:`bt_nav_sim.step`) is exact for a constant command (closed-form
arcs, closed-form acceleration ramps, 2 cm collision sub-steps with bisection to the contact), so the
1/60 s grid steps are merged into one call whenever the command does not change and nothing samples
the state in between, and skipped while the robot rests under a zero command. The result equals
fixed 1/60 s stepping to within 1e-4 m (``tests/test_lockstep.py`` checks it; the difference is the
arc approximation inside acceleration ramps) with half the physics calls. Collision events are the
rising edges of the physics' ``collided`` flag.

Everything random comes from ``seed``: the LiDAR noise, a small perturbation of the spawn pose (so
seeds explore different paths, as Gazebo's own jitter does) and maneuver A's random choices.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim import HOMEWORK_LIDAR, LDS01, LidarModel, RayCaster, RobotParams, RobotState, World, load_world, step
from bt_nav_sim.plot import Trajectory, branch_of_tip, plot_run
from bt_nav_sim.referee_core import Referee, RefereeConfig

from bt_nav.mission.core import MissionCore
from bt_nav.mission.params import normalise_maneuver
from bt_nav.mission.scan import Scan
from bt_nav.mission.trace import TraceRecorder
from bt_nav.testing import LocalTriggerClient, TriggerRequest, TriggerResponse

#: LiDAR model per profile: the course homework's simulated scanner, or the real TurtleBot3's LDS-01.
PROFILES: dict[str, LidarModel] = {"homework": HOMEWORK_LIDAR, "lab": LDS01}
ODOM_HZ = 30  # odometry and ground truth, as the TurtleBot3's Gazebo plugins publish them
REFEREE_HZ = 2
HARD_STOP = 60.0  # s after t0: the run ends even if the referee has not reported
#: Spawn perturbation: uniform within +-metres and +-degrees (None/0 for the exact spawn).
DEFAULT_JITTER = (0.05, 10.0)


def profile_parameters(profile: str) -> dict[str, Any]:
    """The tree parameters of the profile's params file (``config/homework.yaml`` or ``config/lab.yaml``),
    without its maneuver: lock-step runs what ``bt-nav demo`` and the launch files run."""
    from bt_nav.mission.params import SPECS
    from bt_nav.ros.bringup import config_file, file_parameters

    path = config_file(f"{profile}.yaml")
    values = file_parameters(path) if path is not None else {}
    return {k: v for k, v in values.items() if k in SPECS and SPECS[k].in_tree and k != "maneuver"}


@dataclass
class MissionResult:
    """Everything one lock-step mission produced."""

    world: str
    maneuver: str
    seed: int
    profile: str
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

    @property
    def failed_checks(self) -> list[str]:
        """Names of the referee checks that failed."""
        return [c["name"] for c in self.results.get("checks", ()) if not c["passed"]]

    def summary(self) -> dict[str, Any]:
        """JSON-able summary without the trajectory."""
        return {
            "world": self.world, "maneuver": self.maneuver, "seed": self.seed, "profile": self.profile,
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


def _rate(value: float, what: str) -> int:
    """A rate as an integer number of Hz (the base grid needs integer rates)."""
    rate = int(round(value))
    if rate <= 0 or abs(rate - value) > 1e-9:
        raise ValueError(f"lock-step needs a positive integer {what}, got {value}")
    return rate


class _Clock:
    """The simulated mission clock the tree and the local evaluation client read."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def spawn_pose(world: World, seed: int, jitter: tuple[float, float] | None) -> tuple[float, float, float]:
    """The world's spawn, perturbed per seed within ``jitter`` (metres, degrees)."""
    x, y, yaw = world.spawn
    if not jitter or (jitter[0] <= 0 and jitter[1] <= 0):
        return x, y, yaw
    rng = np.random.default_rng([int(seed), 1])
    dx, dy = rng.uniform(-jitter[0], jitter[0], size=2)
    dyaw = math.radians(rng.uniform(-jitter[1], jitter[1]))
    return x + float(dx), y + float(dy), math.remainder(yaw + dyaw, 2 * math.pi)


def run_mission(world: str | World = "stage_4", maneuver: str = "none", seed: int = 0,
                overrides: dict[str, Any] | None = None, profile: str = "homework",
                trace_path: str | Path | None = None, duration: float | None = None,
                jitter: tuple[float, float] | None = DEFAULT_JITTER, merge_steps: bool = True,
                referee_config: RefereeConfig | None = None) -> MissionResult:
    """Run one homework mission in lock-step; deterministic per (world, maneuver, seed, overrides).

    Args:
        world: a bundled world name, a YAML path, or a loaded World (generated worlds use ``seed``).
        maneuver: none, A, B or C (any spelling :func:`bt_nav.mission.params.normalise_maneuver` accepts).
        seed: LiDAR noise, spawn perturbation and maneuver A's randomness.
        overrides: parameter values over the defaults (``random_seed`` defaults to ``seed``).
        profile: ``homework`` (10 Hz, 10 m LiDAR) or ``lab`` (LDS-01, 5 Hz, 3.5 m).
        trace_path: write the per-tick JSONL trace here.
        duration: end after this many simulated seconds instead of when the referee reports.
        jitter: spawn perturbation (metres, degrees); None for the exact spawn.
        merge_steps: merge 1/60 s physics steps under an unchanged command (see the module doc).
        referee_config: the referee's schedule and thresholds (the homework's by default).
    """
    started = time.perf_counter()
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r}; choose from {', '.join(PROFILES)}")
    model = PROFILES[profile]
    world_obj = world if isinstance(world, World) else load_world(world, seed=seed)
    maneuver = normalise_maneuver(maneuver)
    settings = {**profile_parameters(profile), "random_seed": int(seed) % 2**31, **(overrides or {}),
                "maneuver": maneuver}

    clock = _Clock()
    referee = Referee(referee_config or RefereeConfig())

    def evaluate(_request: TriggerRequest) -> TriggerResponse:
        ok, message = referee.on_evaluate(clock.now)
        return TriggerResponse(ok, message)

    client = LocalTriggerClient(default=evaluate, clock=clock)
    core = MissionCore(settings, clock=clock, evaluation_client=client, events=_QuietEvents())
    recorder = TraceRecorder(core, trace_path) if trace_path is not None else None

    tick_hz = _rate(float(core.params["tick_rate_hz"]), "tick_rate_hz")
    lidar_hz = _rate(model.rate_hz, "LiDAR rate")
    base_hz = math.lcm(tick_hz, ODOM_HZ, lidar_hz, REFEREE_HZ)
    every_tick, every_odom = base_hz // tick_hz, base_hz // ODOM_HZ
    every_scan, every_referee = base_hz // lidar_hz, base_hz // REFEREE_HZ
    end_k = int(round((duration if duration is not None else HARD_STOP) * base_hz))

    caster = RayCaster(world_obj, model)
    noise = np.random.default_rng([int(seed), 2])
    robot_params = RobotParams()
    x0, y0, yaw0 = spawn_pose(world_obj, seed, jitter)
    state = RobotState(x0, y0, yaw0)
    phys_k = 0  # grid index the physics state is at
    colliding = False
    cmd_v = cmd_w = 0.0
    dt = 1.0 / base_hz
    v_max = float(core.params["max_linear_speed"])

    samples_t: list[float] = []
    samples_x: list[float] = []
    samples_y: list[float] = []
    samples_yaw: list[float] = []
    samples_branch: list[str] = []
    branch = "Stopped"
    branch_ticks: Counter[str] = Counter()
    maneuvers = 0
    active_ticks = 0

    def advance(k: int) -> None:
        """Bring the physics to grid index k under the current command."""
        nonlocal state, phys_k, colliding
        if k <= phys_k:
            return
        if cmd_v == 0.0 and cmd_w == 0.0 and state.v == 0.0 and state.w == 0.0:
            phys_k = k  # at rest under a zero command: nothing can change
            return
        n = k - phys_k if merge_steps else 1
        while phys_k < k:
            state, collided = step(state, cmd_v, cmd_w, n * dt, world_obj, robot_params)
            phys_k += n
            if collided and not colliding:
                referee.on_collision(phys_k * dt, state.x, state.y)
            colliding = collided

    referee.start(0.0)
    k = 0
    try:
        while k <= end_k:
            t = k * dt
            clock.now = t
            if k % every_odom == 0:
                advance(k)
                referee.observe(t, state.x, state.y, state.yaw)
                core.feed_odom(state.yaw, t)
                samples_t.append(t)
                samples_x.append(state.x)
                samples_y.append(state.y)
                samples_yaw.append(state.yaw)
                samples_branch.append(branch)
            if k % every_scan == 0:
                advance(k)
                ranges = caster.cast(state.x, state.y, state.yaw, noise)
                core.feed_scan(Scan(model.angle_min, model.angle_max, model.angle_increment, model.range_min,
                                    model.range_max, ranges), t)
            if k % every_referee == 0:
                for action in referee.step(t):
                    ok, _ = core.request_arm(action.data)
                    referee.on_activate_result(t, action.data, ok)
                if referee.done and duration is None:
                    break
            if k % every_tick == 0:
                command = core.tick()
                if recorder is not None:
                    recorder.record(command, extra={"pose": [round(state.x, 4), round(state.y, 4),
                                                             round(state.yaw, 4)]})
                new_branch = branch_of_tip(core.tip)
                armed = bool(core.value("armed", False)) and not core.mission_over
                if armed:
                    active_ticks += 1
                    branch_ticks[new_branch] += 1
                if new_branch == "Maneuver" and branch != "Maneuver":
                    maneuvers += 1
                branch = new_branch
                if (command.linear, command.angular) != (cmd_v, cmd_w):
                    advance(k)
                    cmd_v, cmd_w = command.linear, command.angular
            k += 1
    finally:
        if recorder is not None:
            recorder.close()

    results = referee.results()
    active_time = active_ticks / tick_hz
    travelled = float(results["travelled"])
    efficiency = travelled / (v_max * active_time) if active_time > 0 and v_max > 0 else 0.0
    results = {**results, "efficiency": round(efficiency, 4), "active_time": round(active_time, 3)}
    trajectory = Trajectory(np.array(samples_t), np.array(samples_x), np.array(samples_y),
                            np.array(samples_yaw), np.array(samples_branch, dtype=object))
    return MissionResult(
        world=world_obj.name, maneuver=maneuver, seed=int(seed), profile=profile, results=results,
        passed=referee.passed, travelled=travelled, efficiency=efficiency, active_time=active_time,
        collisions=int(results["collisions"]), wall_time=time.perf_counter() - started,
        sim_time=clock.now, branch_ticks=dict(branch_ticks), maneuvers=maneuvers,
        report_lines=referee.report_lines(), trajectory=trajectory, faults=core.faults,
        world_model=world_obj,
    )


class _QuietEvents:
    """Event sink for batch runs: the leaves' one-line messages are kept, not printed."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def info(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("info", msg))

    def warning(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("warning", msg))

    def error(self, msg: str) -> None:  # noqa: D102
        self.lines.append(("error", msg))


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """``name=value`` pairs; values parsed as JSON when possible (numbers, true/false), else strings."""
    out: dict[str, Any] = {}
    for item in items:
        name, sep, raw = item.partition("=")
        if not sep:
            raise ValueError(f"--set expects name=value, got {item!r}")
        try:
            out[name.strip()] = json.loads(raw)
        except json.JSONDecodeError:
            out[name.strip()] = raw
    return out


def main(argv: list[str] | None = None) -> int:
    """``bt-nav lockstep``: one mission; prints the referee's report; exit 0 only if it passed."""
    parser = argparse.ArgumentParser(prog="bt-nav lockstep", description=__doc__.splitlines()[0])
    parser.add_argument("--world", default="stage_4", help="bundled world name or YAML path")
    parser.add_argument("--maneuver", default="none", help="none, A, B or C")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--profile", default="homework", choices=sorted(PROFILES))
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter override (repeatable)")
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds (default: until report)")
    parser.add_argument("--no-jitter", action="store_true", help="start exactly at the world's spawn")
    parser.add_argument("--trace", default=None, help="write the per-tick JSONL trace here")
    parser.add_argument("--plot", default=None, help="write the trajectory picture here (.png/.svg)")
    parser.add_argument("--json", default=None, help="write results (with trajectory) as JSON here")
    args = parser.parse_args(argv)
    try:
        overrides = parse_overrides(args.overrides)
        result = run_mission(args.world, args.maneuver, args.seed, overrides, args.profile, args.trace,
                             args.duration, jitter=None if args.no_jitter else DEFAULT_JITTER)
    except (ValueError, FileNotFoundError) as exc:
        parser.error(str(exc))
    for line in result.report_lines:
        print(line)
    ticks = ", ".join(f"{name} {n}" for name, n in sorted(result.branch_ticks.items(), key=lambda kv: -kv[1]))
    print(f"{result.world}, maneuver {result.maneuver}, seed {result.seed}: "
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
    if args.trace:
        print(f"trace: {args.trace}")
    return 0 if result.passed else 1
