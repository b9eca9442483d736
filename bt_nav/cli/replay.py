"""``bt-nav replay TRACE``: print a recorded run tick by tick, or render one tick as svg.

A trace (see :mod:`bt_nav.mission.trace`) stores statuses by node name; replay rebuilds the same tree from
the tree file (the header names the maneuver), sets every node's status and feedback as recorded
and prints it with py_trees' own unicode display, so a replayed tick looks exactly like the live one. The leaves'
announcements (a maneuver's start and end, the emergency brake) come before the tick they happened in, at their
time: ``  [   12.30] [INFO] SmartPivot: front 0.47 m: turning left 90 deg``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import py_trees

from bt_nav.cli import plain
from bt_nav.media.bagreplay import is_bag, replay_bag
from bt_nav.media.treedot import GraphvizMissingError, graphviz, tree_to_dot
from bt_nav.mission.core import strip_ansi
from bt_nav.mission.snapshot import event_line
from bt_nav.mission.trace import read_trace
from bt_nav.mission.tree import load_tree


def apply(root: py_trees.behaviour.Behaviour, line: dict[str, Any], feedback: dict[str, str]) -> None:
    """Set statuses (and the feedback known so far) on the rebuilt tree."""
    feedback.update(line.get("feedback", {}))
    for node in root.iterate():
        node.status = py_trees.common.Status(line["statuses"].get(node.name, "INVALID"))
        node.feedback_message = feedback.get(node.name, "")


def summary(line: dict[str, Any]) -> str:
    """One line: tick, time, tip, command, changed blackboard values."""
    cmd = line.get("cmd", {})
    changed = ", ".join(f"{k}={v}" for k, v in line.get("changed", {}).items() if k not in ("cmd_vel", "scan_stamp"))
    text = (f"tick {line['tick']:>5}  t={line['time']:8.2f} s  tip={line['tip']:<16} "
            f"cmd=({cmd.get('linear', 0):+.3f} m/s, {cmd.get('angular', 0):+.3f} rad/s)")
    return text + (f"  | {changed}" if changed else "")


def picture_format(path: str) -> str | None:
    """The graphviz format a picture file's extension asks for (svg, png), None for anything else: a
    ``.png`` that holds SVG text opens nowhere."""
    suffix = Path(path).suffix.lower().lstrip(".")
    return suffix if suffix in ("svg", "png") else None


def main(argv: list[str] | None = None) -> int:
    """``bt-nav replay``."""
    parser = argparse.ArgumentParser(prog="bt-nav replay", description=plain(__doc__),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("trace", help="a JSON-lines trace written by a lock-step or ROS run, or a rosbag2 bag "
                        "(directory or .mcap: --from/--to are then sim seconds)")
    parser.add_argument("--tick", type=int, help="only this tick")
    parser.add_argument("--from", dest="first", type=int, default=0, help="first tick to show")
    parser.add_argument("--to", dest="last", type=int, default=None, help="last tick to show")
    parser.add_argument("--compact", action="store_true", help="one line per tick, no tree")
    parser.add_argument("--changes-only", action="store_true", help="skip ticks whose tip and command repeat")
    parser.add_argument("--svg", metavar="FILE", help="render --tick as a picture with statuses coloured, "
                        "in the format of FILE's extension: .svg or .png (needs graphviz)")
    args = parser.parse_args(argv)
    if is_bag(args.trace):
        return replay_bag(args.trace, args.first, args.last, args.compact)
    fmt = picture_format(args.svg) if args.svg else None
    if args.svg and fmt is None:
        parser.error(f"--svg {args.svg}: unknown picture format; use a .svg or .png file name")
    try:
        header, ticks = read_trace(args.trace)
    except (OSError, ValueError) as exc:
        print(f"bt-nav replay: {exc}", file=sys.stderr)
        return 2
    if not ticks:
        print(f"bt-nav replay: {args.trace} holds no ticks", file=sys.stderr)
        return 2
    known = sorted(t["tick"] for t in ticks)
    for option, value in (("--tick", args.tick), ("--from", args.first if args.first else None),
                          ("--to", args.last)):
        if value is not None and not known[0] <= value <= known[-1]:
            print(f"bt-nav replay: {option} {value} is outside the trace's ticks {known[0]}..{known[-1]}",
                  file=sys.stderr)
            return 2
    root = load_tree(str(header.get("maneuver", "none")))
    feedback: dict[str, str] = {}
    if args.svg:
        if args.tick is None:
            parser.error("--svg needs --tick")
        line = next((t for t in ticks if t["tick"] == args.tick), None)
        if line is None:
            print(f"bt-nav replay: tick {args.tick} is not in the trace", file=sys.stderr)
            return 2
        statuses = line["statuses"]
        try:
            picture = graphviz(tree_to_dot(root, statuses, title=summary(line)), fmt)
        except GraphvizMissingError as exc:
            print(f"bt-nav replay: {exc}", file=sys.stderr)
            return 2
        Path(args.svg).write_bytes(picture)
        print(f"wrote {args.svg}")
        return 0
    previous: tuple[str, Any] | None = None
    for line in ticks:
        apply(root, line, feedback)
        if args.tick is not None and line["tick"] != args.tick:
            continue
        if line["tick"] < args.first or (args.last is not None and line["tick"] > args.last):
            continue
        key = (line["tip"], line.get("cmd"))
        if args.changes_only and key == previous and not line.get("events"):
            continue
        previous = key
        for record in line.get("events", ()):  # the leaves' announcements since the previous tick
            print(f"  [{float(record.get('t', line['time'])):8.2f}] {event_line(record)}")
        print(summary(line))
        if not args.compact:
            print(strip_ansi(py_trees.display.unicode_tree(root, show_status=True)))
    return 0
