"""The lab's evasive maneuvers, one record each: the one home of everything that names a maneuver.

A record says what a maneuver is called (letter, title, aliases), which leaf performs it and under which
name it shows in the tree, its log and its pictures (the tip), which subtree of ``trees/mission.xml`` holds
it, when it fires (its trigger), how far and which way it turns (its angle and side rules) and in which
arenas it is checked off. Every other table derives from :data:`MANEUVER_SPECS`: the ``maneuver`` parameter's
spellings and titles (:mod:`bt_nav.mission.params`), the leaf registry and the tree's subtree slot, the
check-off judge's trigger and angle rules (:mod:`bt_nav.judge.checkoff_core`), the default check-off
arenas, the plots' maneuver tips, the terminal's shown lines, the grader's ``# CHOICE:`` line and the docs.

Why lookups are calls (or live views) rather than tables built at import: a maneuver added to
:data:`MANEUVER_SPECS` later (a test registers a throw-away one) must reach every consumer, and a table built at
import would keep the old set.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, overload

NONE = "none"
#: What a trigger reads: the sectors it compares, in words, and the trigger leaf that reads them.
TRIGGER_READS: dict[str, tuple[str, str]] = {
    "front": ("front", "FrontTrigger"),
    "sides": ("left and right", "SqueezeTrigger"),
}
#: Side rules: ``either`` (any way round passes) or ``clearer`` (towards the side that reads more room).
SIDE_RULES = ("either", "clearer")
#: What a maneuver is for, which decides how a chain of them back to back (each begun with its trigger still holding)
#: is judged: ``search`` (a turn to find a new path: another turn on a still-blocked front is the search going on) or
#: ``exit`` (a turn to get out: one that never leads out, however often repeated, failed its purpose).
PURPOSES = ("search", "exit")


@dataclass(frozen=True)
class Purpose:
    """Why a maneuver turns, in the sheet's words (``to find a new path``), and its kind (:data:`PURPOSES`)."""

    kind: str
    words: str

    def __post_init__(self) -> None:
        if self.kind not in PURPOSES:
            raise ValueError(f"a maneuver's purpose is one of {PURPOSES}, not {self.kind!r}")


@dataclass(frozen=True)
class Trigger:
    """When a maneuver fires, as the lab's sheet says it: its sectors read nearer than a distance parameter.

    ``or_braked_at``: another parameter a node may trigger at, one that brakes at that distance and turns
    there (the Smart Pivot's sheet distance is nearer than a creeping node's braking distance)."""

    reads: str
    distance: str
    or_braked_at: str = ""

    def __post_init__(self) -> None:
        if self.reads not in TRIGGER_READS:
            raise ValueError(f"a trigger reads {' or '.join(TRIGGER_READS)}, not {self.reads!r}")

    @property
    def words(self) -> str:
        """The sectors read, as a sentence says them (``front``, ``left and right``)."""
        return TRIGGER_READS[self.reads][0]

    @property
    def leaf(self) -> str:
        """The trigger leaf's class name (a generated subtree uses it)."""
        return TRIGGER_READS[self.reads][1]

    @property
    def distances(self) -> tuple[str, ...]:
        """Every distance parameter the trigger may fire at, the sheet's first."""
        return (self.distance, self.or_braked_at) if self.or_braked_at else (self.distance,)


@dataclass(frozen=True)
class AngleRule:
    """How far a maneuver turns (``low_deg`` to ``high_deg``, one angle when equal) and which way (``side``)."""

    low_deg: float
    high_deg: float
    side: str = "either"

    def __post_init__(self) -> None:
        if self.side not in SIDE_RULES or not 0 < self.low_deg <= self.high_deg:
            raise ValueError(f"an angle rule needs 0 < low <= high and a side among {SIDE_RULES}: {self}")

    def holds(self, size: float, tolerance: float) -> bool:
        """Whether a turn of ``size`` deg (unsigned) is within the rule's range, ``tolerance`` deg either end."""
        if self.low_deg == self.high_deg:
            return abs(size - self.low_deg) <= tolerance
        return self.low_deg - tolerance <= size <= self.high_deg + tolerance

    def words(self, tolerance: float, side: str = "either side") -> str:
        """The rule as the judge's lines say it (``90-190 deg either side``, ``90 +- 10 deg left``); ``side`` is
        the clearer side's words, used only by a ``clearer`` rule."""
        where = side if self.side == "clearer" else "either side"
        if self.low_deg == self.high_deg:
            return f"{self.low_deg:.0f} +- {tolerance:.0f} deg {where}"
        return f"{self.low_deg - tolerance:.0f}-{self.high_deg + tolerance:.0f} deg {where}"


@dataclass(frozen=True)
class ManeuverSpec:
    """One lab maneuver (see the module docstring for who reads which field).

    ``tip`` is the leaf's node name in the tree: the tip the trace and the pictures show and the label its
    log lines start with (``Randomizer: front 0.49 m: turning right 143 deg``). ``arenas``: the worlds that
    can check it off, the default first (each lists the letter in its ``checkoff_maneuvers``). ``purpose``: why
    it turns (the check-off judges a chain of them back to back by it)."""

    letter: str
    title: str
    aliases: tuple[str, ...]
    leaf: str
    tip: str
    subtree: str
    trigger: Trigger
    angle: AngleRule
    arenas: tuple[str, ...]
    purpose: Purpose = Purpose("search", "to find a new path")

    @property
    def full_title(self) -> str:
        """``A Randomizer``: the letter and the title, as the executive's up line says it."""
        return f"{self.letter} {self.title}"

    @property
    def log_label(self) -> str:
        """The label the leaf's log lines start with (its node name, :attr:`tip`)."""
        return self.tip


#: The arenas with something ahead to trigger a front maneuver (the lone object first: the default check-off).
_FRONT_ARENAS = ("lab_object", "lab_appearing", "lab_cluttered", "lab_dead_end", "lab_narrow_gap", "lab_passerby",
                 "lab_side", "lab_beside")
MANEUVER_SPECS: dict[str, ManeuverSpec] = {spec.letter: spec for spec in (
    ManeuverSpec("A", "Randomizer", ("randomizer",), "RandomizerManeuver", "Randomizer", "ManeuverA",
                 Trigger("front", "safety_distance"), AngleRule(90.0, 180.0), _FRONT_ARENAS,
                 Purpose("search", "to find a new path")),
    ManeuverSpec("B", "Retreat", ("retreat",), "RetreatManeuver", "Retreat", "ManeuverB",
                 Trigger("sides", "safety_distance"), AngleRule(180.0, 180.0),
                 ("lab_dead_end", "lab_cluttered", "lab_narrow_gap", "lab_hallway"),
                 Purpose("exit", "to exit the narrow space")),
    ManeuverSpec("C", "Smart Pivot", ("smart_pivot", "smartpivot", "pivot"), "SmartPivotManeuver", "SmartPivot",
                 "ManeuverC", Trigger("front", "pivot_distance", or_braked_at="safety_distance"),
                 AngleRule(90.0, 90.0, side="clearer"), (*_FRONT_ARENAS, "lab_slant"),
                 Purpose("search", "toward the clearest side")),
)}
"""Letter -> record, in the order the lab lists them. The one place a maneuver is defined."""
NONE_SUBTREE = "ManeuverNone"


def lab_letters() -> tuple[str, ...]:
    """The lab's maneuver letters, in order (``A``, ``B``, ``C``)."""
    return tuple(MANEUVER_SPECS)


def maneuver_spec(letter: str) -> ManeuverSpec:
    """The record of maneuver ``letter``. Raises ValueError for any other (never a silent default)."""
    try:
        return MANEUVER_SPECS[letter]
    except (KeyError, TypeError):
        raise ValueError(f"unknown maneuver {letter!r}: the lab's maneuvers are {letters_text()}") from None


def letters_text(last: str = "or") -> str:
    """The letters as a sentence lists them: ``A, B or C``."""
    letters = lab_letters()
    return letters[0] if len(letters) == 1 else f"{', '.join(letters[:-1])} {last} {letters[-1]}"


def choices_text() -> str:
    """Every value of the ``maneuver`` parameter as a help line lists them: ``none, A, B, C``."""
    return ", ".join((NONE, *lab_letters()))


def names_text() -> str:
    """Each maneuver's first alias, as a help line offers them: ``randomizer, retreat, smart_pivot``."""
    return ", ".join(spec.aliases[0] for spec in MANEUVER_SPECS.values() if spec.aliases)


def aliases() -> dict[str, str]:
    """Every accepted spelling (lower case, ``_`` for spaces) -> ``none`` or a letter."""
    out = {NONE: NONE}
    for spec in MANEUVER_SPECS.values():
        out[spec.letter.lower()] = spec.letter
        out.update(dict.fromkeys(spec.aliases, spec.letter))
    return out


def titles() -> dict[str, str]:
    """``none`` or a letter -> its title with the letter (``A Randomizer``)."""
    return {NONE: NONE, **{letter: spec.full_title for letter, spec in MANEUVER_SPECS.items()}}


def judge_names() -> dict[str, str]:
    """Letter -> the name the check-off's sentences use (``the Randomizer``)."""
    return {letter: f"the {spec.title}" for letter, spec in MANEUVER_SPECS.items()}


def subtrees() -> dict[str, str]:
    """``none`` or a letter -> the subtree that fills the tree's maneuver slot."""
    return {NONE: NONE_SUBTREE, **{letter: spec.subtree for letter, spec in MANEUVER_SPECS.items()}}


def tips() -> frozenset[str]:
    """The maneuver leaves' tip names (what the trace, the plots and the log labels show)."""
    return frozenset(spec.tip for spec in MANEUVER_SPECS.values())


def default_arenas() -> dict[str, str]:
    """Letter -> the world a check-off of it runs in unless told otherwise."""
    return {letter: spec.arenas[0] for letter, spec in MANEUVER_SPECS.items()}


def checked_off_in(world: str) -> tuple[str, ...]:
    """The letters whose arenas include ``world``, in the spec's order."""
    return tuple(letter for letter, spec in MANEUVER_SPECS.items() if world in spec.arenas)


def choice_pattern() -> str:
    """A regex alternation of the letters (``A|B|C``), longest first, for lines that declare one."""
    return "|".join(sorted(lab_letters(), key=len, reverse=True))


class LiveLetters(Sequence[str]):
    """A tuple-like view of the letters (after ``prefix``) that follows :data:`MANEUVER_SPECS` (a module-level constant
    that ``from ... import`` binds once, yet sees a maneuver registered later)."""

    def __init__(self, prefix: tuple[str, ...] = ()) -> None:
        self._prefix = prefix

    def _now(self) -> tuple[str, ...]:
        return (*self._prefix, *MANEUVER_SPECS)

    @overload
    def __getitem__(self, index: int) -> str: ...
    @overload
    def __getitem__(self, index: slice) -> tuple[str, ...]: ...
    def __getitem__(self, index: int | slice) -> str | tuple[str, ...]:  # noqa: D105
        return self._now()[index]

    def __len__(self) -> int:  # noqa: D105
        return len(MANEUVER_SPECS) + len(self._prefix)

    def __eq__(self, other: object) -> bool:  # noqa: D105
        return isinstance(other, Sequence) and not isinstance(other, str) and self._now() == tuple(other)

    def __hash__(self) -> int:  # noqa: D105
        return hash(self._now())

    def __repr__(self) -> str:  # noqa: D105
        return repr(self._now())


class LiveMap(Mapping[str, Any]):
    """A read-only mapping rebuilt from :data:`MANEUVER_SPECS` on each use (see :class:`LiveLetters`)."""

    def __init__(self, build: Callable[[], Mapping[str, Any]]) -> None:
        self._build = build

    def __getitem__(self, key: str) -> Any:  # noqa: D105
        return self._build()[key]

    def __iter__(self) -> Iterator[str]:  # noqa: D105
        return iter(self._build())

    def __len__(self) -> int:  # noqa: D105
        return len(self._build())

    def __repr__(self) -> str:  # noqa: D105
        return repr(dict(self._build()))
