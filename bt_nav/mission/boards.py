"""A blackboard of its own for each mission tree, in a process where py_trees has only one.

Why: py_trees keeps the blackboard on the ``Blackboard`` class (process-wide dicts), and the leaves hold
references to those very dict objects. Two mission trees in one process (several robots in lock-step,
two executives in a test) would read each other's scans and arming. So each
:class:`bt_nav.mission.core.MissionCore` owns an :class:`OwnBoard` and enters it before anything touches
its tree: when another board is current, the live dicts' contents are saved into that one and replaced
by this one's (the dict objects stay). With one tree in the process the board is always current and
entering is one identity check, so the single-robot path costs nothing.

Not thread-safe across trees: two trees ticked from two threads at once would still share the dicts.
Every driver here ticks its trees from one thread.
"""

from __future__ import annotations

from typing import Any, ClassVar

import py_trees

_BLACKBOARD = py_trees.blackboard.Blackboard
#: The class-level dicts a blackboard consists of (the clients' registrations and the key metadata too).
_FIELDS = ("storage", "metadata", "clients")


class OwnBoard:
    """One tree's blackboard contents, swapped into py_trees' process-wide dicts on :meth:`enter`."""

    _current: ClassVar[OwnBoard | None] = None

    def __init__(self) -> None:
        self._saved: dict[str, dict[Any, Any]] = {name: {} for name in _FIELDS}

    def enter(self) -> None:
        """Make this board the live one (a no-op when it already is): the live contents go to the board
        that was current, and this board's come in. A new board enters empty (a cleared blackboard)."""
        current = OwnBoard._current
        if current is self:
            return
        for name in _FIELDS:
            live = getattr(_BLACKBOARD, name)
            if current is not None:
                current._saved[name] = dict(live)
            live.clear()
            live.update(self._saved[name])
            self._saved[name] = {}
        OwnBoard._current = self

    @property
    def is_current(self) -> bool:
        """This board is the live one."""
        return OwnBoard._current is self
