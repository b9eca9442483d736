"""The hand-in's terminal text (``bt-nav demo --exe``): a command shown as one would type it, the judge's report said
on the sim clock, lines that came late over DDS printed in time order, and the film's console script and its
per-frame record. No DDS: the clock is a stand-in."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from bt_nav.grading.exe.run import exe_ros_args
from bt_nav.grading.handin_film import StandIn, launch_stand_in, terminal_head
from bt_nav.media.console import CONSOLE_ROWS, ConsoleLog, ConsoleScript, read_console_log
from bt_nav.mission.snapshot import call_event, snapshot_json
from bt_nav.run.terminal import NodeTerminal, on_sim_clock, shell_text

LAUNCHES = Path(__file__).resolve().parents[1] / "fixtures" / "launch"


def test_a_command_is_shown_as_typed_and_splits_back_to_what_ran() -> None:
    argv = ["python3", "my node.py", *exe_ros_args("C", "lab", (("safety_distance", 0.5),)),
            "-p", 'name:="on"', "-p", 'words:="two words"']
    text = shell_text(argv)
    assert "-p maneuver:=C" in text and '"C"' not in text
    assert "-p safety_distance:=0.5" in text and "-p use_sim_time:=true" in text
    assert "'my node.py'" in text  # quoted only where a shell needs it
    assert "name:=\"on\"" in shlex.split(text)  # a bare on would be a YAML boolean: kept as the string it was
    assert shlex.split(text)[-1] == 'words:="two words"'
    assert [w.replace('maneuver:="C"', "maneuver:=C") for w in argv] == shlex.split(text)


@pytest.mark.parametrize(("line", "said"), [
    ("toggle_navigation answered (true at t=5.00 s, false at t=65.02 s): PASSED",
     "toggle_navigation answered (true at sim 5.76 s, false at sim 65.78 s): PASSED"),
    ("static before activation (peak 0.000 m/s, 0.000 rad/s over t=0.00-5.00 s): PASSED",
     "static before activation (peak 0.000 m/s, 0.000 rad/s over sim 0.76-5.76 s): PASSED"),
    ("maneuver 1 (C at t=18.29 s (sim 19.05 s): front 0.30 m < 0.55 m): PASSED",
     "maneuver 1 (C at sim 19.05 s: front 0.30 m < 0.55 m): PASSED"),
    ("no collision (1 collision, t=3.4 s (0.10, 0.20)): FAILED",
     "no collision (1 collision, sim 4.2 s (0.10, 0.20)): FAILED"),
    ("overall: PASSED", "overall: PASSED"),
])
def test_the_judges_report_is_said_on_the_sim_clock(line: str, said: str) -> None:
    assert on_sim_clock(line, 0.76) == said


class _Clock:
    """Sim time as the test sets it, whatever the wall time (a SimClock's ``sim_at``)."""

    def __init__(self) -> None:
        self.sim = 0.0

    def sim_at(self, wall_ns: int) -> int:
        return round(self.sim * 1e9)


def test_a_late_call_is_printed_before_the_later_node_lines() -> None:
    """The node's pipe is quicker than DDS: a call at 5.5 s read after a node line at 15.9 s still comes first."""
    shown: list[str] = []
    clock = _Clock()
    terminal = NodeTerminal(clock, out=shown.append, hold=2.0)
    terminal._listening_since -= 60.0  # the judge's events are taken as found (no DDS here)
    terminal.sink("node", "[INFO] [1712345678.000000000] [reactive_navigator]: started")
    clock.sim = 15.9
    terminal.sink("node", "[INFO] [1712345678.500000000] [reactive_navigator]: Retreat: 180 deg spin done")
    terminal.on_judge_event(snapshot_json(call_event("call", 5.5, "toggle_navigation", True)))
    clock.sim = 18.0
    terminal.release()
    terminal.close()
    assert [line[:15] for line in shown] == ["[sim   0.00 s] ", "[sim   5.50 s] ", "[sim   5.50 s] ",
                                             "[sim  15.90 s] "]
    assert [e["kind"] for e in terminal.transcript()] == ["node", "call", "call", "node"]


def test_held_lines_wait_for_the_clock() -> None:
    shown: list[str] = []
    clock = _Clock()
    terminal = NodeTerminal(clock, out=shown.append, hold=2.0)
    terminal._listening_since -= 60.0
    clock.sim = 10.0
    terminal.sink("node", "[INFO] [1712345678.000000000] [n]: a")
    assert shown == []  # held: something at 8-10 s may still come over DDS
    clock.sim = 12.5
    terminal.release()
    assert shown == ["[sim  10.00 s] [INFO] [n]: a"]


def test_the_console_script_pins_its_head_and_scrolls_in_time_order() -> None:
    head = ("$ python3 node.py", "# stands in for: ros2 launch pkg turtlebot_bringup.launch.py")
    lines = tuple((float(t), f"line {t}") for t in (9, 1, 5, 3, 7, 2, 4, 6, 8, 10))  # not in order
    script = ConsoleScript(head, lines)
    assert script.rows(0.5) == list(head)
    assert script.rows(2.0) == [*head, "[sim   1.00 s] line 1", "[sim   2.00 s] line 2"]
    rows = script.rows(100.0)
    assert len(rows) == CONSOLE_ROWS and rows[:2] == list(head)
    assert rows[2:] == [f"[sim {t:6.2f} s] line {t}" for t in range(4, 11)]


def test_the_console_log_reads_back_per_frame(tmp_path: Path) -> None:
    log = ConsoleLog(tmp_path / "v.mp4", "on the sim clock")
    log.add(0.0, ["a", "b"])
    log.add(0.1, ["a", "b", "c"])
    log.add(0.2, ["b", "c"])
    path = log.write(tmp_path / "v.console.json")
    assert read_console_log(path) == [(0.0, ["a", "b"]), (0.1, ["a", "b", "c"]), (0.2, ["b", "c"])]


def test_the_stand_in_line_names_the_launch_files_package() -> None:
    launched = launch_stand_in(LAUNCHES / "sheet.launch.py", None)
    assert launched.package == "my_package" and dict(launched.params) == {"safety_distance": 0.5}
    assert launched.line() == "# stands in for: ros2 launch my_package sheet.launch.py"
    missing = launch_stand_in(None, Path("reactive_navigator.py"))
    assert missing.params == () and "no launch file beside reactive_navigator.py" in missing.line()
    assert terminal_head(["python3", "n.py"], None) == ("$ python3 n.py",)
    assert terminal_head(["python3", "n.py"], StandIn(package="p"))[1].startswith("# stands in for: ros2 launch p ")


def test_the_reports_command_row_is_typed_as_a_shell_takes_it(tmp_path: Path) -> None:
    from bt_nav.grading.exe.run import ExeSettings
    from bt_nav.grading.html import report_html
    from bt_nav.grading.report import summarize_exe

    settings = ExeSettings("python3 n.py", "lab", tmp_path, maneuvers=True, node_params=(("safety_distance", 0.6),))
    page = report_html([], summarize_exe([]), settings, {}, [])
    row = next(line for line in page.splitlines() if line.startswith("<tr><th>command</th>"))
    assert "-p maneuver:=X -p safety_distance:=0.6</code>" in row and "&quot;" not in row, row
