"""Turn :mod:`bt_nav.ros.bringup`'s node table into ``launch_ros`` actions, for ``launch/*.launch.py``.

The launch files stay a few lines each: which profile, which launch arguments. The nodes, their
parameters and remaps come from the same table ``bt-nav sim-run`` uses, so the two ways of starting
bt_nav cannot drift apart. ``launch`` and ``launch_ros`` are imported only when a launch file runs.
"""

from __future__ import annotations

from typing import Any

from bt_nav.mission.params import SPECS
from bt_nav.ros.bringup import NodeSpec

#: Launch arguments that are not executive parameters: name -> (default, description, target node)
EXTRA_ARGUMENTS: dict[str, tuple[str, str]] = {
    "use_sim_time": ("false", "follow /clock (true in simulation)"),
    "world": ("stage_4", "simulator world (name under sim/bt_nav_sim/worlds or a YAML path)"),
    "seed": ("0", "seed of the simulator's noise and generated worlds"),
    "real_time_factor": ("1.0", "simulator speed (0: as fast as the executive keeps up)"),
    "results_json": ("", "where the referee writes its verdict (empty: not written)"),
    "stamped": ("true", "cmd_vel as geometry_msgs/TwistStamped (what the TurtleBot3 Jazzy stack expects); "
                "false: Twist, for turtlebot3_node with enable_stamped_cmd_vel: false (e.g. Humble)"),
    "stamped_frame_id": ("base_footprint", "header.frame_id of stamped commands (TurtleBot3's base frame)"),
    "namespace": ("", "namespace of every node, e.g. robot1 for one robot of several (empty: none); the "
                  "service names are relative, so inside it they are /<namespace>/reactive_control/..."),
}
#: Launch arguments that are not in the parameter table but are not strings either.
_EXTRA_TYPES: dict[str, type] = {"use_sim_time": bool, "stamped": bool}

_TYPES = {bool: bool, int: int, float: float, str: str}


def argument_default(name: str) -> str:
    """A launch argument's default as text: from the parameter table, or :data:`EXTRA_ARGUMENTS`."""
    if name in SPECS:
        value = SPECS[name].default
        return str(value).lower() if isinstance(value, bool) else str(value)
    return EXTRA_ARGUMENTS[name][0]


def argument_description(name: str) -> str:
    """The parameter table's description (with unit), or the extra argument's."""
    if name in SPECS:
        spec = SPECS[name]
        return spec.description + (f" [{spec.unit}]" if spec.unit else "")
    return EXTRA_ARGUMENTS[name][1]


def declare(names: list[str], defaults: dict[str, str] | None = None) -> list[Any]:
    """``DeclareLaunchArgument`` for each name, defaults and descriptions from the tables; ``defaults``
    overrides a default where a launch file needs its own (the lab check-off's maneuver and arena)."""
    from launch.actions import DeclareLaunchArgument

    own = defaults or {}
    return [DeclareLaunchArgument(n, default_value=own.get(n, argument_default(n)), description=argument_description(n))
            for n in names]


def typed(name: str) -> Any:
    """``LaunchConfiguration(name)`` as a parameter value of the parameter's declared type."""
    from launch.substitutions import LaunchConfiguration
    from launch_ros.parameter_descriptions import ParameterValue

    python_type = type(SPECS[name].default) if name in SPECS else _EXTRA_TYPES.get(name, str)
    return ParameterValue(LaunchConfiguration(name), value_type=_TYPES[python_type])


Wiring = dict[str, list[str | tuple[str, str]]]


def to_actions(specs: list[NodeSpec], from_arguments: Wiring, namespace: str | None = None) -> list[Any]:
    """A ``launch_ros.actions.Node`` per spec; ``from_arguments[executable]`` lists the parameters of
    that node whose values come from launch arguments: a name (argument of the same name) or a
    ``(parameter, argument)`` pair. ``namespace``: the launch argument that names every node's namespace
    (build the specs with ``nodes(..., namespace="")`` then, so their service names are relative)."""
    from launch.substitutions import LaunchConfiguration
    from launch_ros.actions import Node

    actions = []
    for spec in specs:
        parameters: dict[str, Any] = dict(spec.parameters)
        for item in from_arguments.get(spec.executable, []):
            parameter, argument = (item, item) if isinstance(item, str) else item
            parameters[parameter] = typed(argument)
        extra = {"namespace": LaunchConfiguration(namespace)} if namespace else \
            ({"namespace": spec.namespace} if spec.namespace else {})
        actions.append(Node(package="bt_nav", executable=spec.executable, name=spec.name, output="screen",
                            arguments=spec.arguments, parameters=[*spec.parameter_files, parameters],
                            remappings=spec.remappings, **extra))
    return actions
