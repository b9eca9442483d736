"""The speed of ``bt-nav grade --exe`` (:mod:`bt_nav.grading.exe.pace`) without DDS: ``--rtf 0`` by default (as
fast as the node keeps up) and ``--rtf-max``, what they set in the simulator, what they refuse, and the factor each
run achieved read from the simulator's ``pace.json``."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import grade
from bt_nav.grading.exe import pace
from bt_nav.grading.exe.run import ExeSettings, exe_graph
from bt_nav.grading.grid import Job

JOB = Job("lab_object", "C", 0, "lab", sim_params=(("lidar", "lds01"),))


def _sim(tmp_path: Path, **kw: Any) -> dict[str, Any]:
    return exe_graph(JOB, ExeSettings("python3 node.py", "lab", tmp_path, **kw), tmp_path / "verdict.json").parameters


def test_the_default_is_as_fast_as_the_node_keeps_up_with_a_bounded_idle_pace(tmp_path: Path) -> None:
    """rtf 0: no cap while the node is followed, alone (solo_rtf, which bringup sets to 5 for a graph with a judge)
    or not, the simulator kept just behind the node (afap_adapt) under any cap; 10x while it is silent."""
    args = grade._parser().parse_args([])
    assert args.rtf == 0.0 and ExeSettings("n", "lab", tmp_path).rtf == 0.0
    assert pace.rtf_cap(args.rtf, args.rtf_max) == 0.0, "no cap unless --rtf-max"
    sim = _sim(tmp_path)
    assert (sim["real_time_factor"], sim["afap_max_rtf"], sim["solo_rtf"], sim["idle_rtf"]) == (0.0, 0.0, 0.0, 10.0)
    assert sim["afap_adapt"] is True
    capped = _sim(tmp_path, rtf_max=4.0)
    assert (capped["afap_max_rtf"], capped["solo_rtf"], capped["idle_rtf"], capped["afap_adapt"]) == (4.0, 4.0, 4.0,
                                                                                                      True)
    assert "afap_adapt" not in _sim(tmp_path, rtf=5.0), "a fixed factor is kept as it is"
    assert _sim(tmp_path, rtf_max=20.0)["idle_rtf"] == 10.0


def test_a_fixed_factor_keeps_the_simulators_own_settings_and_sim_params_win(tmp_path: Path) -> None:
    fixed = _sim(tmp_path, rtf=5.0)
    assert fixed["real_time_factor"] == 5.0 and "afap_max_rtf" not in fixed and "idle_rtf" not in fixed
    job = Job("lab_object", "C", 0, "lab", sim_params=(("lidar", "lds01"), ("idle_rtf", 3.0)))
    sim = exe_graph(job, ExeSettings("n", "lab", tmp_path), tmp_path / "verdict.json").parameters
    assert sim["idle_rtf"] == 3.0


@pytest.mark.parametrize(("argv", "said"), [
    (["--rtf", "5", "--rtf-max", "8"], "--rtf-max caps --rtf 0 (as fast as the node keeps up); --rtf 5 is a fixed"),
    (["--rtf", "-1"], "--rtf -1: sim seconds per wall second, >= 0"),
    (["--rtf-max", "-2"], "--rtf-max -2: the cap of --rtf 0, >= 0"),
])
def test_a_speed_no_run_can_keep_is_refused_before_any_run(argv: list[str], said: str, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture) -> None:
    for mode in (["--exe", f"{sys.executable} -c pass"], ["--class", str(tmp_path / "class.yaml")]):
        (tmp_path / "class.yaml").write_text("ann: python3 node.py\n")
        with pytest.raises(SystemExit) as exc:
            grade.main([*mode, *argv, "--seeds", "1", "--out", str(tmp_path / "g")])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and said in err, err
        assert len([line for line in err.splitlines() if "error:" in line]) == 1
        assert not (tmp_path / "g").exists()


def test_rtf_max_is_refused_in_lock_step(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        grade.main(["--rtf-max", "3", "--seeds", "1"])
    assert exc.value.code == 2 and "--rtf-max caps the speed of --exe and --class runs" in capsys.readouterr().err


def test_the_words_never_say_0x() -> None:
    assert pace.speed_words(0.0) == "as fast as the node keeps up"
    assert pace.speed_words(0.0, 6.0) == "as fast as the node keeps up (at most 6x real time)"
    assert pace.speed_words(5.0) == "5x real time"


def _pace_file(run_dir: Path, t_end: float, wall_s: float, node: tuple[float, float] | None) -> None:
    """A simulator's record as it writes it at exit (bt_nav_sim.pacing.PaceStops.record)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    followed = {} if node is None else {"cmd_vel": {"sim_s": node[0], "wall_s": node[1]}}
    (run_dir / "pace.json").write_text(json.dumps({"follower_timeout": 1.0, "hold_timeout": 5.0, "t_end": t_end,
                                                    "wall_s": wall_s, "followed": followed, "stops": []}))


def _row(run_dir: Path, passed: bool = True) -> dict[str, Any]:
    return {"passed": passed, "outcome": "verdict", "reason": "passed" if passed else "failed: angle",
            "findings": [], "run_dir": str(run_dir)}


def test_each_run_carries_the_factor_it_achieved(tmp_path: Path) -> None:
    _pace_file(tmp_path / "r", t_end=74.4, wall_s=8.0, node=(60.0, 6.5))
    row = pace.with_speed(_row(tmp_path / "r"), 0.0)
    assert row["rtf"] == 9.3 and row["speed"] == {"set": 0.0, "sim_s": 74.4, "wall_s": 8.0, "rtf": 9.3,
                                                   "node_sim_s": 60.0, "node_wall_s": 6.5, "node_rtf": 9.23}
    assert row["findings"] == [] and pace.achieved(row, 0.0) == 9.3 and pace.achieved(row, 5.0) == 5.0
    assert pace.node_factor(row, 0.0) == 9.23 and pace.node_factor(row, 5.0) == 5.0
    assert pace.with_speed(row, 0.0) is row  # once only
    assert pace.factor_text(row) == "9.3x"
    missing = pace.with_speed(_row(tmp_path / "none"), 0.0)  # a simulator killed before its exit wrote nothing
    assert "rtf" not in missing and missing["speed"] == {"set": 0.0} and pace.achieved(missing, 0.0) == 1.0


def test_a_node_that_kept_up_with_less_than_1x_is_too_slow_for_the_robot(tmp_path: Path) -> None:
    """At rtf 0 only, not a failure by itself (the row passes still), and only over enough followed wall time."""
    _pace_file(tmp_path / "slow", t_end=70.0, wall_s=90.0, node=(64.0, 80.0))
    row = pace.with_speed(_row(tmp_path / "slow"), 0.0)
    said = "too slow for the robot: the node kept up with 0.8x real time"
    assert row["passed"] and row["findings"][0].startswith(said) and row["reason"].startswith(f"passed; {said}")
    assert pace.with_speed(_row(tmp_path / "slow"), 5.0)["findings"] == []  # a fixed factor says nothing of it
    _pace_file(tmp_path / "brief", t_end=70.0, wall_s=20.0, node=(0.5, 1.5))  # it spoke once: under 5 sim s
    brief = pace.with_speed(_row(tmp_path / "brief"), 0.0)
    assert brief["findings"] == [] and brief["speed"]["node_rtf"] is None


def test_the_run_line_and_the_report_show_the_factors(capsys: pytest.CaptureFixture) -> None:
    from bt_nav.cli.grade.exe import _show

    _show({"world": "lab_object", "maneuver": "C", "lidar": "lds01", "seed": 0, "outcome": "verdict", "passed": True,
           "reason": "passed", "wall_time": 8.1, "rtf": 9.34, "run_dir": "/r"})
    assert "lab_object C lds01 seed 0: PASSED (passed; 8.1 s wall, 9.3x) /r" in capsys.readouterr().out
    rows = [{"rtf": 7.4}, {"rtf": 12.3}, {"rtf": 9.3}, {}]
    assert pace.achieved_text(rows) == " (the runs went at 7.4-12.3x, median 9.3x)"
    assert pace.achieved_text([{}]) == ""
