"""Recording stand-ins for the ROS 2 launch API (``launch``, ``launch_ros``, ``ament_index_python``): a launch file's
``generate_launch_description()`` runs against them as it would under ``ros2 launch``, and what it builds can then
be inspected (:mod:`bt_nav.grading.launch.evaluate` walks it) or asserted on (tests/test_launch.py).

Why stand-ins and not the real packages: ``launch`` and ``launch_ros`` are not on PyPI, so neither a pip venv nor a
Gradescope image has them; and a stand-in keeps what it was called with (``.args``, ``.kwargs``, the student's
source position) where the real classes hide it. Why substitutions perform here as launch performs them: a student
writes the default of ``safety_distance`` many ways (``'0.5'``, ``str(0.5)``, a ``PythonExpression``, a
``LaunchConfiguration`` with ``default=``); only resolving them says what the node gets.

What the stand-ins do not know is never guessed: any other name imported from these packages is a generic
recorded action or substitution, and performing an unknown substitution raises :class:`UnresolvableError` (the caller
turns that into "not checked", never a failure). Pure: no rclpy, no launch.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys
import types
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

#: The packages served by stand-ins (any submodule of them too: ``launch_ros.actions.node``).
PACKAGES = ("launch", "launch_ros", "ament_index_python")
#: The folder ``get_package_share_directory`` / ``FindPackageShare`` stand for (a hand-in's); set by the caller.
SHARE: list[Path] = [Path.cwd()]
#: A launch configuration whose value the stand-ins could not work out starts with this (then why).
UNSURE = "\x00unsure: "


class UnresolvableError(Exception):
    """A value the stand-ins cannot work out as launch would (an unknown substitution, a shell ``Command``)."""


class LaunchError(Exception):
    """What ``ros2 launch`` itself would stop with (a float ``default_value``, a missing launch configuration)."""

    def __init__(self, message: str, where: tuple[str, int] | None = None) -> None:
        super().__init__(message)
        self.where = where


def _standin_files() -> set[str]:
    here = Path(__file__).resolve().parent
    return {str(here / "standins.py"), str(here / "evaluate.py")}


_OWN = _standin_files()


def caller_position() -> tuple[str, int, int, int, int] | None:
    """(file, line, column, end line, end column) of the call into the stand-ins from outside them (the student's
    ``Node(...)``): where a check cites it."""
    frame = sys._getframe(1)
    while frame is not None and (frame.f_code.co_filename in _OWN or frame.f_code.co_filename == __file__):
        frame = frame.f_back
    if frame is None:
        return None
    try:
        line, end, col, end_col = list(frame.f_code.co_positions())[frame.f_lasti // 2]
    except (IndexError, ValueError):
        return frame.f_code.co_filename, frame.f_lineno, -1, -1, -1
    return frame.f_code.co_filename, line or frame.f_lineno, -1 if col is None else col, end or -1, \
        -1 if end_col is None else end_col


class Recorded:
    """A stand-in launch object: keeps its constructor arguments and where in the student's file it was built."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs
        self.position = caller_position()

    def arg(self, index: int, name: str, default: Any = None) -> Any:
        """The argument given at ``index`` or as ``name``."""
        if len(self.args) > index:
            return self.args[index]
        return self.kwargs.get(name, default)

    def __repr__(self) -> str:
        shown = [repr(a) for a in self.args] + [f"{k}={v!r}" for k, v in self.kwargs.items()]
        return f"{type(self).__name__}({', '.join(shown)})"


# ---------------------------------------------------------------------------------------------- substitutions
class Substitution(Recorded):
    """A value known when the launch runs: ``perform(context)`` gives its text."""

    def perform(self, context: Any) -> str:
        raise UnresolvableError(f"{type(self).__name__} is not one the grader can resolve")


def perform(context: Any, value: Any) -> str:
    """Text of ``value`` as launch's ``perform_substitutions`` gives it: a string, a substitution, or a list of them
    (joined). Anything else is what launch's ``normalize_to_list_of_substitutions`` refuses (TypeError)."""
    if isinstance(value, str):
        return value
    if isinstance(value, Substitution):
        return value.perform(context)
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, list | tuple):
        return "".join(perform(context, v) for v in value)
    raise LaunchError(f"{value!r} ({type(value).__name__}) is neither a string nor a substitution (TypeError)")


class TextSubstitution(Substitution):
    def perform(self, context: Any) -> str:
        return str(self.arg(0, "text", ""))


class LaunchConfiguration(Substitution):
    def perform(self, context: Any) -> str:
        name = perform(context, self.arg(0, "variable_name"))
        if name in context.launch_configurations:
            value = context.launch_configurations[name]
            if value.startswith(UNSURE):
                raise UnresolvableError(value.removeprefix(UNSURE))
            return value
        default = self.arg(1, "default")
        if default is None:
            raise LaunchError(f"launch configuration '{name}' does not exist (no DeclareLaunchArgument with a "
                              "default, no default=, and not given on the command line)", _line(self))
        return perform(context, default)


class EnvironmentVariable(Substitution):
    def perform(self, context: Any) -> str:
        name = perform(context, self.arg(0, "name"))
        default = self.arg(1, "default_value")
        if name in os.environ:
            return os.environ[name]
        if default is None:
            raise UnresolvableError(f"environment variable {name} (not set where the grader runs)")
        return perform(context, default)


class PythonExpression(Substitution):
    def perform(self, context: Any) -> str:
        import math

        text = perform(context, self.arg(0, "expression"))
        try:
            return str(eval(text, {"__builtins__": {}, "math": math}, {}))  # noqa: S307 (the student's own text)
        except Exception as exc:  # noqa: BLE001 (anything the expression raises)
            raise UnresolvableError(f"PythonExpression({text!r}): {type(exc).__name__}: {exc}") from None


class PathJoinSubstitution(Substitution):
    def perform(self, context: Any) -> str:
        parts = self.arg(0, "substitutions") or []
        return os.path.join(*(perform(context, p) for p in parts)) if parts else ""


class FindPackageShare(Substitution):
    def perform(self, context: Any) -> str:
        return str(SHARE[0])


class FindPackagePrefix(FindPackageShare):
    pass


class ThisLaunchFileDir(Substitution):
    def perform(self, context: Any) -> str:
        return str(Path(context.current_file).parent)


class ThisLaunchFile(Substitution):
    def perform(self, context: Any) -> str:
        return str(context.current_file)


class AnonName(Substitution):
    def perform(self, context: Any) -> str:
        return f"{perform(context, self.arg(0, 'name'))}_anon"


class NotSubstitution(Substitution):
    def perform(self, context: Any) -> str:
        return "false" if truthy(perform(context, self.arg(0, "value"))) else "true"


def truthy(text: str) -> bool:
    """A condition's text as launch reads it (``true``/``1`` true, ``false``/``0`` false; anything else refused)."""
    low = text.strip().lower()
    if low in ("true", "1"):
        return True
    if low in ("false", "0"):
        return False
    raise LaunchError(f"a condition is {text!r}: launch accepts true/false/1/0")


# ---------------------------------------------------------------------------------------------- conditions
class Condition(Recorded):
    def evaluate(self, context: Any) -> bool:
        raise UnresolvableError(f"{type(self).__name__} is not a condition the grader can evaluate")


class IfCondition(Condition):
    def evaluate(self, context: Any) -> bool:
        return truthy(perform(context, self.arg(0, "predicate_expression")))


class UnlessCondition(IfCondition):
    def evaluate(self, context: Any) -> bool:
        return not super().evaluate(context)


class LaunchConfigurationEquals(Condition):
    def evaluate(self, context: Any) -> bool:
        name = self.arg(0, "launch_configuration_name")
        return context.launch_configurations.get(name) == perform(context, self.arg(1, "expected_value") or "")


class LaunchConfigurationNotEquals(LaunchConfigurationEquals):
    def evaluate(self, context: Any) -> bool:
        return not super().evaluate(context)


# ---------------------------------------------------------------------------------------------- actions
class Action(Recorded):
    """A launch action (what a description holds)."""


class LaunchDescription(Action):
    def __init__(self, initial_entities: Sequence[Any] | None = None, **kwargs: Any) -> None:
        super().__init__(*(() if initial_entities is None else (initial_entities,)), **kwargs)
        self.entities = list(initial_entities or [])

    def add_action(self, action: Any) -> None:
        self.entities.append(action)

    add_entity = add_action


class DeclareLaunchArgument(Action):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        default = self.arg(1, "default_value")
        if default is not None and not isinstance(default, str | Substitution | list | tuple):
            raise LaunchError(f"DeclareLaunchArgument('{self.arg(0, 'name')}', default_value={default!r}): a "
                              f"{type(default).__name__} is not a string or substitution (TypeError); write "
                              f"default_value='{default}'", _line(self))


class SetLaunchConfiguration(Action):
    pass


class GroupAction(Action):
    pass


class TimerAction(Action):
    pass


class OpaqueFunction(Action):
    pass


class IncludeLaunchDescription(Action):
    pass


class ExecuteProcess(Action):
    pass


class LogInfo(Action):
    pass


class Node(Action):
    pass


class LifecycleNode(Node):
    pass


class PushRosNamespace(Action):
    pass


class SetParameter(Action):
    pass


class SetRemap(Action):
    pass


class ParameterValue(Recorded):
    pass


class ParameterFile(Recorded):
    pass


class PythonLaunchDescriptionSource(Recorded):
    pass


class AnyLaunchDescriptionSource(PythonLaunchDescriptionSource):
    pass


class LaunchContext:
    """What an ``OpaqueFunction`` gets: the launch configurations in effect, ``perform_substitution``."""

    def __init__(self, configurations: dict[str, str], current_file: Path) -> None:
        self.launch_configurations = configurations
        self.current_file = current_file
        self.locals = types.SimpleNamespace()
        self.environment = dict(os.environ)

    def perform_substitution(self, substitution: Any) -> str:
        return perform(self, substitution)


def get_package_share_directory(package_name: str, *args: Any, **kwargs: Any) -> str:
    """The hand-in folder, whatever the package: a student's installed share is what they handed in."""
    return str(SHARE[0])


def _line(obj: Recorded) -> tuple[str, int] | None:
    return (obj.position[0], obj.position[1]) if obj.position else None


# ---------------------------------------------------------------------------------------------- the modules
#: module -> the names it holds (a submodule such as ``launch.actions.node`` serves its package's names).
MODULES: dict[str, tuple[type | Any, ...]] = {
    "launch": (LaunchDescription, LaunchContext, Substitution, Condition, Action),
    "launch.actions": (DeclareLaunchArgument, SetLaunchConfiguration, GroupAction, TimerAction, OpaqueFunction,
                       IncludeLaunchDescription, ExecuteProcess, LogInfo),
    "launch.substitutions": (TextSubstitution, LaunchConfiguration, EnvironmentVariable, PythonExpression,
                             PathJoinSubstitution, ThisLaunchFileDir, ThisLaunchFile, AnonName, NotSubstitution),
    "launch.conditions": (IfCondition, UnlessCondition, LaunchConfigurationEquals, LaunchConfigurationNotEquals),
    "launch.launch_description_sources": (PythonLaunchDescriptionSource, AnyLaunchDescriptionSource),
    "launch.utilities": (perform,),
    "launch_ros": (),
    "launch_ros.actions": (Node, LifecycleNode, PushRosNamespace, SetParameter, SetRemap),
    "launch_ros.substitutions": (FindPackageShare, FindPackagePrefix),
    "launch_ros.parameter_descriptions": (ParameterValue, ParameterFile),
    "ament_index_python": (get_package_share_directory,),
    "ament_index_python.packages": (get_package_share_directory,),
}


def _generic(name: str, module: str) -> Any:
    """A name these stand-ins do not know: a recorded substitution or action (by its module), never a guess."""
    base = Substitution if module.startswith(("launch.substitutions", "launch_ros.substitutions")) else Action
    if module.startswith("launch.conditions"):
        base = Condition
    return type(name, (base,), {"__module__": module})


class _StandinModule(types.ModuleType):
    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        value = _generic(name, self.__name__)
        setattr(self, name, value)
        return value


def _module(name: str) -> types.ModuleType:
    module = _StandinModule(name)
    module.__path__ = []  # a package: its submodules import
    for value in MODULES.get(name, ()):
        setattr(module, value.__name__, value)
    parent = name.rpartition(".")[0]
    if name not in MODULES and parent:  # launch.actions.declare_launch_argument: its package's names
        for value in MODULES.get(parent, ()):
            setattr(module, value.__name__, value)
    return module


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Serves every module of :data:`PACKAGES` from the stand-ins."""

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if fullname.split(".")[0] in PACKAGES:
            return importlib.machinery.ModuleSpec(fullname, self, is_package=True)
        return None

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        return _module(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        parent, _, child = module.__name__.rpartition(".")
        if parent and parent in sys.modules:
            setattr(sys.modules[parent], child, module)


def standin_modules() -> dict[str, types.ModuleType]:
    """Every known stand-in module, each package's submodules set as its attributes (``launch.actions``)."""
    modules = {name: _module(name) for name in MODULES}
    for name, module in modules.items():
        parent, _, child = name.rpartition(".")
        if parent in modules:
            setattr(modules[parent], child, module)
    return modules


@contextmanager
def installed() -> Iterator[None]:
    """The stand-ins in ``sys.modules`` (and any submodule of them importable) while the block runs."""
    saved = {n: m for n, m in sys.modules.items() if n.split(".")[0] in PACKAGES}
    finder = _Finder()
    for name in saved:
        del sys.modules[name]
    sys.modules.update(standin_modules())
    sys.meta_path.insert(0, finder)
    try:
        yield
    finally:
        sys.meta_path.remove(finder)
        for name in [n for n in sys.modules if n.split(".")[0] in PACKAGES]:
            del sys.modules[name]
        sys.modules.update(saved)
