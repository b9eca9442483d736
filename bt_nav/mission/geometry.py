"""Planar angle helpers shared by the mission core, the ROS edge and the simulator (:mod:`bt_nav_sim`).

One home for two small formulas that were written out in several places: wrapping an angle into
``[-pi, pi)`` and reading a heading from an orientation quaternion. Pure Python and numpy, so the
simulator's physics can import it without pulling in py_trees or rclpy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(a: Any) -> Any:
    """Wrap an angle (float) or array of angles to ``[-pi, pi)``.

    Beam angles are not wrapped (an LDS-01 beam at 350 deg is really -10 deg) and integrated yaws
    grow without bound, so every comparison of directions goes through this. The final correction
    handles the floating-point case where ``x % 2pi`` rounds up to exactly ``2pi`` for a tiny
    negative ``x``, which would otherwise yield ``+pi`` and break the half-open interval.
    Scalars (Python or numpy) come back as ``float``; arrays as float64 ``ndarray``.
    """
    if isinstance(a, float | int) or np.ndim(a) == 0:  # the isinstance test keeps the physics' hot path cheap
        w = (float(a) + math.pi) % TWO_PI - math.pi
        return w - TWO_PI if w >= math.pi else w
    w = np.mod(np.asarray(a, dtype=np.float64) + math.pi, TWO_PI) - math.pi
    w[w >= math.pi] -= TWO_PI
    return w


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Heading (rad, about +z) of an orientation quaternion; NaN when it is not a rotation at all.

    Both atan2 terms scale with ``|q|^2``, so an unnormalised quaternion gives the right heading too;
    the NaN lets a caller drop a corrupt message instead of steering by it.
    """
    sin_term = 2.0 * (w * z + x * y)
    cos_term = w * w + x * x - y * y - z * z
    if not (math.isfinite(sin_term) and math.isfinite(cos_term)) or (sin_term == 0.0 and cos_term == 0.0):
        return math.nan
    return math.atan2(sin_term, cos_term)
