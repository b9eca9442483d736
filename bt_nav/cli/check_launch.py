"""``bt-nav check-launch FILE|DIR [--node NODE_FILE]``: the lab sheet's launch-file checks (Task 3: it starts the
node, declares ``safety_distance`` with the default 0.5, passes it to the node) of one launch file or hand-in folder,
printed alone. The file is evaluated as ``ros2 launch`` would run it (:mod:`bt_nav.grading.launch.check`: stand-ins of
launch and launch_ros in a time-limited child, with the defaults and with ``safety_distance:=0.7``), the same checks
``bt-nav grade --class`` gives each hand-in. Exit 0 every check passed, 1 one failed, 2 one could not be checked
(a TA should look)."""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_nav.cli import plain


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="bt-nav check-launch", description=plain(__doc__))
    parser.add_argument("target", metavar="FILE|DIR",
                        help="a launch file (its folder is the hand-in), or a hand-in folder (its launch file and node "
                        "found as bt-nav grade --class finds them)")
    parser.add_argument("--node", default=None, metavar="NODE_FILE",
                        help="the student's node file, whose name the launch file's Node must run (default: the "
                        "folder's reactive_navigator.py or its one rclpy node; the sheet's name is always accepted)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Print the checks; the exit code says the verdict (module docstring)."""
    from bt_nav.grading.launch import check_launch, exit_code, launch_target

    parser = _parser()
    args = parser.parse_args(argv)
    try:
        launch, node, folder = launch_target(Path(args.target), Path(args.node) if args.node else None)
    except ValueError as exc:
        parser.error(str(exc))
    report = check_launch(launch, node, folder)
    shown = launch.relative_to(folder) if launch is not None and launch.is_relative_to(folder) else launch
    print(f"{shown or args.target} (node: {node.name if node else 'none found; the sheet names reactive_navigator'})")
    for line in [*report.lines(), *(f"note: {n}" for n in report.notes)]:
        print(f"  {line}")
    return exit_code(report)
