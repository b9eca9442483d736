"""The check-off on two real TurtleBot3 recordings (Jacopo-oranneZ/SESASR-LAB, lab03_pkg/recordings/), read where
they lie (``BT_NAV_REALBAGS``, default ../shared/realbags beside the clone: never copied into the project). Each
maneuver's verdict is checked against the bag's own pose yaw and scans, in the whole recording and in windows that
hold the turn. In CI (``CI`` set) a missing folder fails; on a user's clone it skips."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.judge.recorded import Recording, Window, judge_recording, report_lines
from bt_nav.media.robotbag import read_robot_bag

ROOT = Path(os.environ.get("BT_NAV_REALBAGS", Path(__file__).resolve().parents[3] / "shared" / "realbags"))


def _bag(name: str) -> Recording:
    path = ROOT / name
    if not path.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{path}: the real recordings are missing (CI has ../shared/realbags; set BT_NAV_REALBAGS)")
        pytest.skip(f"{path}: no real recordings here (set BT_NAV_REALBAGS)")
    return _read(str(path))


_CACHE: dict[str, Recording] = {}


def _read(path: str) -> Recording:
    if path not in _CACHE:
        _CACHE[path] = read_robot_bag(path)
    return _CACHE[path]


def _judge(rec: Recording, start: float | None = None, end: float | None = None) -> dict:
    return judge_recording(rec, CheckoffConfig(maneuver="C"), Window(start, end))


def _at(res: dict, t: float) -> dict:
    """The maneuver that began near ``t`` s (its verdict: judged or not)."""
    return next(e for e in res["maneuvers"] if abs(e["t"] - t) < 0.6)


def _yaw_turned(rec: Recording, a: float, b: float) -> float:
    pose = np.asarray(rec.odom)
    t, yaw = pose[:, 0] - rec.start, np.unwrap(pose[:, 3])
    return math.degrees(float(np.interp(b, t, yaw) - np.interp(a, t, yaw)))


def _front(rec: Recording, t: float, half_deg: float = 30.0) -> float:
    """The nearest finite return within +-``half_deg`` of straight ahead in the last scan at or before ``t``."""
    ts, scan = [(s0, s) for s0, s in rec.scans if s0 - rec.start <= t][-1]
    del ts
    ang = np.remainder(scan.angle_min + scan.angle_increment * np.arange(scan.num_beams) + math.pi, 2 * math.pi)
    r = np.asarray(scan.ranges, dtype=float)
    ok = np.isfinite(r) & (r > 0) & (np.abs(np.degrees(ang - math.pi)) <= half_deg)
    return float(r[ok].min())


def test_1653_first_turn_failed_on_its_trigger_second_set_apart_by_hand() -> None:
    rec = _bag("sesasr_tb3_lab03_1653")
    assert 0.6 <= _front(rec, 20.3) <= 0.67  # the bag's own scan: nothing within 0.55 m ahead when it turned
    assert -96 <= _yaw_turned(rec, 20.2, 29.0) <= -90  # its pose: a clean right turn
    for window in ((None, None), (15.0, 29.5), (19.0, 45.0)):
        res = _judge(rec, *window)
        first = _at(res, 20.3)
        assert first["not_judged"] is None and not first["passed"] and not first["trigger"], window
        line = next(c for c in res["checks"] if c["name"].startswith("maneuver ") and "t=20.29" in c["detail"])
        assert "neither the sheet's 0.3 m nor the accepted safety_distance 0.5 m held" in line["detail"]
        assert res["verdict"] == "FAILED"
    res = _judge(rec)
    second = _at(res, 29.6)
    assert second["not_judged"] and "moved by hand" in second["not_judged"] and "against the command" in \
        second["not_judged"]
    assert any(f.startswith("data: moved by hand from t=35.") for f in report_lines(res))
    assert report_lines(res)[-1] == "overall: FAILED"


def test_1700_first_passed_at_the_accepted_reading_second_stuck_then_by_hand_third_set_apart() -> None:
    rec = _bag("sesasr_tb3_lab03_1700")
    assert 0.35 <= _front(rec, 10.0) <= 0.45
    assert -97 <= _yaw_turned(rec, 9.9, 18.0) <= -90
    assert abs(_yaw_turned(rec, 20.2, 26.7)) < 12  # stuck: the yaw hardly moved while -0.22 rad/s was commanded
    assert _yaw_turned(rec, 26.8, 27.6) > 40  # then the other way, fast: a hand
    for window in ((None, None), (5.0, 19.5), (9.0, 30.0), (0.0, 35.4)):
        res = _judge(rec, *window)
        first = _at(res, 10.0)
        assert first["not_judged"] is None and first["passed"] and 93 <= -first["angle_deg"] <= 96, window
        line = next(c for c in res["checks"] if c["name"].startswith("maneuver ") and "t=10.00" in c["detail"])
        assert "front 0.40 m: the sheet's 0.3 m did not hold; accepted at safety_distance 0.5 m" in line["detail"]
        assert res["verdict"] == "PASSED"
    for window in ((None, None), (17.95, 29.5), (19.0, 35.4)):
        second = _at(_judge(rec, *window), 19.7)
        assert second["not_judged"].startswith(("stuck from t=20.2", "moved by hand from t=19.2")), window
        assert "stuck" in second["not_judged"] and "then moved by hand at t=26.8 s: +48 deg" in second["not_judged"]
    for window in ((None, None), (30.0, None)):
        third = _at(_judge(rec, *window), 31.7)
        assert third["not_judged"] and "stuck" in third["not_judged"] and "while commanded +0.22 rad/s" in \
            third["not_judged"] and "then the recording ends" in third["not_judged"]
        assert -13 <= third["angle_deg"] <= -8
    res = _judge(rec)
    summary = next(c for c in res["checks"] if c["name"] == "maneuvers")
    assert summary["detail"].startswith("3 seen: 1 judged, 1 passed, 0 failed; 2 not judged")


def test_a_window_with_no_whole_turn_is_incomplete_never_passed() -> None:
    rec = _bag("sesasr_tb3_lab03_1700")
    res = _judge(rec, 17.5, 29.5)
    assert res["verdict"] == "INCOMPLETE" and not res["passed"]
    assert "its turn began before the window" in _at(res, 17.6)["not_judged"]
    assert report_lines(res)[-1].startswith("overall: INCOMPLETE (no maneuver could be judged: maneuver 1")
