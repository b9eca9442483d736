"""Benchmark 1: the cost of one tick (scan processing included), tree vs the if/else baseline.

Both see the same scan stream (an obstacle drifting through the far band so the tree's TurnAway
branch and its guards run) at 360, 1440 and 4096 beams; timings are per call, perf_counter, after a
warm-up, reported as p50 / p99 over many repetitions, and as a ratio measured in the same run.
"""

from __future__ import annotations

import gc
import math
import time

import numpy as np

from bt_nav import params as P
from bt_nav.testing import Layout, TickHarness, synthetic_scan

from .baseline import IfElseController

TARGET_P99_MS = {360: 0.25, 1440: 0.5, 4096: 0.5}


def _stats(samples: list[float]) -> dict[str, float]:
    ms = np.array(samples) * 1e3
    return {"p50_ms": round(float(np.percentile(ms, 50)), 4), "p99_ms": round(float(np.percentile(ms, 99)), 4),
            "mean_ms": round(float(ms.mean()), 4)}


def measure(beams: int, ticks: int = 5000, maneuver: str = "C") -> dict:
    """Tree and baseline timings for one scan size."""
    layout = Layout(beams, 0.0, 2 * math.pi / beams, 0.12, 3.5)
    scans = [synthetic_scan([(12.0, 0.45 + 0.004 * (i % 50))], layout=layout) for i in range(100)]
    h = TickHarness(maneuver, overrides={"mission_duration": 3600.0}, layout=layout)
    h.tick()
    h.arm()
    h.tick()
    baseline = IfElseController(P.resolve({"maneuver": maneuver, "mission_duration": 3600.0}))
    baseline.armed, baseline.first_armed_at = True, 0.0
    tree_times: list[float] = []
    base_times: list[float] = []
    tips: dict[str, int] = {}
    gc.collect()
    for i in range(ticks + 200):
        now = h.clock.advance(0.05)
        scan = scans[i % len(scans)]
        h.core.feed_scan(scan, now)
        h.core.feed_odom(0.0, now)
        t0 = time.perf_counter()
        h.core.tick()
        t1 = time.perf_counter()
        baseline.step(now, scan, now, 0.0)
        t2 = time.perf_counter()
        if i >= 200:
            tree_times.append(t1 - t0)
            base_times.append(t2 - t1)
            tips[h.core.tip] = tips.get(h.core.tip, 0) + 1
    tree, base = _stats(tree_times), _stats(base_times)
    return {"beams": beams, "ticks": ticks, "tree": tree, "baseline": base,
            "ratio_p50": round(tree["p50_ms"] / base["p50_ms"], 2),
            "target_p99_ms": TARGET_P99_MS.get(beams), "meets_target": tree["p99_ms"] <= TARGET_P99_MS.get(beams, 1e9),
            "tips": tips}


def run(quick: bool = False) -> list[dict]:
    """All scan sizes."""
    return [measure(beams, ticks=1000 if quick else 5000) for beams in (360, 1440, 4096)]


if __name__ == "__main__":
    for row in run():
        print(row)
