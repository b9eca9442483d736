"""The node table of bt_nav.ros.bringup, its command lines, and the demo's tree-tip parser (no DDS)."""

from __future__ import annotations

import math
import sys

import pytest

from bt_nav.cli import sim_run
from bt_nav.ros import bringup, supervise
from bt_nav.ros.bringup import NodeSpec, choose_domain_id, nodes, param_arg, parse_assignments


def _by_name(specs: list[NodeSpec]) -> dict[str, NodeSpec]:
    return {spec.executable: spec for spec in specs}


def test_homework_profile() -> None:
    specs = _by_name(nodes("homework", maneuver="B", seed=7, rtf=0.0))
    assert set(specs) == {"sim", "executive"}
    exe = specs["executive"]
    assert exe.name == "bt_nav_executive"
    assert exe.remappings == [("arm", "/reactive_control/activate"),
                              ("evaluate_mission", "/reactive_control/evaluate_mission")]
    assert exe.parameters["use_sim_time"] is True
    assert (exe.parameters["maneuver"], exe.parameters["random_seed"]) == ("B", 7)
    assert all(path.endswith("config/homework.yaml") for path in exe.parameter_files)
    sim = specs["sim"]
    assert (sim.name, sim.parameters["world"], sim.parameters["profile"]) == ("bt_nav_sim", "stage_4", "homework")
    assert (sim.parameters["seed"], sim.parameters["real_time_factor"]) == (7, 0.0)


@pytest.mark.parametrize(("maneuver", "world"), [("A", "lab_object"), ("randomizer", "lab_object"),
                                                  ("B", "lab_dead_end"), ("C", "lab_object")])
def test_checkoff_profile_judges_the_executives_maneuver_in_the_simulators_world(maneuver: str, world: str) -> None:
    specs = nodes("checkoff", maneuver=maneuver, seed=3, results_json="/tmp/c.json")
    assert [s.executable for s in specs] == ["sim", "executive", "checkoff"]  # the judge last: started last
    sim, exe, judge = (s.parameters for s in specs)
    assert exe["maneuver"] == judge["maneuver"] == {"randomizer": "A"}.get(maneuver, maneuver)
    assert sim["world"] == judge["world"] == world and sim["seed"] == judge["seed"] == 3
    assert sim["profile"] == "lab" and sim["solo_rtf"] == bringup.SOLO_RTF
    assert specs[1].remappings == [("arm", "toggle_navigation")] and judge["activate_service"] == "toggle_navigation"
    assert (judge["json"], judge["wait_for_cmd_vel"], judge["use_sim_time"]) == ("/tmp/c.json", True, True)
    assert specs[2].name == "bt_nav_checkoff"
    assert sim_run.arm_hint(specs, 100) is None  # the judge arms the robot
    assert _by_name(nodes("checkoff", maneuver="A", world="lab_cluttered"))["checkoff"].parameters["world"] == \
        "lab_cluttered"


def test_checkoff_refuses_no_maneuver() -> None:
    with pytest.raises(ValueError, match="A, B or C"):
        nodes("checkoff", maneuver="none")


def test_eval_adds_the_referee_and_lab_remaps_arm() -> None:
    specs = _by_name(nodes("eval", results_json="/tmp/r.json"))
    assert list(specs) == ["sim", "executive", "referee"]  # the referee last: the demo starts it last
    referee = specs["referee"]
    assert referee.name == "bt_nav_referee"
    assert referee.parameters == {"use_sim_time": True, "wait_for_cmd_vel": True, "json": "/tmp/r.json"}
    assert specs["sim"].parameters["solo_rtf"] == bringup.SOLO_RTF
    assert "solo_rtf" not in _by_name(nodes("homework"))["sim"].parameters
    lab = _by_name(nodes("lab", world="corridor"))
    assert lab["executive"].remappings == [("arm", "toggle_navigation")]
    assert (lab["sim"].parameters["profile"], lab["sim"].parameters["world"]) == ("lab", "corridor")
    real_robot = nodes("lab", include_sim=False)
    assert [s.executable for s in real_robot] == ["executive"]
    assert real_robot[0].parameters["use_sim_time"] is False


def test_stamped_commands_reach_the_simulator_and_referee() -> None:
    specs = _by_name(nodes("eval", executive={"cmd_vel_stamped": True}))
    assert specs["sim"].parameters["cmd_vel_stamped"] is True
    assert specs["referee"].parameters["cmd_vel_stamped"] is True


def test_a_simulated_lidar_tells_the_executive_where_it_sits() -> None:
    """As TF would on a robot: the off-centre scanner's mount reaches the executive, a centred one adds nothing,
    and a parameter given for the executive wins."""
    def executive(**kw: object) -> dict:
        return next(s for s in nodes("eval", **kw) if s.executable == "executive").parameters

    assert executive(sim={"lidar": "ust10"})["scan_mount_x"] == pytest.approx(0.08)
    assert executive(sim={"lidar": "ust10"})["scan_mount_y"] == pytest.approx(0.03)
    assert "scan_mount_x" not in executive(sim={"lidar": "rplidar"})
    assert executive(sim={"lidar": "ust10"}, executive={"scan_mount_x": 0.1})["scan_mount_x"] == 0.1


def test_bad_profiles() -> None:
    with pytest.raises(ValueError, match="unknown profile"):
        nodes("gazebo")
    with pytest.raises(ValueError, match="referee"):
        nodes("lab", with_referee=True)


def test_command_line() -> None:
    spec = NodeSpec("sim", "bt_nav_sim", {"world": "stage_4", "real_time_factor": 2.0, "seed": 3, "noise": False},
                    [("cmd_vel", "/robot/cmd_vel")], parameter_files=["/x.yaml"])
    assert spec.command("py") == [
        "py", "-m", "bt_nav.cli", "sim", "--ros-args", "-r", "__node:=bt_nav_sim", "--params-file", "/x.yaml",
        "-p", 'world:="stage_4"', "-p", "real_time_factor:=2.0", "-p", "seed:=3", "-p", "noise:=false",
        "-r", "cmd_vel:=/robot/cmd_vel"]
    assert spec.command()[0] == sys.executable


@pytest.mark.parametrize("value, text", [
    (True, "true"), (3, "3"), (1.0, "1.0"), (math.nan, ".nan"), (-math.inf, "-.inf"), ("1.5", '"1.5"'),
    ("A", '"A"'), ([1, 2], "[1, 2]"),
])
def test_param_arg_types(value: object, text: str) -> None:
    assert param_arg("p", value) == f"p:={text}"


def test_parse_assignments() -> None:
    assert parse_assignments(["a=1", "b=0.5", "c=x", "d=true"]) == {"a": 1, "b": 0.5, "c": "x", "d": True}
    with pytest.raises(ValueError):
        parse_assignments(["novalue"])


def test_domain_id(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    assert choose_domain_id(42) == 42
    monkeypatch.setenv("ROS_DOMAIN_ID", "7")
    assert choose_domain_id() == 7  # the user's choice is kept
    monkeypatch.delenv("ROS_DOMAIN_ID")
    monkeypatch.setenv("TMPDIR", str(tmp_path))  # private lock files: this test's claims only
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", "140-142")
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    claimed = {choose_domain_id() for _ in range(3)}
    assert claimed == {140, 141, 142}, "concurrent runs (claims held by this process) never share a domain"
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", "9-x")
    with pytest.raises(ValueError, match="BT_NAV_DOMAIN_RANGE"):
        choose_domain_id()
    monkeypatch.delenv("BT_NAV_DOMAIN_RANGE")
    assert supervise.launcher_domains() == (100, 199)


def test_arm_hint_names_the_domain_and_the_service() -> None:
    hint = sim_run.arm_hint(nodes("homework"), 123)
    assert hint is not None and hint.startswith("ROS_DOMAIN_ID=123 ")
    assert hint.endswith(" arm --service /reactive_control/activate")
    assert sim_run.arm_hint(nodes("lab"), 5).endswith("arm --service /toggle_navigation")
    assert sim_run.arm_hint(nodes("eval"), 5) is None  # the referee arms


def test_child_env_is_local(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROS_LOCALHOST_ONLY", "1")
    env = bringup.child_env(123)
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST" and env["ROS_DOMAIN_ID"] == "123"
    assert "ROS_LOCALHOST_ONLY" not in env


def test_commands_parse_and_print_the_layers_run() -> None:
    """sim-run's command line lives in the commands (bt_nav.cli.sim_run), its start/watch/stop in the run layer
    (run_graph), the node table alone in bringup; the Foxglove bridge is media's; a verdict file is read by its one
    reader (no json.loads of it in demo, the lab demo or the ROS benchmark)."""
    from pathlib import Path

    from bt_nav.cli import COMMANDS
    from bt_nav.media.foxglove import FoxgloveBridge  # noqa: F401 - importable from media
    from bt_nav.run.rosmission import run_graph  # noqa: F401

    assert COMMANDS["sim-run"][0] == "bt_nav.cli.sim_run"
    assert not hasattr(bringup, "main") and not hasattr(bringup, "build_parser")
    root = Path(__file__).resolve().parents[1]
    for path in ("bt_nav/cli/demo/__init__.py", "bt_nav/cli/demo/lab.py", "bench/ros_mission.py"):
        assert "json.loads" not in (root / path).read_text(encoding="utf-8"), path
