"""``bt-nav dump-tree``: the static mission tree as text, dot, svg, png, xml or json.

dot text is generated here (no graphviz needed); svg and png pipe it through graphviz's ``dot``
binary (Debian package ``graphviz``) and say so clearly when it is missing. The same dot generator
colours nodes by status for ``bt-nav replay --svg``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bt_nav.cli import plain
from bt_nav.media.treedot import FORMATS, GraphvizMissingError, render
from bt_nav.mission.maneuver_spec import choices_text
from bt_nav.mission.params import normalise_maneuver


def main(argv: list[str] | None = None) -> int:
    """``bt-nav dump-tree``."""
    parser = argparse.ArgumentParser(prog="bt-nav dump-tree", description=plain(__doc__),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maneuver", default="none", help=f"{choices_text()} (or their names)")
    parser.add_argument("--format", default="unicode", choices=FORMATS,
                        help="text (ascii, unicode), graphviz (dot, svg, png), the tree file (xml), json, or the "
                             "Groot2 node model; default unicode")
    parser.add_argument("-o", "--output", help="write to this file instead of stdout")
    args = parser.parse_args(argv)
    try:
        normalise_maneuver(args.maneuver)
        out = render(args.maneuver, args.format)
    except (ValueError, GraphvizMissingError) as exc:
        print(f"bt-nav dump-tree: {exc}", file=sys.stderr)
        return 2
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_bytes(out if isinstance(out, bytes) else out.encode())
    elif isinstance(out, bytes):
        sys.stdout.buffer.write(out)
    else:
        sys.stdout.write(out)
    return 0
