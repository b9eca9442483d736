"""The lab sheet's mistakes, each a one-line change of a generated right node, and what the grader must say.

A mistake replaces text on the template line marked ``# <name>`` (:mod:`tests.nodegen.template`); the markers are
then removed, so a right node and its mutant differ in that one line only. :data:`EXPECT` is what the grader must
fail each for: the reasons reuse the patterns and names of the lab fixture's mutation suite
(``tests/ros/test_mutants.py``, ``LAB_BY_CHOICE``) where the mistake is one of its own, and the cells of the
choice's default grid where the mistake shows (a regex on the cell's label; None: every cell).
"""

from __future__ import annotations

import re

#: mistake -> (the choices it applies to, the text replaced on its marked line, the replacement, in words)
MUTATIONS: dict[str, tuple[str, str, str, str]] = {
    "hardcoded_indices": ("ABC", "offset = math.radians(angle_deg) - msg.angle_min",
                          "return int(round(angle_deg)) % len(msg.ranges)  # 360 beams, ranges[0] ahead",
                          "indices hard-coded: ranges[deg] as if every LiDAR gave 360 beams from straight ahead"),
    "left_or_right": ("B", 'r["left"] < sd and r["right"] < sd', 'r["left"] < sd or r["right"] < sd',
                      "B fires on left OR right (the sheet: AND)"),
    "angle_45": ("ABC", "math.radians(angle)", "math.radians(45.0)", "turns 45 deg whatever its choice"),
    "wrong_side": ("C", "sign, angle = clearer, 90.0", "sign, angle = -clearer, 90.0",
                   "C pivots towards the closer side"),
    "forward_while_turning": ("ABC", "self.send(0.0, self.sign * rate)", "self.send(CREEP, self.sign * rate)",
                              "creeps forward during the turn"),
    "ignores_safety_distance": ("AB", 'return float(self.get_parameter("safety_distance").value)', "return 0.5",
                                "declares safety_distance but keeps 0.5 m whatever it is given"),
    "moves_before_toggle": ("ABC", "self.active = False", "self.active = True",
                            "armed from the start: moves before toggle_navigation true"),
    "ignores_toggle_off": ("ABC", "self.active = request.data", "self.active = self.active or request.data",
                           "answers toggle_navigation false but keeps going (no stop on deactivation)"),
    "never_creeps": ("ABC", "self.send(CREEP, 0.0)", "self.send(0.0, 0.0)",
                     "stands still when nothing triggers (the sheet: maintain a slow forward velocity)"),
}

NOT_HELD_LEFT = r"turned although its trigger did not hold \(left"
_EVERY = None
#: mistake -> choice -> (what the failing runs must say, the cells it must fail in). Patterns as the lab fixture's
#: mutation suite's (LAB_C, LAB_BY_CHOICE) for the mistakes it has too.
EXPECT: dict[str, dict[str, tuple[str, str | None]]] = {
    "hardcoded_indices": {c: (r"performed no maneuver|hit an obstacle|trigger did not hold|turned late|needs", _EVERY)
                          for c in "ABC"},
    "left_or_right": {"B": (NOT_HELD_LEFT, "lab_hallway")},
    "angle_45": {"A": (r"turned [3-5]\d deg \w+; the Randomizer needs 80-190 deg", _EVERY),
                 "B": (r"turned [3-5]\d deg \w+; the Retreat needs 180 \+- 10 deg", _EVERY),
                 "C": (r"turned [3-5]\d deg \w+; the Smart Pivot needs 90 \+- 10 deg", _EVERY)},
    # caught where every reasonable reading of the sides agrees: lab_slant (made for it, as the mutation suite says)
    "wrong_side": {"C": (r"the Smart Pivot needs 90 \+- 10 deg (left|right)", "lab_slant")},
    "forward_while_turning": {c: (r"drove forward during the turn \(commanded up to 0\.05 m/s", _EVERY)
                              for c in "ABC"},
    "ignores_safety_distance": {
        "A": (r"turned late: triggered at front 0\.[3-5]\d m with safety_distance 0\.70: it crept on 0\.[12]\d m",
              "safety_distance=0.7"),
        "B": (r"turned late: triggered at left 0\.\d\d m and right 0\.\d\d m with safety_distance 0\.70: it crept on",
              "safety_distance=0.7")},
    "moves_before_toggle": {c: (r"moved before it was activated", _EVERY) for c in "ABC"},
    "ignores_toggle_off": {c: (r"did not stop and stay still after the deactivation", _EVERY) for c in "ABC"},
    # the check-off's creep check (bt_nav/judge/checkoff_creep.py), or no maneuver at all. B only in lab_hallway:
    # a B node whose sides reach 45 deg reads the dead end's mouth as a squeeze at its spawn, spins there without
    # creeping, and the run may end before it stood 3 s (seen passing once in two runs)
    "never_creeps": {c: (r"stood still for [\d.]+ s from t=[\d.]+ s while armed with nothing triggering|"
                         r"performed no maneuver", "lab_hallway" if c == "B" else _EVERY) for c in "ABC"},
}
#: Mistakes only some LiDARs show: (the LiDAR it passes with, the one it must fail with), as the mutation suite's.
BY_LIDAR = {"hardcoded_indices": ("lds01", "rplidar")}

MARKER = re.compile(r"  # <([a-z_0-9]+)>$", re.MULTILINE)


def apply(source: str, mistake: str | None) -> str:
    """``source`` (the template filled in, markers and all) with ``mistake`` made, and every marker removed."""
    if mistake is not None:
        _, old, new, _ = MUTATIONS[mistake]
        lines = source.split("\n")
        marked = [i for i, line in enumerate(lines) if line.endswith(f"  # <{mistake}>")]
        if len(marked) != 1 or old not in lines[marked[0]]:
            raise ValueError(f"the template has no single line marked {mistake} holding {old!r}")
        lines[marked[0]] = lines[marked[0]].replace(old, new)
        source = "\n".join(lines)
    return MARKER.sub("", source)


def applies(mistake: str, choice: str) -> bool:
    """Whether the mistake is one a node of this choice can make and the choice's default grid shows."""
    return choice in MUTATIONS[mistake][0] and choice in EXPECT[mistake]
