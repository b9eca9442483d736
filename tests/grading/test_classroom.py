"""A class's runs share one pool (bt_nav.grading.classroom.run_class): orchestration only, with the run and the
report replaced by recorders (the real runs over DDS are tests/ros/test_mutants.py's)."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading import classroom, report
from bt_nav.grading.classroom import Student, read_manifest, run_class
from bt_nav.grading.exe import grid as exe_grid


@dataclass(frozen=True)
class FakeJob:
    key: str


class FakeSettings(str):
    """A student's settings, named as the student: their grid runs at 1x, so no failure is checked again."""

    rtf = 1.0


class Recorder:
    """Stands in for one run: notes how many run at once, returns a row."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.running = 0
        self.most = 0
        self.started: list[str] = []
        self.reports: dict[str, list[str]] = {}

    def run(self, job: FakeJob, settings: Any, stop: Any) -> dict[str, Any]:
        with self.lock:
            self.running += 1
            self.most = max(self.most, self.running)
            self.started.append(job.key)
        time.sleep(0.05)
        with self.lock:
            self.running -= 1
        return {"job": job.key, "outcome": "verdict", "passed": job.key.endswith("ok")}

    def report(self, rows: list[dict[str, Any]], settings: Any) -> None:
        self.reports[settings] = [r["job"] for r in rows]


@pytest.fixture
def recorder(monkeypatch: pytest.MonkeyPatch) -> Recorder:
    rec = Recorder()
    monkeypatch.setattr(exe_grid, "run_unless_stopped", rec.run)  # what run_pool calls
    monkeypatch.setattr(exe_grid, "prepare_out", lambda settings, jobs, resume: {})
    monkeypatch.setattr(report, "write_exe_report", rec.report)
    return rec


def test_students_with_one_run_each_still_fill_every_worker(recorder: Recorder) -> None:
    students = [Student(f"s{i}", "cmd") for i in range(4)]
    plan = {s.name: (FakeSettings(s.name), [FakeJob(f"{s.name}-ok")]) for s in students}
    out = run_class(students, lambda s: plan[s.name], workers=2)
    assert recorder.most == 2  # two students' runs at once: one grid at a time would run one
    assert recorder.started[0] == "s0-ok" and sorted(recorder.started) == [f"s{i}-ok" for i in range(4)]
    assert {name: [r["job"] for r in rows] for name, rows in out.items()} == {f"s{i}": [f"s{i}-ok"] for i in range(4)}
    assert recorder.reports == {f"s{i}": [f"s{i}-ok"] for i in range(4)}  # one report per student


def test_a_students_rows_keep_their_jobs_order(recorder: Recorder) -> None:
    jobs = [FakeJob(f"a{i}-{'ok' if i % 2 else 'bad'}") for i in range(5)]
    out = run_class([Student("a", "cmd")], lambda s: (FakeSettings("a"), jobs), workers=3)
    assert [r["job"] for r in out["a"]] == [j.key for j in jobs]
    assert [r["passed"] for r in out["a"]] == [False, True, False, True, False]


def test_a_manifest_names_its_problem(tmp_path: Path) -> None:
    path = tmp_path / "class.yaml"
    path.write_text("alice: python3 a.py\nbob: python3 b.py\n")
    assert [s.name for s in read_manifest(path)] == ["alice", "bob"]
    path.write_text("al ice: python3 a.py\n")
    with pytest.raises(ValueError, match="letters, digits"):
        read_manifest(path)
    path.write_text("[]\n")
    with pytest.raises(ValueError):
        read_manifest(path)
    assert classroom.NAME.match("carol_1.x")


def test_a_class_says_once_which_arenas_cannot_check_its_maneuver(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                  capsys: pytest.CaptureFixture) -> None:
    """lab_object cannot check a Retreat off: a class of three hears it once, not once per student."""
    import sys

    from bt_nav.cli import grade

    node = tmp_path / "node.py"
    node.write_text("# CHOICE: B\n")
    manifest = tmp_path / "class.yaml"
    manifest.write_text("".join(f"{name}: {sys.executable} {node}\n" for name in ("ann", "bob", "cy")))
    planned: dict[str, int] = {}

    def no_runs(students: list[Student], plan: Any, *rest: Any) -> dict[str, Any]:
        planned.update({s.name: len(plan(s)[1]) for s in students})
        return {}

    monkeypatch.setattr(classroom, "run_class", no_runs)
    monkeypatch.setattr(classroom, "write_class_page", lambda *args: [])
    grade.main(["--class", str(manifest), "--profile", "lab", "--worlds", "lab_object,lab_dead_end",
                "--lidars", "lds01", "--seeds", "1", "--progress", "off", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert err.count("not checked off there: lab_object B") == 1, err
    assert planned == {"ann": 1, "bob": 1, "cy": 1}, "each student's grid keeps lab_dead_end"


def _entries(tmp_path: Path) -> dict[str, str]:
    """A class with one good lab node and one entry of each kind that cannot be graded."""
    import sys

    good, plain, binary = tmp_path / "good.py", tmp_path / "plain.py", tmp_path / "binary.py"
    good.write_text("# CHOICE: C\nprint('node')\n")
    plain.write_text("print('a node that declares no maneuver')\n")
    binary.write_bytes(b"PK\x03\x04\x00\x00word document")
    return {"ann": f"{sys.executable} {good}", "bob": f"{sys.executable} {tmp_path / 'bob.py'}",
            "cy": f"{sys.executable} {plain}", "dee": f"{sys.executable} {binary}", "eve": "",
            "fay": f"{sys.executable} {tmp_path}", "gus": f"{sys.executable} '{good}"}


def test_a_bad_entry_fails_only_its_student_naming_its_file(tmp_path: Path) -> None:
    entries = _entries(tmp_path)
    students = [Student(name, command) for name, command in entries.items()]
    admitted, refused = classroom.admit(students, True, lambda command: f"resolved {command}")
    assert admitted == {"ann": f"resolved {entries['ann']}"}
    assert refused == {
        "bob": f"{tmp_path / 'bob.py'} does not exist",
        "cy": f"{tmp_path / 'plain.py'} declares no maneuver (the lab template's '# CHOICE: X' line), and "
              "--maneuvers is not given",
        "dee": f"{tmp_path / 'binary.py'} is not a Python source file (it holds binary data)",
        "eve": "no command",
        "fay": f"{tmp_path} is not a file",
        "gus": f"command {entries['gus']!r} cannot be split into words: No closing quotation"}
    with_maneuvers, refused = classroom.admit(students, False, lambda command: command)
    assert set(with_maneuvers) == {"ann", "cy"}, refused  # --maneuvers given: no choice needed


def test_a_program_the_grader_refuses_fails_its_student(tmp_path: Path) -> None:
    def resolve(command: str) -> str:
        raise ValueError("--exe: program './nosuch' not found")

    admitted, refused = classroom.admit([Student("ann", "./nosuch")], True, resolve)
    assert admitted == {} and refused == {"ann": "program './nosuch' not found"}


def test_a_class_with_bad_entries_grades_the_others_and_shows_each_reason(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
    """``bt-nav grade --class``: the bad entries are failed students on the terminal, in class.json and class.md;
    the good one is graded; the exit code says a student failed."""
    import json

    from bt_nav.cli import grade

    entries = _entries(tmp_path)
    manifest = tmp_path / "class.yaml"
    manifest.write_text("".join(f"{name}: {json.dumps(command)}\n" for name, command in entries.items()))
    graded: list[str] = []

    def one_passed_run(students: list[Student], plan: Any, *rest: Any) -> dict[str, Any]:
        graded.extend(s.name for s in students)
        return {s.name: [{"passed": True}] for s in students}

    monkeypatch.setattr(classroom, "run_class", one_passed_run)
    out = tmp_path / "out"
    code = grade.main(["--class", str(manifest), "--profile", "lab", "--worlds", "lab_object", "--lidars", "lds01",
                       "--seeds", "1", "--progress", "off", "--out", str(out)])
    stdout = capsys.readouterr().out
    assert code == 1 and graded == ["ann"], stdout
    assert f"  bob: FAILED (not run: {tmp_path / 'bob.py'} does not exist)" in stdout.splitlines()
    assert f"  cy: FAILED (not run: {tmp_path / 'plain.py'} declares no maneuver" in stdout
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert page["bob"]["refused"] == f"{tmp_path / 'bob.py'} does not exist" and page["bob"]["passed"] == 0
    assert "refused" not in page["ann"]
    md = (out / "class.md").read_text()
    assert f"{tmp_path / 'binary.py'} is not a Python source file" in md
    assert "| bob | FAILED, not run |" in md and "bob/report.html" not in md  # a refused student has no report


def test_the_choice_is_read_from_the_file_the_command_runs(tmp_path: Path) -> None:
    from bt_nav.grading.exe.grid import declared_choice, node_file

    node = tmp_path / "node"  # no .py: python runs it all the same
    node.write_text("#  CHOICE:  C  (Smart Pivot)\n")
    assert node_file(f"python3 -X dev -u {node} --choice A") == node
    assert declared_choice(f"python3 {node}") == "C"
    assert node_file("python3 -m my_pkg.node") is None and node_file("ros2 run pkg node") is None
    assert node_file(f"./{node.name}.py --ros-args") == Path(f"./{node.name}.py")


