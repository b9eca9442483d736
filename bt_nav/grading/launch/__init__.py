"""Launch-file checking, one room: a hand-in's launch file read as ``ros2 launch`` would run it (``bt-nav
check-launch``, the sheet's Task 3) -- evaluated in a sandboxed child against recording stand-ins of ``launch`` and
``launch_ros`` (:mod:`~bt_nav.grading.launch.evaluate`, :mod:`~bt_nav.grading.launch.standins`), read statically when
it cannot be evaluated (:mod:`~bt_nav.grading.launch.static`), its checks and their words
(:mod:`~bt_nav.grading.launch.report`, :mod:`~bt_nav.grading.launch.check`) -- and which launch file and node a check
outside a class is about (:mod:`~bt_nav.grading.launch.target`).

The rest of bt_nav imports the entry points below from this package, never a module inside it (``tests/arch`` holds
it), so the room can be rearranged without touching its users.
"""

from bt_nav.grading.launch.check import (
    ARGUMENT,
    DECLARES,
    DEFAULT,
    LAUNCH_NAME,
    NOT_CHECKED,
    OVERRIDE,
    PASSES,
    STARTS,
    LaunchCheck,
    LaunchReport,
    check_launch,
    launch_ros_installed,
)
from bt_nav.grading.launch.target import (
    attach_launch,
    check_target,
    exe_launch,
    exit_code,
    find_launch,
    launch_passed,
    launch_target,
)

__all__ = ["ARGUMENT", "DECLARES", "DEFAULT", "LAUNCH_NAME", "NOT_CHECKED", "OVERRIDE", "PASSES", "STARTS",
           "LaunchCheck", "LaunchReport", "attach_launch", "check_launch", "check_target", "exe_launch", "exit_code",
           "find_launch", "launch_passed", "launch_ros_installed", "launch_target"]
