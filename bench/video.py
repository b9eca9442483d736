"""Benchmark ``video``: record a whole lock-step mission into a bag, read it back and film it.

Target: a ~55 s mission at 10 fps renders (frames + H.264 encoding) in <= 20 s on this machine. Also
reported: what writing the bag adds to a lock-step run (the in-process sink; over DDS the recorder is
a process of its own, outside the executive), the bag's size and the time to read it back.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from .common import Target, at_most

RENDER_LIMIT_S = 20.0
FPS = 10.0


def run(quick: bool = False) -> dict[str, Any]:
    """Measure; ``quick`` films a 20 s slice instead of the whole mission."""
    from bt_nav.media.bag import MissionBag
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.video import world_of, write_video
    from bt_nav.run.lockstep import run_mission
    from bt_nav.run.settings import profile_maneuver

    duration = 20.0 if quick else None
    maneuver = profile_maneuver("homework")
    t0 = time.perf_counter()
    plain = run_mission("stage_4", maneuver, 1, duration=duration)
    plain_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        bag_dir = Path(tmp) / "bag"
        t0 = time.perf_counter()
        with MissionBag(bag_dir, mission={"world": "stage_4", "maneuver": maneuver, "seed": 1}) as bag:
            run_mission("stage_4", maneuver, 1, duration=duration, sink=bag)
        recorded_s = time.perf_counter() - t0
        size = sum(f.stat().st_size for f in bag_dir.iterdir())
        t0 = time.perf_counter()
        record = read_bag(bag_dir)
        read_s = time.perf_counter() - t0
        stats = write_video(record, Path(tmp) / "mission.mp4", FPS, world_of(record))
    print(f"  {record.duration:.1f} s mission -> {stats.frames} frames in {stats.seconds:.1f} s "
          f"({1000 * stats.seconds / max(stats.frames, 1):.1f} ms/frame); bag {size / 1e6:.1f} MB", flush=True)
    return {"mission_s": round(record.duration, 2), "fps": FPS, "frames": stats.frames,
            "render_s": round(stats.seconds, 2), "ms_per_frame": round(1000 * stats.seconds / max(stats.frames, 1), 2),
            "lockstep_s": round(plain_s, 3), "lockstep_with_bag_s": round(recorded_s, 3),
            "bag_mb": round(size / 1e6, 2), "read_s": round(read_s, 3), "sim_time_s": round(plain.sim_time, 2)}


def targets(result: dict[str, Any]) -> list[Target]:
    """Render time of a 55 s mission at 10 fps (scaled to 55 s when the mission was shorter)."""
    scaled = result["render_s"] * 55.0 / max(result["mission_s"], 1e-9)
    return [Target("video_render_55s", "video", "render + encode a 55 s mission at 10 fps (H.264, 1280x720)",
                   f"<= {RENDER_LIMIT_S:g} s", round(scaled, 2), "s", at_most(scaled, RENDER_LIMIT_S))]
