"""MissionCore.limit: speed clamps, and the per-wheel limit that keeps the commanded arc."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bt_nav.mission.core import MissionCore
from bt_nav.mission.datatypes import Command, keep_wheels_within
from bt_nav.testing import FakeClock


def test_no_limit_leaves_the_command_alone() -> None:
    assert keep_wheels_within(0.22, 2.5, 0.0, 0.16) == (0.22, 2.5)


def test_scaled_command_keeps_its_curvature() -> None:
    # wheels would need 0.22 - 0.2 and 0.22 + 0.2 = 0.42 m/s: scale 0.2272 / 0.42
    v, w = keep_wheels_within(0.22, 2.5, 0.2272, 0.16)
    assert (v, w) == pytest.approx((0.22 * 0.2272 / 0.42, 2.5 * 0.2272 / 0.42))
    assert v / w == pytest.approx(0.22 / 2.5)
    assert keep_wheels_within(0.1, 1.0, 0.2272, 0.16) == (0.1, 1.0)  # feasible: unchanged


@given(v=st.floats(-0.3, 0.3), w=st.floats(-3.0, 3.0))
@settings(max_examples=200, deadline=None)
def test_no_wheel_ever_exceeds_the_limit(v: float, w: float) -> None:
    lin, ang = keep_wheels_within(v, w, 0.2272, 0.16)
    assert abs(lin) + abs(ang) * 0.08 <= 0.2272 + 1e-12
    assert lin * v >= 0 and ang * w >= 0  # never reversed
    assert abs(lin) <= abs(v) and abs(ang) <= abs(w)  # only ever slower


def test_core_applies_the_wheel_limit_from_its_parameters() -> None:
    ideal = MissionCore({}, clock=FakeClock())
    assert ideal.limit(Command(0.22, 1.5, "x")) == Command(0.22, 1.5, "x")
    burger = MissionCore({"wheel_speed_limit": 0.2272}, clock=FakeClock())
    limited = burger.limit(Command(0.22, 1.5, "x"))
    assert limited.source == "x"
    assert abs(limited.linear) + abs(limited.angular) * 0.08 == pytest.approx(0.2272)
    assert limited.linear / limited.angular == pytest.approx(0.22 / 1.5)
