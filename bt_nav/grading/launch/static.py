"""A student's launch file read statically (Python's ``ast``; nothing of it run): the fallback of
:func:`bt_nav.grading.launch.check.check_launch` when the file cannot be evaluated, and the first word on files that
are not Python or have no ``generate_launch_description()``.

Why the checks follow the launch description and not just any call in the file: a ``Node(...)`` built but never
returned by ``generate_launch_description()`` starts nothing. Where the description cannot be followed (a helper
function's result, a comprehension), every call in the file counts. Pure: no rclpy, no launch; never raises on a
student's file (a syntax error is a failed check quoting it).
"""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Any

from bt_nav.grading.launch.report import (
    ARGUMENT,
    DECLARES,
    DEFAULT,
    LAUNCH_NAME,
    PASSES,
    STARTS,
    LaunchCheck,
    LaunchReport,
)

_NODE = {"launch_ros.actions.Node", "launch_ros.actions.node.Node"}
_PROCESS = {"launch.actions.ExecuteProcess", "launch.actions.execute_process.ExecuteProcess"}
_DECLARE = {"launch.actions.DeclareLaunchArgument", "launch.actions.declare_launch_argument.DeclareLaunchArgument"}
_CONFIG = {"launch.substitutions.LaunchConfiguration",
           "launch.substitutions.launch_configuration.LaunchConfiguration"}
_DESCRIPTION = {"launch.LaunchDescription", "launch.launch_description.LaunchDescription"}
#: Actions that hold other actions (``actions=[...]``).
_GROUPS = {"launch.actions.GroupAction", "launch.actions.TimerAction"}


def _all_failed(reason: str, line: int | None = None) -> tuple[LaunchCheck, ...]:
    return tuple(LaunchCheck(name, False, reason, line) for name in (STARTS, DECLARES, PASSES))


def read_statically(path: Path | None, node: Path | None) -> LaunchReport:
    """The sheet's three checks of the launch file ``path`` for the node file ``node`` (None: none found), read
    from its source alone."""
    if path is None:
        return LaunchReport(None, _all_failed(f"no launch file handed in (expected {LAUNCH_NAME})"))
    try:
        source = path.read_bytes()
        tree = ast.parse(source, filename=path.name)
    except OSError as exc:
        return LaunchReport(path.name, _all_failed(f"{path.name} cannot be read ({exc.strerror or exc})"))
    except (SyntaxError, ValueError) as exc:
        line = getattr(exc, "lineno", None)
        msg = getattr(exc, "msg", None) or str(exc)
        return LaunchReport(path.name, _all_failed(f"{path.name} is not valid Python: {msg}", line))
    reader = _Reader(tree)
    described = reader.described()
    if described is None:
        return LaunchReport(path.name, _all_failed(
            "no generate_launch_description() function (ros2 launch calls it)"))
    return LaunchReport(path.name, reader.checks(described, node))


class _Reader:
    """What the module binds (imports, assignments, functions) and the calls its launch description holds."""

    def __init__(self, tree: ast.Module) -> None:
        self.tree = tree
        self.aliases: dict[str, str] = {}  # local name -> dotted name it was imported as
        self.stars: list[str] = []  # modules imported with *
        self.values: dict[str, ast.expr] = {}  # name -> the last value assigned to it anywhere
        self.functions: dict[str, ast.FunctionDef] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    self.aliases[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
            elif isinstance(node, ast.ImportFrom) and node.module:
                for a in node.names:
                    if a.name == "*":
                        self.stars.append(node.module)
                    else:
                        self.aliases[a.asname or a.name] = f"{node.module}.{a.name}"
            elif isinstance(node, ast.Assign):
                for target in node.targets:
                    if isinstance(target, ast.Name):
                        self.values[target.id] = node.value
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
                self.values[node.target.id] = node.value
            elif isinstance(node, ast.FunctionDef):
                self.functions[node.name] = node
        self.unsure = False  # the description holds something this reader cannot follow

    def qualname(self, func: ast.expr) -> str:
        """The dotted name a callee stands for (``Node`` -> ``launch_ros.actions.Node``), '' when unknown."""
        parts: list[str] = []
        while isinstance(func, ast.Attribute):
            parts.insert(0, func.attr)
            func = func.value
        if not isinstance(func, ast.Name):
            return ""
        head = self.aliases.get(func.id)
        if head is None:
            known = {"Node": "launch_ros.actions", "ExecuteProcess": "launch.actions",
                     "DeclareLaunchArgument": "launch.actions", "LaunchConfiguration": "launch.substitutions",
                     "LaunchDescription": "launch", "GroupAction": "launch.actions", "TimerAction": "launch.actions"}
            module = known.get(func.id)
            head = f"{module}.{func.id}" if module in self.stars else func.id
        return ".".join([head, *parts])

    def resolve(self, expr: ast.expr | None, depth: int = 0) -> ast.expr | None:
        """``expr`` with a variable replaced by the value last assigned to it."""
        while isinstance(expr, ast.Name) and expr.id in self.values and depth < 20:
            expr, depth = self.values[expr.id], depth + 1
        return expr

    def constant(self, expr: ast.expr | None) -> Any:
        """The constant ``expr`` resolves to (None: not a constant)."""
        expr = self.resolve(expr)
        return expr.value if isinstance(expr, ast.Constant) else None

    def described(self) -> list[ast.Call] | None:
        """The calls ``generate_launch_description()`` puts in its description (None: no such function)."""
        func = self.functions.get("generate_launch_description")
        if func is None:
            return None
        return self._entities_of_function(func, set())

    def _entities_of_function(self, func: ast.FunctionDef, seen: set[str]) -> list[ast.Call]:
        seen.add(func.name)
        out: list[ast.Call] = []
        for node in ast.walk(func):
            if isinstance(node, ast.Return) and node.value is not None:
                out += self._entities(node.value, seen, 0)
            elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                  and node.func.attr in ("add_action", "add_entity", "append", "extend", "insert")):
                for arg in node.args[-1:]:
                    out += self._entities(arg, seen, 0)
        return out

    def _entities(self, expr: ast.expr | None, seen: set[str], depth: int) -> list[ast.Call]:
        """The launch actions ``expr`` stands for: a list or tuple's elements, a description's, a group's."""
        expr = self.resolve(expr)
        if expr is None or depth > 30:
            return []
        if isinstance(expr, ast.List | ast.Tuple | ast.Set):
            return [c for e in expr.elts for c in self._entities(e, seen, depth + 1)]
        if isinstance(expr, ast.Starred):
            return self._entities(expr.value, seen, depth + 1)
        if isinstance(expr, ast.BinOp):
            return self._entities(expr.left, seen, depth + 1) + self._entities(expr.right, seen, depth + 1)
        if not isinstance(expr, ast.Call):
            self.unsure = self.unsure or not isinstance(expr, ast.Constant)
            return []
        name = self.qualname(expr.func)
        if name in _DESCRIPTION or name in _GROUPS:
            inner = [*expr.args[:1], *(k.value for k in expr.keywords if k.arg in ("initial_entities", "actions"))]
            return [expr] + [c for e in inner for c in self._entities(e, seen, depth + 1)]
        if isinstance(expr.func, ast.Name) and expr.func.id in self.functions and expr.func.id not in seen:
            return self._entities_of_function(self.functions[expr.func.id], seen)
        if name in _NODE | _PROCESS | _DECLARE:
            return [expr]
        if name.endswith("OpaqueFunction"):  # its actions come from a function run at launch time
            self.unsure = True
        self.unsure = self.unsure or not name.startswith(("launch.", "launch_ros."))
        return [expr]

    def calls(self, described: list[ast.Call], names: set[str]) -> tuple[list[ast.Call], list[ast.Call]]:
        """(the calls to ``names`` in the description, those elsewhere in the file); when the description could not
        be followed, every call in the file is taken as in it."""
        every = [n for n in ast.walk(self.tree) if isinstance(n, ast.Call) and self.qualname(n.func) in names]
        inside = [c for c in every if any(c is d for d in described)]
        if self.unsure:
            return every, []
        return inside, [c for c in every if not any(c is d for d in described)]

    def keyword(self, call: ast.Call, *names: str) -> ast.expr | None:
        return next((k.value for k in call.keywords if k.arg in names), None)

    def checks(self, described: list[ast.Call], node: Path | None) -> tuple[LaunchCheck, ...]:
        started, starts = self._starts(described, node)
        return starts, self._declares(described), self._passes(started)

    def _starts(self, described: list[ast.Call], node: Path | None) -> tuple[ast.Call | None, LaunchCheck]:
        """The call that starts the node (None: none) and the check saying so."""
        names = {"reactive_navigator", "reactive_navigator.py"}  # the sheet's name, whatever the file is named
        names |= {node.stem, node.name} if node is not None else set()
        nodes, outside = self.calls(described, _NODE)
        for call in nodes:
            executable = self.constant(self.keyword(call, "executable", "node_executable"))
            if isinstance(executable, str) and executable in names:
                package = self.constant(self.keyword(call, "package"))
                what = f"Node(package={package!r}, executable={executable!r})"
                return call, LaunchCheck(STARTS, True, what, call.lineno)
        for call in self.calls(described, _PROCESS)[0]:
            words = self.resolve(self.keyword(call, "cmd"))
            elts = words.elts if isinstance(words, ast.List | ast.Tuple) else []
            for word in (self.constant(e) for e in elts):
                if isinstance(word, str) and Path(word).name in names:
                    return call, LaunchCheck(STARTS, True, f"ExecuteProcess running {word!r}", call.lineno)
        want = " or ".join(sorted(names))
        if nodes:
            found = ", ".join(repr(self.constant(self.keyword(c, "executable", "node_executable"))) for c in nodes)
            return None, LaunchCheck(STARTS, False, f"its Node runs executable {found}, not {want}",
                                     nodes[0].lineno)
        if outside:
            return None, LaunchCheck(STARTS, False, "a Node is built but generate_launch_description() does not "
                                     "return it in the launch description", outside[0].lineno)
        return None, LaunchCheck(STARTS, False, f"no launch_ros.actions.Node (nor ExecuteProcess) starts {want}")

    def _declares(self, described: list[ast.Call]) -> LaunchCheck:
        declared, outside = self.calls(described, _DECLARE)
        mine = [c for c in declared if self._argument_name(c) == ARGUMENT]
        if not mine:
            if any(self._argument_name(c) == ARGUMENT for c in outside):
                return LaunchCheck(DECLARES, False, f"DeclareLaunchArgument('{ARGUMENT}') is built but not in the "
                                   "launch description", outside[0].lineno)
            return LaunchCheck(DECLARES, False, f"no DeclareLaunchArgument('{ARGUMENT}', default_value='0.5')")
        call = mine[0]
        default = self.keyword(call, "default_value")
        if default is None:
            return LaunchCheck(DECLARES, False, f"DeclareLaunchArgument('{ARGUMENT}') has no default_value (the "
                               "sheet's default is 0.5)", call.lineno)
        value = self.constant(default)
        try:
            right = not isinstance(value, bool) and float(value) == DEFAULT
        except (TypeError, ValueError):
            right = False
        shown = ast.unparse(self.resolve(default) or default)
        if right:
            return LaunchCheck(DECLARES, True, f"DeclareLaunchArgument('{ARGUMENT}', default_value={shown})",
                               call.lineno)
        return LaunchCheck(DECLARES, False, f"default_value is {shown}, the sheet asks 0.5", call.lineno)

    def _argument_name(self, call: ast.Call) -> Any:
        return self.constant(call.args[0] if call.args else self.keyword(call, "name"))

    def _passes(self, started: ast.Call | None) -> LaunchCheck:
        if started is None:
            return LaunchCheck(PASSES, False, "no Node starts the student's node: nothing to pass it to")
        if self.qualname(started.func) in _PROCESS:
            return self._passes_on_command_line(started)
        params = self.resolve(self.keyword(started, "parameters"))
        if params is None:
            return LaunchCheck(PASSES, False, "the Node has no parameters=[...]", started.lineno)
        entries = params.elts if isinstance(params, ast.List | ast.Tuple) else [params]
        for entry in (self.resolve(e) for e in entries):
            for key, value in self._items(entry):
                if self.constant(key) != ARGUMENT:
                    continue
                value = self.resolve(value)
                line = getattr(value, "lineno", started.lineno)
                if isinstance(value, ast.Call) and self.qualname(value.func) in _CONFIG:
                    name = self.constant(value.args[0] if value.args else self.keyword(value, "variable_name"))
                    if name == ARGUMENT:
                        return LaunchCheck(PASSES, True, f"parameters {{'{ARGUMENT}': LaunchConfiguration("
                                           f"'{ARGUMENT}')}}", line)
                    return LaunchCheck(PASSES, False, f"{ARGUMENT} is given LaunchConfiguration({name!r}), not "
                                       f"the launch argument '{ARGUMENT}'", line)
                shown = ast.unparse(value) if value is not None else "?"
                return LaunchCheck(PASSES, False, f"{ARGUMENT} is given {shown}, not "
                                   f"LaunchConfiguration('{ARGUMENT}'): the launch argument never reaches the node",
                                   line)
        return LaunchCheck(PASSES, False, f"{ARGUMENT} is not among the Node's parameters", started.lineno)

    def _passes_on_command_line(self, call: ast.Call) -> LaunchCheck:
        """An ExecuteProcess passes the argument in its ``cmd`` (``-p safety_distance:=`` then the configuration)."""
        for sub in ast.walk(self.resolve(self.keyword(call, "cmd")) or call):
            sub = self.resolve(sub) if isinstance(sub, ast.Name) else sub
            if isinstance(sub, ast.Call) and self.qualname(sub.func) in _CONFIG and self.constant(
                    sub.args[0] if sub.args else self.keyword(sub, "variable_name")) == ARGUMENT:
                return LaunchCheck(PASSES, True, f"LaunchConfiguration('{ARGUMENT}') on the command line",
                                   sub.lineno)
        return LaunchCheck(PASSES, False, f"the command never passes LaunchConfiguration('{ARGUMENT}')",
                           call.lineno)

    def _items(self, entry: ast.expr | None) -> list[tuple[ast.expr | None, ast.expr]]:
        """(key, value) pairs of a parameters entry: a dict literal, or ``dict(name=value)``."""
        if isinstance(entry, ast.Dict):
            return list(zip(entry.keys, entry.values, strict=True))
        if isinstance(entry, ast.Call) and isinstance(entry.func, ast.Name) and entry.func.id == "dict":
            return [(ast.Constant(k.arg), k.value) for k in entry.keywords if k.arg]
        return []
