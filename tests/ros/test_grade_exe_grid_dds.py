"""``bt-nav grade --exe`` grids over real DDS, as a user runs them: SIGTERM mid-grid leaves no process and a
report of the runs that ended, ``--resume`` runs only the others, and a grid on a Dask cluster (a worker
killed mid-run) gives the verdicts of the same grid run here.

Every process a grade starts inherits a marker in its environment, so "no process survives" is checked over
every process of this machine, not only the ones seen before the signal.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path
from typing import Any

import psutil
import pytest
from dask_cluster import REPO, DaskProcesses, marked

from bt_nav.testing import wait_until

FIXTURES = REPO / "tests" / "fixtures"
HOMEWORK = f"{sys.executable} {FIXTURES / 'homework_node.py'}"
CRASH = f"{sys.executable} {FIXTURES / 'crash_node.py'}"
MARK = "BT_NAV_TEST_GRID_MARK"


def _env(mark: str) -> dict[str, str]:
    return {**os.environ, MARK: mark, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def _grade(command: str, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "bt_nav.cli", "grade", "--exe", command, "--worlds", "stage_4",
            "--rtf", "0", "--realtime-check", "off", "--lidars", "profile", "--out", str(out),
            "--progress", "off", "--timeout", "120", *extra]


#: The compared grids run at 3x real time: a fraction of the CPU per wall second of the default (as fast as the node
#: keeps up), so that the judges of two runs at once keep up on a 2-core machine that other work shares.
COMPARED = ("--rtf", "3")
#: How the referee details a check it had no samples for (bt_nav/judge/referee_core.py).
NO_DATA = "no ground truth"


def _marked(mark: str) -> list[psutil.Process]:
    """Every live process carrying ``mark`` in its environment."""
    return marked(MARK, mark)


def _describe(procs: list[psutil.Process]) -> str:
    out = []
    for proc in procs:
        try:
            out.append(f"{proc.pid} {' '.join(proc.cmdline())[:160]}")
        except psutil.Error:
            continue
    return "\n".join(out)


def _nodes(root: psutil.Process) -> list[psutil.Process]:
    """The homework nodes below ``root`` (one per run underway)."""
    try:
        return [p for p in root.children(recursive=True) if "homework_node.py" in " ".join(p.cmdline())]
    except psutil.Error:
        return []


def test_sigterm_mid_grid_leaves_no_process_and_resume_runs_the_rest(tmp_path: Path) -> None:
    out, mark = tmp_path / "grid", uuid.uuid4().hex
    argv = _grade(HOMEWORK, out, "--seeds", "4", "--jobs", "2")
    grade = subprocess.Popen(argv, cwd=REPO, env=_env(mark), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
    try:
        root = psutil.Process(grade.pid)

        def later_runs_underway() -> bool:
            assert grade.poll() is None, "the grade ended before the signal"
            return any(out.glob("*/result.json")) and bool(_nodes(root))

        wait_until(later_runs_underway, 150, "a finished run and a later one underway", interval=0.1)
        before = root.children(recursive=True)
        grade.send_signal(signal.SIGTERM)
        stdout, stderr = grade.communicate(timeout=90)
    finally:
        if grade.poll() is None:
            os.killpg(grade.pid, signal.SIGKILL)
    assert grade.returncode == 128 + signal.SIGTERM, stdout + stderr
    gone, alive = psutil.wait_procs(before, timeout=5)
    assert not alive, f"survived the grade: {_describe(alive)}"
    assert not _marked(mark), f"processes of the grid left: {_describe(_marked(mark))}"

    results = [json.loads(p.read_text()) for p in sorted(out.glob("*/result.json"))]
    ended = sorted(r["job"] for r in results if r["outcome"] != "stopped")
    stopped = [r for r in results if r["outcome"] == "stopped"]
    assert ended and stopped, [(r["job"], r["outcome"]) for r in results]
    assert all(r["reason"] == "stopped by SIGTERM" for r in stopped)
    report = json.loads((out / "grade.json").read_text())
    assert sorted(r["job"] for r in report["runs"]) == ended, "the report holds exactly the runs that ended"
    assert "STOPPED (stopped by SIGTERM" in stdout and "--resume runs them" in stderr

    resumed = subprocess.run([*argv, "--resume"], cwd=REPO, env=_env(mark), capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode in (0, 1), resumed.stdout + resumed.stderr
    assert f"resuming: {len(ended)} of 4 runs" in resumed.stderr
    # grade.json's rows are result.json's plus the report's pictures and videos of the run ("media")
    again = {r["job"]: {k: v for k, v in r.items() if k != "media"}
             for r in json.loads((out / "grade.json").read_text())["runs"]}
    assert len(again) == 4 and all(r["outcome"] != "stopped" for r in again.values())
    kept = {r["job"]: r for r in results if r["job"] in ended}
    assert all(again[job] == kept[job] for job in ended), "a finished run ran again"
    assert not _marked(mark)


def _verdicts(out: Path) -> dict[str, Any]:
    """Per job: what must not depend on where a run ran: the outcome, each check the judge could evaluate, and
    ``passed`` when it could evaluate them all. A check the judge had no data for (``no ground truth over ...``:
    a judge starved of CPU on a loaded machine missed the samples of its window) says nothing about the node,
    so it is left out, and so is ``passed`` then."""
    rows = json.loads((out / "grade.json").read_text())["runs"]
    out_: dict[str, Any] = {}
    for r in rows:
        checks = (r["verdict"] or {}).get("checks", [])
        judged = [(c["name"], c["passed"]) for c in checks if not str(c.get("detail", "")).startswith(NO_DATA)]
        out_[r["job"]] = (r["outcome"], judged, r["passed"] if len(judged) == len(checks) else "unjudged")
    return out_


def _same(dask: dict[str, Any], local: dict[str, Any]) -> bool:
    """The same verdicts, where both sides judged (see :func:`_verdicts`)."""
    if dask.keys() != local.keys():
        return False
    for job in dask:
        (outcome_a, checks_a, passed_a), (outcome_b, checks_b, passed_b) = dask[job], local[job]
        both = {name for name, _ in checks_a} & {name for name, _ in checks_b}
        if outcome_a != outcome_b or [c for c in checks_a if c[0] in both] != [c for c in checks_b if c[0] in both]:
            return False
        if "unjudged" not in (passed_a, passed_b) and passed_a != passed_b:
            return False
    return True


@pytest.mark.suite
def test_a_dask_grid_gives_the_local_verdicts_despite_a_killed_worker(tmp_path: Path) -> None:
    mark = uuid.uuid4().hex
    cluster = DaskProcesses(tmp_path, workers=2, nthreads=1, env=_env(mark), cwd=tmp_path)  # not the grade's cwd
    grade: subprocess.Popen[str] | None = None
    try:
        grade = subprocess.Popen(_grade(HOMEWORK, tmp_path / "dask_hw", "--seeds", "2", *COMPARED, "--scheduler",
                                        str(cluster.file)), cwd=REPO, env=_env(mark), stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, start_new_session=True)
        victim = psutil.Process(cluster.workers[0].pid)
        wait_until(lambda: bool(_nodes(victim)) or grade.poll() is not None, 120, "a run on worker 0", interval=0.1)
        orphans = victim.children(recursive=True)
        time.sleep(1.0)  # mid-run
        os.killpg(cluster.workers[0].pid, signal.SIGKILL)
        _, alive = psutil.wait_procs(orphans, timeout=15)
        assert not alive, f"the killed worker's run outlived it: {_describe(alive)}"
        stdout, stderr = grade.communicate(timeout=300)
        assert grade.returncode in (0, 1), stdout + stderr
        crash = subprocess.run(_grade(CRASH, tmp_path / "dask_crash", "--seeds", "2", *COMPARED, "--scheduler",
                                      str(cluster.file)),
                               cwd=REPO, env=_env(mark), capture_output=True, text=True, timeout=200)
        assert crash.returncode == 1, crash.stdout + crash.stderr
    finally:
        if grade is not None and grade.poll() is None:
            os.killpg(grade.pid, signal.SIGKILL)
        cluster.close()
    rows = json.loads((tmp_path / "dask_hw" / "grade.json").read_text())["runs"]
    assert len(rows) == 2 and any(r["run_dir"].endswith("-2") for r in rows), "the lost run was not rerun"
    for name in ("hw", "crash"):
        command = HOMEWORK if name == "hw" else CRASH
        local = subprocess.run(_grade(command, tmp_path / f"local_{name}", "--seeds", "2", *COMPARED, "--jobs", "2"),
                               cwd=REPO, env=_env(mark), capture_output=True, text=True, timeout=300)
        assert local.returncode in (0, 1), local.stdout + local.stderr
        dask, here = _verdicts(tmp_path / f"dask_{name}"), _verdicts(tmp_path / f"local_{name}")
        assert _same(dask, here), f"Dask {dask}\nlocal {here}"
    assert all(outcome == "node exited" for outcome, _, _ in _verdicts(tmp_path / "dask_crash").values())
    hw = _verdicts(tmp_path / "dask_hw").values()
    assert all(("evaluation service called", True) in checks for _, checks, _ in hw), hw
    wait_until(lambda: not _marked(mark), 15, "every process of the grids to end", lambda: _describe(_marked(mark)))
