"""``stats_path``: the executive writes its exit statistics (those of its ``final stats`` log line) as JSON, the
benchmarks' source (bench/ros_mission.py, bench/latency.py) instead of the log line."""

from __future__ import annotations

import json
import signal
from collections.abc import Callable
from pathlib import Path

from ros_harness import Harness

from bt_nav.testing import front_scan, laserscan_msg


def test_stats_path_holds_the_exit_statistics(executive: Callable[..., Harness], tmp_path: Path) -> None:
    stats = tmp_path / "stats.json"
    h = executive("-p", f"stats_path:={stats}")
    assert h.arm(True).success
    h.ticks(3, scan=laserscan_msg(front_scan()))
    assert not stats.exists(), "written on the way out"
    h.process.proc.send_signal(signal.SIGINT)
    assert h.process.wait_exit(10.0, step=h.spin) == 0
    record = json.loads(stats.read_text(encoding="utf-8"))
    assert record["ticks"] >= 3 and record["durations"] == record["ticks"]
    assert record["tick_stats"].startswith("tick ms min/mean/p99/max ")
    assert record["tick_stats"].endswith(f" over {record['durations']}")
    assert {"overruns", "period_ms", "exceptions", "vetoed_commands", "scans", "dropped_scans", "evaluation_calls",
            "watchdog_stops"} <= set(record)
    assert record["scans"] >= 3 and record["exceptions"] == 0
