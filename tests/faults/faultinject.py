"""Test-only fault injection: make chosen tree leaves raise, to prove an exception stops the robot.

``BT_NAV_FAULT_INJECT=<leaf>[@<n>]`` (comma-separated for several) makes the n-th ``update`` (default:
the first) of each named tree node raise :class:`InjectedFaultError` once. In-process tests call
:func:`inject_faults` on a tree; process tests start ``faulty_executive.py``, which arms the variable's
faults on the real executive's tree. Product code knows nothing of this module.
"""

from __future__ import annotations

from typing import Any

from bt_nav.ros.rosutil import ConfigError

#: The environment variable ``faulty_executive.py`` reads.
FAULT_INJECT_ENV = "BT_NAV_FAULT_INJECT"


class InjectedFaultError(RuntimeError):
    """What an injected fault raises: its own type, so a log line can never pass for a real bug."""


def inject_faults(root: Any, spec: str) -> list[str]:
    """Arm the faults of a ``BT_NAV_FAULT_INJECT`` value on the tree under ``root``; returns ``name@n`` each.

    The behaviour's ``update`` is wrapped on the instance (the class stays untouched): the n-th call
    raises once, every other call runs the original.

    Raises:
        ConfigError: for an entry that names no node of the tree or has a bad count (a typo must not
            silently test nothing; the executive refuses to start on it).
    """
    nodes = {node.name: node for node in root.iterate()}
    armed: list[str] = []
    for entry in filter(None, (part.strip() for part in spec.split(","))):
        name, _, count = entry.partition("@")
        node = nodes.get(name)
        if node is None:
            raise ConfigError(f"{FAULT_INJECT_ENV}: no tree node named {name!r} (nodes: {', '.join(sorted(nodes))})")
        try:
            nth = int(count) if count else 1
        except ValueError:
            nth = 0
        if nth < 1:
            raise ConfigError(f"{FAULT_INJECT_ENV}: {entry!r}: the count after @ must be an integer >= 1")
        _raise_on_update(node, nth)
        armed.append(f"{name}@{nth}")
    return armed


def _raise_on_update(node: Any, nth: int) -> None:
    """Make the ``nth`` call of ``node.update`` raise :class:`InjectedFaultError` (once)."""
    original = node.update
    calls = 0

    def update() -> Any:
        nonlocal calls
        calls += 1
        if calls == nth:
            raise InjectedFaultError(f"injected by {FAULT_INJECT_ENV} into update {nth} of {node.name}")
        return original()

    node.update = update
