"""The launch-file checker's edges (bt_nav.grading.launch.check): the reasons' words and lines, the node matched by
its name, odd files never crashing it, a file that hangs, the static reader as the fallback, the JSON record. The
suite of right and wrong files is tests/grading/test_launch_suite.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_nav.grading.launch import DECLARES, PASSES, STARTS, LaunchReport, check_launch
from bt_nav.grading.launch.static import read_statically

LAUNCH = Path(__file__).resolve().parents[1] / "fixtures" / "launch"
NODE = Path("reactive_navigator.py")

def test_the_reasons_name_what_is_wrong_and_where() -> None:
    forgot = check_launch(LAUNCH / "forgets_safety.launch.py", NODE)
    assert forgot.lines() == [
        "launch file: starts the node: PASSED (forgets_safety.launch.py:7: Node(package='my_package', "
        "executable='reactive_navigator'))",
        "launch file: declares safety_distance (default 0.5): FAILED (no DeclareLaunchArgument('safety_distance', "
        "default_value='0.5'))",
        "launch file: passes safety_distance to the node: FAILED (forgets_safety.launch.py:7: the Node has no "
        "parameters=[...])"]
    wrong = {c.name: c for c in check_launch(LAUNCH / "wrong_default.launch.py", NODE).checks}
    assert wrong[DECLARES].reason == "default_value is '0.3', the sheet asks 0.5" and wrong[DECLARES].line == 9
    hard = {c.name: c for c in check_launch(LAUNCH / "hardcoded_value.launch.py", NODE).checks}
    assert hard[PASSES].passed and hard[PASSES].line == 10
    assert hard[DECLARES].reason.startswith("`safety_distance:=0.7` would not reach the node: the launch argument "
                                            "is declared at hardcoded_value.launch.py:8 but the node is given 0.5")
    built = {c.name: c for c in check_launch(LAUNCH / "not_returned.launch.py", NODE).checks}
    assert "not return it in the launch description" in built[STARTS].reason and built[STARTS].line == 9
    exe = {c.name: c for c in check_launch(LAUNCH / "wrong_executable.launch.py", NODE).checks}
    assert exe[STARTS].reason == "its Node runs executable 'turtlesim_node', not navigator or reactive_navigator " \
                                 "or reactive_navigator.py"  # navigator: the fixtures' setup.py console script


def test_a_constant_passes_the_value_but_not_the_argument(tmp_path: Path) -> None:
    """The lead's case: ``parameters=[{'safety_distance': 0.5}]`` alone."""
    path = tmp_path / "turtlebot_bringup.launch.py"
    path.write_text("from launch import LaunchDescription\nfrom launch_ros.actions import Node\n\n\n"
                    "def generate_launch_description():\n    return LaunchDescription([Node(\n"
                    "        package='my_package', executable='reactive_navigator',\n"
                    "        parameters=[{'safety_distance': 0.5}])])\n")
    checks = {c.name: c for c in check_launch(path, NODE).checks}
    assert checks[PASSES].passed and (checks[PASSES].file, checks[PASSES].line) == (path.name, 8)
    assert not checks[DECLARES].passed
    assert checks[DECLARES].reason == "`safety_distance:=0.7` would not reach the node; declare a launch argument"


def test_a_file_that_hangs_is_killed_and_not_checked(tmp_path: Path) -> None:
    path = tmp_path / "turtlebot_bringup.launch.py"
    path.write_text((LAUNCH / "sheet.launch.py").read_text() + "\n\nwhile True:\n    pass\n")
    report = check_launch(path, NODE, limit=1.0)
    assert report.passed and not report.checked
    assert all(c.status == "NOT CHECKED" for c in report.checks), report.lines()
    assert "did not finish describing itself within 1 s (killed)" in report.checks[0].reason
    assert "read statically: passed" in report.checks[0].reason  # what the TA is told the source says


def test_the_file_runs_in_the_hand_in_folder_without_network(tmp_path: Path) -> None:
    """Working directory the hand-in, sockets refused, nothing written beside the file."""
    path = tmp_path / "turtlebot_bringup.launch.py"
    path.write_text("import os, socket\n"
                    "open('cwd.txt', 'w').write(os.getcwd())\n"
                    "socket.socket()\n" + (LAUNCH / "sheet.launch.py").read_text())
    report = check_launch(path, NODE)
    assert (tmp_path / "cwd.txt").read_text() == str(tmp_path.resolve())
    assert not report.checked and "no network while a launch file is evaluated" in report.checks[0].reason
    assert not (tmp_path / "__pycache__").exists()


def test_the_static_reader_is_the_fallback() -> None:
    """Where the evaluation cannot answer, what the source shows is said; its passes stand, the rest is for a TA."""
    static = read_statically(LAUNCH / "sheet.launch.py", NODE)
    assert static.passed and [c.name for c in static.checks] == [STARTS, DECLARES, PASSES]


def test_the_node_is_matched_by_the_sheets_name_or_the_students_own(tmp_path: Path) -> None:
    assert check_launch(LAUNCH / "sheet.launch.py", Path("pkg/my_nav.py")).passed
    own = tmp_path / "own.launch.py"
    own.write_text((LAUNCH / "sheet.launch.py").read_text().replace("executable='reactive_navigator'",
                                                                     "executable='my_nav'"))
    assert check_launch(own, Path("pkg/my_nav.py")).passed
    assert not check_launch(own, NODE).checks[0].passed
    assert check_launch(LAUNCH / "wrong_executable.launch.py", Path("my_nav.py")).checks[0].reason == \
        "its Node runs executable 'turtlesim_node', not my_nav or my_nav.py or navigator or reactive_navigator or " \
        "reactive_navigator.py"


def test_no_launch_file_is_one_failed_line() -> None:
    report = check_launch(None, NODE)
    assert not report.passed and report.file is None
    assert report.lines() == ["launch file: FAILED (no launch file handed in (expected turtlebot_bringup.launch.py))"]


@pytest.mark.parametrize(("content", "said"), [
    (b"def generate_launch_description()\n    return []\n", "is not valid Python: expected ':'"),
    (b"\x00\x01binary", "is not valid Python: source code string cannot contain null bytes"),
    (b"", "no generate_launch_description() function"),
    (b"def generate_launch_description():\n    return make()\n", "raised NameError"),
    (b"import x\ndef generate_launch_description():\n    a = a\n    return x.y(*a, **{})\n", "No module named"),
    (b"from launch import LaunchDescription\ndef generate_launch_description():\n    return LaunchDescription()\n",
     "no launch_ros.actions.Node"),
])
def test_odd_files_fail_with_a_reason_and_never_crash(tmp_path: Path, content: bytes, said: str) -> None:
    path = tmp_path / "turtlebot_bringup.launch.py"
    path.write_bytes(content)
    report = check_launch(path, NODE)
    assert not (report.passed and report.checked), "failed, or not checked where the grader cannot follow it"
    assert said in " ".join(report.lines()), report.lines()


def test_the_report_survives_its_json_record() -> None:
    for name in ("hardcoded_value", "command_default"):
        report = check_launch(LAUNCH / f"{name}.launch.py", NODE)
        assert LaunchReport.from_dict(report.to_dict()) == report
