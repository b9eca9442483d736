"""The grader's mutation suite: a student's node done right passes every run, and each copy of it with one typical
mistake is failed for that mistake, named in words a student can act on.

The students are plain rclpy nodes importing nothing of bt_nav (``tests/fixtures/lab_student_node.py`` and, for the
homework, ``tests/fixtures/timer_node.py``), each mistake switched on by ``--mistake``. Each class is graded the way
an instructor grades one: ``bt-nav grade --class MANIFEST`` over real DDS, every student on the same worlds, LiDARs
and seeds; the verdicts are read from each student's ``grade.json`` and the class page.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

import pytest
from bt_nav_sim.lidar import LIDARS

from bt_nav.cli import grade

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
LAB = f"{sys.executable} {FIXTURES / 'lab_student_node.py'}"
HOMEWORK = f"{sys.executable} {FIXTURES / 'timer_node.py'}"

#: Lab mistakes (choice C) and what the failing runs must say (a regex on the row's reason). The LiDARs are the
#: LDS-01 and the RPLIDAR: fixed indices are right for the first only.
LAB_C = {
    "hardcoded_indices": r"performed no maneuver|hit an obstacle",
    "ignores_toggle_off": r"did not stop and stay still after the deactivation",
    "no_stop_on_toggle_off": r"did not stop and stay still after the deactivation",
    "moves_before_toggle": r"moved before it was activated",
    "half_angle": r"turned 4\d deg \w+; the Smart Pivot needs 90 \+- 10 deg",
    "wrong_side": r"the Smart Pivot needs 90 \+- 10 deg (left|right)",
    "no_trigger": r"performed no maneuver.*hit an obstacle",
    "forward_while_turning": r"drove forward during the turn \(commanded up to 0\.05 m/s",
    "never_stops_turning": r"it was still turning at the disarm",
    "wrong_topic": r"no node published on /cmd_vel \(it publishes .* on /cmd_vel_out\)",
    "twist_stamped": r"publishes /cmd_vel as geometry_msgs/msg/TwistStamped",
    "no_safety_param": r"no node declares the parameter safety_distance",
    "zero_is_obstacle": r"turned although its trigger did not hold",
}
#: Mistakes only one of the LiDARs shows: (the LiDAR it passes with, the one it fails with). Fixed indices read the
#: LDS-01 right and the RPLIDAR's rear as its front; a 0.0 is "no return" only on the LDS-01.
BY_LIDAR = {"hardcoded_indices": ("lds01", "rplidar"), "zero_is_obstacle": ("rplidar", "lds01")}
#: Each choice's mistakes as the choice's default grid grades them (``--maneuvers X`` without ``--worlds``: the lab's
#: cells, bt_nav.mission.assignments.LAB.exe_grid): mistake -> (what its failing runs must say, the cells it must
#: fail in: a regex on the cell's label, None for every cell). Elsewhere a mistake may not show (a node ignoring
#: safety_distance is right where it is 0.5 m; left OR right fires with both sides near too).
NOT_HELD = r"turned although its trigger did not hold \(front"
_EVERY_CHOICE = {name: (LAB_C[name], None) for name in (
    "ignores_toggle_off", "no_stop_on_toggle_off", "moves_before_toggle", "forward_while_turning",
    "never_stops_turning", "wrong_topic", "twist_stamped", "no_safety_param")}
LAB_BY_CHOICE: dict[str, dict[str, tuple[str, str | None]]] = {
    "A": {**_EVERY_CHOICE, "no_trigger": (r"performed no maneuver", None),
          # in lab_dead_end a Randomizer turns back to back with no creep between, so the schedule has no toggle
          # cycle there, and the one disarm may find it between two turns, standing on its last zero twist: the
          # robot does stop then, as a TA would see it do
          "no_stop_on_toggle_off": (LAB_C["no_stop_on_toggle_off"], "lab_beside"),
          "front_is_whole_scan": (NOT_HELD, "lab_beside"),
          "ignores_safety_distance": (r"turned late: triggered at front 0\.[3-5]\d m with safety_distance 0\.70: "
                                      r"it crept on 0\.[12]\d m", "safety_distance=0.7"),
          "spins_360": (r"turned 3[0-7]\d deg \w+; the Randomizer needs 80-190 deg", None),
          # clear comes at 130-150 deg in lab_dead_end and lab_beside (within A's 90-180: at 1x it passes there), at
          # 30-60 deg in lab_object's open room: caught there (A's default cell at the sheet's 0.5 m)
          "spins_until_clear": (r"turned \d+ deg \w+; the Randomizer needs 80-190 deg", "lab_object")},
    "B": {**_EVERY_CHOICE, "no_trigger": (r"performed no maneuver", None),
          "half_angle": (r"turned [89]\d deg \w+; the Retreat needs 180 \+- 10 deg", None),
          "left_or_right": (r"turned although its trigger did not hold \(left", "lab_hallway"),
          "ignores_safety_distance": (r"turned late: triggered at left 0\.\d\d m and right 0\.\d\d m with "
                                      r"safety_distance 0\.70: it crept on", "safety_distance=0.7"),
          # respins_forever ("never moved on") is a finding since issue 52 (the sheet only implies driving out): it
          # fails only with --strict-findings back_to_back (tests/sim/test_checkoff_chains.py)
          "spins_360": (r"turned 3[0-7]\d deg \w+; the Retreat needs 180 \+- 10 deg", None)},
    "C": {**_EVERY_CHOICE, **{name: (LAB_C[name], None) for name in (
              "hardcoded_indices", "zero_is_obstacle", "half_angle", "no_trigger")},
          # wrong_side is caught where every reasonable reading of the sides agrees (lab_slant, made for it); in
          # lab_beside the box's corners fall in a 30-150 deg side sector (issue 52: a right node's), so either side
          # passes there, with a finding
          "wrong_side": (LAB_C["wrong_side"], "lab_slant"),
          "side_as_front": (NOT_HELD, "lab_beside"),
          "spins_360": (r"turned 3[0-7]\d deg \w+; the Smart Pivot needs 90 \+- 10 deg", None)},
}
#: Homework mistakes and their reasons.
HOMEWORK_MISTAKES = {
    "moves_before_activation": r"moved before it was activated",
    "ignores_deactivation": r"did not stop and stay still after the deactivation",
    "no_evaluation": r"did not call the evaluation service in time \(never called\)",
    # the evaluator stops waiting at 56 s: a call after it is never seen, so late reads as never
    "late_evaluation": r"did not call the evaluation service in time \(never called\)",
    "too_slow": r"did not travel far enough \(travelled [0-7]\.\d\d m, required 8\.0 m\)",
    "no_avoidance": r"hit an obstacle",
    "moving_at_evaluation": r"still moving at the end",
}


#: The tests of ``make test`` grade in the preview, as fast as the nodes keep up, its failures shown as they are:
#: their subject is the judge's verdicts, not timing (the ``suite`` ones grade at the shipped default, 1x).
PREVIEW = ("--rtf", "0", "--realtime-check", "off")


def _class(tmp_path: Path, students: dict[str, str], *options: str) -> dict[str, Any]:
    """Grade the students as one class; each student's rows (from their own grade.json) and the class page."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    manifest = tmp_path / "class.yaml"
    manifest.write_text("".join(f"{name}: {command}\n" for name, command in students.items()))
    out = tmp_path / "class"
    code = grade.main(["--class", str(manifest), "--seeds", "1", "--jobs", "2", "--record", "off",
                       "--progress", "off", "--out", str(out), *options])
    page = json.loads((out / "class.json").read_text())
    rows = {name: json.loads((out / name / "grade.json").read_text()) for name in students}
    return {"code": code, "page": page, "grades": rows}


def _failed_for(doc: dict[str, Any], pattern: str) -> list[str]:
    """Rows that failed for a reason other than ``pattern`` (empty: every failed row names it), and the runs
    that passed although they should not have."""
    wrong = []
    for row in doc["runs"]:
        assert row["outcome"] != "bt_nav error", row  # bt_nav's own failures never stand in for a verdict
        if not re.search(pattern, row["reason"]):
            wrong.append(f"{row['world']} {row.get('lidar')}: {'PASSED' if row['passed'] else row['reason']}")
    return wrong


@pytest.mark.slow
@pytest.mark.suite
def test_the_lab_mutants_are_each_failed_for_their_own_mistake(tmp_path: Path) -> None:
    students = {"correct": f"{LAB} --choice C",
                **{name: f"{LAB} --choice C --mistake {name}" for name in LAB_C}}
    result = _class(tmp_path, students, "--profile", "lab", "--maneuvers", "C", "--worlds", "lab_side",
                    "--lidars", "lds01,rplidar")
    correct = result["grades"]["correct"]
    assert all(row["passed"] for row in correct["runs"]), [row["reason"] for row in correct["runs"]]
    assert correct["findings"] == []
    problems = {}
    for name, pattern in LAB_C.items():
        doc = result["grades"][name]
        if name in BY_LIDAR:  # right with one LiDAR, wrong with the other: failed there, and the grid says so
            by_lidar = {row["lidar"]: row for row in doc["runs"]}
            good, bad = BY_LIDAR[name]
            assert by_lidar[good]["passed"] and not by_lidar[bad]["passed"], doc["runs"]
            assert re.search(pattern, by_lidar[bad]["reason"]), by_lidar[bad]["reason"]
            assert any(f"fails with {LIDARS[bad].label}" in f and "angle_min and angle_increment" in f
                       for f in doc["findings"]), doc["findings"]
            continue
        wrong = _failed_for(doc, pattern)
        if wrong or any(row["passed"] for row in doc["runs"]):
            problems[name] = wrong
    assert not problems, json.dumps(problems, indent=1)
    page = {s["name"]: s for s in result["page"]["students"]}
    assert page["correct"]["passed"] == page["correct"]["runs"] == 2 and result["code"] == 1
    assert (tmp_path / "class" / "class.html").read_text().count('href="') >= len(students)


#: The mistakes each choice's default grid is made to catch: a trigger that fires where it must not (a side or the
#: whole scan for front; left OR right), the side, and safety_distance passed but not read (its cells give 0.7 m).
DEFAULT_GRID_MISTAKES = {"A": ("front_is_whole_scan", "ignores_safety_distance"),
                         "B": ("left_or_right", "ignores_safety_distance"), "C": ("side_as_front", "wrong_side")}


@pytest.mark.slow
@pytest.mark.suite
@pytest.mark.parametrize("choice", sorted(DEFAULT_GRID_MISTAKES))
def test_each_choice_s_default_grid_fails_its_trigger_mistakes(tmp_path: Path, choice: str) -> None:
    """Graded as a class is by default (``--maneuvers X``, no ``--worlds``: the choice's cells, one LiDAR, one seed):
    the right node passes every cell and applied the parameters each cell passed it; each mistake fails in the cells
    made for it, for its reason."""
    from bt_nav.grading.grid import cell_label

    names = DEFAULT_GRID_MISTAKES[choice]
    students = {"correct": f"{LAB} --choice {choice} --seed 1",
                **{name: f"{LAB} --choice {choice} --seed 1 --mistake {name}" for name in names}}
    result = _class(tmp_path, students, "--profile", "lab", "--maneuvers", choice, "--lidars", "lds01")
    correct = result["grades"]["correct"]["runs"]
    assert len(correct) == len({cell_label(row) for row in correct}) >= 2 and all(row["passed"] for row in correct), \
        [row["reason"] for row in correct]
    for row in correct:
        given = row["parameters"]["given"]
        assert set(given) == set(row["cell_params"]) and all(p["applied"] for p in given.values()), row["parameters"]
        assert "safety_distance" in row["parameters"]["nodes"][0]["names"]
    for name in names:
        pattern, cells = LAB_BY_CHOICE[choice][name]
        runs = [row for row in result["grades"][name]["runs"] if cells is None or re.search(cells, cell_label(row))]
        assert runs and all(not row["passed"] and re.search(pattern, row["reason"]) for row in runs), \
            [(cell_label(row), row["reason"]) for row in result["grades"][name]["runs"]]


@pytest.mark.slow
def test_a_node_ignoring_its_safety_distance_triggers_late(tmp_path: Path) -> None:
    """The TA sets safety_distance 0.6 m (as the lab's launch file may): a node that declares the parameter but
    triggers at its own 0.5 m turns late, and the line asks whether it reads the parameter."""
    students = {"correct": f"{LAB} --choice A --seed 1",
                "ignores": f"{LAB} --choice A --seed 1 --mistake ignores_safety_distance"}
    result = _class(tmp_path, students, *PREVIEW, "--profile", "lab", "--maneuvers", "A", "--worlds", "lab_object",
                    "--lidars", "lds01", "--node-param", "safety_distance=0.6")
    [ok] = result["grades"]["correct"]["runs"]
    [late] = result["grades"]["ignores"]["runs"]
    assert ok["passed"], ok["reason"]
    assert not late["passed"] and "with safety_distance 0.60: it crept on" in late["reason"], late["reason"]
    assert "does it read its distance parameter, and its sectors at their angles" in late["reason"]


@pytest.mark.slow
def test_the_homework_mutants_are_each_failed_for_their_own_mistake(tmp_path: Path) -> None:
    students = {"correct": HOMEWORK, **{name: f"{HOMEWORK} --mistake {name}" for name in HOMEWORK_MISTAKES}}
    result = _class(tmp_path, students, *PREVIEW, "--worlds", "stage_4", "--lidars", "profile")
    correct = result["grades"]["correct"]
    assert all(row["passed"] for row in correct["runs"]), [row["reason"] for row in correct["runs"]]
    problems = {name: _failed_for(result["grades"][name], pattern) for name, pattern in HOMEWORK_MISTAKES.items()}
    problems = {name: wrong for name, wrong in problems.items() if wrong}
    assert not problems, json.dumps(problems, indent=1)


@pytest.mark.slow
def test_homework_indices_hard_coded_fail_on_the_rplidar(tmp_path: Path) -> None:
    students = {"correct": HOMEWORK, "hardcoded": f"{HOMEWORK} --mistake hardcoded_indices"}
    result = _class(tmp_path, students, *PREVIEW, "--worlds", "stage_4", "--lidars", "profile,rplidar")
    assert all(row["passed"] for row in result["grades"]["correct"]["runs"])
    by_lidar = {row["lidar"]: row for row in result["grades"]["hardcoded"]["runs"]}
    assert by_lidar[""]["passed"] and not by_lidar["rplidar"]["passed"], result["grades"]["hardcoded"]["runs"]
    assert any("fails with TurtleBot4 RPLIDAR" in f for f in result["grades"]["hardcoded"]["findings"])


def _failed_checks(row: dict[str, Any]) -> list[Any]:
    """A row's verdict as kinds of check (passed, or which kinds failed): the figures of a DDS run vary a little,
    and so may how many turns fit before the disarm ("maneuver 3" and "maneuver 4" are one kind)."""
    checks = (row.get("verdict") or {}).get("checks", [])
    kinds = {re.sub(r" \d+$", "", c["name"]) for c in checks if not c.get("passed")}
    return [row["outcome"], row["passed"], *sorted(kinds)]


@pytest.mark.slow
def test_a_class_graded_together_equals_each_student_graded_alone(tmp_path: Path) -> None:
    """Three students in one ``--class`` command, then each alone with ``--exe``: the same verdicts, check by check,
    and the class page counts what each student's own grid says."""
    students = {"correct": f"{LAB} --choice C", "wrong_side": f"{LAB} --choice C --mistake wrong_side",
                "half_angle": f"{LAB} --choice C --mistake half_angle"}
    grid = [*PREVIEW, "--profile", "lab", "--maneuvers", "C", "--worlds", "lab_slant", "--lidars", "lds01"]
    together = _class(tmp_path / "together", students, *grid)
    page = {s["name"]: s for s in together["page"]["students"]}
    for name, command in students.items():
        out = tmp_path / "alone" / name
        grade.main(["--exe", command, "--seeds", "1", "--jobs", "2", "--record", "off",
                    "--progress", "off",
                    "--out", str(out), *grid])
        alone = json.loads((out / "grade.json").read_text())["runs"]
        with_class = together["grades"][name]["runs"]
        assert [_failed_checks(r) for r in alone] == [_failed_checks(r) for r in with_class], (name, alone)
        assert page[name]["passed"] == sum(r["passed"] for r in with_class), page[name]
    assert page["correct"]["passed"] == 1 and page["wrong_side"]["passed"] == page["half_angle"]["passed"] == 0
