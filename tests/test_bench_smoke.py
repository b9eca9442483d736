"""Smoke test of the benchmark code (not of bt_nav's speed): ``bench.run --quick`` runs and writes its files.

Only the benchmarks without DDS run (``--only tick,sim --no-dds``), into a temporary directory, so the
committed ``bench/results`` stay untouched. Timings are never asserted on: a test that fails because
the machine is busy would teach people to ignore failures. What is checked is the structure the
README and later comparisons rely on: every target has a value and a verdict, every row its fields.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_quick_run_writes_json_and_markdown(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.run([sys.executable, "-m", "bench.run", "--quick", "--only", "tick,sim", "--no-dds",
                           "--out", str(tmp_path)], cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr

    doc = json.loads((tmp_path / "latest.json").read_text(encoding="utf-8"))
    assert doc["schema"] == 1
    assert doc["run"]["mode"] == "quick" and doc["run"]["only"] == ["tick", "sim"] and doc["run"]["no_dds"]
    for key in ("cpu", "cores", "python", "numpy", "py_trees"):
        assert doc["machine"][key], key
    assert set(doc["benchmarks"]) == {"tick", "sim"}
    for section in doc["benchmarks"].values():
        assert "error" not in section, section.get("traceback")
        assert section["quick"] is True and section["measured_at"]

    tick = doc["benchmarks"]["tick"]["result"]
    assert [row["beams"] for row in tick["rows"]] == [360, 1440, 4096]
    for row in tick["rows"]:
        for key in ("tree_ms", "tree_cpu_ms", "baseline_ms"):
            assert row[key]["n"] == row["ticks"] > 0
            assert 0 < row[key]["p50"] <= row[key]["p99"]
        assert row["ratio_p50"] > 0 and isinstance(row["meets_target"], bool)
    assert tick["profile"]["top_own_time"] and tick["profile"]["area_share"]
    assert tick["already_removed"]

    sim = doc["benchmarks"]["sim"]["result"]
    assert sim["lidar"]["beams"] == 360 and sim["lidar"]["scans_per_s"] > 0
    assert len(sim["lockstep"]["runs"]) == sim["lockstep"]["seeds"] > 0
    assert all(run["sim_s"] > 0 and run["wall_s"] > 0 for run in sim["lockstep"]["runs"])
    assert sim["lockstep"]["profile"]["inclusive_s"]["core.py:tick"] > 0
    assert "skipped" in sim["ros"]

    targets = {t["id"]: t for t in doc["targets"]}
    assert {"tick_p99_360", "tick_p99_1440", "tick_p99_4096", "lidar_scans_per_s", "lockstep_mission_wall",
            "ros_rtf"} <= set(targets)
    for target in targets.values():
        assert set(target) == {"id", "benchmark", "description", "goal", "value", "unit", "met"}
        assert target["met"] in (True, False, None)
        assert (target["met"] is None) == (target["value"] is None), target
    assert targets["ros_rtf"]["met"] is None  # skipped, so neither met nor missed

    md = (tmp_path / "latest.md").read_text(encoding="utf-8")
    assert doc["machine"]["cpu"] in md
    for heading in ("## Machine", "## Targets", "## 1. Tick cost", "## 3. Simulator throughput"):
        assert heading in md, heading
    assert "| 4096 |" in md
