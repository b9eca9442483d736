"""The hand-in of ``bt-nav demo --exe``: the terminal a student films, and the film of it.

The lab sheet's hand-in is a video of "the terminal output of starting the launch file and calling the service" and
of the robot reacting. bt_nav runs the student's node itself (no ``ros2`` CLI, no ``launch`` package), so the
terminal says honestly what ran and what it stands in for (:func:`terminal_head`):

- ``$ python3 reactive_navigator.py --ros-args ...``: the command that ran, as one would type it
  (:func:`bt_nav.run.terminal.shell_text`), with the parameters the launch file gives the node;
- ``# stands in for: ros2 launch my_package turtlebot_bringup.launch.py``: the launch it replaces, its package from
  the launch file beside the node (or ``--launch FILE``; :func:`launch_stand_in`, the one place this reads a launch
  file);

then the node's own log lines (its ``/rosout``, from the bag, its start-up line too) and the judge's service calls
as ``ros2 service call`` prints them (from the terminal's transcript, ``terminal.json``), in time order on the sim
clock. Not the simulator's or the judge's own lines: they are in the run's log files. :func:`film_handin` films the
bag with that console (:class:`bt_nav.media.console.ConsoleScript`) and writes, beside the video, the console rows
of every frame (``<video>.console.json``).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_nav.grading.launch import LAUNCH_NAME
from bt_nav.media.console import ConsoleScript, node_lines, ros_log_line

#: The terminal's transcript in the run directory (:meth:`bt_nav.run.terminal.NodeTerminal.transcript`).
TRANSCRIPT = "terminal.json"
#: The package a stand-in line names when the launch file does not say (or there is none).
UNKNOWN_PACKAGE = "<your_package>"


@dataclass(frozen=True)
class StandIn:
    """The ``ros2 launch`` a run stands in for: the launch file's name, its node's package (None: not known), the
    parameters it gives the node (name, value), and a note when there is no launch file to read."""

    launch: str = LAUNCH_NAME
    package: str | None = None
    params: tuple[tuple[str, Any], ...] = ()
    note: str = ""

    def line(self) -> str:
        """``# stands in for: ros2 launch my_package turtlebot_bringup.launch.py`` (a comment: it did not run)."""
        tail = f" ({self.note})" if self.note else ""
        return f"# stands in for: ros2 launch {self.package or UNKNOWN_PACKAGE} {self.launch}{tail}"


def launch_stand_in(launch: Path | None, node: Path | None) -> StandIn:
    """What the launch file ``launch`` (None: none found) says of the node file ``node``: its package and the
    parameters the node gets, through :func:`bt_nav.grading.launch.check.check_launch`.

    The one use of the launch-file reader here (adapt it when that module offers the package and parameters
    directly): the package is the one its passed "starts the node" check names, and ``safety_distance`` is given the
    sheet's default when its "passes" check passed (the check passes when the node would get that value).
    """
    from bt_nav.grading.launch import ARGUMENT, DEFAULT, PASSES, STARTS, check_launch

    if launch is None:
        where = f"beside {node.name}" if node is not None else "for this command"
        return StandIn(note=f"no launch file {where}; --launch FILE names one")
    checks = {c.name: c for c in check_launch(launch, node).checks}
    starts, passes = checks.get(STARTS), checks.get(PASSES)
    found = re.search(r"package='([^']+)'", starts.reason) if starts and starts.passed and starts.checked else None
    params = ((ARGUMENT, DEFAULT),) if passes is not None and passes.passed and passes.checked else ()
    return StandIn(launch.name, found.group(1) if found else None, params)


def launch_beside(node: Path | None) -> Path | None:
    """The launch file beside the node file ``node``: ``turtlebot_bringup.launch.py`` in its folder, or in a
    ``launch/`` folder of it or of its parent (a ROS package's layout), else the one ``*.launch.py`` in its folder."""
    if node is None:
        return None
    folder = node.resolve().parent
    for place in (folder, folder / "launch", folder.parent / "launch"):
        if (place / LAUNCH_NAME).is_file():
            return place / LAUNCH_NAME
    others = sorted(folder.glob("*.launch.py"))
    return others[0] if len(others) == 1 else None


def terminal_head(argv: list[str] | tuple[str, ...], stand_in: StandIn | None) -> tuple[str, ...]:
    """The terminal's first lines: the command that ran (``$ ...``) and the launch it stands in for (none without
    ``stand_in``: the homework has no launch file)."""
    from bt_nav.run.terminal import shell_text

    command = f"$ {shell_text(argv)}"
    return (command,) if stand_in is None else (command, stand_in.line())


def write_transcript(run_dir: Path, head: tuple[str, ...], lines: list[dict[str, Any]]) -> Path:
    """The terminal's transcript (``terminal.json``): its head and every line shown (``{"t", "text", "kind"}``)."""
    path = run_dir / TRANSCRIPT
    path.write_text(json.dumps({"time_base": "sim clock", "head": list(head), "lines": lines}, indent=1) + "\n",
                    encoding="utf-8")
    return path


def handin_script(record: Any, transcript: dict[str, Any]) -> ConsoleScript:
    """The console of the hand-in film: the transcript's head, then the node's /rosout lines (the bag's events of
    nodes that are not bt_nav's) and the transcript's service-call lines, in time order on the sim clock."""
    node = [(t, ros_log_line(text)) for t, text in node_lines(record.events)]
    calls = [(float(line["t"]), str(line["text"])) for line in transcript.get("lines", [])
             if line.get("kind") == "call" and line.get("t") is not None]
    return ConsoleScript(tuple(transcript.get("head", ())), tuple(node + calls))


def film_handin(run_dir: Path, bag: Path, video: str | Path, fps: float = 10.0) -> Any:
    """Film ``bag`` with the hand-in console of ``run_dir``'s transcript into ``video``, the console rows of every
    frame beside it (:func:`bt_nav.media.console.console_log_path`); the :class:`bt_nav.media.video.VideoStats`."""
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.console import console_log_path
    from bt_nav.media.video import world_of, write_video

    record = read_bag(bag)
    path = run_dir / TRANSCRIPT
    transcript = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
    return write_video(record, video, fps, world_of(record), script=handin_script(record, transcript),
                       console_log=console_log_path(video))
