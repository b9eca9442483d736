"""The lab's bringup: the bt_nav executive on a TurtleBot3, armed through ``/toggle_navigation``.

    ros2 launch bt_nav turtlebot_bringup.launch.py safety_distance:=0.4 maneuver:=C
    ros2 param list /bt_nav_executive
    ros2 service call /toggle_navigation std_srvs/srv/SetBool "{data: true}"
    (without ros2: bt-nav arm --service /toggle_navigation)

/cmd_vel type. The TurtleBot3 Jazzy stack subscribes to geometry_msgs/TwistStamped on /cmd_vel:
- ROBOTIS-GIT/turtlebot3, branch jazzy (1f67e8d), turtlebot3_node/include/turtlebot3_node/
  twist_subscriber.hpp: TwistStamped when the parameter ``enable_stamped_cmd_vel`` is true (declared
  false), and turtlebot3_bringup/param/burger.yaml (also waffle, waffle_pi) sets
  ``enable_stamped_cmd_vel: true``; the Humble files under param/humble/ set it false;
- ROBOTIS-GIT/turtlebot3_simulations, branch jazzy (0f833fc),
  turtlebot3_gazebo/params/turtlebot3_burger_bridge.yaml bridges ros_topic_name "cmd_vel" as
  ``ros_type_name: "geometry_msgs/msg/TwistStamped"`` to gz.msgs.Twist;
- the robot's base frame there is ``base_footprint`` (burger.yaml odometry child_frame_id,
  turtlebot3_fake_node base_frame), hence the stamped commands' frame id.

So ``stamped`` defaults to true with frame id base_footprint; ``stamped:=false`` for a robot whose
turtlebot3_node runs with ``enable_stamped_cmd_vel: false``. A mismatch is silent in ROS (two types
on one topic never connect): the robot would just not move.
"""

from launch import LaunchDescription

from bt_nav.ros.bringup import nodes
from bt_nav.ros.launching import declare, to_actions

ARGUMENTS = ["safety_distance", "maneuver", "use_sim_time", "stamped", "stamped_frame_id", "namespace"]


def generate_launch_description() -> LaunchDescription:
    """The executive only (no simulator): the real robot provides scan, odom and consumes cmd_vel."""
    specs = nodes("lab", include_sim=False, namespace="")
    return LaunchDescription(declare(ARGUMENTS) + to_actions(specs, {"executive": [
        "safety_distance", "maneuver", "use_sim_time",
        ("cmd_vel_stamped", "stamped"), ("frame_id", "stamped_frame_id")]}, namespace="namespace"))
