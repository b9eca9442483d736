"""The launch-file suite: the lab sheet's Task 3 checked as ``ros2 launch`` would run each file
(bt_nav.grading.launch.check), on right files written the many ways students write them and on wrong ones, each with
the verdict it must get and the words of its reason. The grader must pass every right file, fail every wrong one
for its reason, and say "not checked" (never "failed") where it cannot follow a file.

The fixtures are one hand-in folder (tests/fixtures/launch: its package.xml names the package ``my_package``, its
setup.py the node's console script ``navigator``, its params files and ``included/navigator.launch.py`` are found as
an installed share's would be).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_nav.grading.launch import DECLARES, PASSES, STARTS, check_launch

LAUNCH = Path(__file__).resolve().parents[1] / "fixtures" / "launch"
NODE = Path("reactive_navigator.py")
P, F, N, D = "PASSED", "FAILED", "NOT CHECKED", "DEPENDS"  # D: not checked, another failed

#: fixture -> (right or wrong, (starts, declares, passes), words the reason of the first check not passed says)
SUITE: dict[str, tuple[str, tuple[str, str, str], str]] = {
    # right: ros2 launch starts the node with safety_distance 0.5, and safety_distance:=0.7 reaches it
    "sheet": ("right", (P, P, P), ""),
    "parameter_value": ("right", (P, P, P), ""),
    "config_default": ("right", (P, P, P), ""),
    "str_default": ("right", (P, P, P), ""),
    "aliases": ("right", (P, P, P), ""),
    "variables_add_action": ("right", (P, P, P), ""),
    "module_style": ("right", (P, P, P), ""),
    "group_star": ("right", (P, P, P), ""),
    "helper_function": ("right", (P, P, P), ""),
    "helper_lists": ("right", (P, P, P), ""),
    "yaml_then_argument": ("right", (P, P, P), ""),
    "include": ("right", (P, P, P), ""),
    "opaque_function": ("right", (P, P, P), ""),
    "namespace_group": ("right", (P, P, P), ""),
    "python_expression": ("right", (P, P, P), ""),
    "conditions_timer": ("right", (P, P, P), ""),
    "ros_arguments": ("right", (P, P, P), ""),
    "execute_process": ("right", (P, P, P), ""),
    "console_script": ("right", (P, P, P), ""),  # setup.py's console script for the node's module
    # wrong: each for its reason
    "forgets_safety": ("wrong", (P, F, F), "no DeclareLaunchArgument('safety_distance'"),
    "hardcoded_value": ("wrong", (P, F, P), "`safety_distance:=0.7` would not reach the node"),
    "yaml_only": ("wrong", (P, F, P), "`safety_distance:=0.7` would not reach the node; declare a launch argument"),
    "wrong_default": ("wrong", (P, F, D), "default_value is '0.3', the sheet asks 0.5"),
    "declared_not_passed": ("wrong", (P, D, F), "is declared but never reaches the node"),
    "typo_name": ("wrong", (P, P, F), "the Node is given 'saftey_distance', not 'safety_distance' (a typo?)"),
    "remapping_string": ("wrong", (P, D, F), "is declared but never reaches the node"),
    "string_type": ("wrong", (P, P, F), "as the string '0.5'"),
    "wrong_executable": ("wrong", (F, P, D), "its Node runs executable 'turtlesim_node'"),
    "wrong_package": ("wrong", (F, P, P), "the hand-in's package is 'my_package'"),
    "other_console_script": ("wrong", (F, P, D), "its Node runs executable 'teleop', not navigator or"),
    "not_returned": ("wrong", (F, P, D), "does not return it in the launch description"),
    "condition_off": ("wrong", (F, P, D), "its Node's IfCondition is false with the default launch arguments"),
    "other_config": ("wrong", (F, F, F), "'safety_distance' has no default_value and was not given"),
    "undeclared_no_default": ("wrong", (F, F, F), "launch configuration 'safety_distance' does not exist"),
    "float_default": ("wrong", (F, F, F), "a float is not a string or substitution (TypeError)"),
    "plain_list": ("wrong", (F, F, F), "returns a list, not a LaunchDescription"),
    "no_function": ("wrong", (F, F, F), "no generate_launch_description() function"),
    # the grader cannot follow these: a TA looks, nothing is failed
    "command_default": ("TA", (P, N, N), "Command is not one the grader can resolve"),
    "unknown_import": ("TA", (N, N, N), "No module named 'nav2_common'"),
}

#: The reason of a wrong file's check that is not its first failure, where it names its own mistake.
SECOND_REASONS = {
    "typo_name": (DECLARES, "DeclareLaunchArgument('safety_distance', default_value='0.5'); safety_distance:=0.7 "
                            "reaches the node as 'saftey_distance'"),
    "remapping_string": (PASSES, "safety_distance is given as a remapping, not in parameters=[...]"),
    "wrong_default": (PASSES, "the node gets safety_distance=0.3, the sheet asks 0.5"),
    "declared_not_passed": (PASSES, "safety_distance is not among the Node's parameters"),
}


@pytest.mark.parametrize("name", sorted(SUITE))
def test_each_launch_file_gets_its_verdict_for_its_reason(name: str) -> None:
    kind, statuses, said = SUITE[name]
    report = check_launch(LAUNCH / f"{name}.launch.py", NODE)
    assert [c.name for c in report.checks] == [STARTS, DECLARES, PASSES]
    assert tuple(D if c.depends else c.status for c in report.checks) == statuses, report.lines()
    assert report.passed == (kind != "wrong"), "a right file passes, a wrong one fails, one a TA looks at passes"
    assert report.checked == (kind != "TA")
    first = next((c for c in report.checks if c.status != P), None)
    if kind == "right":
        assert first is None
        assert any("safety_distance:=0.7 reaches it" in n for n in report.notes), report.notes
    else:
        assert first is not None and said in first.reason, report.lines()
    if name in SECOND_REASONS:
        check, words = SECOND_REASONS[name]
        assert next(c for c in report.checks if c.name == check).reason == words


def test_every_fixture_is_in_the_suite_and_the_suite_is_big_enough() -> None:
    names = sorted(p.name.removesuffix(".launch.py") for p in LAUNCH.glob("*.launch.py"))
    assert names == sorted(SUITE)
    kinds = [kind for kind, _, _ in SUITE.values()]
    assert len(SUITE) >= 25 and kinds.count("right") >= 12 and kinds.count("wrong") >= 12


@pytest.mark.parametrize(("name", "cited"), [
    ("sheet", ("sheet.launch.py", 15)),  # the Node's parameters= line, not the Node's first line
    ("variables_add_action", ("variables_add_action.launch.py", 12)),  # not the params variable's line (11)
    ("include", ("navigator.launch.py", 11)),  # the included file's Node
    ("yaml_only", ("yaml_only.launch.py", 12)),
])
def test_passes_cites_the_nodes_parameters_line(name: str, cited: tuple[str, int]) -> None:
    check = check_launch(LAUNCH / f"{name}.launch.py", NODE).checks[2]
    assert (check.file, check.line) == cited, check
    assert check.text().startswith(f"{PASSES}: PASSED ({cited[0]}:{cited[1]}: ")


def test_the_override_is_said_to_reach_the_node_or_not() -> None:
    reached = check_launch(LAUNCH / "config_default.launch.py", NODE)
    constant = check_launch(LAUNCH / "hardcoded_value.launch.py", NODE)
    assert "with the defaults the node gets safety_distance=0.5; safety_distance:=0.7 reaches it" in reached.notes
    assert "with the defaults the node gets safety_distance=0.5; safety_distance:=0.7 would not reach it" in \
        constant.notes


def test_a_check_not_checked_scores_as_passed_with_a_note_for_the_ta() -> None:
    """Gradescope: a check the grader could not follow gets its points and says a TA looks (never failed for the
    grader's limits); a failed one gets none."""
    from bt_nav.grading.formats import gradescope_results

    for name, statuses in (("command_default", ["passed", "passed", "passed"]),
                           ("hardcoded_value", ["passed", "failed", "passed"])):
        record = {"runs": [], "launch": check_launch(LAUNCH / f"{name}.launch.py", NODE).to_dict()}
        tests = [t for t in gradescope_results(record)["tests"] if t["name"].startswith("launch file: ")]
        assert [t["status"] for t in tests] == statuses
        assert [t["score"] == t["max_score"] for t in tests] == [s == "passed" for s in statuses]
        if name == "command_default":
            assert [t["output"].startswith("**NOT CHECKED: a TA will look**") for t in tests] == [False, True, True]


@pytest.mark.parametrize("name", sorted(n for n, (kind, _, _) in SUITE.items() if kind == "wrong"))
def test_a_fix_says_what_the_file_holds_and_never_asks_to_add_what_is_there(name: str) -> None:
    """Each failed check carries its fix from the file; a check failed for another's root cause is not failed
    (it depends on it), and no fix asks to add a declaration, a parameter or a Node the file already holds."""
    report = check_launch(LAUNCH / f"{name}.launch.py", NODE)
    source = (LAUNCH / f"{name}.launch.py").read_text()
    failed = [c for c in report.checks if not c.passed]
    assert failed and all(c.fix for c in failed if c.reason != failed[0].reason or len(failed) < 3), report
    for check in failed:
        fix = check.fix or ""
        if "DeclareLaunchArgument('safety_distance'" in source:
            assert "add `DeclareLaunchArgument" not in fix and "declare `DeclareLaunchArgument" not in fix, fix
        if "parameters=" in source:
            assert "has no `parameters=" not in fix, fix
    for check in report.checks:
        if check.depends:
            assert next(c for c in report.checks if c.name == check.depends).status == F, report


def test_a_parameter_typo_costs_one_check_and_its_fix_names_the_typo() -> None:
    """The issue's hand-in: ``{'safety_dist': LaunchConfiguration('safety_distance')}`` fails "passes" alone, and
    its fix says what the Node gets and what the parameter is called."""
    report = check_launch(LAUNCH / "typo_name.launch.py", NODE)
    assert [c.status for c in report.checks] == [P, P, F], report.lines()
    assert report.checks[2].fix == ("the Node gets `{'saftey_distance': LaunchConfiguration('safety_distance')}` "
                                    "(typo_name.launch.py:11): the parameter is `safety_distance`")
