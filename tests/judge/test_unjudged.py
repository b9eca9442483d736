"""The account of a run never judged (its node never offered the arming service): what the robot did, from ground
truth, and no check that passes over a schedule that never ran."""

from __future__ import annotations

import math

import pytest

from bt_nav.judge.unjudged import FreeMotion


def _drive(free: FreeMotion, seconds: float, v: float, w: float, t0: float = 0.0, dt: float = 0.1) -> None:
    x = y = yaw = 0.0
    for k in range(round(seconds / dt) + 1):
        free.observe(t0 + k * dt, x, y, yaw)
        x += v * dt * math.cos(yaw)
        y += v * dt * math.sin(yaw)
        yaw += w * dt


def test_a_robot_that_stood_still_fails_only_for_the_missing_service() -> None:
    free = FreeMotion()
    _drive(free, 20.0, 0.0, 0.0)
    checks = free.checks("/toggle_navigation", "the service /toggle_navigation never appeared within 20 s wall")
    assert [c["name"] for c in checks] == ["/toggle_navigation offered"] and not checks[0]["passed"]
    assert free.summary() == "" and free.results()["travelled"] == 0.0 and free.results()["collisions"] == 0


def test_a_robot_that_drove_on_its_own_is_told_how_far_and_what_it_hit() -> None:
    """10 s at 0.2 m/s straight: 2 m travelled and 2 m away, a collision at 8 s; every figure as driven."""
    free = FreeMotion()
    _drive(free, 10.0, 0.2, 0.0, t0=1.0)
    free.on_collision(8.0, 1.4, 0.0)
    checks = free.checks("/activate", "the service /activate never appeared within 18 s wall")
    assert [c["name"] for c in checks] == ["/activate offered", "still while not armed", "no collision"]
    assert not any(c["passed"] for c in checks)
    results = free.results()
    assert results["travelled"] == pytest.approx(2.0, abs=1e-6)
    assert results["max_distance_from_start"] == pytest.approx(2.0, abs=1e-6)
    assert results["collisions"] == 1 and results["collision_events"] == [{"t": 8.0, "x": 1.4, "y": 0.0}]
    assert "travelled 2.00 m and turned 0 deg from sim 1.10 s to 11.00 s, 2.00 m from its start" in free.summary()
    assert "1 collision while not armed: sim 8.0 s (1.40, 0.00)" in free.summary()


def test_a_spin_in_place_is_motion_too() -> None:
    free = FreeMotion()
    _drive(free, 3.0, 0.0, 1.0)
    assert free.moved and free.results()["travelled"] == 0.0
    assert "turned 172 deg" in free.motion_text()
