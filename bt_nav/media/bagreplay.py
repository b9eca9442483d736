"""A recorded bag (rosbag2 directory or ``.mcap``) printed in time order: what ``bt-nav replay BAG`` shows.

A bag keeps the executive's ``~/tree`` snapshots (JSON documents, :mod:`bt_nav.mission.snapshot`, as published: when
a status or the tip changed; printed as py_trees' art, :func:`~bt_nav.mission.snapshot.render_art`), the
commands and the mission's log lines; replay prints each snapshot with its sim time, the command in
force and the log lines since the previous one, so a DDS run can be read like a trace.
"""

from __future__ import annotations

import bisect
import sys
from pathlib import Path

from bt_nav.media.bag import BagError


def is_bag(path: str) -> bool:
    """A rosbag2 directory or an .mcap file (anything else is a JSON-lines trace)."""
    p = Path(path)
    return p.suffix == ".mcap" or p.is_dir()


def replay_bag(path: str, first: float = 0.0, last: float | None = None, compact: bool = False) -> int:
    """Print the bag's snapshots between sim times ``first`` and ``last``; exit status (2: unreadable)."""
    from bt_nav.media.bagread import read_bag
    from bt_nav.mission.snapshot import render_art

    try:
        rec = read_bag(path)
    except BagError as exc:
        print(f"bt-nav replay: {exc}", file=sys.stderr)
        return 2
    if rec.truncated:
        print(f"bt-nav replay: {path} was cut short; replaying the {rec.duration:.1f} s it holds", file=sys.stderr)
    if not rec.trees:
        print(f"bt-nav replay: {path} holds no tree snapshots (/bt_nav_executive/tree; a bag recorded before the "
              "snapshots were JSON has none that can be read)", file=sys.stderr)
        return 2
    cmd_t = rec.cmd[:, 0].tolist()
    event_t = [t for t, _ in rec.events]
    shown_events = 0
    for t, snapshot in rec.trees:
        if t < first or (last is not None and t > last):
            continue
        upto = bisect.bisect_right(event_t, t)
        for et, line in rec.events[shown_events:upto]:
            print(f"  [{et:8.2f}] {line}")
        shown_events = max(shown_events, upto)
        c = bisect.bisect_right(cmd_t, t) - 1
        v, w = (rec.cmd[c, 1], rec.cmd[c, 2]) if c >= 0 else (0.0, 0.0)
        print(f"t={t:8.2f} s  tip={snapshot.get('tip', ''):<16} cmd=({v:+.3f} m/s, {w:+.3f} rad/s)")
        if not compact:
            print(render_art(snapshot), end="")
    return 0
