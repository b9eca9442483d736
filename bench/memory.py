"""Benchmark 5: peak memory of the executive during a whole mission over DDS.

``VmHWM`` (the kernel's high-water mark of the resident set) of the executive subprocess, read from
``/proc/<pid>/status`` after the referee's verdict while the process still runs, so the peak covers
start-up, the 55 s mission and the evaluation call (:mod:`bench.ros_mission`). The simulator's is
reported next to it, and the executive's after the latency benchmark's ~2 minutes of 20 Hz ticking
when that ran too (a growing number there would be a leak). The missions are the ROS-path ones of
the simulator benchmark when it ran in the same invocation; otherwise one mission is run here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .common import median


def run(missions: list[dict[str, Any]] | None, run_ros: Callable[[int, Any], dict[str, Any]] | None,
        latency: dict[str, Any] | None = None) -> dict[str, Any]:
    """Summarise the processes' memory over ``missions`` (one new mission when there are none)."""
    source = "the ROS-path missions of the sim benchmark"
    if not missions:
        if run_ros is None:
            return {"skipped": "no DDS in this run (--no-dds)"}
        missions = [run_ros(0, None)]
        source = "one ROS-path mission run for this benchmark"
    per_mission = [{"seed": m.get("seed"), "passed": m.get("passed"), **{name: m.get("memory", {}).get(name, {})
                                                                          for name in ("executive", "sim")}}
                   for m in missions]
    out: dict[str, Any] = {"source": source, "missions": per_mission}
    for name in ("executive", "sim"):
        peaks = [m[name]["VmHWM_kb"] for m in per_mission if m[name].get("VmHWM_kb")]
        out[f"{name}_vmhwm_mb_median"] = round(median(peaks) / 1024, 1) if peaks else None
        out[f"{name}_vmhwm_mb_max"] = round(max(peaks) / 1024, 1) if peaks else None
    if latency and latency.get("executive_memory"):
        out["executive_after_latency_run"] = {**latency["executive_memory"], "wall_s": latency.get("wall_s")}
    return out
