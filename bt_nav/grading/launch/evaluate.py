"""A launch file evaluated as ``ros2 launch`` would run it, against the stand-ins of
:mod:`bt_nav.grading.launch.standins`: which nodes and processes it starts, with which parameters, and which launch
arguments it declares -- once with the defaults, once with ``safety_distance:=0.7`` given on the command line.

Why in a child process (:func:`evaluate`): evaluating runs the student's Python. The child has a time limit (a file
that hangs is killed at it), the hand-in folder as working directory, no bytecode written into it, DDS kept on the
machine and sockets refused (a launch file has no reason to open one), and it dies with its parent. What it finds
is plain JSON (:func:`walk`'s records), so the parent never holds a student's object.

Never raises on a student's file: what launch itself would stop with is ``{"stop": ...}``; what the stand-ins cannot
follow is ``{"unsure": ...}`` (the caller says "not checked", never "failed").
"""

from __future__ import annotations

import ast
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

import bt_nav.grading.launch.standins as s

#: Seconds a launch file may take to describe itself.
TIME_LIMIT = 10.0
#: How deep IncludeLaunchDescription may nest (a file including itself stops there).
INCLUDE_DEPTH = 8
#: The child's program: :func:`child_main` called, not this module run with ``-m`` (the package's ``__init__``
#: imports this module first, and ``-m`` would then run a second copy of it).
CHILD = "import sys; from bt_nav.grading.launch.evaluate import child_main; sys.exit(child_main(sys.argv[1:]))"


@dataclass
class Scope:
    """What a GroupAction scopes: the launch configurations, the ROS namespace, SetParameter's parameters."""

    configurations: dict[str, str]
    namespace: str = ""
    parameters: list[tuple[str, Any, str]] = field(default_factory=list)

    def copy(self) -> Scope:
        return Scope(dict(self.configurations), self.namespace, list(self.parameters))


def where(position: Any) -> str:
    """``file.launch.py:12`` of a stand-in's position (the file's name only: the hand-in is the reader's context)."""
    if not position:
        return "?"
    return f"{Path(position[0]).name}:{position[1]}"


_SOURCES: dict[str, ast.Module | None] = {}


def keyword_line(position: Any, keyword: str) -> int | None:
    """The line of ``keyword=`` in the call at ``position`` (the Node's ``parameters=``), None when not written so."""
    if not position or position[2] < 0:
        return None
    path = position[0]
    if path not in _SOURCES:
        try:
            _SOURCES[path] = ast.parse(Path(path).read_bytes())
        except (OSError, SyntaxError, ValueError):
            _SOURCES[path] = None
    tree = _SOURCES[path]
    for node in ast.walk(tree) if tree is not None else ():
        if isinstance(node, ast.Call) and (node.lineno, node.col_offset, node.end_lineno, node.end_col_offset) == \
                tuple(position[1:]):
            return next((k.lineno for k in node.keywords if k.arg == keyword), None)
    return None


class Walker:
    """One pass over a launch description, as launch executes it, recording what it starts."""

    def __init__(self, file: Path, arguments: dict[str, str]) -> None:
        self.file = file
        self.scope = Scope(dict(arguments))
        self.declared: list[dict[str, Any]] = []
        self.started: list[dict[str, Any]] = []
        self.unsure: list[str] = []
        self.skipped: list[dict[str, Any]] = []  # nodes whose condition was false
        self.depth = 0

    def context(self) -> s.LaunchContext:
        return s.LaunchContext(self.scope.configurations, self.file)

    def text(self, value: Any) -> str:
        return s.perform(self.context(), value)

    def visit(self, entity: Any) -> None:
        """Execute ``entity`` (an action, a description, a list of them) in the current scope."""
        if isinstance(entity, list | tuple):
            for e in entity:
                self.visit(e)
            return
        if not isinstance(entity, s.Recorded):
            return
        condition = entity.kwargs.get("condition")
        if isinstance(condition, s.Condition) and not condition.evaluate(self.context()):
            if isinstance(entity, s.Node):  # said, so a node left out by its condition is named as such
                executable = entity.kwargs.get("executable")
                self.skipped.append({"executable": executable if isinstance(executable, str) else "",
                                     "where": where(entity.position), "condition": type(condition).__name__})
            return
        handler = getattr(self, f"_{type(entity).__name__}", None)
        if handler is None and isinstance(entity, s.Node):
            handler = self._Node
        if handler is not None:
            try:
                handler(entity)
            except s.UnresolvableError as exc:  # this action only: the rest of the description still runs
                self.unsure.append(f"{exc} ({where(entity.position)})")
        elif _holds_node(entity):
            self.unsure.append(f"a Node inside {type(entity).__name__} ({where(entity.position)}): the grader does "
                               "not follow it")

    def _LaunchDescription(self, entity: s.LaunchDescription) -> None:
        self.visit(entity.entities)

    def _DeclareLaunchArgument(self, entity: s.Recorded) -> None:
        name = self.text(entity.arg(0, "name"))
        default = entity.arg(1, "default_value")
        try:
            text = None if default is None else self.text(default)
        except s.UnresolvableError as exc:  # its value unknown: whatever reads it is not checked
            self.declared.append({"name": name, "default": None, "unsure": str(exc), "where": where(entity.position)})
            self.scope.configurations.setdefault(name, s.UNSURE + str(exc))
            return
        self.declared.append({"name": name, "default": text, "where": where(entity.position)})
        if name not in self.scope.configurations:
            if text is None:
                raise s.LaunchError(f"the launch argument '{name}' has no default_value and was not given "
                                    "(a missing required argument)", _at(entity))
            self.scope.configurations[name] = text

    def _SetLaunchConfiguration(self, entity: s.Recorded) -> None:
        self.scope.configurations[self.text(entity.arg(0, "name"))] = self.text(entity.arg(1, "value"))

    def _GroupAction(self, entity: s.Recorded) -> None:
        saved = self.scope
        if entity.kwargs.get("scoped", True):
            self.scope = saved.copy()
            if not entity.kwargs.get("forwarding", True):
                self.scope.configurations = {}
        for key, value in (entity.kwargs.get("launch_configurations") or {}).items():
            self.scope.configurations[self.text(key)] = self.text(value)
        try:
            self.visit(entity.arg(0, "actions") or [])
        finally:
            if entity.kwargs.get("scoped", True):
                self.scope = saved

    def _TimerAction(self, entity: s.Recorded) -> None:
        self.visit(entity.kwargs.get("actions") or entity.arg(1, "actions") or [])

    def _OpaqueFunction(self, entity: s.Recorded) -> None:
        function = entity.arg(0, "function")
        args, kwargs = entity.kwargs.get("args") or [], entity.kwargs.get("kwargs") or {}
        self.visit(function(self.context(), *args, **kwargs) or [])

    def _IncludeLaunchDescription(self, entity: s.Recorded) -> None:
        source = entity.arg(0, "launch_description_source")
        if not isinstance(source, s.PythonLaunchDescriptionSource):
            self.unsure.append(f"IncludeLaunchDescription of {source!r} ({where(entity.position)})")
            return
        path = find_file(self.text(source.arg(0, "launch_file_path")), self.file)
        if path is None or self.depth >= INCLUDE_DEPTH:
            self.unsure.append(f"the included {self.text(source.arg(0, 'launch_file_path'))} is not in the hand-in "
                               f"({where(entity.position)})")
            return
        arguments = entity.arg(1, "launch_arguments") or []
        for key, value in (arguments.items() if isinstance(arguments, dict) else arguments):
            self.scope.configurations[self.text(key)] = self.text(value)
        saved, self.file = self.file, path
        self.depth += 1
        try:
            self.visit(describe(path))
        finally:
            self.file, self.depth = saved, self.depth - 1

    def _PushRosNamespace(self, entity: s.Recorded) -> None:
        self.scope.namespace = _join_ns(self.scope.namespace, self.text(entity.arg(0, "namespace")))

    def _SetParameter(self, entity: s.Recorded) -> None:
        self.scope.parameters.append((self.text(entity.arg(0, "name")), self.value(entity.arg(1, "value")),
                                      f"SetParameter at {where(entity.position)}"))

    def _ExecuteProcess(self, entity: s.Recorded) -> None:
        cmd = [self.text(c) for c in entity.kwargs.get("cmd") or []]
        params = {}
        for i, word in enumerate(cmd[:-1]):
            if word == "-p" and ":=" in cmd[i + 1]:
                name, _, value = cmd[i + 1].partition(":=")
                params[name] = {"value": _yaml(value), "source": where(entity.position)}
        self.started.append({"kind": "process", "cmd": cmd, "executable": "", "package": None,
                             "where": where(entity.position), "parameters": params})

    def _Node(self, entity: s.Recorded) -> None:
        kw = entity.kwargs
        line = keyword_line(entity.position, "parameters")
        cited = f"{Path(entity.position[0]).name}:{line}" if line and entity.position else where(entity.position)
        params: dict[str, dict[str, Any]] = {}
        for name, value, source in self.scope.parameters:
            params[name] = {"value": value, "source": source}
        for entry in kw.get("parameters") or []:
            self._parameters(entry, params, cited, kw)
        for word in _ros_args(self, kw):
            name, _, value = word.partition(":=")
            params[name] = {"value": _yaml(value), "source": where(entity.position)}
        optional = {k: (self.text(kw[k]) if kw.get(k) is not None else None) for k in ("package", "name", "namespace")}
        self.started.append({
            "kind": "node", "package": optional["package"], "name": optional["name"],
            "executable": self.text(kw.get("executable") or kw.get("node_executable") or ""),
            "namespace": _join_ns(self.scope.namespace, optional["namespace"] or ""),
            "where": where(entity.position), "parameters_at": cited, "parameters": params,
            "remappings": [[self.text(a), self.text(b)] for a, b in kw.get("remappings") or []]})

    def _parameters(self, entry: Any, params: dict[str, dict[str, Any]], cited: str, kw: dict[str, Any]) -> None:
        """One entry of a Node's ``parameters=``: a dict (nested keys joined with dots) or a params file."""
        if isinstance(entry, dict):
            for name, value in _flatten(entry, self):
                try:
                    params[name] = {"value": self.value(value), "source": cited}
                except s.UnresolvableError as exc:
                    params[name] = {"unsure": str(exc), "source": cited}
            return
        target = entry.arg(0, "param_file") if isinstance(entry, s.ParameterFile) else entry
        path = find_file(self.text(target), self.file)
        if path is None:
            raise s.UnresolvableError(f"the params file {self.text(target)} ({cited}) is not in the hand-in")
        name = self.text(kw["name"]) if kw.get("name") is not None else None
        for key, (value, line) in yaml_parameters(path, name).items():
            params[key] = {"value": value, "source": f"{path.name}:{line}, given at {cited}"}

    def value(self, value: Any) -> Any:
        """A parameter's value as launch_ros gives it to the node: substitutions performed and read as YAML,
        ``ParameterValue(value_type=...)`` converted, plain Python values as they are."""
        if isinstance(value, s.ParameterValue):
            inner, kind = value.arg(0, "value"), value.kwargs.get("value_type")
            if not isinstance(inner, str | s.Substitution | list | tuple):
                return inner
            text = self.text(inner)
            if kind in (float, int, str):
                try:
                    return kind(text)
                except ValueError:
                    raise s.LaunchError(f"ParameterValue({text!r}, value_type={kind.__name__}): launch_ros cannot "
                                        f"convert it ({where(value.position)})", _at(value)) from None
            return _yaml(text)
        if isinstance(value, str | s.Substitution) or (isinstance(value, list | tuple) and any(
                isinstance(v, s.Substitution) for v in value)):
            return _yaml(self.text(value))
        if isinstance(value, list | tuple):
            return [self.value(v) for v in value]
        return value


def _at(obj: s.Recorded) -> tuple[str, int] | None:
    return (obj.position[0], obj.position[1]) if obj.position else None


def _holds_node(entity: s.Recorded, depth: int = 0) -> bool:
    values = [*entity.args, *entity.kwargs.values()]
    for v in values:
        if isinstance(v, s.Node):
            return True
        items = v if isinstance(v, list | tuple) else [v]
        if depth < 4 and any(isinstance(i, s.Recorded) and (isinstance(i, s.Node) or _holds_node(i, depth + 1))
                             for i in items):
            return True
    return False


def _ros_args(walker: Walker, kw: dict[str, Any]) -> list[str]:
    """``-p name:=value`` pairs of a Node's ``arguments`` / ``ros_arguments``."""
    words = [walker.text(w) for w in [*(kw.get("ros_arguments") or []), *(kw.get("arguments") or [])]]
    return [words[i + 1] for i in range(len(words) - 1) if words[i] in ("-p", "--param") and ":=" in words[i + 1]]


def _flatten(entry: dict[Any, Any], walker: Walker, prefix: str = "") -> list[tuple[str, Any]]:
    out = []
    for key, value in entry.items():
        name = prefix + walker.text(key)
        out += _flatten(value, walker, name + ".") if isinstance(value, dict) else [(name, value)]
    return out


def _join_ns(outer: str, inner: str) -> str:
    if inner.startswith("/"):
        return inner
    return "/".join(p for p in (outer.strip("/"), inner.strip("/")) if p)


def _yaml(text: str) -> Any:
    """A substitution's text as launch_ros types it (YAML): ``'0.5'`` -> 0.5, ``'true'`` -> True."""
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        return text
    return value if isinstance(value, bool | int | float | str | list) else text


#: Folders of a hand-in never searched: a colcon workspace's outputs, caches, a virtual environment.
SKIPPED = {"build", "install", "log", "__pycache__", "node_modules", "venv"}


def hand_in_files(folder: Path, *names: str) -> list[Path]:
    """The files named ``names`` in the hand-in ``folder``, hidden and :data:`SKIPPED` folders pruned (a workspace's
    ``build/`` or a ``.venv`` is never walked), in a stable order."""
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in SKIPPED)
        found += [Path(root) / f for f in sorted(files) if f in names]
    return found


def find_file(text: str, launch_file: Path) -> Path | None:
    """A file a launch file names, in the hand-in: as named (relative to the working directory: the hand-in), else
    the file of that name anywhere in the hand-in (an installed share's ``config/x.yaml`` is the hand-in's
    ``x.yaml``), else beside the launch file."""
    path = Path(text)
    if path.is_file():
        return path.resolve()
    for base in (s.SHARE[0], launch_file.parent):
        found = hand_in_files(Path(base), path.name)
        if found:
            return found[0].resolve()
    return None


def yaml_parameters(path: Path, node_name: str | None) -> dict[str, tuple[Any, int]]:
    """The parameters a params file gives a node (``/**`` or the node's name, then ``ros__parameters``): name ->
    (value, line in the file). ``node_name`` None (the Node sets none): every node's section counts."""
    try:
        text = path.read_text(encoding="utf-8")
        doc = yaml.safe_load(text)
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise s.LaunchError(f"the params file {path.name} is not valid YAML: {exc}") from None
    out: dict[str, tuple[Any, int]] = {}
    for key, section in (doc or {}).items() if isinstance(doc, dict) else ():
        leaf = str(key).rstrip("/").rpartition("/")[2]
        if not isinstance(section, dict) or "ros__parameters" not in section:
            continue
        if leaf in ("**", "*") or node_name is None or leaf == node_name:
            for name, value in _flat(section["ros__parameters"] or {}):
                match = re.search(rf"^\s*{re.escape(name.rpartition('.')[2])}\s*:", text, re.MULTILINE)
                out[name] = (value, text[:match.start()].count("\n") + 1 if match else 1)
    return out


def _flat(doc: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    out = []
    for key, value in doc.items():
        out += _flat(value, f"{prefix}{key}.") if isinstance(value, dict) else [(f"{prefix}{key}", value)]
    return out


def describe(path: Path) -> Any:
    """What the launch file's ``generate_launch_description()`` returns (the stand-ins installed)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"launch_file_{abs(hash(str(path)))}", path)
    if spec is None or spec.loader is None:
        raise s.LaunchError(f"{path.name} cannot be loaded as Python")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    function = getattr(module, "generate_launch_description", None)
    if function is None:
        raise s.LaunchError("no generate_launch_description() function (ros2 launch calls it)")
    return function()


def walk(path: Path, arguments: dict[str, str]) -> dict[str, Any]:
    """One run of the launch file with the command-line ``arguments``: what it declares and starts, or why launch
    would stop (``stop``), or what the grader could not follow (``unsure``)."""
    walker = Walker(path, arguments)
    try:
        description = describe(path)
        if not isinstance(description, s.LaunchDescription):
            raise s.LaunchError(f"generate_launch_description() returns a {type(description).__name__}, not a "
                                "LaunchDescription (launch asks the description for its arguments)")
        walker.visit(description)
    except s.LaunchError as exc:
        return {"stop": str(exc), "where": None if exc.where is None else where(exc.where)}
    except s.UnresolvableError as exc:
        walker.unsure.append(str(exc))
    except Exception as exc:  # noqa: BLE001 (the student's code raised: reported, never re-raised)
        return {"unsure": [f"evaluating it raised {type(exc).__name__}: {exc}" + _student_frame(exc, path)],
                "raised": True}
    return {"declared": walker.declared, "started": walker.started, "unsure": walker.unsure,
            "skipped": walker.skipped}


def _student_frame(exc: BaseException, path: Path) -> str:
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if Path(f.filename).parent == path.parent]
    return f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""


def _no_sockets(*args: Any, **kwargs: Any) -> Any:
    raise OSError("no network while a launch file is evaluated")


def child_main(argv: list[str]) -> int:
    """In the child: ``FILE SHARE OUT [NAME:=VALUE ...]``; writes ``{"runs": [defaults, overrides]}`` to OUT."""
    file, share, out, *given = argv
    sys.dont_write_bytecode = True
    socket.socket = _no_sockets  # type: ignore[assignment,misc]
    s.SHARE[0] = Path(share).resolve()
    overrides = dict(a.split(":=", 1) for a in given)
    sys.stdout = sys.stderr  # whatever the file prints is not the answer
    with s.installed():
        runs = [walk(Path(file).resolve(), {}), walk(Path(file).resolve(), overrides)]
    Path(out).write_text(json.dumps({"runs": runs}, default=repr), encoding="utf-8")
    return 0


def evaluate(path: Path, share: Path, overrides: dict[str, str], limit: float = TIME_LIMIT) -> dict[str, Any]:
    """Evaluate ``path`` in a child process (module docstring): ``{"runs": [with defaults, with overrides]}``, or
    ``{"failed": why}`` when the child did not answer (a hang killed at the limit, a crash)."""
    from bt_nav.ros.supervise import child_preexec

    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONDONTWRITEBYTECODE": "1"}
    with tempfile.TemporaryDirectory(prefix="bt_nav_launch_") as tmp:
        out = Path(tmp) / "evaluation.json"
        command = [sys.executable, "-P", "-c", CHILD, str(Path(path).resolve()),
                   str(Path(share).resolve()), str(out), *(f"{k}:={v}" for k, v in overrides.items())]
        try:
            done = subprocess.run(command, cwd=share, env=env, capture_output=True, timeout=limit, check=False,
                                  preexec_fn=child_preexec(os.getpid(), 9), stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            return {"failed": f"it did not finish describing itself within {limit:g} s (killed)", "hung": True}
        try:
            return json.loads(out.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError):
            tail = done.stderr.decode(errors="replace").strip().splitlines()[-1:] or ["no output"]
            return {"failed": f"evaluating it ended with exit code {done.returncode} ({tail[0]})"}

