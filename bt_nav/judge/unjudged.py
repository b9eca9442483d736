"""What the robot did while no judge had started: the account of a run that was never judged.

A judge starts its schedule (t0) when the robot's node offers the service that arms it. A node that never does
(a wanderer from another course, a typo in the service name) may still drive on its own for the whole wait, and
hit a wall. Its verdict must say so from ground truth, not report ``travelled 0.00 m`` and ``no collision:
PASSED`` over a schedule that never ran. :class:`FreeMotion` keeps that account from the run's first pose on;
its checks never pass vacuously: the service's absence fails, and motion or a collision while not armed adds a
failed check of its own (a robot that stood still and hit nothing adds none: there was nothing to judge).

Pure: no rclpy; the judge nodes feed it the poses and collisions they would have ignored before t0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

#: Ground-truth displacement (m) or rotation (deg) from the first pose that counts as having moved.
MOVED_DISTANCE, MOVED_TURN_DEG = 0.02, 5.0


@dataclass
class FreeMotion:
    """Ground truth and collisions seen before t0: distance, rotation, farthest point, collisions."""

    first: tuple[float, float, float, float] | None = None  # t, x, y, yaw of the first pose
    last: tuple[float, float, float, float] | None = None
    travelled: float = 0.0
    turned: float = 0.0  # rad, summed absolute
    farthest: float = 0.0
    moved_at: float | None = None  # sim s the robot first left its first pose
    collisions: list[tuple[float, float, float]] = field(default_factory=list)

    def observe(self, t: float, x: float, y: float, yaw: float) -> None:
        """One ground-truth pose (sim s, m, rad); out-of-order stamps are skipped."""
        if self.last is not None and t < self.last[0]:
            return
        if self.first is None:
            self.first = self.last = (t, x, y, yaw)
            return
        _, lx, ly, lyaw = self.last
        self.travelled += math.hypot(x - lx, y - ly)
        self.turned += abs(math.remainder(yaw - lyaw, math.tau))
        _, fx, fy, _ = self.first
        away = math.hypot(x - fx, y - fy)
        self.farthest = max(self.farthest, away)
        if self.moved_at is None and (away >= MOVED_DISTANCE or math.degrees(self.turned) >= MOVED_TURN_DEG):
            self.moved_at = t
        self.last = (t, x, y, yaw)

    def on_collision(self, t: float, x: float, y: float) -> None:
        """A collision event of the simulator (the start of one contact)."""
        self.collisions.append((float(t), float(x), float(y)))

    @property
    def moved(self) -> bool:
        return self.moved_at is not None

    def motion_text(self) -> str:
        """``travelled 4.12 m and turned 35 deg from sim 3.20 s to 24.00 s, 2.10 m from its start`` (true figures)."""
        if self.first is None or self.last is None:
            return "no ground truth came"
        if not self.moved:
            return f"stood still over sim {self.first[0]:.2f}-{self.last[0]:.2f} s"
        return (f"travelled {self.travelled:.2f} m and turned {math.degrees(self.turned):.0f} deg from sim "
                f"{self.moved_at:.2f} s to {self.last[0]:.2f} s, {self.farthest:.2f} m from its start")

    def collision_text(self) -> str:
        where = ", ".join(f"sim {t:.1f} s ({x:.2f}, {y:.2f})" for t, x, y in self.collisions[:3])
        more = f" and {len(self.collisions) - 3} more" if len(self.collisions) > 3 else ""
        n = len(self.collisions)
        return f"{n} collision{'s' if n != 1 else ''} while not armed: {where}{more}"

    def checks(self, service: str, why: str) -> list[dict[str, Any]]:
        """The run's checks: ``service`` never offered (``why``), and what the robot did meanwhile when it did
        anything (a failed check each: moving and colliding while not armed)."""
        out = [{"name": f"{service} offered", "passed": False, "value": False, "required": "offered",
                "detail": why}]
        if self.moved:
            out.append({"name": "still while not armed", "passed": False, "value": round(self.travelled, 3),
                        "required": "no motion before the arming", "detail": f"moved without being armed: "
                                                                             f"{self.motion_text()}"})
        if self.collisions:
            out.append({"name": "no collision", "passed": False, "value": len(self.collisions), "required": 0,
                        "detail": self.collision_text()})
        return out

    def results(self) -> dict[str, Any]:
        """The verdict's figures from ground truth (the keys every judge's results carry): sim times, as there is
        no t0 to count from."""
        return {"travelled": round(self.travelled, 4), "max_distance_from_start": round(self.farthest, 4),
                "collisions": len(self.collisions),
                "collision_events": [{"t": t, "x": x, "y": y} for t, x, y in self.collisions],
                "unjudged_motion": self.motion_text()}

    def summary(self) -> str:
        """One clause for a run's reason: what the robot did while nobody judged it (empty: nothing)."""
        parts = [f"it moved without being armed ({self.motion_text()})"] if self.moved else []
        if self.collisions:
            parts.append(self.collision_text())
        return "; ".join(parts)
