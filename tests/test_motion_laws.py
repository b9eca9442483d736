"""The TurnAway control law: speed kept high across the far band, turn direction with hysteresis.

Run with the homework profile (config/homework.yaml over bt_nav/params.py's defaults: front +-20 deg,
sides 0..60 deg, close 0.3 m, far 1.2 m, speeds 0.2..0.22 m/s, angular_speed 2.5 rad/s), the tuning
these laws were made for; the tests read the values from there.
"""

from __future__ import annotations

import pytest

from bt_nav.cli.lockstep import profile_parameters
from bt_nav.mission import params as P
from bt_nav.mission.behaviours.motion import TurnAway
from bt_nav.testing import TickHarness

HOMEWORK = profile_parameters("homework")
D = {**P.defaults(), **HOMEWORK}


def armed() -> TickHarness:
    h = TickHarness(overrides=HOMEWORK)
    h.tick()
    assert h.arm()[0]
    return h


def test_speed_stays_near_max_until_deep_in_the_band() -> None:
    h = armed()
    close, far = D["close_distance"], D["far_distance"]
    samples = []
    for distance in (far - 0.05, (close + far) / 2, close + 0.05):
        h.see((5.0, distance))
        r = h.tick()
        assert r.tip == "TurnAway"
        samples.append((r.command.linear, abs(r.command.angular)))
    (v_edge, w_edge), (v_mid, w_mid), (v_deep, w_deep) = samples
    v_max, v_slow, w_max = D["max_linear_speed"], D["slow_linear_speed"], D["angular_speed"]
    assert v_max > v_edge > v_mid > v_deep >= v_slow
    assert v_mid >= v_max - (v_max - v_slow) * 0.25 - 1e-9, "quadratic: a quarter of the drop at mid-band"
    assert w_edge == pytest.approx(w_max * (TurnAway.MIN_TURN + (1 - TurnAway.MIN_TURN) * 0.05 / (far - close)))
    assert w_edge < w_mid < w_deep <= w_max


def test_direction_has_hysteresis() -> None:
    h = armed()
    h.see((10.0, 0.6))  # obstacle ahead-left: turn right
    assert h.tick().command.angular < 0
    h.see((10.0, 0.6), (-30.0, 0.6 - TurnAway.SWITCH_MARGIN + 0.05))  # right a bit nearer: keep turning right
    for _ in range(5):
        assert h.tick().command.angular < 0
    h.see((10.0, 0.6), (-30.0, 0.6 - TurnAway.SWITCH_MARGIN - 0.05))  # right now clearly nearer: flip
    r = h.tick()
    assert r.tip == "TurnAway" and r.command.angular > 0


def test_square_on_wall_does_not_dither() -> None:
    """Readings that alternate by a few centimetres around a symmetric wall never flip the turn."""
    h = armed()
    h.see((0.0, 0.7), width_deg=130.0)
    first = h.tick().command.angular
    for i in range(40):
        h.see((-25.0, 0.7 + 0.03 * (i % 2)), (25.0, 0.7 + 0.03 * ((i + 1) % 2)), (0.0, 0.7))
        r = h.tick()
        assert r.tip == "TurnAway" and r.command.angular * first > 0


def test_sides_see_the_shoulders() -> None:
    """An obstacle at 50 deg (beside the robot, outside the front cone) decides the turn direction."""
    h = armed()
    h.see((15.0, 0.9), (50.0, 0.25), (-15.0, 0.9))
    r = h.tick()
    assert r.tip == "TurnAway"
    assert r.command.angular < 0, "turns away from the shoulder obstacle on the left"
