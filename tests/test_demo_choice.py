"""``bt-nav demo --exe`` films the maneuver the node's file declares (the lab template's ``# CHOICE: X``), as
``bt-nav grade`` grades it, in the arena that checks it off; ``--maneuver`` wins and a conflict is said.
The real run over DDS: tests/ros/test_demo_exe.py."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pytest

from bt_nav.cli.demo import build_parser
from bt_nav.cli.demo.exe import _settings
from bt_nav.run.settings import profile_maneuver


def _opts(tmp_path: Path, source: str, *args: str) -> argparse.Namespace:
    node = tmp_path / "reactive_navigator.py"
    node.write_text(source)
    return build_parser().parse_args(["--exe", f"{sys.executable} {node}", "--out", str(tmp_path), *args])


def test_the_lab_node_is_filmed_on_its_declared_choice_in_its_arena(tmp_path: Path) -> None:
    job, settings, note = _settings(_opts(tmp_path, "# CHOICE: C\n", "--profile", "lab"))
    assert (job.maneuver, job.world, note) == ("C", "lab_object", "")
    job, _, note = _settings(_opts(tmp_path, "#CHOICE: B  (Retreat)\n", "--profile", "lab"))
    assert (job.maneuver, job.world, note) == ("B", "lab_dead_end", "")


def test_an_explicit_maneuver_wins_and_the_conflict_is_said(tmp_path: Path) -> None:
    opts = _opts(tmp_path, "# CHOICE: C\n", "--profile", "lab", "--maneuver", "a")
    job, _, note = _settings(opts)
    assert (job.maneuver, job.world) == ("A", "lab_object")
    assert note == f"--maneuver a wins over the '# CHOICE: C' in {tmp_path / 'reactive_navigator.py'}"
    job, _, note = _settings(_opts(tmp_path, "# CHOICE: C\n", "--profile", "lab", "--maneuver", "smart_pivot"))
    assert job.maneuver == "C" and note == ""


def test_a_lab_node_without_a_choice_is_asked_which_maneuver(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"which maneuver does the node perform\? give --maneuver A, B or C"):
        _settings(_opts(tmp_path, "print('no choice')\n", "--profile", "lab"))
    job, _, _ = _settings(_opts(tmp_path, "# CHOICE: A\n"))  # the homework: the file's lab choice means nothing
    assert (job.world, job.maneuver) == ("stage_4", profile_maneuver("homework"))
