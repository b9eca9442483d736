"""The default ``--exe`` grid's cells: each lab choice graded where its mistakes show, a cell's own node parameters
given to the node and its judge and named in every label, and the parameters the node lists and applied.

No DDS here: the jobs, the command line and the judge's configuration a run would get, and the reports of rows
as a run writes them. The runs over DDS: tests/ros/test_mutants.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli.grade import _parser
from bt_nav.grading.exe.grid import parameters_lines, with_parameters
from bt_nav.grading.exe.run import ExeSettings, exe_graph, exe_ros_args
from bt_nav.grading.grid import Job, cell_label, params_text, run_label
from bt_nav.grading.plan import build_jobs, grid_axes
from bt_nav.grading.report import summarize_exe, write_exe_report
from bt_nav.mission.assignments import LAB

SD = (("safety_distance", 0.7),)


def _jobs(*argv: str) -> list[Job]:
    args = _parser().parse_args(["--profile", "lab", "--exe", "python node.py", *argv])
    return build_jobs(args, *grid_axes(args))


@pytest.mark.parametrize(("choice", "cells"), [
    ("A", {("lab_beside", SD), ("lab_dead_end", ()), ("lab_object", (("safety_distance", 0.5),))}),
    ("B", {("lab_dead_end", ()), ("lab_hallway", SD)}),
    ("C", {("lab_beside", ()), ("lab_dead_end", ()), ("lab_slant", ())}),
])
def test_each_choice_is_graded_in_its_own_cells(choice: str, cells: set[tuple[str, Any]]) -> None:
    jobs = _jobs("--maneuvers", choice)
    assert {(j.world, j.node_params) for j in jobs} == cells
    assert len(jobs) == len(cells) * 3 * 2  # the cells x the three LiDARs x two seeds
    assert {j.maneuver for j in jobs} == {choice} and {j.seed for j in jobs} == {0, 1}
    assert len({j.key for j in jobs}) == len(jobs)


def test_worlds_given_replace_the_cells_and_a_parameter_given_wins() -> None:
    plain = _jobs("--maneuvers", "A", "--worlds", "lab_object", "--lidars", "lds01")
    assert [(j.world, j.node_params) for j in plain] == [("lab_object", ()), ("lab_object", ())]
    assert plain[0].key == "lab_object|A|0|lab|-|0.05m10deg|lidar=lds01"  # no parameters: the key as before
    given = _jobs("--maneuvers", "A", "--node-param", "safety_distance=0.6", "--lidars", "lds01", "--seeds", "1")
    assert {(j.world, j.node_params) for j in given} == {("lab_beside", ()), ("lab_dead_end", ()), ("lab_object", ())}
    every = _jobs("--maneuvers", "A,B,C", "--lidars", "lds01", "--seeds", "1")
    assert len(every) == 8
    # the grid's cells for B: lab_beside's cell of its trigger distance too; the plan keeps what the world checks off
    assert [c.world for c in LAB.exe_grid.cells_of("B")] == ["lab_beside", "lab_dead_end", "lab_hallway", "lab_slant",
                                                              "lab_object"]
    assert [(c.world, c.params) for c in LAB.exe_grid.cells_of("C")] == [("lab_beside", ()), ("lab_dead_end", ()),
                                                                         ("lab_slant", ())]


def test_a_cell_s_parameters_reach_the_node_and_its_judge(tmp_path: Path) -> None:
    [job] = _jobs("--maneuvers", "B", "--lidars", "lds01", "--seeds", "1", "--node-param", "pivot_distance=0.25")[1:]
    settings = ExeSettings("python node.py", "lab", tmp_path, node_params=(("pivot_distance", 0.25),))
    given = job.params_over(settings.node_params)
    assert given == (("pivot_distance", 0.25), ("safety_distance", 0.7))
    argv = exe_ros_args(job.maneuver, "lab", given)
    assert "safety_distance:=0.7" in argv and "pivot_distance:=0.25" in argv
    judge = json.loads(exe_graph(job, settings, tmp_path / "verdict.json").arguments[3])  # the hosted judge's args
    assert "safety_distance:=0.7" in judge  # the check-off judged at the value the node was given
    assert "|p:safety_distance=0.7" in job.key


def _row(world: str, params: dict[str, float], passed: bool, read: Any, lidar: str = "lds01") -> dict[str, Any]:
    names = ["safety_distance", "use_sim_time"] if read is not None else ["use_sim_time"]
    values = {"use_sim_time": True, **({"safety_distance": read} if read is not None else {})}
    return {"job": f"{world}|B|0|{params}", "world": world, "maneuver": "B", "lidar": lidar, "seed": 0,
            "cell_params": params, "node_params": params, "passed": passed, "outcome": "verdict",
            "reason": "passed" if passed else "failed: maneuver 1 turned late", "wall_time": 17.0, "run_dir": "",
            "findings": [], "verdict": {"parameters": [{"node": "/reactive_navigator", "names": names,
                                                          "values": values}]}}


def test_the_parameters_a_run_passed_are_said_applied_or_not() -> None:
    applied = with_parameters(_row("lab_hallway", {"safety_distance": 0.7}, True, 0.7))
    assert applied["parameters"]["given"]["safety_distance"] == {"given": 0.7, "read": 0.7, "declared": True,
                                                                  "applied": True}
    assert parameters_lines(applied) == [
        "ros2 param list /reactive_navigator: safety_distance, use_sim_time",
        "safety_distance: passed 0.7, read back 0.7 (applied)"]
    kept = with_parameters(_row("lab_hallway", {"safety_distance": 0.7}, False, 0.5))
    assert parameters_lines(kept)[-1] == "safety_distance: passed 0.7, read back 0.5 (NOT applied)"
    undeclared = with_parameters(_row("lab_hallway", {"safety_distance": 0.7}, False, None))
    assert "does not declare it (not applied)" in parameters_lines(undeclared)[-1]
    assert "parameters" not in with_parameters({"verdict": None})


def test_a_cell_s_parameters_name_it_in_every_report(tmp_path: Path) -> None:
    rows = [with_parameters(_row("lab_hallway", {"safety_distance": 0.7}, False, 0.7)),
            with_parameters(_row("lab_dead_end", {}, True, 0.5))]
    assert cell_label(rows[0]) == "lab_hallway B lds01 safety_distance=0.7"
    assert run_label(rows[1]) == "lab_dead_end B lds01 seed 0"
    assert params_text({"safety_distance": 0.7, "pivot_distance": 0.25}) == "safety_distance=0.7 pivot_distance=0.25"
    summary = summarize_exe(rows)
    assert [(s["world"], s["params"], s["passed"]) for s in summary] == [
        ("lab_dead_end", "", 1), ("lab_hallway", "safety_distance=0.7", 0)]
    settings = ExeSettings("python node.py", "lab", tmp_path, videos="off", record="off")
    json_path, md_path = write_exe_report(rows, settings)
    text = md_path.read_text()
    assert "| lab_hallway safety_distance=0.7 | lds01 | 0/1 |" in text
    assert "- lab_hallway B lds01 safety_distance=0.7 seed 0: failed: maneuver 1 turned late" in text
    assert "## Parameters (safety_distance=0.7)" in text and "read back 0.7 (applied)" in text
    doc = json.loads(json_path.read_text())
    assert doc["runs"][0]["cell_params"] == {"safety_distance": 0.7}
    assert doc["runs"][0]["parameters"]["given"]["safety_distance"]["applied"] is True
