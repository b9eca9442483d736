"""The simulator's real-robot odometry effects in a pivot (``odom_yaw_scale``, ``odom_turn_drift``): /odom
over-reads the turn and drifts sideways, ground truth stays exact; off by default."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bt_nav_sim.core import SimConfig, SimCore


def _pivot(**effects: float) -> tuple[float, float, float]:
    """Odometry yaw turned / true yaw turned, and the odometry's and the truth's displacement after a 90 deg pivot."""
    core = SimCore(SimConfig(world="lab_object", profile="lab", noise=False, **effects))
    x0, y0 = core.state.x, core.state.y
    true_turn = odom_turn = 0.0
    last_true, last_odom = core.state.yaw, core.odom_yaw
    while true_turn < math.pi / 2:
        if not core.advance(0.0, 1.0).odom:
            continue  # odometry integrates at its own rate: compare at its samples
        true_turn += math.remainder(core.state.yaw - last_true, math.tau)
        odom_turn += math.remainder(core.odom_yaw - last_odom, math.tau)
        last_true, last_odom = core.state.yaw, core.odom_yaw
    return odom_turn / true_turn, float(np.hypot(core.odom_x, core.odom_y)), math.hypot(core.state.x - x0,
                                                                                       core.state.y - y0)


def test_off_by_default_and_the_effects_on_odometry_only() -> None:
    ratio, odom_moved, truth_moved = _pivot()
    assert ratio == pytest.approx(1.0, abs=1e-9) and odom_moved < 1e-9 and truth_moved < 1e-9
    ratio, odom_moved, truth_moved = _pivot(odom_yaw_scale=1.05, odom_turn_drift=0.02)
    assert ratio == pytest.approx(1.05, abs=1e-3)
    # 0.02 m per radian sideways while the heading turns: an arc of radius 0.02 m, its chord over a quarter turn
    assert odom_moved == pytest.approx(2 * 0.02 * math.sin(math.pi / 4), rel=0.05) and truth_moved < 1e-9


def test_out_of_range_values_are_refused() -> None:
    with pytest.raises(ValueError, match="odom_yaw_scale"):
        SimConfig(odom_yaw_scale=3.0).check()
