"""The README is the user's manual: what it states about parameters and commands must be true."""

from __future__ import annotations

import re
from pathlib import Path

from bt_nav.cli import COMMANDS
from bt_nav.mission.params import markdown_table

README = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")


def test_parameter_table_is_current() -> None:
    assert markdown_table() in README, "paste bt_nav.mission.params.markdown_table() into the README"


def test_no_unfilled_placeholders() -> None:
    assert not re.findall(r"<<[A-Z]+[^>]*>>", README)


def test_bt_nav_commands_in_the_readme_exist() -> None:
    used = set(re.findall(r"bt-nav ([a-z][a-z-]+)", README))
    assert used, "the README shows bt-nav commands"
    assert used <= set(COMMANDS), f"unknown commands in README: {used - set(COMMANDS)}"


def test_the_two_commands_come_first() -> None:
    first_block = README.split("```", 2)[1]
    assert "make demo" in first_block and "make test" in first_block
