"""Maneuver triggers in the whole tree, tick by tick: a lasting condition cannot trap the robot."""

from __future__ import annotations

import pytest

from bt_nav.testing import TickHarness

CASES = [  # maneuver, its leaf, a scan that meets its condition, one that clears it beyond the hysteresis
    ("A", "Randomizer", [(0.0, 0.45)], [(0.0, 0.8)]),
    ("B", "Retreat", [(60.0, 0.4), (-60.0, 0.4), (0.0, 0.9)], [(60.0, 0.4), (-60.0, 0.9), (0.0, 0.9)]),
    ("C", "SmartPivot", [(0.0, 0.25), (30.0, 1.0)], [(0.0, 0.5), (30.0, 1.0)]),
]


def armed(maneuver: str, **overrides: float) -> TickHarness:
    """Armed, with one tick of a clear scan: the triggers have seen their conditions clear."""
    h = TickHarness(maneuver, {"side_center_deg": 60.0, "side_half_angle_deg": 30.0, **overrides})
    h.tick()
    assert h.arm()[0]
    h.tick()
    return h


def finish(h: TickHarness, leaf: str) -> list:
    """Ticks from the maneuver's start to its end (the scan stays as it is)."""
    records = [h.tick()]
    assert records[0].tip == leaf, f"{leaf} did not start: tip {records[0].tip}"
    while records[-1].statuses[leaf] == "RUNNING" or len(records) == 1:
        records.append(h.tick())
        assert len(records) < 300
    return records


@pytest.mark.parametrize(("maneuver", "leaf", "condition", "clear"), CASES)
def test_a_persisting_condition_does_not_refire(maneuver, leaf, condition, clear) -> None:
    h = armed(maneuver, trigger_rearm_distance=0.0)
    h.see(*condition)
    records = finish(h, leaf)
    assert all(r.command.linear == 0.0 for r in records), "rotation only"
    after = [h.tick() for _ in range(60)]  # 3 s with the same condition: the reactive branches drive
    assert all(r.tip != leaf for r in after), "the maneuver re-fired while its condition merely persisted"


@pytest.mark.parametrize(("maneuver", "leaf", "condition", "clear"), CASES)
def test_a_fresh_condition_fires_again(maneuver, leaf, condition, clear) -> None:
    h = armed(maneuver, trigger_rearm_distance=0.0)
    h.see(*condition)
    finish(h, leaf)
    h.see(*clear)
    h.tick(3)
    h.see(*condition)
    finish(h, leaf)


def test_rearming_needs_clearing_away_from_where_it_fired() -> None:
    h = armed("B", trigger_rearm_distance=1.0)
    squeezed = [(60.0, 0.4), (-60.0, 0.4), (0.0, 5.0)]  # a long corridor: both walls near, nothing ahead
    opening = [(60.0, 0.4), (-60.0, 2.0), (0.0, 5.0)]  # a side opening
    h.see(*opening)
    h.tick()
    h.see(*squeezed)
    finish(h, "Retreat")
    x0, y0 = h.x, h.y
    h.see(*opening)  # cleared on the spot: no re-arm
    h.tick()
    h.see(*squeezed)
    for _ in range(200):  # 10 s down a corridor that never clears: it stays quiet
        assert h.tick().tip != "Retreat", "re-fired while the squeeze merely lasted"
    driven = ((h.x - x0) ** 2 + (h.y - y0) ** 2) ** 0.5
    assert driven > 1.0
    h.see(*opening)  # an opening, far from the last firing: re-armed
    h.tick()
    h.see(*squeezed)
    assert h.tick().tip == "Retreat"


def test_a_maneuver_never_restarts_while_it_runs() -> None:
    h = armed("A", trigger_rearm_distance=0.0)
    h.see((0.0, 0.45))
    first = h.tick()
    leaf = next(n for n in h.core.root.iterate() if n.name == "Randomizer")
    rotation = leaf.rotation
    h.see((0.0, 0.45), (30.0, 0.3))  # the condition flickers and changes: nothing restarts the turn
    for _ in range(5):
        h.see()
        h.tick()
        h.see((0.0, 0.45))
        r = h.tick()
        assert r.tip == "Randomizer" and leaf.rotation == rotation
    assert first.tip == "Randomizer"


def test_a_new_arming_starts_afresh() -> None:
    h = armed("C", trigger_rearm_distance=5.0)
    h.see((0.0, 0.25), (30.0, 1.0))
    finish(h, "SmartPivot")
    assert h.tick().tip != "SmartPivot"
    h.arm(False)
    h.tick(3)
    h.arm(True)
    assert h.tick().tip != "SmartPivot", "a condition holding at the arming is not a rising edge"
    h.see()
    h.tick()  # seen clear once after the new arming: armed again, however near the last firing
    h.see((0.0, 0.25), (30.0, 1.0))
    assert h.tick().tip == "SmartPivot"
