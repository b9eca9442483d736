"""A launch file's checks as the grade records them: the lab sheet's Task 3 in three checks (it starts the student's
node, declares the launch argument ``safety_distance`` with the default 0.5, and passes it to the node), each
passed, failed, or not checked.

Why "not checked" is a status of its own: the grader evaluates a launch file against stand-ins of the launch API
(:mod:`bt_nav.grading.launch.evaluate`), and a file may do what they cannot follow (a shell ``Command``, a package of
its own). Such a check is never failed for the grader's limits: it counts as passed, and says a TA should look.
A check may also be "not checked" because it depends on another that failed (``depends``: nothing to pass to a
Node that is not started; a launch argument declared right that reaches no parameter of the sheet's name): one root
cause fails one check, so a typo costs one check, and a TA need not look. A failed check carries its ``fix``: what
the file holds and what it misses, said from the file (never "add" what is there).
Pure: no rclpy, no launch.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

#: The lab sheet's name for the launch file, and its launch argument with the default it asks.
LAUNCH_NAME = "turtlebot_bringup.launch.py"
ARGUMENT, DEFAULT = "safety_distance", 0.5
#: The value given on the command line to see whether the argument reaches the node.
OVERRIDE = 0.7
#: The three checks, in the verdict's order (their names are stable: other formats key on them).
STARTS, DECLARES, PASSES = ("starts the node", f"declares {ARGUMENT} (default {DEFAULT:g})",
                            f"passes {ARGUMENT} to the node")
#: What a check the grader could not follow says (and the TA reads).
NOT_CHECKED = "not checked: a TA should look"


def depends_words(name: str | None) -> str:
    """What a check not checked because check ``name`` failed says: ``not checked: depends on starts the node``."""
    return f"not checked: depends on {name}"


@dataclass(frozen=True)
class LaunchCheck:
    """One check of the launch file: its name, whether it passed, why, the line it is about (None: none), and
    whether it was checked at all (``checked`` False: the grader could not follow the file; ``passed`` is then True,
    so a grade never fails for it; :meth:`text` says :data:`NOT_CHECKED`, the formats say it from ``checked``)."""

    name: str
    passed: bool
    reason: str
    line: int | None = None
    checked: bool = True
    file: str | None = None  # the file the line is in (an included launch file, a params YAML); None: not said
    depends: str | None = None  # not checked because this check (its name) failed: the root cause, charged once
    fix: str | None = None  # a failed check's advice from the file: what is there and what is missing

    @property
    def at(self) -> str:
        """``turtlebot_bringup.launch.py:12: `` (or ``line 12: ``), '' without a line."""
        if not self.line:
            return ""
        return f"{self.file}:{self.line}: " if self.file else f"line {self.line}: "

    @property
    def status(self) -> str:
        """``PASSED``, ``FAILED`` or ``NOT CHECKED``."""
        return "NOT CHECKED" if not self.checked else "PASSED" if self.passed else "FAILED"

    def text(self) -> str:
        """``starts the node: PASSED (line 12: Node(package='my_package', executable='reactive_navigator'))``."""
        reason = f"{depends_words(self.depends)}; {self.reason}" if self.depends else \
            f"{NOT_CHECKED}; {self.reason}" if not self.checked else self.reason
        return f"{self.name}: {self.status} ({self.at}{reason})"


@dataclass(frozen=True)
class LaunchReport:
    """The launch file's checks: the file read (None: none handed in), the checks, and a note on how it was used."""

    file: str | None
    checks: tuple[LaunchCheck, ...]
    notes: tuple[str, ...] = field(default=())

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def checked(self) -> bool:
        """Whether every check was checked (False: a TA should look at the file; a check not checked because
        another failed needs no TA)."""
        return all(c.checked or c.depends for c in self.checks)

    def lines(self) -> list[str]:
        """A line per check; one line when every check failed for the same reason (no file, a syntax error)."""
        reasons = {c.reason for c in self.checks}
        if not self.passed and len(reasons) == 1 and not any(c.passed for c in self.checks):
            check = self.checks[0]
            return [f"launch file: FAILED ({check.at}{check.reason})"]
        return [f"launch file: {c.text()}" for c in self.checks]

    def to_dict(self) -> dict[str, Any]:
        return {"file": self.file, "passed": self.passed, "checked": self.checked,
                "checks": [asdict(c) for c in self.checks], "notes": list(self.notes)}

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> LaunchReport:
        return cls(doc.get("file"), tuple(LaunchCheck(**c) for c in doc.get("checks", [])),
                   tuple(doc.get("notes", [])))


