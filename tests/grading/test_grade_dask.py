"""Grading on a Dask cluster gives the same results as local processes, survives a killed worker, resumes.

Everything listens on 127.0.0.1 only, without dashboards.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading.grid import make_jobs, run_grid
from bt_nav.testing import wait_until
from tests.dask_cluster import REPO, DaskProcesses

WORLDS, MANEUVERS = ("stage_4", "corridor"), ("none", "B")


def _comparable(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """A run's result without the wall time it took (which is all the executor may change)."""
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]


@pytest.fixture(scope="module")
def local_rows() -> list[dict[str, Any]]:
    return run_grid(make_jobs(WORLDS, MANEUVERS, 2), processes=1)


def test_local_cluster_matches_local_processes(local_rows: list[dict[str, Any]]) -> None:
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        rows = run_grid(make_jobs(WORLDS, MANEUVERS, 2), scheduler=cluster.scheduler_address)
    assert len(rows) == 8
    assert _comparable(rows) == _comparable(local_rows)


def test_dask_cli_cluster_survives_a_killed_worker_and_resumes(tmp_path: Path,
                                                                local_rows: list[dict[str, Any]]) -> None:
    cluster = DaskProcesses(tmp_path)
    out = tmp_path / "grade.json"
    try:
        grade = subprocess.Popen([sys.executable, "-m", "bt_nav.cli", "grade", "--worlds", ",".join(WORLDS),
                                  "--maneuvers", ",".join(MANEUVERS), "--seeds", "2", "--scheduler", str(cluster.file),
                                  "--json", str(out), "--progress", "off"], cwd=REPO, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)

        def first_mission_in() -> bool:
            assert grade.poll() is None, "grade exited before a mission finished"
            return out.exists() and bool(json.loads(out.read_text())["runs"])

        wait_until(first_mission_in, 60, "a finished mission", interval=0.05)
        os.killpg(cluster.workers[0].pid, signal.SIGKILL)  # mid-grid: its running mission is lost
        stdout, stderr = grade.communicate(timeout=120)
    finally:
        cluster.close()
    assert grade.returncode in (0, 1), stdout + stderr
    data = json.loads(out.read_text())
    assert data["complete"] is True
    keys = [row["job"] for row in data["runs"]]
    assert len(keys) == len(set(keys)) == 8, "a run was lost or counted twice"
    assert _comparable(data["runs"]) == _comparable(local_rows)

    # Resume: drop half the runs as an interrupted grid would have, and finish locally.
    data["runs"] = data["runs"][:4]
    data["complete"] = False
    out.write_text(json.dumps(data))
    resumed = subprocess.run([sys.executable, "-m", "bt_nav.cli", "grade", "--worlds", ",".join(WORLDS),
                              "--maneuvers", ",".join(MANEUVERS), "--seeds", "2", "--json", str(out), "--resume",
                              "--progress", "off", "--jobs", "1"], cwd=REPO, capture_output=True, text=True,
                             timeout=120)
    assert "resuming: 4 of 8 missions" in resumed.stderr, resumed.stderr
    again = json.loads(out.read_text())
    assert again["complete"] and _comparable(again["runs"]) == _comparable(local_rows)
    assert [r["wall_time"] for r in again["runs"][:4]] == [r["wall_time"] for r in data["runs"]]  # not rerun
