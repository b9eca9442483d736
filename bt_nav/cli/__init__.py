"""``bt-nav <command>``: one console script for the pip path, plus the ``ros2 run bt_nav <exe>`` entry points.

Each command lives in its own module with a ``main(argv) -> int``; this file only dispatches, and
imports a command's module when it runs, so ``bt-nav dump-tree`` does not pay for rclpy.
"""

from __future__ import annotations

import importlib
import os
import sys

#: command -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "executive": ("bt_nav.ros.executive", "run the mission executive node (ros2 run bt_nav executive)"),
    "sim": ("bt_nav.ros.nodes.simulator", "run the 2D TurtleBot3 simulator node"),
    "referee": ("bt_nav.ros.nodes.referee", "run the homework referee node"),
    "checkoff": ("bt_nav.cli.checkoff", "the lab's check-off: the judge node over DDS (calls toggle_navigation), or "
                 "a real robot's bag (--bag)"),
    "rehearse": ("bt_nav.cli.rehearse", "lab day rehearsed here: a simulated TurtleBot3 on a domain of its own and "
                 "checkoff --robot beside it"),
    "sim-run": ("bt_nav.cli.sim_run", "simulator + executive (+ referee) in one go, without ros2 launch"),
    "demo": ("bt_nav.cli.demo", "the homework mission (or --profile lab: the lab's check-off) over DDS in sim time"),
    "lockstep": ("bt_nav.cli.lockstep", "run one mission in lock-step (no DDS), deterministic per seed"),
    "grade": ("bt_nav.cli.grade", "grade worlds x maneuvers x seeds in lock-step, in parallel"),
    "rules": ("bt_nav.cli.rules", "print what a graded node must do: topics, services, parameters, each maneuver's "
              "trigger and tolerances, the schedule"),
    "check-launch": ("bt_nav.cli.check_launch", "check a launch file or hand-in folder for the lab's Task 3, "
                     "evaluated as ros2 launch would run it"),
    "dump-tree": ("bt_nav.cli.dump_tree", "print or render the static mission tree"),
    "replay": ("bt_nav.cli.replay", "print a recorded tick trace tick by tick, or render one tick"),
    "watch": ("bt_nav.cli.watch", "print the executive's ~/tree snapshots as they change"),
    "record": ("bt_nav.cli.record", "record the live graph into a rosbag2 (MCAP) bag"),
    "video": ("bt_nav.cli.video", "film a recorded mission (bag) as an H.264 MP4"),
    "view": ("bt_nav.cli.view", "serve the live (or recorded) mission in a browser on 127.0.0.1"),
    "arm": ("bt_nav.cli.arm", "arm (or --off: disarm) a running executive through its SetBool service"),
}


def plain(text: str) -> str:
    """Docstring text as plain ``--help`` text: reStructuredText roles and literals (``:func:`x```,
    double backquotes) reduced to their words, so help reads as prose in a terminal."""
    import re

    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"\1", text)
    return text.replace("``", "")


def usage() -> str:
    """The command list."""
    width = max(len(name) for name in COMMANDS)
    lines = ["usage: bt-nav <command> [options]   (bt-nav <command> --help for its options)", "", "commands:"]
    lines += [f"  {name:<{width}}  {help_}" for name, (_, help_) in COMMANDS.items()]
    return "\n".join(lines)


def run(command: str, argv: list[str]) -> int:
    """Import the command's module and run its ``main``.

    Every command gets the same two edges: a launcher's watchdog pipe is watched (a node started by
    ``bt-nav demo``/``sim-run`` stops when its launcher dies, see :mod:`bt_nav.ros.supervise`), and
    output piped into ``head`` that closes early ends the command quietly (exit 0 on EPIPE: the
    reader asked for no more) instead of with a BrokenPipeError traceback.
    """
    from bt_nav.ros.supervise import watch_parent_pipe

    watch_parent_pipe()
    module_name, _ = COMMANDS[command]
    try:
        module = importlib.import_module(module_name)
        code = int(module.main(argv) or 0)
        sys.stdout.flush()
    except BrokenPipeError:
        _silence_stdout()
        return 0
    return code


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush does not raise again (Python docs,
    "Note on SIGPIPE")."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``bt-nav``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help", "help"):
        print(usage())
        return 0
    command, rest = argv[0], argv[1:]
    if command not in COMMANDS:
        print(f"bt-nav: unknown command {command!r}\n\n{usage()}", file=sys.stderr)
        return 2
    return run(command, rest)


def _entry(command: str) -> int:
    return run(command, sys.argv[1:])


def executive_main() -> int:
    """``ros2 run bt_nav executive``."""
    return _entry("executive")


def sim_main() -> int:
    """``ros2 run bt_nav sim``."""
    return _entry("sim")


def referee_main() -> int:
    """``ros2 run bt_nav referee``."""
    return _entry("referee")


def checkoff_main() -> int:
    """``ros2 run bt_nav checkoff``."""
    return _entry("checkoff")


def dump_tree_main() -> int:
    """``ros2 run bt_nav dump_tree``."""
    return _entry("dump-tree")


def watch_main() -> int:
    """``ros2 run bt_nav watch``."""
    return _entry("watch")

