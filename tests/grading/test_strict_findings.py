"""``bt-nav grade --strict-findings``: the one option that makes the check-off's findings (what the lab sheet only
implies, issue 52) fail for a course that teaches them, as the hosted judge's ``strict_findings`` parameter."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

from bt_nav.cli.grade import _parser
from bt_nav.grading.exe.grid import strict_option
from bt_nav.grading.exe.run import ExeSettings, exe_graph
from bt_nav.grading.grid import Job


def _judge_args(tmp_path: Path, strict: str) -> list[str]:
    settings = ExeSettings("python3 node.py", "lab", tmp_path, strict_findings=strict)
    sim = exe_graph(Job("lab_dead_end", "B", 0, "lab"), settings, tmp_path / "verdict.json")
    return json.loads(sim.arguments[sim.arguments.index("--judge-args") + 1])


def test_the_option_reaches_the_hosted_judge_and_an_unknown_kind_is_refused(tmp_path: Path) -> None:
    args = _parser().parse_args(["--exe", "python3 node.py", "--profile", "lab", "--strict-findings",
                                      "back_to_back,side"])
    assert strict_option(args) == "back_to_back,side"
    assert 'strict_findings:="back_to_back,side"' in _judge_args(tmp_path, "back_to_back,side")  # a string
    assert not any("strict_findings" in a for a in _judge_args(tmp_path, ""))  # by default each finding passes
    with pytest.raises(ValueError, match="unknown finding kind"):
        strict_option(SimpleNamespace(strict_findings="never_moved_on"))
