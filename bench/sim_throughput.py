"""Benchmark 3: how fast the simulation runs: LiDAR scans, lock-step missions, the ROS path.

- LiDAR: :meth:`sim.lidar.RayCaster.cast` in stage_4 with the homework LiDAR (360 beams, seeded
  noise, as the simulator and the lock-step runner call it), from random poses; per-call timings,
  scans/s = 1 / p50. The noise-free geometry (``true_ranges``) is timed in the same loop.
- Lock-step: :func:`bt_nav.run.lockstep.run_mission` on stage_4 with ``config/homework.yaml``'s
  parameters over several seeds, serially in this process; wall seconds per mission (median) and
  what one mission's time is spent on (cProfile: inclusive time of the tree tick, the ray casting,
  the physics, the referee).
- ROS path: whole missions over DDS (:mod:`bench.ros_mission`), simulated / wall seconds over the
  referee's mission, median of several runs, with the CPU seconds each process spent; then one more
  mission with the executive under cProfile, to say where its time goes (not counted in the median).
  The measured runs also feed the memory benchmark.
"""

from __future__ import annotations

import math
import pstats
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from bt_nav_sim import HOMEWORK_LIDAR, RayCaster, load_world

from bt_nav.mission import params as P
from bt_nav.run.lockstep import run_mission
from bt_nav.run.settings import profile_maneuver

from .common import (
    Target,
    at_least,
    at_most,
    homework_overrides,
    median,
    percentiles,
    profile_call,
    summarize_profile,
)

#: Runs one ROS-path mission: (seed, where the executive's profile goes or None) -> its summary.
RosRunner = Callable[[int, Path | None], dict[str, Any]]

TARGET_SCANS_PER_S = 5000.0
TARGET_LOCKSTEP_S = 0.15  # wall seconds per 55 s mission
TARGET_RTF = 40.0  # issue 27: "bt-nav demo --quiet >= 40x; the bench's ROS path likewise"
LOCKSTEP_AREAS = (
    ("py_trees/", "py_trees framework"),
    ("behaviours/control.py", "compiled ticker (composites)"),
    ("bt_nav/mission/behaviours", "bt_nav leaves"),
    ("bt_nav/mission/scan.py", "scan processing (bt_nav.mission.scan)"),
    ("bt_nav/mission/paths.py", "free paths and steering (bt_nav.mission.paths)"),
    ("bt_nav_sim/lidar.py", "LiDAR ray casting (Python side)"),
    ("bt_nav_sim/physics.py", "physics"),
    ("bt_nav_sim/world.py", "world geometry (collision clearance)"),
    ("bt_nav/judge/referee_core.py", "referee"),
    ("numpy", "numpy kernels"),
    ("enum.py", "enum formatting (py_trees debug strings)"),
    ("bt_nav/", "bt_nav core, lock-step loop"),
)
#: The executive's profile areas (ROS path); ``_rclpy_pybind11.wait`` (idle) is left out of them.
EXECUTIVE_AREAS = (
    ("_rclpy_pybind11.publish", "DDS publish (rclpy -> Fast DDS, in C)"),
    ("_rclpy_pybind11.take", "DDS take and deserialise (in C)"),
    ("rclpy", "rclpy executor and wrappers (Python)"),
    ("contextlib", "rclpy executor and wrappers (Python)"),
    ("importlib", "start-up (imports)"),
    ("py_trees/display", "tree text for ~/tree (py_trees.display)"),
    ("py_trees/", "py_trees framework"),
    ("bt_nav/executive.py", "executive edge (callbacks, vet, ~/tree, stats)"),
    ("bt_nav/behaviours", "bt_nav leaves"),
    ("bt_nav/scan.py", "scan processing (bt_nav.mission.scan)"),
    ("numpy", "numpy kernels"),
    ("enum.py", "enum formatting (py_trees debug strings)"),
    ("bt_nav/", "bt_nav core"),
)
EXECUTIVE_PARTS = ("executive.py:_on_tick", "core.py:tick", "executive.py:_publish_tree",
                   "core.py:statuses", "core.py:snapshot", "rosutil.py:publish", "executive.py:_on_scan",
                   "executive.py:_on_odom", "executive.py:vet")
#: Functions whose inclusive time splits a lock-step mission into its parts.
LOCKSTEP_PARTS = ("core.py:tick", "lidar.py:cast", "physics.py:step", "referee_core.py:observe",
                  "referee_core.py:step", "core.py:feed_scan", "core.py:feed_odom", "plot.py:branch_of_tip",
                  "core.py:__init__")


def lidar(scans: int = 3000, seed: int = 0) -> dict[str, Any]:
    """Per-scan cost of the homework LiDAR in stage_4 (with noise, and geometry only)."""
    world = load_world("stage_4")
    caster = RayCaster(world, HOMEWORK_LIDAR)
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = world.bounds
    poses = [(float(rng.uniform(xmin, xmax)), float(rng.uniform(ymin, ymax)), float(rng.uniform(-math.pi, math.pi)))
             for _ in range(256)]
    noise = np.random.default_rng([seed, 2])
    cast_times: list[float] = []
    geometry_times: list[float] = []
    perf = time.perf_counter
    for i in range(scans + 100):
        x, y, yaw = poses[i % len(poses)]
        t0 = perf()
        caster.cast(x, y, yaw, noise)
        t1 = perf()
        caster.true_ranges(x, y, yaw)
        t2 = perf()
        if i >= 100:
            cast_times.append(t1 - t0)
            geometry_times.append(t2 - t1)
    cast = percentiles(cast_times, 1e6, 2)
    geometry = percentiles(geometry_times, 1e6, 2)
    return {
        "world": "stage_4", "beams": HOMEWORK_LIDAR.num_beams, "segments": int(world.segments.shape[0]),
        "circles": int(world.circles.shape[0]), "scans": scans,
        "cast_us": cast, "true_ranges_us": geometry,
        "scans_per_s": round(1e6 / cast["p50"], 1), "scans_per_s_p99": round(1e6 / cast["p99"], 1),
        "scans_per_s_aggregate": round(len(cast_times) / sum(cast_times), 1),
    }


def lockstep(seeds: int = 10, world: str = "stage_4", profile: bool = True) -> dict[str, Any]:
    """Wall time of whole lock-step missions (serial, this process), and a profile of one of them."""
    maneuver = profile_maneuver("homework")
    tick_hz = float(P.SPECS["tick_rate_hz"].default)
    overrides = homework_overrides()
    run_mission(world, maneuver, 0, overrides)  # warm-up: imports, caches, the tree file
    runs = []
    for seed in range(seeds):
        result = run_mission(world, maneuver, seed, overrides)
        runs.append({"seed": seed, "wall_s": round(result.wall_time, 4), "sim_s": round(result.sim_time, 3),
                     "passed": result.passed, "ticks": int(round(result.sim_time * tick_hz))})
    walls = [r["wall_s"] for r in runs]
    sims = [r["sim_s"] for r in runs]
    out: dict[str, Any] = {
        "world": world, "maneuver": maneuver, "overrides": overrides, "seeds": seeds, "runs": runs,
        "wall_s": percentiles(walls, 1.0, 4), "sim_s_median": median(sims),
        "rtf_median": round(median([s / w for s, w in zip(sims, walls, strict=True)]), 1),
        "wall_per_55s_mission": round(median(walls) * 55.0 / median(sims), 4),
    }
    out["split"] = _split_mission(world, maneuver, seeds=min(seeds, 5))
    if profile:
        out["profile"] = _profile_mission(world, maneuver)
    return out


def _split_mission(world: str, maneuver: str, seeds: int) -> dict[str, Any]:
    """Wall seconds of a mission in the tree's ticks and in everything else (the simulator, mostly), without
    a profiler (which inflates the many small Python calls of the tick): median over seeds 0..seeds-1.
    Says how much of the lock-step target the tree alone could reach."""
    from bt_nav.mission.core import MissionCore

    spent = [0.0]
    original = MissionCore.tick

    def timed(self: MissionCore) -> Any:
        t0 = time.perf_counter()
        try:
            return original(self)
        finally:
            spent[0] += time.perf_counter() - t0

    rows = []
    MissionCore.tick = timed  # type: ignore[method-assign]
    try:
        for seed in range(seeds):
            spent[0] = 0.0
            result = run_mission(world, maneuver, seed, homework_overrides())
            rows.append((result.wall_time, spent[0], result.sim_time))
    finally:
        MissionCore.tick = original  # type: ignore[method-assign]
    total, tick, sim = (median([r[i] for r in rows]) for i in range(3))
    return {"seeds": seeds, "wall_s": round(total, 4), "tree_tick_s": round(tick, 4),
            "rest_s": round(total - tick, 4), "tick_share": round(tick / total, 3) if total else None,
            "tick_ms_mean": round(tick / max(1, round(sim * float(P.SPECS["tick_rate_hz"].default))) * 1e3, 4)}


def _profile_mission(world: str, maneuver: str) -> dict[str, Any]:
    """cProfile of one mission (seed 0): areas, top functions and the inclusive time of its parts."""
    holder: dict[str, Any] = {}

    def one() -> None:
        holder["result"] = run_mission(world, maneuver, 0, homework_overrides())

    prof = profile_call(one, top=10, areas=LOCKSTEP_AREAS, cumulative_of=LOCKSTEP_PARTS)
    result = holder["result"]
    prof["armed_ticks"] = int(sum(result.branch_ticks.values()))
    return prof


def ros_rtf(run_ros: RosRunner, runs: int = 3, profile: bool = True) -> dict[str, Any]:
    """Real-time factor of whole missions over DDS (median of ``runs``; seeds 0..runs-1), the CPU each
    process spent, and (``profile``) where the executive's time goes, from one more, profiled, mission."""
    missions = [run_ros(seed, None) for seed in range(runs)]
    rtfs = [m["rtf"] for m in missions if m.get("rtf")]
    out: dict[str, Any] = {"runs": runs, "missions": missions,
                           "rtf_median": round(median(rtfs), 2) if rtfs else None,
                           "rtf_min": min(rtfs) if rtfs else None, "rtf_max": max(rtfs) if rtfs else None,
                           "passed": sum(1 for m in missions if m.get("passed"))}
    cpu: dict[str, list[float]] = {}
    for m in missions:
        for name, seconds in (m.get("cpu_s") or {}).items():
            if seconds is not None:
                cpu.setdefault(name, []).append(seconds)
    out["cpu_s_median"] = {name: round(median(values), 2) for name, values in cpu.items()}
    spans = [m["cpu_span_wall_s"] for m in missions if m.get("cpu_span_wall_s")]
    out["cpu_span_wall_s_median"] = round(median(spans), 2) if spans else None
    if profile:
        out["executive_profile"] = _profile_executive(run_ros)
    return out


def _profile_executive(run_ros: RosRunner) -> dict[str, Any]:
    """One mission with the executive under cProfile; where its (non-idle) time goes."""
    with tempfile.TemporaryDirectory(prefix="bt_nav_bench_prof_") as tmp:
        path = Path(tmp) / "executive.prof"
        mission = run_ros(0, path)
        if not path.is_file():
            return {"error": "the profiled executive wrote no profile", "mission": mission.get("error")}
        summary = summarize_profile(pstats.Stats(str(path)), top=10, areas=EXECUTIVE_AREAS,
                                    cumulative_of=EXECUTIVE_PARTS, idle=("_rclpy_pybind11.wait",))
    summary.update({"rtf_under_profiler": mission.get("rtf"), "passed": mission.get("passed"),
                    "ticks": mission.get("executive_ticks")})
    return summary


def run(quick: bool = False, run_ros: RosRunner | None = None) -> dict[str, Any]:
    """LiDAR, lock-step and (when ``run_ros`` is given) the ROS path."""
    out: dict[str, Any] = {"lidar": lidar(scans=300 if quick else 3000),
                           "lockstep": lockstep(seeds=3 if quick else 10, profile=True)}
    if run_ros is not None:
        out["ros"] = ros_rtf(run_ros, runs=1 if quick else 3, profile=not quick)
    else:
        out["ros"] = {"skipped": "no DDS in this run (--no-dds)"}
    return out


def targets(result: dict[str, Any]) -> list[Target]:
    """Scans/s, lock-step wall time per mission, ROS-path real-time factor."""
    scans = result["lidar"]["scans_per_s"]
    mission = result["lockstep"].get("wall_per_55s_mission", result["lockstep"]["wall_s"]["p50"])
    rtf = result["ros"].get("rtf_median")
    return [
        Target("lidar_scans_per_s", "sim", "LiDAR scans/s (360 beams, stage_4, RayCaster.cast)",
               f">= {TARGET_SCANS_PER_S:g}", scans, "scans/s", at_least(scans, TARGET_SCANS_PER_S)),
        Target("lockstep_mission_wall", "sim",
               "lock-step mission wall time per 55 s of mission (stage_4, median over seeds)",
               f"<= {TARGET_LOCKSTEP_S} s", mission, "s", at_most(mission, TARGET_LOCKSTEP_S)),
        Target("ros_rtf", "sim", "ROS-path real-time factor (sim + executive + referee, rtf 0, median)",
               f">= {TARGET_RTF:g}x", rtf, "x", at_least(rtf, TARGET_RTF)),
    ]
