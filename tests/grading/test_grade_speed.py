"""The speed of ``bt-nav grade --exe`` (:mod:`bt_nav.grading.exe.pace`) without DDS: real time (1x) by default, the
preview (``--rtf 0`` with ``--rtf-max``, or ``--rtf N``), what they set in the simulator, what they refuse, the factor
each run achieved and how real time was kept, read from the simulator's ``pace.json``; and how a cell's verdict is
reached (:mod:`bt_nav.grading.exe.realtime`): a preview's failure graded at 1x, a 1x run that fell behind run again,
then not graded."""

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


def test_the_default_is_real_time_and_the_preview_is_as_fast_as_the_node_keeps_up(tmp_path: Path) -> None:
    """1x by default: the robot's world does not wait for its node. rtf 0 (a preview): no cap while the node is
    followed, the simulator kept just behind the node (afap_adapt) under any cap; 10x while it is silent."""
    args = grade._parser().parse_args([])
    assert args.rtf == 1.0 and ExeSettings("n", "lab", tmp_path).rtf == 1.0 and not pace.preview(args.rtf)
    assert pace.rtf_cap(args.rtf, args.rtf_max) == 0.0, "no cap unless --rtf-max"
    real = _sim(tmp_path)
    assert (real["real_time_factor"], real["follow"]) == (1.0, False) and "afap_adapt" not in real
    sim = _sim(tmp_path, rtf=0.0)
    assert (sim["real_time_factor"], sim["afap_max_rtf"], sim["solo_rtf"], sim["idle_rtf"]) == (0.0, 0.0, 0.0, 10.0)
    assert sim["afap_adapt"] is True and sim["follow"] is True and pace.preview(0.0) and pace.preview(5.0)
    capped = _sim(tmp_path, rtf=0.0, rtf_max=4.0)
    assert (capped["afap_max_rtf"], capped["solo_rtf"], capped["idle_rtf"], capped["afap_adapt"]) == (4.0, 4.0, 4.0,
                                                                                                      True)
    assert "afap_adapt" not in _sim(tmp_path, rtf=5.0), "a fixed factor is kept as it is"
    assert _sim(tmp_path, rtf=0.0, rtf_max=20.0)["idle_rtf"] == 10.0


def test_a_fixed_factor_keeps_the_simulators_own_settings_and_sim_params_win(tmp_path: Path) -> None:
    fixed = _sim(tmp_path, rtf=5.0)
    assert fixed["real_time_factor"] == 5.0 and "afap_max_rtf" not in fixed and "idle_rtf" not in fixed
    job = Job("lab_object", "C", 0, "lab", sim_params=(("lidar", "lds01"), ("idle_rtf", 3.0)))
    sim = exe_graph(job, ExeSettings("n", "lab", tmp_path, rtf=0.0), tmp_path / "verdict.json").parameters
    assert sim["idle_rtf"] == 3.0


@pytest.mark.parametrize(("argv", "said"), [
    (["--rtf", "5", "--rtf-max", "8"], "--rtf-max caps the preview --rtf 0 (as fast as the node keeps up); --rtf 5"),
    (["--rtf", "-1"], "--rtf -1: 1 (the default) grades at real time; 0 or above 1 is a preview"),
    (["--rtf", "0.5"], "--rtf 0.5: 1 (the default) grades at real time"),
    (["--rtf", "0", "--gradescope", "r.json"], "--gradescope writes scores, which come from 1x runs only"),
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


def test_the_words_never_say_0x_and_a_preview_says_so() -> None:
    assert pace.speed_words(1.0) == "real time (1x, as on the robot)"
    assert pace.speed_words(0.0).startswith("PREVIEW as fast as the node keeps up (")
    assert pace.speed_words(0.0, 6.0).startswith("PREVIEW as fast as the node keeps up, at most 6x (")
    assert pace.speed_words(5.0).startswith("PREVIEW at 5x real time (failures graded again at 1x; no score)")


def _pace_file(run_dir: Path, t_end: float, wall_s: float, node: tuple[float, float] | None,
               realtime: dict[str, float] | None = None) -> None:
    """A simulator's record as it writes it at exit (bt_nav_sim.pacing.PaceStops.record, RealTimeKeeping.record)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    followed = {} if node is None else {"cmd_vel": {"sim_s": node[0], "wall_s": node[1]}}
    doc = {"follower_timeout": 1.0, "hold_timeout": 5.0, "t_end": t_end, "wall_s": wall_s, "followed": followed,
           "stops": [], **({"realtime": realtime} if realtime else {})}
    (run_dir / "pace.json").write_text(json.dumps(doc))


def _row(run_dir: Path, passed: bool = True) -> dict[str, Any]:
    return {"passed": passed, "outcome": "verdict", "reason": "passed" if passed else "failed: angle",
            "findings": [], "run_dir": str(run_dir)}


def test_each_run_carries_the_factor_it_achieved(tmp_path: Path) -> None:
    _pace_file(tmp_path / "r", t_end=74.4, wall_s=8.0, node=(60.0, 6.5))
    row = pace.with_speed(_row(tmp_path / "r"), 0.0)
    assert row["rtf"] == 9.3 and row["speed"] == {"set": 0.0, "sim_s": 74.4, "wall_s": 8.0, "rtf": 9.3,
                                                   "node_sim_s": 60.0, "node_wall_s": 6.5, "node_rtf": 9.23}
    assert row["findings"] == [] and pace.fell_behind(row) is None  # a preview's run is never doubted so
    assert pace.with_speed(row, 0.0) is row  # once only
    assert pace.factor_text(row) == "9.3x"
    missing = pace.with_speed(_row(tmp_path / "none"), 1.0)  # a simulator killed before its exit wrote nothing
    assert "rtf" not in missing and missing["speed"] == {"set": 1.0} and pace.fell_behind(missing) is None


@pytest.mark.parametrize(("window", "lost", "behind"), [
    (0.0, 0.0, False), (0.031, 0.031, False), (0.15, 1.2, False), (0.16, 0.16, True), (0.1, 1.3, True)])
def test_a_1x_run_fell_behind_by_its_simulators_own_lag(tmp_path: Path, window: float, lost: float,
                                                        behind: bool) -> None:
    """Valid only if the simulator kept real time while judged: more than 0.15 s written off within 2 s, or more than
    2 % of the judged time in all, is a machine too busy for the run."""
    keeping = {"judged_wall_s": 60.0, "judged_sim_s": 60.0 - lost, "worst_s": window, "lost_s": lost,
               "window_lost_s": window, "late_steps": 3}
    _pace_file(tmp_path / "r", t_end=66.0, wall_s=66.5, node=None, realtime=keeping)
    row = pace.with_speed(_row(tmp_path / "r"), 1.0)
    said = pace.fell_behind(row)
    assert (said is not None) == behind, said
    if behind:
        assert said.startswith(f"its simulator fell behind real time while judged ({window:.2f} s lost within 2 s"), \
            said


def test_the_simulator_counts_only_late_steps_while_judged_and_sums_them_within_2_s() -> None:
    from bt_nav_sim.pacing import RealTimeKeeping

    keeping = RealTimeKeeping()
    keeping.step(0.5, True, 99.0)  # before its judge's t0: a node starting up is not judged
    keeping.judging(True, 100.0, 2.0)
    keeping.step(0.01, False, 101.0)  # the scheduler's usual lateness: on time
    keeping.step(0.1, True, 110.0)
    keeping.step(0.05, False, 110.5)  # late, made up: not lost
    keeping.step(0.08, True, 111.5)  # 0.18 s lost within 2 s
    keeping.step(0.12, True, 120.0)  # alone in its window
    keeping.judging(False, 160.0, 61.7)
    keeping.step(0.9, True, 161.0)  # after its verdict
    assert keeping.record(170.0, 70.0) == {"judged_wall_s": 60.0, "judged_sim_s": 59.7, "worst_s": 0.12,
                                           "lost_s": 0.3, "window_lost_s": 0.18, "late_steps": 4}


def _graded(rows: list[dict[str, Any]], rtf: float, tmp_path: Path) -> tuple[dict[str, Any] | None, list[Any]]:
    """:func:`graded_run` over ``rows``, one per attempt; the settings of each attempt."""
    from bt_nav.grading.exe.realtime import graded_run

    tried: list[Any] = []

    def attempt(settings: ExeSettings) -> dict[str, Any]:
        tried.append(settings)
        return rows[len(tried) - 1]

    return graded_run(attempt, ExeSettings("n", "lab", tmp_path, rtf=rtf)), tried


def _kept(row: dict[str, Any], rtf: float, worst: float = 0.0) -> dict[str, Any]:
    keeping = {"judged_wall_s": 60.0, "judged_sim_s": 60.0, "worst_s": worst, "lost_s": worst,
               "window_lost_s": worst, "late_steps": 1}
    return {**row, "speed": {"set": rtf, "realtime": keeping}}


def test_a_1x_verdict_is_the_verdict_and_is_never_run_again(tmp_path: Path) -> None:
    failed = _kept(_row(tmp_path / "a", passed=False), 1.0)
    row, tried = _graded([failed], 1.0, tmp_path)
    assert row is failed and len(tried) == 1 and "preview" not in row


def test_a_1x_run_that_fell_behind_is_run_again_then_not_graded(tmp_path: Path) -> None:
    behind = _kept(_row(tmp_path / "a", passed=False), 1.0, worst=0.5)
    kept = _kept(_row(tmp_path / "b", passed=True), 1.0)
    row, tried = _graded([behind, kept], 1.0, tmp_path)
    assert row is kept and tried[1].out == tmp_path / "again" and "fell behind real time" in row["notes"][0]
    row, tried = _graded([behind, {**behind, "run_dir": "/again"}], 1.0, tmp_path)
    assert row is not None and row["not_graded"] and row["outcome"] == "bt_nav error" and not row["passed"]
    assert row["reason"].startswith("not graded: its simulator fell behind real time while judged"), row["reason"]


def test_a_preview_failure_is_graded_again_at_1x_and_a_pass_stays_a_preview_pass(tmp_path: Path) -> None:
    fast = {**_row(tmp_path / "fast", passed=False), "rtf": 9.3}
    slow = _kept(_row(tmp_path / "slow", passed=True), 1.0)
    row, tried = _graded([fast, slow], 0.0, tmp_path)
    assert row is slow and row["passed"] and tried[1].rtf == 1.0 and tried[1].out == tmp_path / "realtime"
    assert row["preview"] == {"rtf": 9.3, "reason": "failed: angle", "run_dir": str(tmp_path / "fast"),
                              "said": "failed in the preview; graded again at 1x"}
    row, tried = _graded([_row(tmp_path / "ok")], 5.0, tmp_path)
    assert row is not None and row["preview"]["said"] == "passed in the preview" and len(tried) == 1


def test_a_node_that_kept_up_with_less_than_1x_is_too_slow_for_the_robot(tmp_path: Path) -> None:
    """At rtf 0 only, not a failure by itself (the row passes still), and only over enough followed wall time."""
    _pace_file(tmp_path / "slow", t_end=70.0, wall_s=90.0, node=(64.0, 80.0))
    row = pace.with_speed(_row(tmp_path / "slow"), 0.0)
    said = "too slow for the robot: the node kept up with 0.8x real time"
    assert row["passed"] and row["findings"][0].startswith(said) and row["reason"].startswith(f"passed; {said}")
    assert pace.with_speed(_row(tmp_path / "slow"), 5.0)["findings"] == []  # a fixed factor says nothing of it
    assert pace.with_speed(_row(tmp_path / "slow"), 1.0)["findings"] == []
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
