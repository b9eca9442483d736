"""Batch grading over a tiny grid, in two worker processes."""

from __future__ import annotations

import json

from bt_nav.cli.grade import format_table, main
from bt_nav.grading.grid import grade, summarize


def test_tiny_grid_in_parallel_matches_serial() -> None:
    rows = grade(["stage_4"], ["none", "C"], 2, jobs=2)
    assert [(r["maneuver"], r["seed"]) for r in rows] == [("none", 0), ("none", 1), ("C", 0), ("C", 1)]
    assert all("error" not in r for r in rows)
    serial = grade(["stage_4"], ["C"], [1], jobs=1)
    parallel = next(r for r in rows if (r["maneuver"], r["seed"]) == ("C", 1))
    assert {k: v for k, v in serial[0].items() if k != "wall_time"} == \
        {k: v for k, v in parallel.items() if k != "wall_time"}
    summary = summarize(rows)
    assert [(s["world"], s["maneuver"], s["runs"]) for s in summary] == [("stage_4", "none", 2), ("stage_4", "C", 2)]
    for s in summary:
        assert 0.0 <= s["pass_rate"] <= 1.0
        assert s["efficiency_worst"] <= s["efficiency_median"]
    table = format_table(summary)
    assert "stage_4" in table and "eff med" in table


def test_cli_json(tmp_path, capsys) -> None:
    out = tmp_path / "grade.json"
    code = main(["--worlds", "empty_room", "--maneuvers", "A", "--seeds", "2", "--jobs", "2", "--json", str(out)])
    data = json.loads(out.read_text())
    assert len(data["runs"]) == 2 and data["summary"][0]["runs"] == 2
    assert code == (0 if all(r["passed"] for r in data["runs"]) else 1)
    printed = capsys.readouterr().out
    assert "2 missions (homework profile" in printed and "passed (" in printed
    assert data["overall"]["runs"] == 2 and data["settings"]["maneuvers"] == ["A"]
    assert data["overall"]["passed"] == sum(r["passed"] for r in data["runs"])


def test_cli_all_worlds_burger_turtlebot3(tmp_path) -> None:
    from bt_nav_sim.world import list_worlds

    out = tmp_path / "grade.json"
    main(["--worlds", "all", "--maneuvers", "none", "--seeds", "1", "--kinematics", "burger",
          "--profile", "turtlebot3", "--json", str(out)])
    data = json.loads(out.read_text())
    assert sorted({r["world"] for r in data["runs"]}) == list_worlds()
    assert {(r["kinematics"], r["profile"]) for r in data["runs"]} == {("burger", "turtlebot3")}
