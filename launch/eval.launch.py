"""The homework's evaluation: simulator + executive + referee; the referee prints the verdict.

    ros2 launch bt_nav eval.launch.py maneuver:=C results_json:=/tmp/verdict.json
"""

from launch import LaunchDescription

from bt_nav.ros.bringup import nodes
from bt_nav.ros.launching import declare, to_actions

ARGUMENTS = ["maneuver", "safety_distance", "world", "seed", "real_time_factor", "results_json", "namespace"]


def generate_launch_description() -> LaunchDescription:
    """sim + executive + referee in the homework profile."""
    specs = nodes("eval", namespace="")
    return LaunchDescription(declare(ARGUMENTS) + to_actions(specs, {
        "executive": ["maneuver", "safety_distance"],
        "sim": ["world", "seed", "real_time_factor"],
        "referee": [("json", "results_json")],
    }, namespace="namespace"))
