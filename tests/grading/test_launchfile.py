"""The launch file read statically (bt_nav.grading.launchfile): the lab sheet's Task 3 checked on launch files
written the many ways students write them (tests/fixtures/launch), and odd files never crash the reader."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_nav.grading.launchfile import DECLARES, PASSES, STARTS, LaunchReport, check_launch

LAUNCH = Path(__file__).resolve().parents[1] / "fixtures" / "launch"
NODE = Path("reactive_navigator.py")

#: fixture -> (starts the node, declares safety_distance 0.5, passes it to the node)
EXPECTED = {
    "sheet": (True, True, True),
    "variables_add_action": (True, True, True),
    "plain_list": (True, True, True),
    "group_star": (True, True, True),
    "helper_function": (True, True, True),
    "execute_process": (True, True, True),
    "forgets_safety": (True, False, False),
    "hardcoded_value": (True, False, False),
    "wrong_executable": (False, True, False),
    "not_returned": (False, True, False),
    "other_config": (True, False, False),
    "no_function": (False, False, False),
}


def _verdicts(report: LaunchReport) -> tuple[bool, ...]:
    assert [c.name for c in report.checks] == [STARTS, DECLARES, PASSES]
    return tuple(c.passed for c in report.checks)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_launch_file_gets_the_sheets_three_checks(name: str) -> None:
    report = check_launch(LAUNCH / f"{name}.launch.py", NODE)
    assert _verdicts(report) == EXPECTED[name], report.lines()
    assert report.file == f"{name}.launch.py"
    assert all(line.startswith("launch file: ") and ("PASSED" in line or "FAILED" in line) for line in report.lines())


def test_every_fixture_is_in_the_table() -> None:
    assert sorted(p.name.removesuffix(".launch.py") for p in LAUNCH.glob("*.launch.py")) == sorted(EXPECTED)


def test_the_reasons_name_what_is_wrong_and_where() -> None:
    forgot = check_launch(LAUNCH / "forgets_safety.launch.py", NODE)
    assert forgot.lines() == [
        "launch file: starts the node: PASSED (line 7: Node(package='my_package', executable='reactive_navigator'))",
        "launch file: declares safety_distance (default 0.5): FAILED (no DeclareLaunchArgument('safety_distance', "
        "default_value='0.5'))",
        "launch file: passes safety_distance to the node: FAILED (line 7: the Node has no parameters=[...])"]
    hard = {c.name: c for c in check_launch(LAUNCH / "hardcoded_value.launch.py", NODE).checks}
    assert hard[DECLARES].reason == "default_value is '0.3', the sheet asks 0.5" and hard[DECLARES].line == 8
    assert hard[PASSES].reason.startswith("safety_distance is given 0.5, not LaunchConfiguration('safety_distance')")
    built = {c.name: c for c in check_launch(LAUNCH / "not_returned.launch.py", NODE).checks}
    assert "not return it in the launch description" in built[STARTS].reason and built[STARTS].line == 9
    wrong = {c.name: c for c in check_launch(LAUNCH / "wrong_executable.launch.py", NODE).checks}
    assert wrong[STARTS].reason == "its Node runs executable 'turtlesim_node', not reactive_navigator or " \
                                   "reactive_navigator.py"


def test_the_node_is_matched_by_the_sheets_name_or_the_students_own(tmp_path: Path) -> None:
    assert check_launch(LAUNCH / "sheet.launch.py", Path("pkg/my_nav.py")).passed
    own = tmp_path / "own.launch.py"
    own.write_text((LAUNCH / "sheet.launch.py").read_text().replace("executable='reactive_navigator'",
                                                                     "executable='my_nav'"))
    assert check_launch(own, Path("pkg/my_nav.py")).passed
    assert not check_launch(own, NODE).checks[0].passed
    assert check_launch(LAUNCH / "wrong_executable.launch.py", Path("my_nav.py")).checks[0].reason == \
        "its Node runs executable 'turtlesim_node', not my_nav or my_nav.py or reactive_navigator or " \
        "reactive_navigator.py"


def test_no_launch_file_is_one_failed_line() -> None:
    report = check_launch(None, NODE)
    assert not report.passed and report.file is None
    assert report.lines() == ["launch file: FAILED (no launch file handed in (expected turtlebot_bringup.launch.py))"]


@pytest.mark.parametrize(("content", "said"), [
    (b"def generate_launch_description()\n    return []\n", "is not valid Python: expected ':'"),
    (b"\x00\x01binary", "is not valid Python: source code string cannot contain null bytes"),
    (b"", "no generate_launch_description() function"),
    (b"def generate_launch_description():\n    return make()\n", "no launch_ros.actions.Node"),
    (b"import x\ndef generate_launch_description():\n    a = a\n    return x.y(*a, **{})\n", "no launch_ros"),
])
def test_odd_files_fail_with_a_reason_and_never_crash(tmp_path: Path, content: bytes, said: str) -> None:
    path = tmp_path / "turtlebot_bringup.launch.py"
    path.write_bytes(content)
    report = check_launch(path, NODE)
    assert not report.passed
    assert said in " ".join(report.lines()), report.lines()


def test_the_report_survives_its_json_record() -> None:
    report = check_launch(LAUNCH / "hardcoded_value.launch.py", NODE)
    assert LaunchReport.from_dict(report.to_dict()) == report
