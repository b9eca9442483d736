"""Pure-numpy 2D TurtleBot3 simulator core: worlds, kinematics and LiDAR, with no ROS dependency.

Kept free of rclpy so the executive's behaviours can be tested and benchmarked headless and fast; the ROS nodes
that wrap it (the simulator publishing /scan and /odom and consuming /cmd_vel, the two judges) live in
:mod:`bt_nav.ros.nodes`. The judges themselves live in :mod:`bt_nav.judge`; the simulator only feeds them its truth
(:mod:`bt_nav_sim.truth`: readings cast in its world).
"""

from bt_nav_sim.lidar import HOMEWORK_LIDAR, LDS01, LidarModel, RayCaster, cast_rays
from bt_nav_sim.physics import RobotParams, RobotState, step
from bt_nav_sim.world import World, list_worlds, load_world, world_from_dict

__all__ = [
    "HOMEWORK_LIDAR",
    "LDS01",
    "LidarModel",
    "RayCaster",
    "RobotParams",
    "RobotState",
    "World",
    "cast_rays",
    "list_worlds",
    "load_world",
    "step",
    "world_from_dict",
]
