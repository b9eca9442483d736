"""Sizes that keep the code readable, over every package (bt_nav with its subpackages, bt_nav_sim, bench): no
command module over 250 lines (bt_nav/cli and its command packages: the commands parse options and print, the
work lives in the layers below), no other module over 850 lines (a module does one job), no function over 80.
docs/developing.md states these limits for contributors."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.arch.test_layers import ROOT, SOURCES

COMMAND_LINES = 250
MODULE_LINES = 850
FUNCTION_LINES = 80


def long_functions(source: str, limit: int) -> list[tuple[str, int]]:
    """(name, lines) of every function or method in ``source`` longer than ``limit`` lines."""
    return [(node.name, node.end_lineno - node.lineno + 1) for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno - node.lineno + 1 > limit]


def test_no_command_module_is_over_250_lines() -> None:
    commands = sorted((ROOT / "bt_nav" / "cli").rglob("*.py"))
    assert any(p.parent.name == "grade" for p in commands)  # the command packages are walked too
    long = [(str(p.relative_to(ROOT)), n) for p in commands if (n := len(p.read_text().splitlines())) > COMMAND_LINES]
    assert not long, long


def test_no_module_is_over_850_lines() -> None:
    long = [(str(p.relative_to(ROOT)), n) for base, _ in SOURCES for p in sorted(base.rglob("*.py"))
            if (n := len(p.read_text().splitlines())) > MODULE_LINES]
    assert not long, long


def test_no_function_is_over_80_lines() -> None:
    long = [(str(p.relative_to(ROOT)), name, n) for base, _ in SOURCES for p in sorted(base.rglob("*.py"))
            for name, n in long_functions(p.read_text(), FUNCTION_LINES)]
    assert not long, long


def test_the_size_check_can_fail() -> None:
    body = "\n".join(f"    x{i} = {i}" for i in range(FUNCTION_LINES))
    assert long_functions(f"def f():\n{body}\n", FUNCTION_LINES) == [("f", FUNCTION_LINES + 1)]
    assert long_functions("def g():\n    return 1\n", FUNCTION_LINES) == []


def test_sources_exist() -> None:
    assert all(Path(base).is_dir() for base, _ in SOURCES)
