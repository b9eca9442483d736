"""``bt-nav rules``: what a graded node must do (topics, services, parameters, each maneuver's trigger and
tolerances, the schedule), printed as Markdown from the judges' own rules (:mod:`bt_nav.grading.rules`): the page
the docs build as reference/node-rules and every ``bt-nav grade --exe`` writes as ``rules.md``."""

from __future__ import annotations

import argparse

from bt_nav.cli import plain


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="bt-nav rules", description=plain(__doc__))
    parser.add_argument("--profile", choices=("lab", "homework"), default=None,
                        help="one assignment: the lab's check-off or the homework's evaluation (default both)")
    parser.add_argument("--maneuvers", default=None, metavar="A,B,C",
                        help="the lab's maneuvers to list (default all three)")
    parser.add_argument("--node-param", action="append", default=[], metavar="NAME=VALUE",
                        help="as bt-nav grade --node-param gives it to the node (repeatable), e.g. "
                        "safety_distance=0.6: the lab's judge then triggers at it too")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Print the page; exit 2 for options that do not fit."""
    from bt_nav.grading.rules import GradeSetup, rules_markdown
    from bt_nav.mission.params import normalise_maneuver, parse_assignments

    parser = _parser()
    args = parser.parse_args(argv)
    try:
        maneuvers = [normalise_maneuver(m.strip()) for m in (args.maneuvers or "").split(",") if m.strip()]
        setup = GradeSetup(node_params=tuple(parse_assignments(args.node_param).items()))
        page = rules_markdown(args.profile, maneuvers=maneuvers or None, setup=setup)
    except ValueError as exc:
        parser.error(str(exc))
    print(page, end="")
    return 0
