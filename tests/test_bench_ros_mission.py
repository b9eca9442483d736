"""The ROS mission benchmark's bookkeeping (bench/ros_mission.py), without DDS: the executive's tick statistics
come from the JSON it writes to its ``stats_path``, not from its log lines."""

from __future__ import annotations

from collections import deque
from pathlib import Path
from types import SimpleNamespace

from bench.ros_mission import EXECUTIVE_STATS, _summarise, executive_stats


def test_the_tick_statistics_come_from_the_executives_stats_file(tmp_path: Path) -> None:
    path = tmp_path / EXECUTIVE_STATS
    path.write_text('{"tick_stats": "tick ms min/mean/p99/max 0.10/0.20/0.40/0.90 over 1400", "durations": 1400, '
                    '"ticks": 1400}\n')
    rec = SimpleNamespace(t=[0.0, 1.0, 2.0], wall=[0.0, 0.1, 0.2])
    results = {"times": {"t0": 0.0, "report": 2.0}, "checks": [{"name": "static at the end", "passed": False}]}
    logs = {"executive": deque(["[INFO] [1.0] [bt_nav_executive]: final stats: tick ms min/mean/p99/max "
                                "9.00/9.00/9.00/9.00 over 7; ticks 7"])}  # words for people: not read
    out: dict = {}
    _summarise(out, rec, results, logs, executive_stats(path))
    assert out["executive_tick_stats"] == "tick ms min/mean/p99/max 0.10/0.20/0.40/0.90 over 1400"
    assert out["executive_ticks"] == 1400
    assert out["rtf"] == 10.0 and out["failed_checks"] == ["static at the end"]
    empty: dict = {}
    _summarise(empty, rec, results, logs, executive_stats(tmp_path / "none.json"))  # the executive was killed
    assert empty["executive_tick_stats"] is None and empty["executive_ticks"] is None
