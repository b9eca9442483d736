"""The lab's check-off judged live beside a real TurtleBot, from the robot's own topics (no simulator, no ground truth).

    ros2 launch bt_nav checkoff_robot.launch.py maneuver:=C call_toggle:=true duration:=60.0 results_json:=/tmp/c.json

Starts ``bt-nav checkoff --robot`` (:mod:`bt_nav.ros.nodes.robotcheck`) as the node ``bt_nav_checkoff_listener`` on
the shell's own ROS_DOMAIN_ID and discovery range (the robot's). It listens to /odom, /scan (sensor QoS), /cmd_vel,
/rosout and the toggle_navigation service events; with ``call_toggle`` it calls toggle_navigation itself (true after
3 s, false at the end); it prints each maneuver's line as soon as it is decided, and the verdict after ``duration`` s
(0: at Ctrl-C). The student's node runs in its own launch (``turtlebot_bringup.launch.py``).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PythonExpression
from launch_ros.actions import Node

ARGUMENTS = ["maneuver", "call_toggle", "duration", "results_json", "namespace"]
DEFAULTS = {"maneuver": "C", "call_toggle": "false", "duration": "0.0", "results_json": "", "namespace": ""}
DESCRIPTIONS = {
    "maneuver": "the maneuver to check off: A, B or C",
    "call_toggle": "true: the listener calls toggle_navigation itself (true after 3 s, false at the end); "
                   "false: the TA calls it",
    "duration": "seconds to listen, then the verdict (0: until Ctrl-C)",
    "results_json": "write the verdict JSON here (empty: do not)",
    "namespace": "the robot's namespace (its topics and toggle_navigation under it; empty: none)",
}


def _node(call_toggle: bool, with_json: bool) -> Node:
    """The listener with --call-toggle or without, and --json or without (a launch argument cannot drop a flag, so
    each spelling is a node of its own under the condition that picks it)."""
    arguments = ["--robot", "--maneuver", LaunchConfiguration("maneuver"),
                 "--duration", LaunchConfiguration("duration"), "--namespace", LaunchConfiguration("namespace")]
    arguments += ["--call-toggle"] if call_toggle else []
    arguments += ["--json", LaunchConfiguration("results_json")] if with_json else []
    picked = PythonExpression([f"({'' if call_toggle else 'not '}'", LaunchConfiguration("call_toggle"),
                               "'.lower() in ('true', '1')) and '", LaunchConfiguration("results_json"),
                               f"' {'!=' if with_json else '=='} ''"])
    return Node(package="bt_nav", executable="checkoff", name="bt_nav_checkoff_listener", output="screen",
                namespace=LaunchConfiguration("namespace"), remappings=[], arguments=arguments, parameters=[{}],
                condition=IfCondition(picked))


def generate_launch_description() -> LaunchDescription:
    """The listener in one of its four spellings (call_toggle x results_json), each under its condition."""
    declared = [DeclareLaunchArgument(n, default_value=DEFAULTS[n], description=DESCRIPTIONS[n]) for n in ARGUMENTS]
    return LaunchDescription(declared + [_node(c, j) for c in (True, False) for j in (True, False)])
