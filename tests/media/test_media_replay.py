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
