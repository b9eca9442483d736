"""What a student can change when a judge's check fails: advice per *kind* of failure (a trigger that did not hold,
a turn of the wrong angle, forward motion during a turn, ...), per finding, per way a run can end without a verdict
(a crash, a timeout, a node that never offered its service) and for a run the grader could not grade.

Why per kind and not per check: one check, ``maneuver N``, fails for a trigger that did not hold, a turn of the wrong
size, the wrong side or forward motion, and each needs other advice: a student whose trigger is wrong and whose turn
is right, told how to turn, rewrites working code. The judge names the kinds (the check's ``kinds``,
:func:`bt_nav.judge.checkoff_words.maneuver_faults`) and the rule each broke (``rules``); a grade written before the
judge named them is read from its words (:func:`check_kinds`).

Why here and not in the judges: a judge says what happened (``maneuver 1 turned 45 deg right; the Smart Pivot needs
90 +- 10 deg``) and what the rule is (the check's ``required``); what to *do* about it is the grader's advice to a
student, said where the student reads it: each failed test of Gradescope's ``results.json``
(:mod:`bt_nav.grading.formats`) and ``feedback.md``. Every piece of advice is a sentence in Markdown (backticks for
names), true for any node and accepting every method the sheet allows (the sheet prescribes no way of measuring a
turn: odometry and a turn timed at the rate the node commands are both right when they land within the tolerance),
naming no file of the grader's. A launch-file check's advice comes from the file itself (the check's ``fix``,
:mod:`bt_nav.grading.launch.check`); :data:`LAUNCH_HINTS` is the rule said plainly, for a check that carries none.
"""

from __future__ import annotations

import re
from typing import Any

from bt_nav.grading.grid import CRASH_REASONS
from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.judge.checkoff_words import ANGLE, FORWARD, LATE, MOVED_ON, SIDE, STILL_TURNING, TRIGGER
from bt_nav.judge.findings import BACK_TO_BACK
from bt_nav.judge.findings import MOVED_ON as MOVED_ON_FINDING
from bt_nav.judge.findings import SIDE as SIDE_FINDING
from bt_nav.mission.maneuver_spec import maneuver_spec

#: A judge check's advice by its name, for the checks whose name is their one kind of failure.
CHECK_HINTS = {
    "static before activation": "publish no motion before `toggle_navigation` (`data: true`) arms your node: start "
                                "disarmed and send nothing or zero twists until then",
    "toggle_navigation answered": "offer the `toggle_navigation` service (`std_srvs/srv/SetBool`) and answer every "
                                  "call with `success: true`",
    "maneuvers performed": "trigger the maneuver when the sheet's sectors read nearer than the distance parameter: "
                           "find the beams of each sector from `angle_min` and `angle_increment` (LiDARs differ), "
                           "and skip readings that are no return (`inf`, `NaN`, or `0` on some LiDARs)",
    "recovery turns": "send a zero forward speed while you turn away after an emergency stop",
    "creep while armed": "while armed and no trigger holds, keep a slow forward velocity (the sheet's \"Otherwise: "
                         "maintain a slow forward velocity\"): after a maneuver and after `toggle_navigation` true "
                         "again too, not only at the start",
    "back-to-back maneuvers": "a Retreat is a spin to exit the narrow space: after it, drive out before the trigger "
                              "may fire again (e.g. re-arm it once a side reads clearly beyond `safety_distance`)",
    "no collision": "brake earlier: read the nearest valid range over the whole sector ahead, not one beam, and "
                    "treat no-return readings (`inf`, `NaN`, `0`) as no obstacle rather than as a distance",
    "static after deactivation": "after `toggle_navigation` `data: false`, publish a zero twist at once and stay "
                                 "still until armed again (a turn under way stops too)",
    "parameters declared": "declare the parameter in your node: `self.declare_parameter('safety_distance', 0.5)`",
    "static at the end": "stop (publish a zero twist) before you call the evaluation service",
    "minimum distance from start": "keep exploring: turn away from obstacles and drive on rather than circling near "
                                   "the start",
    "minimum travelled distance": "keep driving forward whenever the way ahead is clear; a node that turns in place "
                                  "or stops for long travels too little",
    "evaluation service called": "call the evaluation service (`std_srvs/srv/Trigger`) once, before the deadline, "
                                 "timed in sim time (`use_sim_time`)",
}

#: What the sheet's Task 3 asks of each launch-file check, said plainly: the advice of a check that carries none
#: of its own (``fix``: what the file holds and what it misses, :mod:`bt_nav.grading.launch.check`).
LAUNCH_HINTS = {
    "starts the node": "the sheet asks the launch description returned by `generate_launch_description()` to hold "
                       "a `launch_ros.actions.Node(package=..., executable='reactive_navigator')` for your node",
    "declares safety_distance (default 0.5)": "the sheet asks for a launch argument `safety_distance` with the "
                                              "default `'0.5'` (`DeclareLaunchArgument`) that reaches your node",
    "passes safety_distance to the node": "the sheet asks the Node to get the parameter `safety_distance` from the "
                                          "launch argument: `parameters=[{'safety_distance': "
                                          "LaunchConfiguration('safety_distance')}]`",
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

#: What the grader could not do in a run it did not grade, by words of its reason (the first that matches).
NOT_GRADED_WHAT = (
    ("another program is on", "keep the run's ROS domain to itself (another program joined it)"),
    ("no free ROS_DOMAIN_ID", "find a free ROS domain for the run"),
    ("real time", "keep real time (the grading machine was too busy)"),
    ("bt_nav error", "run its own code without an error"),
)

#: A failed maneuver check's kinds read from its words (a grade written before the judge named them).
_KIND_WORDS = ((TRIGGER, "trigger did not hold"), (LATE, "turned late"), (STILL_TURNING, "still turning at the disarm"),
               (ANGLE, " needs "), (FORWARD, "during the turn"), (MOVED_ON, "did not move on"))


def check_kinds(check: dict[str, Any]) -> list[str]:
    """The kinds of failure of a failed check: a maneuver's as its judge named them (``kinds``), else read from its
    words; any other check's is its name."""
    name = str(check.get("name", ""))
    if not re.fullmatch(r"maneuver \d+", name):
        return [name]
    if check.get("kinds"):
        return [str(k) for k in check["kinds"]]
    reason = str(check.get("reason", ""))
    kinds = [kind for kind, words in _KIND_WORDS if words in reason]
    return [k for k in kinds if not (k == ANGLE and STILL_TURNING in kinds)] or [ANGLE]


def check_rule(check: dict[str, Any]) -> str:
    """The rule a failed check broke, as the student reads it beside the failure: a maneuver's first fault's (the
    trigger's for a trigger that did not hold, the angle's for a turn of the wrong size)."""
    rules = check.get("rules") or {}
    kinds = check_kinds(check)
    return str(rules.get(kinds[0]) or check.get("required") or "") if kinds else str(check.get("required") or "")


def _trigger_words(maneuver: str) -> tuple[str, str]:
    """(the sectors a maneuver's trigger reads, the distance it compares with), as the sheet means them."""
    spec, cfg = maneuver_spec(maneuver), CheckoffConfig(maneuver=maneuver)
    trigger = spec.trigger
    if trigger.reads == "sides":
        where = (f"the left sector AND the right sector (each centred {cfg.side_centre_min_deg:g}-"
                 f"{cfg.side_centre_max_deg:g} deg off the bow, one each side) both read")
    else:
        where = (f"the front sector (straight ahead, any width from +-{cfg.front_min_half_deg:g} to "
                 f"+-{cfg.front_max_half_deg:g} deg) reads")
    distance = f"`{trigger.distance}` ({cfg.distance(trigger.distance):g} m unless the launch file sets it)"
    if trigger.distance != "safety_distance":
        distance = f"the sheet's {cfg.distance(trigger.distance):g} m"
    if trigger.or_braked_at:
        distance += f" (or your `{trigger.or_braked_at}`, where a node that brakes first turns)"
    return where, distance


#: How a sector's beams are found on any LiDAR (the sheet's "Dynamic Indexing").
_INDEXING = ("find each sector's beams from the scan's `angle_min` and `angle_increment` (index = (angle - "
             "angle_min) / angle_increment, the angle taken in the scan's own range: one LiDAR's runs 0..2pi, "
             "another's -pi..pi) and skip no-return readings (`inf`, `NaN`, `0` on some LiDARs)")


def _maneuver_advice(kind: str, maneuver: str) -> str | None:
    """The advice for a maneuver's fault of ``kind`` (None: no such kind), in the terms of ``maneuver``'s rules."""
    try:
        spec, cfg = maneuver_spec(maneuver), CheckoffConfig(maneuver=maneuver)
    except ValueError:
        return None
    where, distance = _trigger_words(maneuver)
    angle = spec.angle.words(cfg.angle_tolerance_deg).removesuffix(" either side")  # the size: the side is SIDE's
    advice = {
        TRIGGER: f"turn only when the sheet's trigger holds: {where} nearer than {distance}; {_INDEXING}",
        LATE: f"turn as soon as {where} nearer than {distance}: compare with the value your node reads from its "
              f"parameter at run time (`get_parameter`), not a constant, and {_INDEXING}",
        ANGLE: f"turn by {angle}. Any way of measuring the turn passes when it lands within the tolerance: the yaw "
               "of odometry, or a turn timed at the rate you command (duration = angle in rad / `angular.z` in "
               "rad/s, on the ROS clock); check the units (degrees or radians), that the rate you time by is the "
               "rate you send, and that the turn ends when its angle or time is reached",
        SIDE: "turn towards the side with more room: when the trigger holds, compare the nearest valid range of your "
              "left sector (positive angles, counter-clockwise) with your right sector's (negative angles, or "
              "2pi minus them on a 0..2pi scan) and turn to the larger; a positive `angular.z` turns left",
        STILL_TURNING: f"end the turn once it has turned {angle}: a turn measured on the yaw must take the "
                       "difference wrapped into -pi..pi (or summed step by step), and a timed one must stop when "
                       "its time is up, whatever scans arrive meanwhile",
        FORWARD: "send `linear.x = 0` in every command from the turn's first to its last, and stop before you turn: "
                 "the check-off allows no forward motion during a maneuver",
        MOVED_ON: "drive on after the turn: this course counts standing still after a maneuver",
    }
    return advice.get(kind)


def kind_advice(kind: str, maneuver: str = "") -> str | None:
    """The advice for a failure of ``kind`` (a maneuver fault's kind or a check's name) of a node graded as
    ``maneuver`` (None: none for it)."""
    if kind in CHECK_HINTS:
        return CHECK_HINTS[kind]
    return _maneuver_advice(kind, maneuver) if maneuver else None


#: Advice for the judge's findings (what the sheet only implies: the run passed), by the finding's kind.
FINDING_HINTS = {
    BACK_TO_BACK: CHECK_HINTS["back-to-back maneuvers"],
    MOVED_ON_FINDING: "after a maneuver, drive on: a robot standing where it turned does not go anywhere",
    SIDE_FINDING: "compare the sides over sectors beside the robot (60-120 deg): sectors that reach towards the "
                  "front see the obstacle you turn from",
}


def finding_hints(row: dict[str, Any]) -> list[str]:
    """The advice for a run's judge findings, each kind once (a passing run may hold them too)."""
    kinds = [str(f.get("kind")) for f in (row.get("verdict") or {}).get("finding_kinds") or [] if isinstance(f, dict)]
    return list(dict.fromkeys(FINDING_HINTS[k] for k in kinds if k in FINDING_HINTS))


def not_graded_hint(reason: str) -> str:
    """What the grader could not do in a run it did not grade, and that it is not the student's doing."""
    what = next((w for words, w in NOT_GRADED_WHAT if words in reason), "finish the run")
    return (f"the grader could not {what}: this is not your node's failure and scores nothing either way; ask for a "
            "regrade and the run is run again")


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


def check_hint(name: str, maneuver: str = "") -> str | None:
    """The advice for a failed check named ``name`` (a maneuver's: its first kind read from nothing but the name,
    the angle; prefer :func:`check_hints`, which reads the check's kinds)."""
    return kind_advice(name, maneuver) or (kind_advice(ANGLE, maneuver) if re.fullmatch(r"maneuver \d+", name)
                                           else None)


def check_hints(check: dict[str, Any], maneuver: str = "") -> list[str]:
    """The advice for one failed check, one per kind of failure it had."""
    return [h for h in (kind_advice(k, maneuver) for k in check_kinds(check)) if h]


def launch_hint(check: dict[str, Any]) -> str | None:
    """The advice for a failed launch-file check: what the file holds and misses (its ``fix``), else the rule."""
    return str(check["fix"]) if check.get("fix") else LAUNCH_HINTS.get(str(check.get("name")))


def run_hints(row: dict[str, Any]) -> list[str]:
    """The advice for a failed run, in the order of its failed checks and their kinds, each once; a run without a
    verdict gets its ending's advice."""
    maneuver = str(row.get("maneuver") or "")
    checks = [c for c in (row.get("verdict") or {}).get("checks") or [] if not c.get("passed")]
    hints = [h for c in checks for h in check_hints(c, maneuver)]
    reason = str(row.get("reason", ""))
    for starts, hint in ENDING_HINTS:
        if not checks and reason.startswith(starts):
            hints.append(hint)
    return list(dict.fromkeys(hints))
