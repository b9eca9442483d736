"""``bt-nav grade --class`` on a Dask cluster over real DDS: a class of three (two right C nodes, one turning half its
angle) graded through a real ``dask scheduler`` and two ``dask worker``s, one of them killed mid-class, gets the
verdicts of the same class graded here, per student and per run, the half-angle student's re-runs (at the grade's
speed and at 1x) among them; and no run of it ran in the grading process itself.

Every process a grade starts inherits a marker in its environment, so "no process survives" is checked over every
process of this machine.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path
from typing import Any

import psutil
import pytest
from dask_cluster import REPO, DaskProcesses, marked

from bt_nav.testing import wait_until

NODE = REPO / "tests" / "fixtures" / "lab_student_node.py"
MARK = "BT_NAV_TEST_CLASS_MARK"
#: How the check-off judge details a check it had no samples for: nothing about the node (a starved judge).
NO_DATA = "no ground truth"
STUDENTS = {"ann": "--choice C", "bob": "--choice C --mistake half_angle", "cy": "--choice C --variant c_stands_05"}


def _env(mark: str) -> dict[str, str]:
    return {**os.environ, MARK: mark, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def _grade(manifest: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "bt_nav.cli", "grade", "--class", str(manifest), "--profile", "lab", "--maneuvers",
            "C", "--worlds", "lab_object", "--lidars", "lds01", "--seeds", "1", "--record", "off", "--out", str(out),
            *extra]


def _marked(mark: str) -> list[psutil.Process]:
    """Every live process carrying ``mark`` in its environment."""
    return marked(MARK, mark)


def _nodes(root: psutil.Process) -> list[psutil.Process]:
    """The student nodes below ``root`` (one per run underway there)."""
    try:
        return [p for p in root.children(recursive=True) if NODE.name in " ".join(p.cmdline())]
    except psutil.Error:
        return []


def _run_verdict(row: dict[str, Any]) -> tuple[Any, ...]:
    """What must not depend on where a run ran: its outcome, each check the judge could evaluate (a check without
    samples says nothing of the node), ``passed`` when it could evaluate them all, and the re-run rule's decision.
    The maneuvers count as one check, passed when each passed: how many a wrong node makes before the schedule's
    end (bob's half turns: 20 in one run, 22 in its twin) is its own timing, as fast as it keeps up, not where it
    ran."""
    checks = [c for c in (row.get("verdict") or {}).get("checks", [])
              if not str(c.get("detail", "")).startswith(NO_DATA)]
    turns = [c["passed"] for c in checks if c["name"].startswith("maneuver ")]
    judged = tuple([(c["name"], c["passed"]) for c in checks if not c["name"].startswith("maneuver ")]
                   + ([("maneuvers", all(turns))] if turns else []))
    passed = row["passed"] if len(judged) == len(checks) else "unjudged"
    return row["outcome"], judged, passed, (row.get("rerun") or {}).get("decision")


def _verdicts(out: Path) -> dict[str, dict[str, tuple[Any, ...]]]:
    """Per student, per run: :func:`_run_verdict`, read from each student's grade.json."""
    return {name: {row["job"]: _run_verdict(row) for row in json.loads((out / name / "grade.json").read_text())["runs"]}
            for name in STUDENTS}


def _same(a: tuple[Any, ...], b: tuple[Any, ...]) -> bool:
    """Two runs' verdicts agree where both judges judged."""
    both = {name for name, _ in a[1]} & {name for name, _ in b[1]}
    return a[0] == b[0] and a[3] == b[3] and [c for c in a[1] if c[0] in both] == [c for c in b[1] if c[0] in both] \
        and ("unjudged" in (a[2], b[2]) or a[2] == b[2])


class LocalRunWatch(threading.Thread):
    """Notes every student node ever seen below the grading process (none may be: on a cluster it runs nothing)."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.root, self.seen, self.done = psutil.Process(pid), set[str](), threading.Event()

    def run(self) -> None:
        while not self.done.is_set():
            self.seen.update(" ".join(p.cmdline()) for p in _nodes(self.root))
            time.sleep(0.2)


@pytest.mark.suite
def test_a_class_on_dask_gives_the_local_verdicts_despite_a_killed_worker(tmp_path: Path) -> None:
    mark = uuid.uuid4().hex
    manifest = tmp_path / "class.yaml"
    manifest.write_text("".join(f"{name}: {sys.executable} {NODE} {flags}\n" for name, flags in STUDENTS.items()))
    cluster = DaskProcesses(tmp_path, workers=2, nthreads=1, env=_env(mark), cwd=tmp_path)  # not the grade's cwd
    grade: subprocess.Popen[str] | None = None
    started = time.monotonic()
    try:
        grade = subprocess.Popen(_grade(manifest, tmp_path / "dask", "--scheduler", str(cluster.file)), cwd=REPO,
                                 env=_env(mark), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 start_new_session=True)
        watch = LocalRunWatch(grade.pid)
        watch.start()
        victim = psutil.Process(cluster.workers[0].pid)
        wait_until(lambda: bool(_nodes(victim)) or grade.poll() is not None, 180, "a run on worker 0", interval=0.1)
        assert grade.poll() is None, "the class ended before a run started on worker 0"
        orphans = victim.children(recursive=True)
        time.sleep(1.0)  # mid-run
        os.killpg(cluster.workers[0].pid, signal.SIGKILL)
        _, alive = psutil.wait_procs(orphans, timeout=15)
        assert not alive, f"the killed worker's run outlived it: {alive}"
        stdout, stderr = grade.communicate(timeout=900)
        watch.done.set()
    finally:
        if grade is not None and grade.poll() is None:
            os.killpg(grade.pid, signal.SIGKILL)
        cluster.close()
    dask_wall = time.monotonic() - started
    print(stdout, stderr, f"Dask class: {dask_wall:.0f} s wall", sep="\n")
    assert grade.returncode == 1, stdout + stderr  # bob fails
    assert not watch.seen, f"runs ran in the grading process, not on the cluster: {watch.seen}"
    assert f"a class of 3 in {tmp_path / 'dask'}/ on {cluster.file}: " in stdout, stdout
    dirs = [p.parent.name for p in (tmp_path / "dask").glob("*/*/result.json")]
    assert any(d.endswith("-2") for d in dirs), f"the killed worker's run was not run again: {dirs}"
    rerun = tmp_path / "dask" / "bob"
    assert any(rerun.glob("rerun/*/result.json")) and any(rerun.glob("realtime/*/result.json")), \
        "bob's failure was not run again at the grade's speed and at 1x"

    local = subprocess.run(_grade(manifest, tmp_path / "local", "--jobs", "2"), cwd=REPO, env=_env(mark),
                           capture_output=True, text=True, timeout=900)
    assert local.returncode == 1, local.stdout + local.stderr
    dask, here = _verdicts(tmp_path / "dask"), _verdicts(tmp_path / "local")
    assert {n: set(v) for n, v in dask.items()} == {n: set(v) for n, v in here.items()}, (dask, here)
    for name in STUDENTS:
        for job, verdict in dask[name].items():
            assert _same(verdict, here[name][job]), f"{name} {job}: Dask {verdict}, local {here[name][job]}"
    page = {s["name"]: (s["passed"], s["runs"]) for s in json.loads((tmp_path / "dask" / "class.json").read_text())
            ["students"]}
    assert page == {s["name"]: (s["passed"], s["runs"])
                    for s in json.loads((tmp_path / "local" / "class.json").read_text())["students"]}
    assert page == {"ann": (1, 1), "bob": (0, 1), "cy": (1, 1)}, page
    wait_until(lambda: not _marked(mark), 15, "every process of the classes to end")
