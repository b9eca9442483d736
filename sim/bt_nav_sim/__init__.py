"""Pure-numpy 2D TurtleBot3 simulator core: worlds, kinematics and LiDAR, with no ROS dependency.

Kept free of rclpy so the executive's behaviours can be tested and benchmarked headless and fast; a ROS
node wraps these functions to publish /scan and /odom and consume /cmd_vel.
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
