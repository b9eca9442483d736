"""BehaviorTree.CPP control nodes mapped onto py_trees composites and decorators.

The tree file uses BehaviorTree.CPP v4 tags so that Groot2 opens it; these classes register those
tags with py_trees' XML parser. ``ReactiveSequence`` / ``ReactiveFallback`` re-evaluate every child
from the first on each tick (py_trees' ``memory=False``), which is what lets a guard higher up preempt
a running action below it.
"""

from __future__ import annotations

from collections.abc import Callable
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


# ---------------------------------------------------------------------------------------------- ticking
Status = py_trees.common.Status
_RUNNING, _SUCCESS, _FAILURE, _INVALID = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID
_STATUSES = list(Status)
Tick = Callable[[], None]
Stop = Callable[[Status], None]


def _hook(node: py_trees.behaviour.Behaviour, name: str) -> Callable[..., None] | None:
    """``node``'s ``initialise`` or ``terminate``, or None when it is py_trees' empty one (nothing to call):
    about 50 such calls a tick in the mission tree do nothing."""
    if name not in vars(node) and getattr(type(node), name) is getattr(py_trees.behaviour.Behaviour, name):
        return None
    return getattr(node, name)


def _checked(node: py_trees.behaviour.Behaviour, status: Any) -> Status:
    """``status`` when it is a Status; INVALID (logged, as py_trees does) otherwise."""
    if status is _SUCCESS or status is _FAILURE or status is _RUNNING or status is _INVALID:
        return status
    if status not in _STATUSES:
        node.logger.error(f"A behaviour returned an invalid status, setting to INVALID [{status}][{node.name}]")
        return _INVALID
    return status


def _is(node: py_trees.behaviour.Behaviour, base: type, *methods: str) -> bool:
    """``node`` is a ``base`` whose ``methods`` are the base's own (not overridden by its class or instance)."""
    return isinstance(node, base) and all(
        name not in vars(node) and getattr(type(node), name) is getattr(base, name) for name in methods)


def compile_tick(root: py_trees.behaviour.Behaviour) -> Tick:
    """A function that ticks ``root`` exactly as ``for _ in root.tick(): pass`` does, only cheaper.

    py_trees ticks through nested generators and formats a debug string (enum names included) at
    every tick and stop of every node, logging on or off: with ~30 nodes and a reactive fallback
    that stops every branch it passes over, that machinery was most of a tick. The functions built
    here replay py_trees 2.6's own ``Behaviour``/``Sequence``/``Selector``/``Decorator`` tick and stop
    logic statement by statement (the same ``initialise``/``update``/``terminate`` calls in the same
    order, the same statuses and ``current_child``), without the generators and the debug strings.
    The only state they leave out is ``Behaviour.iterator`` (a fresh generator py_trees stores at
    every stop and never reads). A node of any other kind (a composite with memory, a Parallel, a
    class that overrides ``tick`` or ``stop``) is ticked and stopped by py_trees itself.

    The tree's shape, and each node's ``initialise`` and ``terminate``, are read once (py_trees' empty
    ones are not called at all): build the ticker after the tree is complete. ``update`` is looked up at
    call time, so an ``update`` wrapped on the instance afterwards (fault injection) is honoured.
    Callers keep py_trees' own tick whenever its debug logging is on (the strings are then wanted).
    """
    return _compile(root)[0]


def _compile(node: py_trees.behaviour.Behaviour) -> tuple[Tick, Stop]:
    """(tick, stop) for one node, by kind."""
    if _is(node, py_trees.composites.Sequence, "tick", "stop") and not node.memory:
        return _sequence(node, [_compile(child) for child in node.children])
    if _is(node, py_trees.composites.Selector, "tick", "stop") and not node.memory:
        return _selector(node, [_compile(child) for child in node.children])
    if _is(node, py_trees.decorators.Decorator, "tick", "stop"):
        return _decorator(node, _compile(node.decorated))
    if (_is(node, py_trees.behaviour.Behaviour, "tick", "stop") and not node.children
            and not isinstance(node, py_trees.composites.Composite | py_trees.decorators.Decorator)):
        return _leaf(node)
    return (lambda: node.tick_once()), (lambda new: node.stop(new))


def _leaf(node: py_trees.behaviour.Behaviour) -> tuple[Tick, Stop]:
    """``Behaviour.tick`` / ``Behaviour.stop``."""
    initialise, terminate = _hook(node, "initialise"), _hook(node, "terminate")

    def stop(new: Status) -> None:
        if terminate is not None:
            terminate(new)
        node.status = new

    def tick() -> None:
        if node.status is not _RUNNING and initialise is not None:
            initialise()
        new = node.update()
        if new is not _SUCCESS and new is not _FAILURE and new is not _RUNNING:
            new = _checked(node, new)
        if new is not _RUNNING:
            stop(new)
        node.status = new

    return tick, stop


def _decorator(node: py_trees.decorators.Decorator, child: tuple[Tick, Stop]) -> tuple[Tick, Stop]:
    """``Decorator.tick`` / ``Decorator.stop``."""
    child_tick, child_stop = child
    decorated = node.decorated
    initialise, terminate = _hook(node, "initialise"), _hook(node, "terminate")

    def stop(new: Status) -> None:
        if terminate is not None:
            terminate(new)
        if new is _INVALID:
            child_stop(new)
        if decorated.status is _RUNNING:
            child_stop(_INVALID)
        node.status = new

    def tick() -> None:
        if node.status is not _RUNNING and initialise is not None:
            initialise()
        child_tick()
        new = _checked(node, node.update())
        if new is not _RUNNING:
            stop(new)
        node.status = new

    return tick, stop


def _composite_stop(node: py_trees.composites.Composite, stops: list[tuple[Any, Stop]]) -> Stop:
    """``Composite.stop`` (what Sequence.stop and Selector.stop call)."""
    terminate = _hook(node, "terminate")

    def stop(new: Status) -> None:
        if new is _INVALID:
            node.current_child = None
            for child, child_stop in stops:
                if child.status is not _INVALID:
                    child_stop(new)
        if terminate is not None:
            terminate(new)
        node.status = new

    return stop


def _sequence(node: py_trees.composites.Sequence, children: list[tuple[Tick, Stop]]) -> tuple[Tick, Stop]:
    """``Sequence.tick`` without memory: every child from the first, the rest invalidated on a non-success."""
    kids = list(node.children)
    stops = [(kid, child[1]) for kid, child in zip(kids, children, strict=True)]
    steps = [(kid, child[0], stops[i + 1:], kids[i + 1] if i + 1 < len(kids) else None)
             for i, (kid, child) in enumerate(zip(kids, children, strict=True))]
    stop = _composite_stop(node, stops)
    first = kids[0] if kids else None
    initialise = _hook(node, "initialise")

    def tick() -> None:
        if node.status is not _RUNNING:
            node.current_child = first
            for kid, kid_stop in stops:
                if kid.status is not _INVALID:
                    kid_stop(_INVALID)
            if initialise is not None:
                initialise()
        else:
            node.current_child = first
        if not kids:
            node.current_child = None
            stop(_SUCCESS)
            return
        for kid, kid_tick, rest, following in steps:
            kid_tick()
            status = kid.status
            if status is not _SUCCESS:
                for other, other_stop in rest:
                    if other.status is not _INVALID:
                        other_stop(_INVALID)
                if status is not _RUNNING:
                    stop(status)
                else:
                    node.status = status
                return
            if following is not None:
                node.current_child = following
        stop(_SUCCESS)

    return tick, stop


def _selector(node: py_trees.composites.Selector, children: list[tuple[Tick, Stop]]) -> tuple[Tick, Stop]:
    """``Selector.tick`` without memory: the first child that runs or succeeds wins; a new winner
    invalidates every child after it."""
    kids = list(node.children)
    stops = [(kid, child[1]) for kid, child in zip(kids, children, strict=True)]
    steps = [(kid, child[0], stops[i + 1:]) for i, (kid, child) in enumerate(zip(kids, children, strict=True))]
    stop = _composite_stop(node, stops)
    first, last = (kids[0], kids[-1]) if kids else (None, None)
    initialise = _hook(node, "initialise")

    def tick() -> None:
        if node.status is not _RUNNING:
            node.current_child = first
            if initialise is not None:
                initialise()
        if not kids:
            node.current_child = None
            stop(_FAILURE)
            return
        previous = node.current_child
        for kid, kid_tick, rest in steps:
            kid_tick()
            status = kid.status
            if status is _RUNNING or status is _SUCCESS:
                node.current_child = kid
                if previous is None or previous is not kid:
                    for other, other_stop in rest:
                        if other.status is not _INVALID:
                            other_stop(_INVALID)
                if status is _SUCCESS:
                    stop(status)
                else:
                    node.status = status
                return
        stop(_FAILURE)
        node.current_child = last

    return tick, stop
