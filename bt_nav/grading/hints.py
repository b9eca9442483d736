"""What a student can change when a judge's check fails: one hint per check (the lab's check-off and the homework's
referee) and per way a run can end without a verdict (a crash, a timeout, a node that never offered its service).

Why here and not in the judges: a judge says what happened (``maneuver 1 turned 45 deg right; the Smart Pivot needs
90 +- 10 deg``) and what the rule is (the check's ``required``); what to *do* about it is the grader's advice to a
student, said where the student reads it: each failed test of Gradescope's ``results.json``
(:mod:`bt_nav.grading.formats`) and the class page (:mod:`bt_nav.grading.classpage`). The launch file's hints are
``LAUNCH_HINTS`` of :mod:`bt_nav.grading.feedback` (one home each). Every hint is a sentence in Markdown (backticks
for names), true for any node, naming no file of the grader's.
"""

from __future__ import annotations

import re
from typing import Any

from bt_nav.grading.grid import CRASH_REASONS

#: A judge check's hint by its name (a maneuver's check is ``maneuver N``: its family's, ``maneuver``).
CHECK_HINTS = {
    "static before activation": "publish no motion before `toggle_navigation` (`data: true`) arms your node: start "
                                "disarmed and send nothing or zero twists until then",
    "toggle_navigation answered": "offer the `toggle_navigation` service (`std_srvs/srv/SetBool`) and answer both "
                                  "calls with `success: true`",
    "maneuvers performed": "trigger the maneuver when the sheet's sectors read nearer than the distance parameter: "
                           "find the beams of each sector from `angle_min` and `angle_increment` (LiDARs differ), "
                           "and skip readings that are no return (`inf`, `NaN`, or `0` on some LiDARs)",
    "maneuver": "turn by the angle and to the side the rule says, measured from odometry's yaw rather than timed, "
                "with no forward command while turning; then drive on",
    "recovery turns": "send a zero forward speed while you turn away after an emergency stop",
    "no collision": "brake earlier: read the nearest valid range over the whole sector ahead, not one beam, and "
                    "treat no-return readings (`inf`, `NaN`, `0`) as no obstacle rather than as a distance",
    "static after deactivation": "after `toggle_navigation` `data: false`, publish a zero twist at once and stay "
                                 "still until armed again",
    "parameters declared": "declare the parameter in your node: `self.declare_parameter('safety_distance', 0.5)`",
    "static at the end": "stop (publish a zero twist) before you call the evaluation service",
    "minimum distance from start": "keep exploring: turn away from obstacles and drive on rather than circling near "
                                   "the start",
    "minimum travelled distance": "keep driving forward whenever the way ahead is clear; a node that turns in place "
                                  "or stops for long travels too little",
    "evaluation service called": "call the evaluation service (`std_srvs/srv/Trigger`) once, before the deadline, "
                                 "timed in sim time (`use_sim_time`)",
}

#: What to change, per launch-file check that failed (``feedback.md`` and Gradescope's tests say it).
LAUNCH_HINTS = {
    "starts the node": "the launch description must hold a `launch_ros.actions.Node(package=..., executable="
                       "'reactive_navigator')` for your node, returned by `generate_launch_description()`",
    "declares safety_distance (default 0.5)": "add `DeclareLaunchArgument('safety_distance', default_value='0.5')` "
                                              "to the launch description",
    "passes safety_distance to the node": "give the Node `parameters=[{'safety_distance': "
                                          "LaunchConfiguration('safety_distance')}]` so `ros2 launch ... "
                                          "safety_distance:=0.6` reaches your node",
}

#: A run that ended without the judge's verdict: (the start of its reason, the hint).
ENDING_HINTS = (
    (CRASH_REASONS, "your node raised the exception quoted here: guard that callback against the input that "
                    "caused it (an empty or short scan, a reading that is `inf` or `NaN`, a message before the "
                    "first scan)"),
    (("no verdict within",), "your node did not finish the run in time: keep every callback short (no `sleep`, "
                             "no loop waiting for a message inside a callback) and keep time with the ROS clock"),
    (("not judged:",), "your node must offer its service and subscribe `/clock` soon after it starts: create them in "
                       "the node's constructor, before `rclpy.spin`"),
)


#: A file the grader wrote, named in a reason: ``(see node.log)``, ``; see node.log)``.
_SEE_FILE = re.compile(r"\s*\(see [^()]*\)|;\s*see [\w.-]+\.\w+(?: and [\w.-]+\.\w+)?(?=\))")
#: An absolute path in a file system (not a ROS name such as ``/reactive_control/evaluate_mission``): said by its
#: last part (a student's own file keeps its name; the grader's folders go).
_ABSOLUTE = re.compile(r"(?<![\w.])/(?:tmp|home|root|autograder|work|usr|opt|var|mnt|srv|Users)/"
                       r"(?:[^\s/'\"():,;]+/)*([^\s/'\"():,;]+)")


def student_words(text: str) -> str:
    """``text`` without the grader's files a student cannot open where they read it (Gradescope): ``(see
    node.log)`` goes (the node's output is quoted instead), an absolute path is said by its file's name."""
    return _ABSOLUTE.sub(r"\1", _SEE_FILE.sub("", text))


def check_hint(name: str) -> str | None:
    """The hint for a failed check named ``name`` (None: no hint for it)."""
    return CHECK_HINTS.get(name) or CHECK_HINTS.get(re.sub(r" \d+$", "", name))


def run_hints(row: dict[str, Any]) -> list[str]:
    """The hints for a failed run, in the order of its failed checks, each once; a run without a verdict gets its
    ending's hint."""
    checks = [c for c in (row.get("verdict") or {}).get("checks") or [] if not c.get("passed")]
    hints = [h for h in (check_hint(str(c.get("name", ""))) for c in checks) if h]
    reason = str(row.get("reason", ""))
    for starts, hint in ENDING_HINTS:
        if not checks and reason.startswith(starts):
            hints.append(hint)
    return list(dict.fromkeys(hints))
