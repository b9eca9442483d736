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
from dataclasses import replace
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


def _check(name: str, passed: bool, reason: str, at: str | None = None, checked: bool = True,
           fix: str | None = None) -> LaunchCheck:
    """A check citing ``at`` (``file.py:12``, or ``params.yaml:3 (given at file.py:12)``: the first one counts);
    ``fix``: a failed check's advice from the file (what is there, what is missing)."""
    match = re.match(r"([^:\s]+):(\d+)", at or "")
    file, line = (match.group(1), int(match.group(2))) if match else (None, None)
    failed = checked and not passed
    return LaunchCheck(name, passed or not checked, reason, line, checked, file, fix=fix if failed else None)


def _depends(check: LaunchCheck, on: LaunchCheck) -> LaunchCheck:
    """``check``, not checked because ``on`` failed: its failure is ``on``'s root cause, charged once there."""
    return replace(check, passed=True, checked=False, depends=on.name, fix=None)


#: The Node's parameter as the sheet asks it, said in a fix.
SHEET_PARAMETER = f"'{ARGUMENT}': LaunchConfiguration('{ARGUMENT}')"
SHEET_ARGUMENT = f"DeclareLaunchArgument('{ARGUMENT}', default_value='0.5')"


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
    """The three checks from the two evaluated runs (defaults, ``safety_distance:=0.7``), each root cause failing
    one check (:meth:`settle`), each failure with its fix from the file."""

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
        checks = self.settle(self.starts(node), self.declares(node, value, after), self.passes(node, value, after))
        return LaunchReport(self.path.name, checks, tuple(notes))

    def settle(self, starts: LaunchCheck, declares: LaunchCheck, passes: LaunchCheck
               ) -> tuple[LaunchCheck, LaunchCheck, LaunchCheck]:
        """One root cause fails one check: a Node not started leaves nothing to pass to (``passes`` depends on
        ``starts``); a wrong default the node gets fails ``declares`` alone; an argument declared right that
        reaches no parameter of the sheet's name fails ``passes`` alone."""
        if not starts.passed and not passes.passed and passes.checked and starts.checked:
            passes = _depends(passes, starts)
        elif not declares.passed and not passes.passed and self.follows(ARGUMENT) and declares.checked:
            passes = _depends(passes, declares)
        elif not declares.passed and not passes.passed and self.declared is not None and \
                _is_default(self.declared["default"]) and declares.checked:
            declares = _depends(declares, passes)
        return starts, declares, passes

    def follows(self, key: str) -> bool:
        """Whether the node's parameter ``key`` follows the launch argument (its value is 0.7 with the override)."""
        other = self.mine(self.override)
        got = None if other is None else other["parameters"].get(key)
        return got is not None and _number(got.get("value")) == OVERRIDE

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
                              "arguments: ros2 launch does not start it", skipped[0]["where"],
                              fix=f"the Node at {skipped[0]['where']} has an {skipped[0]['condition']} that is false "
                              "with the default arguments: make it start by default")
            if nodes:
                found = ", ".join(repr(s["executable"]) for s in nodes)
                return _check(STARTS, False, f"its Node runs executable {found}, not {want}", nodes[0]["where"],
                              fix=f"the Node at {nodes[0]['where']} runs `executable={nodes[0]['executable']!r}`: "
                              f"your node's executable is {want} (the name `setup.py`'s console_scripts gives it)")
            static = read_statically(self.path, None).checks[0]
            if "not return it" in static.reason:
                return LaunchCheck(STARTS, False, static.reason, static.line, file=self.path.name,
                                   fix="the Node is built but not in the `LaunchDescription` that "
                                   "`generate_launch_description()` returns: put it in that list")
            return _check(STARTS, False, f"no launch_ros.actions.Node (nor ExecuteProcess) starts {want}",
                          fix=f"the launch description starts no Node of {want}: add `Node(package=..., "
                          "executable='reactive_navigator')` to the list it returns")
        if node["kind"] == "process":
            return _check(STARTS, True, f"ExecuteProcess running {' '.join(node['cmd'])!r}", node["where"])
        package = _package(self.folder)
        if package is not None and node["package"] != package:
            return _check(STARTS, False, f"Node(package={node['package']!r}): the hand-in's package is {package!r} "
                          "(package.xml): ros2 launch finds no such executable", node["where"],
                          fix=f"the Node at {node['where']} has `package={node['package']!r}`: your package.xml "
                          f"names the package {package!r}")
        return _check(STARTS, True, f"Node(package={node['package']!r}, executable={node['executable']!r})",
                      node["where"])

    def passes(self, node: dict[str, Any] | None, value: dict[str, Any] | None,
               after: dict[str, Any] | None = None) -> LaunchCheck:
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
                          "parameter refuses a string", at,
                          fix=f"the Node at {at} gets `{ARGUMENT}` as a string: give it a number (`value_type="
                          f"float` in `ParameterValue`, or `LaunchConfiguration('{ARGUMENT}')` as it is)")
        return _check(PASSES, False, f"the node gets {ARGUMENT}={_shown(got)}{source}, the sheet asks 0.5", at,
                      fix=f"the Node gets `{ARGUMENT}={_shown(got)}`{source or f' at {at}'}: the sheet asks 0.5 by "
                      "default")

    def _missing(self, node: dict[str, Any], at: str) -> LaunchCheck:
        """The node gets no ``safety_distance``: a near miss named (a typo, a remapping), or none at all."""
        if self.unsure:
            return _check(PASSES, False, f"{ARGUMENT} is not among the Node's parameters, but the grader could not "
                          "follow: " + "; ".join(self.unsure), at, checked=False)
        close = difflib.get_close_matches(ARGUMENT, list(node["parameters"]), n=1, cutoff=0.75)
        if close:
            given = f"LaunchConfiguration('{ARGUMENT}')" if self.follows(close[0]) else \
                _shown(node["parameters"][close[0]].get("value"))
            return _check(PASSES, False, f"the Node is given {close[0]!r}, not {ARGUMENT!r} (a typo?)", at,
                          fix=f"the Node gets `{{{close[0]!r}: {given}}}` ({at}): the parameter is `{ARGUMENT}`")
        if any(ARGUMENT in word for pair in node.get("remappings", []) for word in pair):
            return _check(PASSES, False, f"{ARGUMENT} is given as a remapping, not in parameters=[...]", at,
                          fix=f"the Node at {at} gives `{ARGUMENT}` in `remappings=[...]`, which renames topics: a "
                          f"parameter goes in `parameters=[{{{SHEET_PARAMETER}}}]`")
        if node["kind"] == "process":
            return _check(PASSES, False, f"the command never passes -p {ARGUMENT}:=...", at,
                          fix=f"the command at {at} passes no `-p {ARGUMENT}:=...`: add `--ros-args -p "
                          f"{ARGUMENT}:=` with `LaunchConfiguration('{ARGUMENT}')`")
        if not node["parameters"]:
            return _check(PASSES, False, "the Node has no parameters=[...]", node["where"],
                          fix=f"the Node at {node['where']} has no `parameters=[...]`: give it "
                          f"`parameters=[{{{SHEET_PARAMETER}}}]`")
        keys = ", ".join(repr(k) for k in node["parameters"])
        return _check(PASSES, False, f"{ARGUMENT} is not among the Node's parameters", at,
                      fix=f"the Node gets {keys} ({at}) but not `{ARGUMENT}`: add `{SHEET_PARAMETER}` to them")

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
            return self._declared_alone(node, declared, shown, right, at)
        reach = after is not None and _number(after.get("value")) == OVERRIDE
        if not reach:
            return self._not_reaching(node, value, declared, at)
        if declared is not None and not right:
            return _check(DECLARES, False, f"default_value is {shown!r}, the sheet asks 0.5", at,
                          fix=f"`DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r})` ({at}): the sheet's "
                          "default is `'0.5'`")
        if _number(value["value"]) != DEFAULT:
            return _check(DECLARES, False, f"with the defaults the node gets {_shown(value['value'])}, the sheet asks "
                          "0.5", at or node.get("parameters_at"),
                          fix=f"with the defaults the node gets {_shown(value['value'])} ({value['source']}): the "
                          "sheet's default is 0.5")
        if declared is None:
            return _check(DECLARES, True, f"no DeclareLaunchArgument, but LaunchConfiguration('{ARGUMENT}') has the "
                          f"default 0.5 and {ARGUMENT}:={OVERRIDE:g} reaches the node", node.get("parameters_at"))
        return _check(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r}); "
                      f"{ARGUMENT}:={OVERRIDE:g} reaches the node", at)

    def _declared_alone(self, node: dict[str, Any] | None, declared: dict[str, Any] | None, shown: Any,
                        right: bool, at: str | None) -> LaunchCheck:
        """The argument's check where the node gets no ``safety_distance`` (or is not started): the declaration
        alone, and where it goes (a parameter of another name that follows it)."""
        if declared is None:
            near = difflib.get_close_matches(ARGUMENT, [d["name"] for d in self.default.get("declared", [])], n=1,
                                             cutoff=0.75)
            fix = (f"the file declares the launch argument {near[0]!r}: the sheet's is `{ARGUMENT}`" if near else
                   f"the file declares no launch argument `{ARGUMENT}`: add `{SHEET_ARGUMENT}` to the launch "
                   "description")
            return _check(DECLARES, False, f"no {SHEET_ARGUMENT}", checked=not self.unsure, fix=fix)
        if not right:
            return _check(DECLARES, False, f"default_value is {shown!r}, the sheet asks 0.5", at,
                          fix=f"`DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r})` ({at}): the sheet's "
                          "default is `'0.5'`")
        keys = [k for k in (node or {}).get("parameters", {}) if self.follows(k)]
        if keys:
            return _check(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r}); "
                          f"{ARGUMENT}:={OVERRIDE:g} reaches the node as {keys[0]!r}", at)
        if node is not None and not self.unsure:
            return _check(DECLARES, False, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r}) is "
                          f"declared but never reaches the node: {ARGUMENT}:={OVERRIDE:g} would change nothing", at,
                          fix=f"`DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r})` ({at}) is there; the "
                          f"Node must get it: `parameters=[{{{SHEET_PARAMETER}}}]`")
        return _check(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown!r})", at)

    def _not_reaching(self, node: dict[str, Any], value: dict[str, Any], declared: dict[str, Any] | None,
                      at: str | None) -> LaunchCheck:
        """The argument's check where the node gets ``safety_distance`` but ``safety_distance:=0.7`` does not
        reach it."""
        if "stop" in self.override:
            return _check(DECLARES, False, f"with {ARGUMENT}:={OVERRIDE:g} ros2 launch stops: "
                          f"{self.override['stop']}", self.override.get("where"),
                          fix=f"with `{ARGUMENT}:={OVERRIDE:g}` ros2 launch stops ({self.override['stop']})")
        given = f"the Node gets `{ARGUMENT}={_shown(value['value'])}` ({value['source']})"
        if declared is not None:
            return _check(DECLARES, False, f"`{ARGUMENT}:={OVERRIDE:g}` would not reach the node: the launch "
                          f"argument is declared at {at} but the node is given {_shown(value['value'])} "
                          f"({value['source']}), not LaunchConfiguration('{ARGUMENT}')", node.get("parameters_at"),
                          fix=f"{given}, a constant, while the argument is declared at {at}: give the Node "
                          f"`LaunchConfiguration('{ARGUMENT}')` instead")
        return _check(DECLARES, False, f"`{ARGUMENT}:={OVERRIDE:g}` would not reach the node; declare a launch "
                      "argument", node.get("parameters_at"),
                      fix=f"{given}, and no launch argument `{ARGUMENT}` reaches it: declare `{SHEET_ARGUMENT}` "
                      f"and give the Node `{SHEET_PARAMETER}` (after a params file, so it wins)")


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
