"""A student's launch file checked as ``ros2 launch`` would run it, for what the lab sheet's Task 3 asks: it starts
the student's node, declares the launch argument ``safety_distance`` with the default 0.5, and passes that argument
into the node's parameters.

How: the file's ``generate_launch_description()`` is evaluated in a child process against stand-ins of the launch
API (:mod:`bt_nav.grading.launch.evaluate`), twice -- with the defaults, and with ``safety_distance:=0.7`` given on the
command line. The node passes "passes" when it would get 0.5; "declares" when it would get 0.5 by default *and* 0.7
with the override (a launch argument that reaches it), so a constant ``{'safety_distance': 0.5}`` passes the one
and fails the other. Each check cites the line it is about (the Node's ``parameters=`` line, a params file's line).

Why evaluated and not read: students write the same launch file many ways (variables, helper lists, ``add_action``,
``ParameterValue``, a params YAML, ``OpaqueFunction``, included files); only running it says what the node gets.
What the evaluation cannot follow is "not checked: a TA should look", never a failure; the static reader
(:mod:`bt_nav.grading.launch.static`) is the fallback when the evaluation cannot run at all. Pure: no rclpy.
"""

from __future__ import annotations

import ast
import difflib
import importlib.util
import re
from pathlib import Path
from typing import Any

from bt_nav.grading.launch.evaluate import TIME_LIMIT, evaluate, hand_in_files
from bt_nav.grading.launch.report import (
    ARGUMENT,
    DECLARES,
    DEFAULT,
    LAUNCH_NAME,
    NOT_CHECKED,
    OVERRIDE,
    PASSES,
    STARTS,
    LaunchCheck,
    LaunchReport,
)
from bt_nav.grading.launch.static import read_statically

__all__ = ["ARGUMENT", "DECLARES", "DEFAULT", "LAUNCH_NAME", "NOT_CHECKED", "OVERRIDE", "PASSES", "STARTS",
           "LaunchCheck", "LaunchReport", "check_launch", "launch_ros_installed"]


def launch_ros_installed() -> bool:
    """Whether ``launch_ros`` can be imported here (a real ROS 2 install), without importing it."""
    try:
        return importlib.util.find_spec("launch_ros") is not None
    except (ImportError, ValueError):
        return False


def check_launch(path: Path | None, node: Path | None, folder: Path | None = None,
                 limit: float = TIME_LIMIT) -> LaunchReport:
    """The sheet's three checks of the launch file ``path`` for the node file ``node`` (None: none found), in the
    hand-in ``folder`` (default: the launch file's): the working directory and the package share it is run in."""
    if path is None:
        return read_statically(None, node)
    try:
        ast.parse(path.read_bytes())
    except (OSError, SyntaxError, ValueError):  # ros2 launch could not load it either: the reading says why
        return read_statically(path, node)
    folder = Path(folder) if folder is not None else path.parent
    evaluation = evaluate(path, folder, {ARGUMENT: str(OVERRIDE)}, limit)
    if "failed" in evaluation:
        return _fallback(read_statically(path, node), f"the evaluation failed: {evaluation['failed']}",
                         keep=not evaluation.get("hung"))  # a hang is the file's (ros2 launch would hang too)
    default, override = evaluation["runs"]
    if "stop" in default:
        return LaunchReport(path.name, tuple(_check(name, False, f"ros2 launch stops: {default['stop']}",
                                                    default.get("where")) for name in (STARTS, DECLARES, PASSES)))
    if default.get("raised"):
        return _fallback(read_statically(path, node), "; ".join(default["unsure"]), keep=False)
    return _Judge(path, node, folder, default, override).report()


def _check(name: str, passed: bool, reason: str, at: str | None = None, checked: bool = True) -> LaunchCheck:
    """A check citing ``at`` (``file.py:12``, or ``params.yaml:3 (given at file.py:12)``: the first one counts)."""
    match = re.match(r"([^:\s]+):(\d+)", at or "")
    file, line = (match.group(1), int(match.group(2))) if match else (None, None)
    return LaunchCheck(name, passed or not checked, reason, line, checked, file)


def _fallback(static: LaunchReport, why: str, keep: bool = True) -> LaunchReport:
    """The static reading where the evaluation could not say: its passed checks stand (``keep``), any other check
    is not checked, with why and what the reading said."""
    checks = tuple(c if keep and c.passed else LaunchCheck(c.name, True, f"{why} (read statically: "
                                                           f"{c.status.lower()}, {c.reason})", c.line, False,
                                                           static.file if c.line else None)
                   for c in static.checks)
    return LaunchReport(static.file, checks, (*static.notes, f"{why}: {NOT_CHECKED}"))


def _package(folder: Path) -> str | None:
    """The hand-in's ROS package name (its one ``package.xml``), None when it has none."""
    found = hand_in_files(folder, "package.xml")
    if len(found) != 1:
        return None
    match = re.search(r"<name>\s*([^<\s]+)\s*</name>", found[0].read_text(errors="replace"))
    return match.group(1) if match else None


def _console_scripts(folder: Path, modules: set[str]) -> set[str]:
    """The executables a hand-in's ``setup.py`` / ``setup.cfg`` maps to the node's module (``'navigator =
    my_package.reactive_navigator:main'``): ``ros2 launch`` runs the node by that name too."""
    names = set()
    for path in hand_in_files(folder, "setup.py", "setup.cfg"):
        for executable, module in re.findall(r"([\w.-]+)\s*=\s*([\w.]+)\s*:\s*\w+", path.read_text(errors="replace")):
            if module.rpartition(".")[2] in modules:
                names.add(executable)
    return names


def _shown(value: Any) -> str:
    return repr(value) if isinstance(value, str) else f"{value:g}" if isinstance(value, float) else repr(value)


class _Judge:
    """The three checks from the two evaluated runs (defaults, ``safety_distance:=0.7``)."""

    def __init__(self, path: Path, node: Path | None, folder: Path, default: dict[str, Any],
                 override: dict[str, Any]) -> None:
        self.path, self.folder, self.default, self.override = path, folder, default, override
        self.names = {"reactive_navigator", "reactive_navigator.py"}  # the sheet's name, whatever the file is named
        self.names |= {node.stem, node.name} if node is not None else set()
        self.names |= _console_scripts(folder, {n.removesuffix(".py") for n in self.names})
        self.unsure = list(default.get("unsure", []))
        self.declared = next((d for d in reversed(default.get("declared", [])) if d["name"] == ARGUMENT), None)

    def mine(self, run: dict[str, Any]) -> dict[str, Any] | None:
        """The student's node among what ``run`` starts (by executable, or a process running the node's file)."""
        for started in run.get("started", []):
            if started["executable"] in self.names or any(Path(w).name in self.names for w in started.get("cmd", [])):
                return started
        return None

    def report(self) -> LaunchReport:
        node = self.mine(self.default)
        value = None if node is None else node["parameters"].get(ARGUMENT)
        after = None if (other := self.mine(self.override)) is None else other["parameters"].get(ARGUMENT)
        notes = []
        if value is not None and "value" in (value or {}):
            reach = after is not None and _number(after.get("value")) == OVERRIDE
            notes.append(f"with the defaults the node gets {ARGUMENT}={_shown(value['value'])}; "
                         f"{ARGUMENT}:={OVERRIDE:g} {'reaches it' if reach else 'would not reach it'}")
        notes += [f"not followed: {u}" for u in self.unsure]
        return LaunchReport(self.path.name, (self.starts(node), self.declares(node, value, after),
                                             self.passes(node, value)), tuple(notes))

    def starts(self, node: dict[str, Any] | None) -> LaunchCheck:
        want = " or ".join(sorted(self.names))
        if node is None:
            nodes = [s for s in self.default.get("started", []) if s["kind"] == "node"]
            if self.unsure:
                return _check(STARTS, False, f"no Node of {want} found, but the grader could not follow: "
                              + "; ".join(self.unsure), checked=False)
            skipped = [k for k in self.default.get("skipped", []) if k["executable"] in self.names]
            if skipped:
                return _check(STARTS, False, f"its Node's {skipped[0]['condition']} is false with the default launch "
                              "arguments: ros2 launch does not start it", skipped[0]["where"])
            if nodes:
                found = ", ".join(repr(s["executable"]) for s in nodes)
                return _check(STARTS, False, f"its Node runs executable {found}, not {want}", nodes[0]["where"])
            static = read_statically(self.path, None).checks[0]
            if "not return it" in static.reason:
                return LaunchCheck(STARTS, False, static.reason, static.line, file=self.path.name)
            return _check(STARTS, False, f"no launch_ros.actions.Node (nor ExecuteProcess) starts {want}")
        if node["kind"] == "process":
            return _check(STARTS, True, f"ExecuteProcess running {' '.join(node['cmd'])!r}", node["where"])
        package = _package(self.folder)
        if package is not None and node["package"] != package:
            return _check(STARTS, False, f"Node(package={node['package']!r}): the hand-in's package is {package!r} "
                          "(package.xml): ros2 launch finds no such executable", node["where"])
        return _check(STARTS, True, f"Node(package={node['package']!r}, executable={node['executable']!r})",
                      node["where"])

    def passes(self, node: dict[str, Any] | None, value: dict[str, Any] | None) -> LaunchCheck:
        if node is None:
            return _check(PASSES, False, "no Node starts the student's node: nothing to pass it to",
                          checked=not self.unsure)
        at = node.get("parameters_at", node["where"])
        if value is None:
            return self._missing(node, at)
        if "unsure" in value:
            return _check(PASSES, False, f"{ARGUMENT} is given something the grader cannot resolve: "
                          f"{value['unsure']}", at, checked=False)
        got = value["value"]
        source = "" if value["source"] == at else f" (from {value['source']})"
        if isinstance(got, float) and got == DEFAULT:
            return _check(PASSES, True, f"the node gets {ARGUMENT}={_shown(got)}{source}", at)
        if isinstance(got, str):
            return _check(PASSES, False, f"the node gets {ARGUMENT} as the string {got!r}{source}: its float "
                          "parameter refuses a string", at)
        return _check(PASSES, False, f"the node gets {ARGUMENT}={_shown(got)}{source}, the sheet asks 0.5", at)

    def _missing(self, node: dict[str, Any], at: str) -> LaunchCheck:
        """The node gets no ``safety_distance``: a near miss named (a typo, a remapping), or none at all."""
        if self.unsure:
            return _check(PASSES, False, f"{ARGUMENT} is not among the Node's parameters, but the grader could not "
                          "follow: " + "; ".join(self.unsure), at, checked=False)
        close = difflib.get_close_matches(ARGUMENT, list(node["parameters"]), n=1, cutoff=0.75)
        if close:
            return _check(PASSES, False, f"the Node is given {close[0]!r}, not {ARGUMENT!r} (a typo?)", at)
        if any(ARGUMENT in word for pair in node.get("remappings", []) for word in pair):
            return _check(PASSES, False, f"{ARGUMENT} is given as a remapping, not in parameters=[...]", at)
        if node["kind"] == "process":
            return _check(PASSES, False, f"the command never passes -p {ARGUMENT}:=...", at)
        if not node["parameters"]:
            return _check(PASSES, False, "the Node has no parameters=[...]", node["where"])
        return _check(PASSES, False, f"{ARGUMENT} is not among the Node's parameters", at)

    def declares(self, node: dict[str, Any] | None, value: dict[str, Any] | None,
                 after: dict[str, Any] | None) -> LaunchCheck:
        declared = self.declared
        shown = None if declared is None else declared["default"]
        right = shown is not None and _is_default(shown)
        at = None if declared is None else declared["where"]
        if value is not None and "unsure" in value:
            return _check(DECLARES, False, f"what the node gets cannot be resolved: {value['unsure']}", at,
                          checked=False)
        if node is None or value is None:
            if declared is None:
                return _check(DECLARES, False, f"no DeclareLaunchArgument('{ARGUMENT}', default_value='0.5')",
                              checked=not self.unsure)
            if not right:
                return _check(DECLARES, False, f"default_value is {shown!r}, the sheet asks 0.5", at)
            if node is not None and value is None and not self.unsure:
                return _check(DECLARES, False, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r}) is "
                              f"declared but never reaches the node: {ARGUMENT}:={OVERRIDE:g} would change nothing", at)
            return _check(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r})", at)
        reach = after is not None and _number(after.get("value")) == OVERRIDE
        if not reach:
            if "stop" in self.override:
                return _check(DECLARES, False, f"with {ARGUMENT}:={OVERRIDE:g} ros2 launch stops: "
                              f"{self.override['stop']}", self.override.get("where"))
            if declared is not None:
                return _check(DECLARES, False, f"`{ARGUMENT}:={OVERRIDE:g}` would not reach the node: the launch "
                              f"argument is declared at {at} but the node is given {_shown(value['value'])} "
                              f"({value['source']}), not LaunchConfiguration('{ARGUMENT}')", node.get("parameters_at"))
            return _check(DECLARES, False, f"`{ARGUMENT}:={OVERRIDE:g}` would not reach the node; declare a launch "
                          "argument", node.get("parameters_at"))
        if declared is not None and not right:
            return _check(DECLARES, False, f"default_value is {shown!r}, the sheet asks 0.5", at)
        if _number(value["value"]) != DEFAULT:
            return _check(DECLARES, False, f"with the defaults the node gets {_shown(value['value'])}, the sheet asks "
                          "0.5", at or node.get("parameters_at"))
        if declared is None:
            return _check(DECLARES, True, f"no DeclareLaunchArgument, but LaunchConfiguration('{ARGUMENT}') has the "
                          f"default 0.5 and {ARGUMENT}:={OVERRIDE:g} reaches the node", node.get("parameters_at"))
        return _check(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r}); "
                      f"{ARGUMENT}:={OVERRIDE:g} reaches the node", at)


def _is_default(text: str) -> bool:
    return _number(text) == DEFAULT


def _number(value: Any) -> float | None:
    """A parameter's value as a number (``'0.5'`` too: the type is the "passes" check's business), None: none."""
    if isinstance(value, bool):
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        return None
