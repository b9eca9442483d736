"""A finished class of six hand-ins, built from the real grades of ``tests/fixtures/grades/lab_class`` (graded over
DDS: ann right, bob turning half the angle) for the class page, the gradebook's CSV and Gradescope's results:

- ``ann``: every run passed, but the launch file forgets ``safety_distance`` (the hand-in fails);
- ``bob``: a failed run (the Smart Pivot turns 45 deg), launch file right;
- ``cy``: the node crashed (a traceback in its ``node.log``);
- ``dee``: everything passed, one launch-file check "not checked" (a TA looks): passes;
- ``eve``: refused (no node file);
- ``fay``: a run not graded (another program on its domain).
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

from bt_nav.grading.classroom import Student, write_class_page

GRADES = Path(__file__).resolve().parents[1] / "fixtures" / "grades" / "lab_class"
STARTS, DECLARES, PASSES = "starts the node", "declares safety_distance (default 0.5)", "passes safety_distance to " \
    "the node"
NOTE = "launch file read statically; launch_ros not installed, the node was started as `python3 reactive_navigator.py`"
CRASH = ("the node crashed after 3.2 s wall: ValueError: min() arg is an empty sequence (reactive_navigator.py:57 "
         "in scan_cb; see node.log)")
TRACEBACK = """[INFO] [reactive_navigator]: armed
Traceback (most recent call last):
  File "/autograder/submission/reactive_navigator.py", line 57, in scan_cb
    front = min(r for r in msg.ranges[:10] if r > 0.0)
ValueError: min() arg is an empty sequence
"""
NOT_GRADED = ("not graded: another program is on ROS_DOMAIN_ID 7: the publisher /cmd_vel of pid 4242 (python "
              "other.py); no other domain was free to move to: not the node's failure, --resume runs it again")


def check(name: str, passed: bool, reason: str, line: int | None = 12, checked: bool = True) -> dict[str, Any]:
    return {"name": name, "passed": passed, "reason": reason, "line": line, "checked": checked}


RIGHT = [check(STARTS, True, "Node(package='my_package', executable='reactive_navigator')"),
         check(DECLARES, True, "DeclareLaunchArgument('safety_distance', default_value='0.5')", 11),
         check(PASSES, True, "parameters {'safety_distance': LaunchConfiguration('safety_distance')}", 16)]
LAUNCH = {
    "ann": [RIGHT[0], check(DECLARES, False, "no DeclareLaunchArgument('safety_distance', default_value='0.5')",
                            None), check(PASSES, False, "the Node has no parameters=[...]", 7)],
    "bob": RIGHT, "cy": RIGHT, "fay": RIGHT,
    "dee": [*RIGHT[:2], check(PASSES, True, "a `Command` substitution the grader cannot follow", 16, checked=False)],
    "eve": [check(name, False, "no launch file handed in", None) for name in (STARTS, DECLARES, PASSES)],
}


def _grade(out: Path, name: str, source: str, change: dict[str, Any] | None = None) -> None:
    """``out/name/grade.json``: ``source``'s real grade, its run moved into ``out`` (``change`` applied)."""
    doc = json.loads((GRADES / source / "grade.json").read_text())
    run = doc["runs"][0]
    run["run_dir"] = str(out / name / Path(run["run_dir"]).name)
    run.update(copy.deepcopy(change or {}))
    Path(run["run_dir"]).mkdir(parents=True, exist_ok=True)
    (out / name / "grade.json").write_text(json.dumps(doc))


def make_class(out: Path) -> Path:
    """The class (module docstring) in ``out``: each student's grade.json, class.json, class.md and class.html."""
    _grade(out, "ann", "ann")
    _grade(out, "bob", "bob")
    _grade(out, "cy", "ann", {"passed": False, "outcome": "node exited", "reason": CRASH, "verdict": None,
                              "preview": None, "media": {"picture": None, "video": None}})
    (out / "cy" / "lab_object_C_lds01_seed0" / "node.log").write_text(TRACEBACK)
    _grade(out, "dee", "ann")
    _grade(out, "fay", "ann", {"passed": False, "outcome": "bt_nav error", "not_graded": NOT_GRADED,
                               "reason": NOT_GRADED, "verdict": None})
    students = [Student(n, f"python3 {n}/reactive_navigator.py") for n in ("ann", "bob", "cy", "dee", "eve", "fay")]

    def annotate(rows: list[dict[str, Any]]) -> None:  # what a folder of hand-ins adds to each row
        for row in rows:
            checks = LAUNCH[row["name"]]
            row["handin"] = {"launch": {"file": "turtlebot_bringup.launch.py", "checks": checks, "notes": [NOTE]},
                             "lines": [f"launch file: {c['name']}: {'PASSED' if c['passed'] else 'FAILED'}"
                                       for c in checks] + [f"note: {NOTE}"]}
            row["verdict"] = "PASSED" if row["name"] == "dee" else "FAILED"

    write_class_page(out, students, "Lab 4 (lab profile)",
                     {"eve": "no reactive_navigator.py and no Python file defining an rclpy Node (no Python file)"},
                     annotate)
    return out
