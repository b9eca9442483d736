"""The space of right lab nodes: every knob a student may reasonably turn while following the lab sheet, and a
seeded draw from it.

Each knob's values stay inside what the sheet allows and what the check-off judge accepts
(``bt_nav.judge.readings.SectorFamily``: a front from +-5 to +-30 deg, sides centred 60-110 deg, +-5 to +-30 deg
wide). A few knobs bound one another so every drawn node is right on the grader's LiDARs (the slowest publishes
5 scans a second): an open-loop turn ends on the control step nearest its end, so the angle a step covers
(turn rate x step period) is kept under 0.12 rad (+-3.5 deg at the end); a closed loop on odometry is kept at or
under 0.8 rad/s, where its slow-down over the last 20 deg still lands within the tolerance.
"""

from __future__ import annotations

import math
import random
from dataclasses import asdict, dataclass

#: The slowest scan rate of the grader's LiDARs (the LDS-01, 5 Hz): the step of a node deciding on scans.
SCAN_PERIOD = 0.2
#: rad: the most an open-loop turn may cover between two control steps.
STEP_ANGLE = 0.12
#: rad/s: the fastest closed-loop turn on odometry (faster overshoots the tolerance on the simulated base).
ODOM_MAX_RATE = 0.8

#: Every knob's values (a float range as (low, high) is drawn uniformly; the tests check each listed value shows).
VALUES: dict[str, tuple] = {
    "choice": ("A", "B", "C"),
    "executor": ("single", "multi"),
    "loop": ("scan", "timer"),
    "timer_hz": (5, 10, 20, 50),
    "timing": ("ros_time", "scan_stamp", "integrate", "odom"),
    "announce": (True, False),
    "front_half": (5, 8, 10, 20, 30),
    "side_centre": (60, 70, 75, 80, 90, 100, 110),
    "side_half": (5, 10, 15, 20, 30),
    "side_stat": ("min", "mean"),
    "rearm_margin": (0.0, 0.1),
    "brake": ("direct", "stop"),
    "c_trigger": ("sheet", "safety"),
    "spin": ("clearer", "left", "right"),
}
TURN_RATE_RANGE = (0.3, 2.0)  # rad/s
PAUSE_RANGE = (0.3, 1.0)  # s standing before a turn when braking first


@dataclass(frozen=True)
class Knobs:
    """How one generated student wrote the node (see :data:`VALUES`)."""

    choice: str = "C"
    executor: str = "single"  # single: rclpy.spin; multi: MultiThreadedExecutor (one exclusive callback group)
    loop: str = "timer"  # scan: every decision and command in the scan callback; timer: a control timer
    timer_hz: int = 20  # the control timer's rate (loop == timer)
    timing: str = "ros_time"  # how a turn ends: ROS time, the scans' stamps, the commanded rate summed, odometry
    turn_rate: float = 0.6  # rad/s
    announce: bool = True  # a log line at each turn's start and end
    front_half: int = 30  # deg
    side_centre: int = 90  # deg
    side_half: int = 30  # deg
    side_stat: str = "min"  # C's comparison of the sides: nearest reading or mean
    rearm_margin: float = 0.1  # B: m beyond safety_distance a side must read before the next Retreat
    brake: str = "direct"  # direct: turn at the trigger; stop: stand still `pause` s first
    pause: float = 0.0  # s
    c_trigger: str = "sheet"  # C: front < 0.3 m (sheet) or < safety_distance (safety)
    spin: str = "clearer"  # B's spin direction

    def step_period(self) -> float:
        """The longest time between two control steps: the scans' on the scan loop or with scan-stamp timing."""
        if self.loop == "scan" or self.timing == "scan_stamp":
            return SCAN_PERIOD
        return 1.0 / self.timer_hz

    def as_dict(self) -> dict:
        """The knobs as plain data (a generated file's docstring and the CLI's listing)."""
        return asdict(self)


def max_turn_rate(loop: str, timer_hz: int, timing: str) -> float:
    """The fastest turn that still ends within the tolerance for this loop and timing (see the module doc)."""
    period = SCAN_PERIOD if loop == "scan" or timing == "scan_stamp" else 1.0 / timer_hz
    fastest = min(TURN_RATE_RANGE[1], STEP_ANGLE / period)
    return min(fastest, ODOM_MAX_RATE) if timing == "odom" else fastest


def sides(rng: random.Random, choice: str) -> tuple[int, int]:
    """A side sector of the family: centre 60-110 deg, half 5-30 deg, within 30-140 deg overall. C's sectors stay
    45 deg or more off the bow: one reaching nearer sees the very obstacle C pivots from on both sides."""
    nearest = 45 if choice == "C" else 30
    pairs = [(c, h) for c in VALUES["side_centre"] for h in VALUES["side_half"] if c - h >= nearest and c + h <= 140]
    return rng.choice(pairs)


def sample(seed: int) -> Knobs:
    """The knobs of the generated node ``seed`` (the same seed, the same node). The first seeds sweep the choices
    and loops in turn so that any three consecutive seeds give all three choices."""
    rng = random.Random(f"nodegen-{seed}")
    choice = VALUES["choice"][seed % 3]
    pick = {name: rng.choice(values) for name, values in VALUES.items()}
    centre, half = sides(rng, choice)
    loop, timer_hz, timing = pick["loop"], pick["timer_hz"], pick["timing"]
    if timing == "scan_stamp":
        loop = "scan"  # the stamps come with the scans: a turn timed on them is stepped where they arrive
    fastest = max_turn_rate(loop, timer_hz, timing)
    low = TURN_RATE_RANGE[0]
    # a quarter of the nodes turn at one end of their range or the other: the extremes get tried
    rate = rng.choice((low, fastest, rng.uniform(low, fastest), rng.uniform(low, fastest)))
    brake = pick["brake"]
    return Knobs(choice=choice, executor=pick["executor"], loop=loop, timer_hz=timer_hz, timing=timing,
                 turn_rate=round(rate, 3), announce=pick["announce"], front_half=pick["front_half"],
                 side_centre=centre, side_half=half, side_stat=pick["side_stat"], rearm_margin=pick["rearm_margin"],
                 brake=brake, pause=round(rng.uniform(*PAUSE_RANGE), 2) if brake == "stop" else 0.0,
                 c_trigger=pick["c_trigger"], spin=pick["spin"])


def describe(knobs: Knobs) -> str:
    """One line in words: what this student's node does."""
    k = knobs
    how = {"ros_time": "timed on ROS time", "scan_stamp": "timed on the scans' stamps",
           "integrate": "ended by summing the commanded rate", "odom": "closed loop on odometry"}[k.timing]
    where = "in the scan callback" if k.loop == "scan" else f"in a {k.timer_hz} Hz timer"
    parts = [f"choice {k.choice}", f"{k.executor}-threaded", f"logic {where}", f"turns at {k.turn_rate:g} rad/s {how}",
             f"front +-{k.front_half} deg, sides {k.side_centre}+-{k.side_half} deg",
             f"stands {k.pause:g} s, then turns" if k.brake == "stop" else "turns at once"]
    if k.choice == "C":
        parts.append(f"pivots at {'the sheet 0.3 m' if k.c_trigger == 'sheet' else 'safety_distance'}, "
                     f"compares the sides' {k.side_stat}")
    if k.choice == "B":
        parts.append(f"spins {k.spin}, re-arms {k.rearm_margin:g} m beyond safety_distance")
    parts.append("announces its turns" if k.announce else "silent")
    return "; ".join(parts)


def angle_error_bound(knobs: Knobs) -> float:
    """Degrees an open-loop turn may end off its angle by the step alone (half a step's angle)."""
    return math.degrees(0.5 * knobs.turn_rate * knobs.step_period())
