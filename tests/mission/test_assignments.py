"""The assignments' one record each (bt_nav.mission.assignments): every table that used to repeat them reads them,
and a judge's defaults are the parameter table's (no DDS)."""

from __future__ import annotations

from dataclasses import replace

import pytest
from bt_nav_sim import core as sim_core

from bt_nav.grading.exe import run as exe_run
from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.mission import assignments as A
from bt_nav.mission import profiles
from bt_nav.mission.params import SPECS
from bt_nav.mission.profiles import config_file, file_parameters
from bt_nav.ros import bringup


def test_the_checkoff_defaults_are_the_parameter_tables() -> None:
    """The check-off judge's trigger distances default to the executive's (no copy of 0.5 / 0.3 in the judge)."""
    config = CheckoffConfig()
    for name in A.LAB.judge.shared:
        assert getattr(config, name) == SPECS[name].default == A.LAB.judge.defaults()[name]


def test_the_judge_writes_no_copy_of_a_default() -> None:
    """The judge's trigger distances are read from the table, not written again as numbers in the judge's source
    (a copy would stay 0.5 when the table's default changes)."""
    import ast
    import inspect

    import bt_nav.judge.checkoff_core as checkoff_core

    tree = ast.parse(inspect.getsource(checkoff_core.CheckoffConfig))
    defaults = {node.target.id: node.value for node in ast.walk(tree)
                if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None}
    copies = [name for name in A.LAB.judge.shared if isinstance(defaults[name], ast.Constant)]
    assert not copies, f"CheckoffConfig repeats the table's default of {copies}"


def test_config_lab_yaml_agrees_with_the_table() -> None:
    """config/lab.yaml stays the user's params file: its trigger distances are the table's defaults, so a lab run
    and its judge agree without a --set."""
    path = config_file("lab.yaml")
    assert path is not None
    values = file_parameters(path)
    assert {name: values[name] for name in A.LAB.judge.shared} == A.LAB.judge.defaults()


def test_every_profile_table_is_read_from_the_records() -> None:
    """The params files, the simulated robot, the graphs' services and judges, and a graded node's remaps."""
    assert profiles.PROFILE_FILES == {name: p.files for name, p in A.PROFILES.items()}
    assert list(sim_core.PROFILES) == list(A.PROFILES)
    for name, spec in A.PROFILES.items():
        assert sim_core.PROFILES[name].kinematics == spec.kinematics
        assert sim_core.PROFILES[name].lidar is sim_core.PROFILE_LIDARS[spec.lidar]
    for assignment in A.ASSIGNMENTS.values():
        specs = bringup.nodes(assignment.graph, maneuver="A")
        judge = specs[-1]
        assert (judge.executable, judge.name) == (assignment.judge.executable, assignment.judge.node_name)
        executive = next(s for s in specs if s.executable == "executive")
        assert tuple(executive.remappings) == assignment.remaps()
    assert exe_run.profile_remaps("lab") == (("arm", "/toggle_navigation"),)
    assert exe_run.profile_remaps("homework") == A.HOMEWORK.remaps()
    assert exe_run.profile_remaps("turtlebot3") == ()  # as before: only an assignment's own profile remaps


def test_a_changed_record_changes_every_table(monkeypatch: pytest.MonkeyPatch) -> None:
    """The lab's arm service renamed in its record alone reaches the executive's remap, the judge's call and a
    graded node's remap."""
    lab = replace(A.LAB, arm_service="start_stop")
    monkeypatch.setitem(A.ASSIGNMENTS, "lab", lab)
    monkeypatch.setitem(bringup.GRAPHS, "checkoff", (lab, True))
    specs = bringup.nodes("checkoff", maneuver="B")
    assert dict(specs[1].remappings)["arm"] == "start_stop"
    assert specs[-1].parameters["activate_service"] == "start_stop"
    assert exe_run.exe_ros_args(None, "lab")[-2:] == ["-r", "arm:=/start_stop"]


def test_a_graded_lab_node_is_judged_by_its_given_safety_distance() -> None:
    """--node-param safety_distance reaches the lab's judge (what a TA's launch file gives both), nothing else."""
    assert A.LAB.judge.given({"safety_distance": 1, "pivot_distance": 0.2}, A.LAB.judge.launch_shared) == \
        {"safety_distance": 1.0}
    assert A.HOMEWORK.judge.given({"safety_distance": 1}, A.HOMEWORK.judge.launch_shared) == {}
    with pytest.raises(ValueError, match="unknown profile 'x'; choose one of homework, lab, turtlebot3"):
        A.profile_spec("x")
