"""``bt-nav replay`` reads a bag as well as a trace."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from bt_nav.cli.replay import main as replay_main

if TYPE_CHECKING:
    from conftest import RobotsBag  # tests/media/conftest.py


def test_replay_prints_snapshots_commands_and_events(robots_bag: RobotsBag, capsys: pytest.CaptureFixture) -> None:
    """One robot's bag or several robots' (replay shows the first robot's then)."""
    assert replay_main([str(robots_bag.path), "--compact", "--from", "4", "--to", "8"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.startswith("t=")]
    assert lines and all(4.0 <= float(line[2:].split()[0]) <= 8.0 for line in lines)
    assert "armed" in out and "cmd=(" in out


def test_replay_of_a_broken_bag_names_it(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"\x89MCAP0\r\n" + b"\x01" * 40)
    assert replay_main([str(bad)]) == 2
    assert "bad.mcap" in capsys.readouterr().err


def test_every_reader_carries_a_renamed_leaf_and_a_new_status(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """The readers take the snapshot's fields: a leaf renamed and a status no reader knows reach the replay, the
    browser view and the video's panel as they are, and an event's fields come back whole."""
    from bt_nav.media.bag import MissionBag
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.video import snapshots, status_colour
    from bt_nav.media.view import tree_json
    from bt_nav.mission.snapshot import event
    from bt_nav.testing import TickHarness

    h = TickHarness("A")
    h.tick()
    h.arm()
    h.tick()
    h.see((0.0, 0.45))
    h.tick(3)
    snapshot = h.core.snapshot()
    tip = snapshot["nodes"][snapshot["path"][-1]]
    tip.update(name="Wiggle", status="SKIPPED")
    snapshot["tip"] = "Wiggle"
    record = event("maneuver", 1.0, "Wiggle", maneuver="D", side="left", angle_deg=45.0, readings={"front": 0.3})
    with MissionBag(tmp_path / "bag") as bag:
        bag.cmd(1.0, 0.0, 0.5)
        bag.announce(1.0, record)
        bag.tree(snapshot["t"], snapshot)  # a snapshot is read at its own time (bagread.tree_time)
    rec = read_bag(tmp_path / "bag")
    assert rec.trees == [(snapshot["t"], snapshot)] and rec.announcements == [(1.0, record)]
    assert replay_main([str(tmp_path / "bag")]) == 0
    out = capsys.readouterr().out
    assert "tip=Wiggle " in out and "--> Wiggle [?]" in out
    rows = tree_json(rec.trees[0][1])
    assert [(r["name"], r["status"], r["active"]) for r in rows if r["name"] == "Wiggle"] == \
        [("Wiggle", "SKIPPED", True)]
    (snap,) = snapshots(rec)
    assert snap.tip is not None and (snap.tip.name, snap.tip.status) == ("Wiggle", "SKIPPED")
    assert snap.branch == "ManeuverA_Randomizer" and status_colour("SKIPPED")
