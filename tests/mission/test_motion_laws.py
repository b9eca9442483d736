"""The driving laws on the free paths: speed kept high across the far band, the smallest sufficient turn,
a turn side with hysteresis, and the robot's width (not a cone) deciding what is in the way.

Run with the homework profile (config/homework.yaml over the parameter table's defaults), the tuning
these laws were made for; the tests read the values from there.
"""

from __future__ import annotations

import math

from bt_nav.mission import params as P
from bt_nav.mission.behaviours.motion import STEER_GAIN, TurnAway
from bt_nav.mission.behaviours.perception import ProcessScan
from bt_nav.mission.paths import free_paths
from bt_nav.run.settings import profile_parameters
from bt_nav.testing import TickHarness, synthetic_scan

HOMEWORK = profile_parameters("homework")
D = {**P.defaults(), **HOMEWORK}


def armed() -> TickHarness:
    h = TickHarness(overrides=HOMEWORK)
    h.tick()
    assert h.arm()[0]
    h.tick()
    return h


def ahead(*obstacles: tuple[float, float], **kwargs: float) -> float:
    """The free path straight ahead that the tree computes for this scan."""
    horizon = ProcessScan.HORIZON * D["far_distance"]
    paths = free_paths(synthetic_scan(obstacles, **kwargs), D["path_half_width"], horizon)
    return paths.ahead


def test_speed_stays_near_max_until_deep_in_the_band() -> None:
    h = armed()
    close, far = D["close_distance"], D["far_distance"]
    v_max, v_slow = D["max_linear_speed"], D["slow_linear_speed"]
    speeds = []
    for distance in (far + 0.1, 0.5 * (close + far) + 0.18, close + 0.25):
        h.see((0.0, distance), width_deg=20.0)
        r = h.tick()
        assert r.tip == "TurnAway"
        depth = (far - ahead((0.0, distance), width_deg=20.0)) / (far - close)
        assert 0.0 < depth < 1.0
        assert r.command.linear == v_max - (v_max - v_slow) * depth ** TurnAway.SPEED_EXPONENT
        speeds.append(r.command.linear)
    assert v_max > speeds[0] > speeds[1] > speeds[2] >= v_slow


def test_turn_is_proportional_to_the_heading_and_capped() -> None:
    h = armed()
    h.see((0.0, 0.65), width_deg=10.0)  # a post ahead: a small turn clears it
    small = h.tick()
    assert small.tip == "TurnAway" and 0.0 < abs(small.command.angular) < D["angular_speed"]
    assert abs(small.command.angular) / STEER_GAIN <= math.radians(45)
    h.see((0.0, 0.65), width_deg=200.0)  # a wall wrapping around: the clear heading is far to the side
    wide = h.tick()
    assert abs(wide.command.angular) == D["angular_speed"]


def test_direction_has_hysteresis() -> None:
    h = armed()
    h.see((8.0, 0.65), width_deg=20.0)  # obstacle ahead, a little to the left: turn right
    first = h.tick()
    assert first.tip == "TurnAway" and first.command.angular < 0
    h.see((-4.0, 0.65), width_deg=20.0)  # now a little to the right: the right turn is kept
    for _ in range(5):
        r = h.tick()
        assert r.tip == "TurnAway" and r.command.angular < 0
    h.see((-8.0, 0.65), (-60.0, 0.5), width_deg=40.0)  # the right is walled in: flip to the left
    r = h.tick()
    assert r.tip == "TurnAway" and r.command.angular > 0


def test_square_on_wall_does_not_dither() -> None:
    """Readings that alternate by a few centimetres around a symmetric wall never flip the turn."""
    h = armed()
    h.see((0.0, 0.6), width_deg=130.0)
    first = h.tick().command.angular
    assert first != 0.0
    for i in range(40):
        h.see((-25.0, 0.6 + 0.03 * (i % 2)), (25.0, 0.6 + 0.03 * ((i + 1) % 2)), (0.0, 0.6), width_deg=50.0)
        r = h.tick()
        assert r.tip in ("TurnAway", "RotateInPlace") and r.command.angular * first > 0


def test_an_obstacle_at_the_shoulder_is_in_the_way() -> None:
    """At 45 deg and 0.22 m an obstacle is outside any front cone but inside the robot's swept width."""
    h = armed()
    h.see((45.0, 0.22), width_deg=6.0)
    r = h.tick()
    assert r.tip in ("RotateInPlace", "TurnAway"), "driving straight on would hit it"
    assert r.command.angular < 0, "turns away from the shoulder obstacle on the left"
    h.see((60.0, 0.5), width_deg=6.0)  # 0.43 m to the side: clear of the path, straight on at full speed
    r = h.tick()
    assert r.tip == "FullSpeed" and r.command.linear == D["max_linear_speed"]
