"""The lab's check-off in the bt_nav simulator: simulator + executive (lab mode) + the check-off judge.

    ros2 launch bt_nav lab_checkoff.launch.py maneuver:=C world:=lab_object results_json:=/tmp/checkoff.json

The judge calls ``/toggle_navigation`` itself (true after 5 s static, false 60 s later) and prints the
check-off's PASSED/FAILED lines; the world must be the same for the simulator and the judge (one argument).
``bt-nav demo --profile lab`` starts the same graph without ros2 and prints the lab's terminal.
"""

from launch import LaunchDescription

from bt_nav.ros.bringup import nodes
from bt_nav.ros.launching import declare, to_actions

ARGUMENTS = ["maneuver", "safety_distance", "world", "seed", "real_time_factor", "results_json", "namespace"]
#: A check-off judges a maneuver in an arena made for it (bt_nav.ros.bringup.CHECKOFF_WORLDS).
DEFAULTS = {"maneuver": "C", "world": "lab_object"}


def generate_launch_description() -> LaunchDescription:
    """sim + executive + check-off judge in the checkoff profile."""
    specs = nodes("checkoff", maneuver=DEFAULTS["maneuver"], namespace="")
    return LaunchDescription(declare(ARGUMENTS, DEFAULTS) + to_actions(specs, {
        "executive": ["maneuver", "safety_distance"],
        "sim": ["world", "seed", "real_time_factor"],
        "checkoff": ["maneuver", "safety_distance", "world", "seed", ("json", "results_json")],
    }, namespace="namespace"))
