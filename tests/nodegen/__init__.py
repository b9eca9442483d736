"""Right lab nodes nobody wrote by hand (issue 52): a seeded generator over the lab sheet's reasonable space, and
each right node's mutants, one sheet mistake each.

The lab fixture's right variants are one author's readings of the sheet, switched by flags inside one file. A
grader that never fails a right node must also pass the nodes that author did not think of: these are drawn from
the knobs of :mod:`tests.nodegen.space` (choice, executor, loop, timing, turn rate, sectors, braking, re-arming) and
written out as complete standalone files, as a student hands one in.

    spec = generate(7)           # spec.source: the file's text; spec.knobs: how it was written
    wrong = mutants(spec)        # {"angle_45": source, ...}: the mistakes this choice can make
    python -m tests.nodegen --seed 0 --count 6 --mutants --out /tmp/nodes
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass
from string import Template

from tests.nodegen.mutate import BY_LIDAR, EXPECT, MUTATIONS, applies, apply
from tests.nodegen.space import VALUES, Knobs, describe, sample
from tests.nodegen.template import TEMPLATE

__all__ = ["BY_LIDAR", "EXPECT", "MUTATIONS", "VALUES", "Knobs", "NodeSpec", "generate", "mutants", "render"]


@dataclass(frozen=True)
class NodeSpec:
    """A generated right node: its seed, its knobs and its complete source."""

    seed: int
    knobs: Knobs
    source: str

    @property
    def name(self) -> str:
        """A file and student name: ``gen007_C``."""
        return f"gen{self.seed:03d}_{self.knobs.choice}"


def fill(knobs: Knobs, seed: int, mistake: str | None) -> str:
    """The template with the knobs' constants (markers still in)."""
    k = knobs
    said = "A right node: no mistake." if mistake is None else f"A mutant: {MUTATIONS[mistake][3]} ({mistake})."
    return Template(TEMPLATE).substitute(
        SEED=seed, DESCRIPTION=textwrap.fill(describe(k), 110), MISTAKE=said, CHOICE=k.choice,
        EXECUTOR=k.executor, LOOP=k.loop,
        TIMER_HZ=k.timer_hz, TIMING=k.timing, TURN_RATE=repr(k.turn_rate), ANNOUNCE=k.announce,
        FRONT_HALF=k.front_half, SIDE_CENTRE=k.side_centre, SIDE_HALF=k.side_half, SIDE_STAT=k.side_stat,
        REARM_MARGIN=repr(k.rearm_margin), PAUSE=repr(k.pause), C_TRIGGER=k.c_trigger, SPIN=k.spin)


def render(knobs: Knobs, seed: int = 0, mistake: str | None = None) -> str:
    """The complete source of the node these knobs describe, with ``mistake`` made (None: the right node)."""
    return apply(fill(knobs, seed, mistake), mistake)


def generate(seed: int) -> NodeSpec:
    """The right node of ``seed`` (deterministic)."""
    knobs = sample(seed)
    return NodeSpec(seed=seed, knobs=knobs, source=render(knobs, seed))


def mutants(spec: NodeSpec) -> dict[str, str]:
    """Each sheet mistake this node's choice can make, as a mutated source (``EXPECT`` says what the grader must
    fail it for)."""
    return {name: render(spec.knobs, spec.seed, name) for name in MUTATIONS if applies(name, spec.knobs.choice)}
