"""A folder of hand-ins is a class (bt_nav.grading.handins): the node and the launch file found per student, the
launch checks in each student's verdict, class.json/class.md, and one feedback.md each. The runs are replaced by a
recorder here; the same class over real DDS is tests/ros/test_grade_handins_dds.py."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading import classroom
from bt_nav.grading.handin_files import find_node
from bt_nav.grading.handins import is_submission, read_handins, student_name

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
LAUNCH = FIXTURES / "launch"
NODE_SOURCE = "import rclpy\nfrom rclpy.node import Node\n\n# CHOICE: C\nclass Nav(Node):\n    pass\n"


def _hand_in(folder: Path, node: str | None = "reactive_navigator.py", launch: str | None = "sheet") -> Path:
    folder.mkdir(parents=True)
    if node is not None:
        (folder / node).parent.mkdir(parents=True, exist_ok=True)
        (folder / node).write_text(NODE_SOURCE)
    if launch is not None:
        shutil.copy(LAUNCH / f"{launch}.launch.py", folder / "turtlebot_bringup.launch.py")
    return folder


def test_the_node_is_the_labs_name_else_the_one_rclpy_node(tmp_path: Path) -> None:
    named = _hand_in(tmp_path / "a", "src/pkg/pkg/reactive_navigator.py")
    (named / "build").mkdir()
    (named / "build" / "reactive_navigator.py").write_text(NODE_SOURCE)  # colcon's copy: skipped
    assert find_node(named) == (named / "src/pkg/pkg/reactive_navigator.py", None)
    other = _hand_in(tmp_path / "b", "my_nav.py")
    (other / "helpers.py").write_text("def f():\n    return 1\n")
    assert find_node(other) == (other / "my_nav.py", None)
    import_style = _hand_in(tmp_path / "c", None)
    (import_style / "nav.py").write_text("import rclpy.node as rn\n\nclass N(rn.Node):\n    pass\n")
    assert find_node(import_style) == (import_style / "nav.py", None)


def test_no_usable_node_names_what_was_found(tmp_path: Path) -> None:
    empty = _hand_in(tmp_path / "a", None)
    assert find_node(empty)[1] == ("no reactive_navigator.py and no Python file defining an rclpy Node (no Python "
                                   "file)")
    two = _hand_in(tmp_path / "b", "one.py")
    (two / "two.py").write_text(NODE_SOURCE)
    assert find_node(two)[1] == ("no reactive_navigator.py, and 2 Python files define an rclpy Node (one.py, "
                                 "two.py): name the node's reactive_navigator.py")
    broken = _hand_in(tmp_path / "c", None)
    (broken / "nav.py").write_text("class N(Node:\n")
    assert find_node(broken)[1].endswith("(Python files: nav.py; not valid Python: nav.py)")


def test_a_folder_is_one_submission_or_a_folder_of_students(tmp_path: Path) -> None:
    single = _hand_in(tmp_path / "submission")
    assert is_submission(single) and [h.name for h in read_handins(single)] == ["submission"]
    klass = tmp_path / "export"
    for name in ("Ann Lee_1234_assignsubmission", "bob", ".git"):
        _hand_in(klass / name)
    handins = read_handins(klass)
    assert not is_submission(klass)
    assert [h.name for h in handins] == ["Ann_Lee_1234_assignsubmission", "bob"]
    assert student_name("bob", {"bob"}) == "bob_2"
    with pytest.raises(ValueError, match="no hand-ins"):
        read_handins(_hand_in(tmp_path / "nothing", None, None).parent / "nothing")


def _four(tmp_path: Path) -> Path:
    """The issue's class: two complete hand-ins, one whose launch file forgets safety_distance, one without one;
    and a fifth with no node at all."""
    klass = tmp_path / "hand-ins"
    _hand_in(klass / "ann")
    _hand_in(klass / "bob", "my_navigator.py", "variables_add_action")
    _hand_in(klass / "cy", launch="forgets_safety")
    _hand_in(klass / "dee", launch=None)
    return klass


def test_a_folder_of_hand_ins_gives_each_student_a_verdict_with_the_launch_lines(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
    """``bt-nav grade --class DIR``: every run passed (a recorder), so the launch file decides: ann and bob pass,
    cy (forgets safety_distance) and dee (no launch file) fail with the lines saying why, eve (no node) is not run."""
    from bt_nav.cli import grade

    klass = _four(tmp_path)
    _hand_in(klass / "eve", None)
    out = tmp_path / "out"
    graded: list[str] = []

    def passed_runs(students: list[Any], plan: Any, *rest: Any) -> dict[str, Any]:
        for s in students:
            graded.append(s.name)
            (out / s.name).mkdir(parents=True)
            row = {"job": "j", "world": "lab_object", "maneuver": "C", "lidar": "lds01", "seed": 0, "passed": True,
                   "outcome": "verdict", "reason": "passed", "run_dir": str(out / s.name / "run"),
                   "verdict": {"report_lines": ["no collision (0 collisions): PASSED", "overall: PASSED"]}}
            (out / s.name / "grade.json").write_text(json.dumps({"runs": [row]}))
        return {s.name: [{"passed": True}] for s in students}

    monkeypatch.setattr(classroom, "run_class", passed_runs)
    code = grade.main(["--class", str(klass), "--profile", "lab", "--worlds", "lab_object", "--lidars", "lds01",
                       "--seeds", "1", "--progress", "off", "--out", str(out)])
    stdout = capsys.readouterr().out
    assert code == 1 and graded == ["ann", "bob", "cy", "dee"], stdout
    assert f"  bob: node {klass / 'bob' / 'my_navigator.py'}" in stdout
    assert "  cy: launch file: declares safety_distance (default 0.5): FAILED (no DeclareLaunchArgument(" in stdout
    assert ("  dee: launch file: FAILED (no launch file handed in (expected turtlebot_bringup.launch.py))"
            in stdout.splitlines())
    assert f"  eve: FAILED (not run: no reactive_navigator.py and no Python file defining an rclpy Node (no " \
           f"Python file) in {klass / 'eve'})" in stdout.splitlines(), stdout
    assert "  ann: hand-in PASSED" in stdout.splitlines()
    assert ("  cy: hand-in FAILED (launch file: declares safety_distance (default 0.5), passes safety_distance to "
            "the node failed)") in stdout.splitlines()
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert {n: s["verdict"] for n, s in page.items()} == {"ann": "PASSED", "bob": "PASSED", "cy": "FAILED",
                                                         "dee": "FAILED", "eve": "FAILED"}
    assert [c["passed"] for c in page["cy"]["handin"]["launch"]["checks"]] == [True, False, False]
    assert page["cy"]["passed"] == page["cy"]["runs"] == 1, "the runs' own verdicts stay as they were"
    md = (out / "class.md").read_text()
    assert "| student | hand-in | launch file | passed |" in md
    assert "| [cy](cy/report.html) | FAILED | 1/3 | 1/1 |" in md and "| [ann](ann/report.html) | PASSED | 3/3 |" in md
    assert "- launch file: FAILED (no launch file handed in (expected turtlebot_bringup.launch.py))" in md
    assert "launch file: passes safety_distance to the node: FAILED" in (out / "class.html").read_text()
    feedback = (out / "cy" / "feedback.md").read_text()
    assert feedback.startswith("# cy: FAILED\n")
    assert ("- passes safety_distance to the node: FAILED (turtlebot_bringup.launch.py:7: the Node has no "
            "parameters=[...])") in feedback
    assert "launch_ros not installed, the node was started as" in feedback
    assert "- **lab_object C lds01 seed 0: PASSED** (passed)" in feedback and "  - no collision" in feedback
    assert "add `DeclareLaunchArgument('safety_distance', default_value='0.5')`" in feedback
    assert (out / "ann" / "feedback.md").read_text().startswith("# ann: PASSED\n")
    assert "Not run: no reactive_navigator.py" in (out / "eve" / "feedback.md").read_text()


def test_the_result_api_reads_a_class_back(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """What the Gradescope and JUnit formats build on: one StudentResult per student."""
    from bt_nav.cli import grade
    from bt_nav.grading.handins import load_class

    klass = _four(tmp_path)
    monkeypatch.setattr(classroom, "run_class", lambda students, *rest: {})
    grade.main(["--class", str(klass), "--profile", "lab", "--worlds", "lab_object", "--lidars", "lds01",
                "--seeds", "1", "--progress", "off", "--out", str(tmp_path / "out")])
    results = {r.name: r for r in load_class(tmp_path / "out")}
    assert sorted(results) == ["ann", "bob", "cy", "dee"]
    assert results["ann"].choice == "C" and results["ann"].node == str(klass / "ann" / "reactive_navigator.py")
    assert results["ann"].launch is not None and results["ann"].launch.passed
    assert not results["dee"].launch.passed and results["dee"].reasons[-1].startswith("launch file:")
    assert not any(r.passed for r in results.values()), "no run ended: nobody passes"
    assert sys.executable  # the node runs on the grader's own Python (it has rclpy)
