"""The homework in the bt_nav simulator: simulator + executive (homework services, sim time).

    ros2 launch bt_nav sim.launch.py maneuver:=A world:=stage_4
    ros2 service call /reactive_control/activate std_srvs/srv/SetBool "{data: true}"
"""

from launch import LaunchDescription

from bt_nav.ros.bringup import nodes
from bt_nav.ros.launching import declare, to_actions

ARGUMENTS = ["maneuver", "safety_distance", "world", "seed", "real_time_factor", "namespace"]


def generate_launch_description() -> LaunchDescription:
    """sim + executive in the homework profile."""
    specs = nodes("homework", namespace="")
    return LaunchDescription(declare(ARGUMENTS) + to_actions(specs, {
        "executive": ["maneuver", "safety_distance"],
        "sim": ["world", "seed", "real_time_factor"],
    }, namespace="namespace"))
