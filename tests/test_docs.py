"""The documentation site builds with no warning, and its generated reference pages cover what the code has: a
parameter or a command option without its entry fails here."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from bt_nav.cli import COMMANDS
from bt_nav.mission.params import PARAMS, markdown_table

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import bt_nav_reference  # noqa: E402 - the docs' generator lives with the docs


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    out = tmp_path_factory.mktemp("reference")
    return {p.name: p.read_text(encoding="utf-8") for p in bt_nav_reference.write_reference(out)}


def test_the_site_builds_without_a_warning(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(tmp_path / "html")],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    index = (tmp_path / "html" / "index.html").read_text(encoding="utf-8")
    for page in ("lab.html", "grading.html", "reference/parameters.html", "reference/commands.html",
                 "reference/worlds.html", "reference/checks.html", "reference/node-rules.html", "lidars.html"):
        assert page in index, page


def test_every_parameter_has_its_entry(reference: dict[str, str]) -> None:
    page = reference["parameters.md"]
    assert markdown_table() in page
    for spec in PARAMS:
        assert spec.description.strip(), f"{spec.name} has no description"
        assert f"| `{spec.name}` |" in page


def test_every_command_and_option_has_its_entry(reference: dict[str, str]) -> None:
    page = reference["commands.md"]
    missing = []
    for name in COMMANDS:
        section = page.split(f"## bt-nav {name}\n", 1)[1].split("\n## bt-nav ", 1)[0]
        assert "usage:" in section, name
        options = re.findall(r"^  (-[-\w]+(?:[ ,][^\n]*)?)$", section, flags=re.M)
        # argparse puts an option's help on its line or the next; an option alone on its line followed by
        # another option (or nothing) has no help
        lines = section.splitlines()
        for i, line in enumerate(lines):
            m = re.match(r"^  (-{1,2}[\w-]+)", line)
            if not m or m.group(1) in ("-h", "--help"):
                continue
            text = line.strip()
            has_inline = bool(re.search(r"\S {2,}\S", text))
            follow = lines[i + 1] if i + 1 < len(lines) else ""
            has_next = bool(re.match(r"^ {8,}\S", follow))  # options sit 2 in, their help further
            if not (has_inline or has_next):
                missing.append(f"bt-nav {name} {m.group(1)}")
        assert options or name in ("executive",), name
    assert not missing, f"options without help text: {missing}"


def test_every_world_and_check_has_its_entry(reference: dict[str, str]) -> None:
    from bt_nav_sim.world import list_worlds

    from bt_nav.judge.referee_core import CHECK_WORDS

    for name in list_worlds("all"):
        assert f"### {name}\n" in reference["worlds.md"], name
    for check, words in CHECK_WORDS.items():
        assert f"| {check} | {words} |" in reference["checks.md"]


def test_the_node_rules_page_is_the_rules_bt_nav_rules_prints(reference: dict[str, str]) -> None:
    from bt_nav.grading.rules import rules_markdown

    assert reference["node-rules.md"] == rules_markdown(note=bt_nav_reference.GENERATED)
    assert "## The lab: what your node must do" in reference["node-rules.md"]
