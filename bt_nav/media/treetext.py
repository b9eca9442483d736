"""The executive's ``~/tree`` text (py_trees' unicode tree without colours) as rows the video and the
browser view can colour by status.

A row looks like ``    --> TurnAway [*] -- steering +10 deg``: indentation (4 spaces a level), a marker
(``-->`` leaf, ``[o]`` selector, ``[-]`` sequence, ``-^-`` decorator, ``/_/`` parallel), the name, the
status in brackets (``✓`` success, ``✕`` failure, ``*`` running, ``-`` invalid / not ticked) and the
feedback message. Pure text processing; nothing to import but ``re``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_ROW = re.compile(r"^(?P<indent> *)(?P<marker>\S+) (?P<name>.*?) \[(?P<status>[✓✕*-])\](?: -- (?P<feedback>.*))?$")
#: Status symbol -> py_trees status name.
STATUS_NAMES = {"✓": "SUCCESS", "✕": "FAILURE", "*": "RUNNING", "-": "INVALID"}


@dataclass(frozen=True)
class TreeRow:
    """One node of a snapshot."""

    depth: int
    marker: str
    name: str
    status: str  # SUCCESS, FAILURE, RUNNING or INVALID
    feedback: str


def parse_snapshot(text: str) -> list[TreeRow]:
    """The rows of a snapshot; lines that are not tree rows are skipped (an empty list for foreign text)."""
    rows = []
    for line in text.splitlines():
        match = _ROW.match(line)
        if match:
            rows.append(TreeRow(len(match["indent"]) // 4, match["marker"], match["name"],
                                STATUS_NAMES[match["status"]], match["feedback"] or ""))
    return rows


def active_path(rows: list[TreeRow]) -> list[int]:
    """Indices of the rows on the path of the last tick, root first (ends at the tip).

    In every composite the child a tick ended on is the last child that was ticked (status not
    INVALID): a selector's winner or a sequence's current child, which is what ``Behaviour.tip()`` gives.
    """
    if not rows:
        return []
    path, index = [0], 0
    while True:
        depth, chosen = rows[index].depth, None
        for j in range(index + 1, len(rows)):
            if rows[j].depth <= depth:
                break
            if rows[j].depth == depth + 1 and rows[j].status != "INVALID":
                chosen = j
        if chosen is None:
            return path
        path.append(chosen)
        index = chosen


def tip_name(text: str) -> str:
    """Name of the tip of a snapshot ("" when the text is not a tree)."""
    rows = parse_snapshot(text)
    path = active_path(rows)
    return rows[path[-1]].name if path else ""
