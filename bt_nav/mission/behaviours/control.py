"""BehaviorTree.CPP control nodes mapped onto py_trees composites and decorators.

The tree file uses BehaviorTree.CPP v4 tags so that Groot2 opens it; these classes register those
tags with py_trees' XML parser. ``ReactiveSequence`` / ``ReactiveFallback`` re-evaluate every child
from the first on each tick (py_trees' ``memory=False``), which is what lets a guard higher up preempt
a running action below it.
"""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.ports import PortInformation, PortsMixin


class ReactiveSequence(PortsMixin, py_trees.composites.Sequence):
    """BT.CPP ``ReactiveSequence``: a memory-less py_trees Sequence."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, children: list[py_trees.behaviour.Behaviour] | None = None,
                 **kwargs: Any) -> None:
        super().__init__(name=name, memory=False, children=children, **kwargs)


class ReactiveFallback(PortsMixin, py_trees.composites.Selector):
    """BT.CPP ``ReactiveFallback``: a memory-less py_trees Selector (priority chooser)."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, children: list[py_trees.behaviour.Behaviour] | None = None,
                 **kwargs: Any) -> None:
        super().__init__(name=name, memory=False, children=children, **kwargs)


class ForceSuccess(PortsMixin, py_trees.decorators.FailureIsSuccess):
    """BT.CPP ``ForceSuccess``: a failed child still lets its sequence hold (e.g. stay stopped)."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
