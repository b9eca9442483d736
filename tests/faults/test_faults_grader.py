"""Issue 52 over real DDS: the grader's own failures never decide a grade. Each case grades one cell of the right lab
node (``--rtf 0``, a preview: ~8 s) with one failure of bt_nav's own injected (:mod:`grader_faults`), beside two CPU
hogs: the cell ends in a verdict (after a re-run) or NOT GRADED with a one-line reason, never FAILED without a verdict,
and no traceback of bt_nav's reaches the grade's stdout or stderr."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
NODE = f"{sys.executable} {REPO / 'tests' / 'fixtures' / 'lab_student_node.py'} --choice C"
RUN = "lab_object C lds01 seed 0"


@pytest.fixture(scope="module")
def hogs() -> Iterator[list[subprocess.Popen]]:
    """Two CPU hogs for the module's grades (the machine they were seen on was busy), killed at its end."""
    started = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    yield started
    for hog in started:
        hog.kill()
        hog.wait(10)


def grade(fault: str, out: Path) -> tuple[subprocess.CompletedProcess[str], dict]:
    """``bt-nav grade`` of one cell with ``fault`` injected; the finished process and the cell's row."""
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}  # the grade claims its own domains
    done = subprocess.run([sys.executable, str(HERE / "grader_faults.py"), fault, "grade", "--profile", "lab", "--exe",
                           NODE, "--worlds", "lab_object", "--maneuvers", "C", "--lidars", "lds01", "--seeds", "1",
                           "--rtf", "0", "--record", "off", "--progress", "off", "--out", str(out)],
                          cwd=REPO, env=env, capture_output=True, text=True, check=False, timeout=240)
    print(done.stdout, done.stderr)
    [row] = json.loads((out / "grade.json").read_text())["runs"]
    return done, row


def assert_no_traceback(done: subprocess.CompletedProcess[str]) -> None:
    """Nothing of a traceback on the grade's terminal: its causes are one-line notes and reasons."""
    for stream in (done.stdout, done.stderr):
        assert "Traceback" not in stream and "Error: [Errno" not in stream, stream


@pytest.mark.slow
@pytest.mark.fault("grader", "fork server killed during its hello / its socket closed under a run / never says "
                             "hello / a simulator SIGTERMed by a sibling: a verdict after a re-run, no traceback")
@pytest.mark.parametrize("fault", ["server-killed-in-hello", "server-socket-closed", "server-never-hello",
                                   "sim-killed"])
def test_a_fault_of_the_graders_own_ends_in_a_verdict(fault: str, hogs: list[subprocess.Popen],
                                                      tmp_path: Path) -> None:
    done, row = grade(fault, tmp_path / "grid")
    assert_no_traceback(done)
    assert row["verdict"] is not None and row["passed"], row["reason"]  # the right node's verdict, not a guess
    assert f"{RUN}: PASSED" in done.stdout and done.returncode == 0, done.stdout
    notes = row.get("notes", [])
    if fault in ("server-socket-closed", "sim-killed"):  # its simulator went: the attempt set aside, run again
        [note] = [n for n in notes if "bt_nav's, not the node's" in n]
        assert ("the fork server it was forked from is gone" if fault == "server-socket-closed" else
                "stopped by SIGTERM from outside the run") in note, note
        assert "\n" not in note and f"note: {note}" in done.stdout
        assert Path(note.rsplit("that attempt: ", 1)[1].rstrip(")")).is_dir()
    else:  # the server never forked: the simulator started the usual way, at once
        assert not notes, notes


@pytest.mark.slow
@pytest.mark.fault("grader", "every simulator SIGTERMed by a sibling: NOT GRADED after two re-runs, one line, "
                             "exit 3, no traceback")
def test_a_fault_that_stays_leaves_the_cell_not_graded(hogs: list[subprocess.Popen], tmp_path: Path) -> None:
    done, row = grade("sim-killed-always", tmp_path / "grid")
    assert_no_traceback(done)
    said = row.get("not_graded") or ""
    assert said.startswith("not graded: no verdict in 3 attempts, each ended by bt_nav's own fault (last: the "
                           "simulator was stopped by SIGTERM from outside the run"), row
    assert not row["passed"] and row["outcome"] == "bt_nav error" and len(row["notes"]) == 2, row
    assert f"{RUN}: NOT GRADED (not graded: no verdict in 3 attempts" in done.stdout, done.stdout
    assert "FAILED" not in done.stdout and done.returncode == 3, done.stdout
    assert "not graded (not yours)" in (tmp_path / "grid" / "feedback.md").read_text()
