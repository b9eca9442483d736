"""The lab's bringup: the bt_nav executive on a TurtleBot, armed through ``/toggle_navigation``.

    ros2 launch bt_nav turtlebot_bringup.launch.py safety_distance:=0.4 maneuver:=C
    ros2 param list /bt_nav_executive
    ros2 service call /toggle_navigation std_srvs/srv/SetBool "{data: true}"
"""

from launch import LaunchDescription

from bt_nav.ros.bringup import nodes
from bt_nav.ros.launching import declare, to_actions

ARGUMENTS = ["safety_distance", "maneuver", "use_sim_time"]


def generate_launch_description() -> LaunchDescription:
    """The executive only (no simulator): the real robot provides scan, odom and cmd_vel."""
    specs = nodes("lab", include_sim=False)
    return LaunchDescription(declare(ARGUMENTS) + to_actions(specs, {"executive": ARGUMENTS}))
