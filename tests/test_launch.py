"""The launch files, checked without ``ros2 launch`` (launch/launch_ros are not on PyPI).

Static checks read each file's source; then each ``generate_launch_description()`` runs against
the recording stand-ins of the launch API (bt_nav.grading.launch.standins, the grader's own), so
the real code path executes and what it would hand to ``launch_ros`` is inspected.
Where the real ``launch_ros`` is importable, it runs with that too.
"""

from __future__ import annotations

import ast
import importlib.util
import sys
import tomllib
from pathlib import Path

import pytest

from bt_nav.grading.launch.standins import standin_modules
from bt_nav.mission.params import SPECS

ROOT = Path(__file__).resolve().parent.parent
LAUNCH = ROOT / "launch"
FILES = sorted(LAUNCH.glob("*.launch.py"))
SCRIPTS = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"])


def run_launch_file(path: Path, monkeypatch: pytest.MonkeyPatch):
    for name, module in standin_modules().items():  # the grader's stand-ins: one home for them
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location(path.stem.replace(".", "_"), path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module, module.generate_launch_description()


def test_there_are_the_four_launch_files() -> None:
    assert {f.name for f in FILES} == {"turtlebot_bringup.launch.py", "sim.launch.py", "eval.launch.py",
                                       "lab_checkoff.launch.py", "checkoff_robot.launch.py"}


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_launch_file_parses_and_defines_generate_launch_description(path: Path) -> None:
    tree = ast.parse(path.read_text())
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    assert "generate_launch_description" in functions


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_argument_is_declared_used_and_typed(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    module, description = run_launch_file(path, monkeypatch)
    entities = description.args[0]
    declared = {e.args[0]: e.kwargs for e in entities if type(e).__name__ == "DeclareLaunchArgument"}
    nodes = [e for e in entities if type(e).__name__ == "Node"]
    assert list(declared) == module.ARGUMENTS
    used = set()
    for node in nodes:
        assert node.kwargs["package"] == "bt_nav"
        assert node.kwargs["executable"] in SCRIPTS, f"{node.kwargs['executable']} is not a console script"
        for value in node.kwargs["parameters"][-1].values():
            if type(value).__name__ == "ParameterValue":
                used.add(value.args[0].args[0])
        if type(node.kwargs.get("namespace")).__name__ == "LaunchConfiguration":
            used.add(node.kwargs["namespace"].args[0])
        # a command's options and the condition that picks the node (checkoff_robot: bt-nav checkoff --robot)
        used |= _configurations([node.kwargs.get("arguments", []), node.kwargs.get("condition")])
    assert used == set(declared), "every declared argument reaches a node, and only declared ones"
    own_defaults = getattr(module, "DEFAULTS", {})  # a launch file's own defaults (the lab check-off's arena)
    for name, kwargs in declared.items():
        assert kwargs["description"], f"{name} has no description"
        if name in own_defaults:
            assert kwargs["default_value"] == own_defaults[name]
        elif name in SPECS:
            expected = SPECS[name].default
            assert kwargs["default_value"] == (str(expected).lower() if isinstance(expected, bool) else str(expected))


def _configurations(value: object) -> set[str]:
    """The names of every LaunchConfiguration inside ``value`` (stand-ins' args, lists, nested)."""
    if type(value).__name__ == "LaunchConfiguration":
        return {value.args[0]}
    if isinstance(value, list | tuple):
        return set().union(*(_configurations(v) for v in value)) if value else set()
    return _configurations(list(getattr(value, "args", ()))) if hasattr(value, "args") else set()


def test_lab_bringup_is_the_labs_interface(monkeypatch: pytest.MonkeyPatch) -> None:
    _, description = run_launch_file(LAUNCH / "turtlebot_bringup.launch.py", monkeypatch)
    entities = description.args[0]
    declared = {e.args[0]: e.kwargs for e in entities if type(e).__name__ == "DeclareLaunchArgument"}
    assert declared["safety_distance"]["default_value"] == "0.5"
    assert declared["use_sim_time"]["default_value"] == "false"
    (node,) = [e for e in entities if type(e).__name__ == "Node"]
    assert node.kwargs["executable"] == "executive" and node.kwargs["name"] == "bt_nav_executive"
    assert ("arm", "toggle_navigation") in node.kwargs["remappings"]
    value = node.kwargs["parameters"][-1]["safety_distance"]
    assert value.kwargs["value_type"] is float
    _assert_lab_mode(node)


def _assert_lab_mode(node) -> None:
    """The executive loads config/lab.yaml first (lab mode: creep, AEB, no deadline), explicit values after."""
    from bt_nav.mission.profiles import file_parameters

    files, explicit = node.kwargs["parameters"][:-1], node.kwargs["parameters"][-1]
    assert [Path(f).name for f in files] == ["lab.yaml"]
    lab = file_parameters(files[0])
    assert (lab["mode"], lab["mission_duration"]) == ("lab", 0.0)
    assert "mode" not in explicit and "mission_duration" not in explicit  # nothing overrides lab mode


def test_lab_checkoff_launch_has_sim_executive_and_judge(monkeypatch: pytest.MonkeyPatch) -> None:
    """Simulator, the executive in lab mode on toggle_navigation, and the judge calling that service in the
    simulator's world (the same launch arguments reach both), with the executive's maneuver and distance."""
    module, description = run_launch_file(LAUNCH / "lab_checkoff.launch.py", monkeypatch)
    entities = description.args[0]
    declared = {e.args[0]: e.kwargs for e in entities if type(e).__name__ == "DeclareLaunchArgument"}
    assert (declared["maneuver"]["default_value"], declared["world"]["default_value"]) == ("C", "lab_object")
    nodes = {e.kwargs["executable"]: e for e in entities if type(e).__name__ == "Node"}
    assert list(nodes) == ["sim", "executive", "checkoff"]
    assert nodes["checkoff"].kwargs["name"] == "bt_nav_checkoff"
    assert dict(nodes["executive"].kwargs["remappings"]) == {"arm": "toggle_navigation"}
    _assert_lab_mode(nodes["executive"])
    judge, sim, exe = (nodes[n].kwargs["parameters"][-1] for n in ("checkoff", "sim", "executive"))
    assert judge["activate_service"] == "toggle_navigation" and judge["use_sim_time"] is True
    assert exe["use_sim_time"] is True and sim["profile"] == "lab"

    def argument(params: dict, name: str) -> str:
        return params[name].args[0].args[0]

    assert argument(judge, "world") == argument(sim, "world") == "world"
    assert argument(judge, "seed") == argument(sim, "seed") == "seed"
    assert argument(judge, "maneuver") == argument(exe, "maneuver") == "maneuver"
    assert argument(judge, "safety_distance") == argument(exe, "safety_distance") == "safety_distance"
    assert argument(judge, "json") == "results_json"


def test_eval_launch_has_sim_executive_and_referee(monkeypatch: pytest.MonkeyPatch) -> None:
    _, description = run_launch_file(LAUNCH / "eval.launch.py", monkeypatch)
    nodes = {e.kwargs["executable"]: e for e in description.args[0] if type(e).__name__ == "Node"}
    assert set(nodes) == {"sim", "executive", "referee"}
    remaps = dict(nodes["executive"].kwargs["remappings"])
    # relative, so with the default empty namespace they are /reactive_control/..., in robot1 /robot1/...
    assert remaps == {"arm": "reactive_control/activate", "evaluate_mission": "reactive_control/evaluate_mission"}
    assert nodes["executive"].kwargs["parameters"][-1]["use_sim_time"] is True
    referee = nodes["referee"].kwargs["parameters"][-1]
    assert (referee["activate_service"], referee["evaluate_service"]) == tuple(remaps.values())


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_every_node_takes_the_namespace_argument(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """One robot of several: every node of the launch file goes into the ``namespace`` argument's
    namespace (default empty: none), and no node keeps an absolute name that would escape it."""
    _, description = run_launch_file(path, monkeypatch)
    entities = description.args[0]
    declared = {e.args[0]: e.kwargs for e in entities if type(e).__name__ == "DeclareLaunchArgument"}
    assert declared["namespace"]["default_value"] == ""
    for node in (e for e in entities if type(e).__name__ == "Node"):
        assert node.kwargs["namespace"].args[0] == "namespace"
        assert not any(dst.startswith("/") for _, dst in node.kwargs["remappings"])
        assert not any(str(v).startswith("/") for k, v in node.kwargs["parameters"][-1].items()
                       if k.endswith("_service"))


def test_launch_files_are_installed_by_setup_py() -> None:
    assert 'glob("launch/*.launch.py")' in (ROOT / "setup.py").read_text()


def test_with_real_launch_ros_when_available() -> None:
    """On a ROS install this builds the real LaunchDescription; here launch_ros is not on PyPI."""
    pytest.importorskip("launch_ros", reason="launch_ros is not on PyPI; the stand-in tests above cover it")
    for path in FILES:
        spec = importlib.util.spec_from_file_location(path.stem.replace(".", "_"), path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        assert module.generate_launch_description().entities


def _bringup_default(declared: dict, node, parameter: str):
    """The value ``parameter`` of the executive gets when the launch runs with default arguments."""
    value = node.kwargs["parameters"][-1][parameter]
    argument = value.args[0].args[0]
    text = declared[argument]["default_value"]
    kind = value.kwargs["value_type"]
    return kind(text == "true") if kind is bool else kind(text)


def test_bringup_publishes_the_cmd_vel_type_the_turtlebot3_jazzy_stack_expects(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The launch file states (and cites) what the TurtleBot3 Jazzy stack subscribes to on /cmd_vel; the
    executive it starts, with default arguments, must publish exactly that type with the stated frame."""
    import re

    from bt_nav.mission.profiles import file_parameters

    path = LAUNCH / "turtlebot_bringup.launch.py"
    module, description = run_launch_file(path, monkeypatch)
    stated = re.search(r"subscribes to (geometry_msgs/\w+) on /cmd_vel", module.__doc__)
    assert stated, "the launch file must state the /cmd_vel type it targets"
    assert "enable_stamped_cmd_vel" in module.__doc__ and "turtlebot3_simulations" in module.__doc__  # cited
    entities = description.args[0]
    declared = {e.args[0]: e.kwargs for e in entities if type(e).__name__ == "DeclareLaunchArgument"}
    (node,) = [e for e in entities if type(e).__name__ == "Node"]
    stamped = _bringup_default(declared, node, "cmd_vel_stamped")
    published = "geometry_msgs/TwistStamped" if stamped else "geometry_msgs/Twist"
    assert published == stated.group(1)
    assert _bringup_default(declared, node, "frame_id") == "base_footprint"
    assert node.kwargs["parameters"][-1]["cmd_vel_stamped"].kwargs["value_type"] is bool
    # the TurtleBot3 params file says the same (one story for launch and file users)
    tb3 = file_parameters(ROOT / "config" / "turtlebot3.yaml")
    assert (tb3["cmd_vel_stamped"], tb3["frame_id"]) == (stamped, "base_footprint")


def test_checkoff_robot_launch_starts_the_live_listener_as_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    """``ros2 launch bt_nav checkoff_robot.launch.py maneuver:=C call_toggle:=... duration:=...``: exactly one
    listener node starts (its condition picks the spelling), with --robot and the arguments as options that
    ``bt-nav checkoff`` accepts (the node's --ros-args follow them)."""
    from types import SimpleNamespace

    from bt_nav.cli.checkoff import parser
    from bt_nav.grading.launch.standins import perform

    module, description = run_launch_file(LAUNCH / "checkoff_robot.launch.py", monkeypatch)
    nodes = [e for e in description.args[0] if type(e).__name__ == "Node"]
    assert {n.kwargs["executable"] for n in nodes} == {"checkoff"}
    for toggle, json_path in (("true", ""), ("false", ""), ("True", "/tmp/v.json"), ("false", "/tmp/v.json")):
        context = SimpleNamespace(launch_configurations={**module.DEFAULTS, "maneuver": "B", "duration": "45.0",
                                                         "call_toggle": toggle, "results_json": json_path})
        started = [n for n in nodes if n.kwargs["condition"].evaluate(context)]
        assert len(started) == 1, (toggle, json_path)
        argv = [perform(context, a) for a in started[0].kwargs["arguments"]]
        opts = parser().parse_args(argv)
        assert (opts.robot, opts.maneuver, opts.duration) == (True, "B", 45.0)
        assert opts.call_toggle is (toggle.lower() == "true") and opts.json == (json_path or None)
