"""The lab's terminal (:mod:`bt_nav.run.terminal`) shows lines from the nodes' structured events, never from their
log lines: the judge's calls and replies, the executive's announced lines and its start-up, each at its source's
sim time."""

from __future__ import annotations

from pathlib import Path

from bt_nav.mission.snapshot import call_event, event, snapshot_json
from bt_nav.run.rundir import Logs
from bt_nav.run.terminal import LabTerminal, NodeTerminal
from bt_nav.testing import TickHarness

LAUNCH = "[INFO] [bt_nav_executive]: up: params file config/lab.yaml, maneuver C Smart Pivot"


def _terminal(tmp_path: Path) -> tuple[LabTerminal, list[str]]:
    shown: list[str] = []
    return LabTerminal(Logs(tmp_path, echo_logs=False), LAUNCH, out=shown.append), shown


def test_the_lines_come_from_the_events_at_their_sim_time(tmp_path: Path) -> None:
    terminal, shown = _terminal(tmp_path)
    tree = snapshot_json(TickHarness("C").core.snapshot() | {"t": 2.5})
    terminal.on_tree(tree)
    terminal.on_tree(tree)  # the launch line once
    terminal.on_judge_event(snapshot_json(call_event("call", 9.0, "toggle_navigation", True)))
    terminal.on_judge_event(snapshot_json(call_event("reply", 9.01, "toggle_navigation", True, answered=True,
                                                     success=True, message="armed at 9.01 s")))
    terminal.on_judge_event(snapshot_json(call_event("unanswered", 30.0, "toggle_navigation", False, attempts=4)))
    terminal.on_announcement(snapshot_json(event("maneuver", 12.345, "SmartPivot", level="INFO",
                                                 text="SmartPivot: front 0.29 m: turning left 90 deg")))
    terminal.on_announcement(snapshot_json(event("brake", 14.0, "AEB", level="WARN",
                                                 text="AEB: path blocked 0.08 m ahead: emergency stop")))
    assert shown == [
        f"[sim   2.50 s] {LAUNCH}",
        '[sim   9.00 s] $ ros2 service call /toggle_navigation std_srvs/srv/SetBool "{data: true}"',
        "[sim   9.00 s] requester: making request: std_srvs.srv.SetBool_Request(data=True)",
        "[sim   9.01 s] response:",
        "[sim   9.01 s] std_srvs.srv.SetBool_Response(success=True, message='armed at 9.01 s')",
        "[sim  12.35 s] [INFO] [bt_nav_executive]: SmartPivot: front 0.29 m: turning left 90 deg",
        "[sim  14.00 s] [WARN] [bt_nav_executive]: AEB: path blocked 0.08 m ahead: emergency stop",
    ]


def test_log_lines_are_not_read(tmp_path: Path) -> None:
    """The judge's and the executive's log lines go to the log files only: the terminal shows nothing of them."""
    terminal, shown = _terminal(tmp_path)
    terminal.sink("sim", "@1712345678123456789 [INFO] [bt_nav_checkoff]: sim 9.00 s (t0 + 5.00 s): "
                         "toggle_navigation(true) sent")
    terminal.sink("executive", "@1712345678123456789 [INFO] [bt_nav_executive]: SmartPivot: front 0.29 m: turning "
                               "left 90 deg")
    terminal.sink("executive", "@1712345678123456789 [INFO] [bt_nav_executive]: up: params file x")
    terminal.logs.close()
    assert shown == [] and "toggle_navigation(true) sent" in (tmp_path / "sim.log").read_text()


def test_a_foreign_nodes_terminal_shows_the_judges_calls_from_its_events() -> None:
    shown: list[str] = []
    terminal = NodeTerminal(clock=None, out=shown.append)
    terminal.sink("sim", "[INFO] [1712345678.1] [bt_nav_referee]: sim 9.00 s: activate(true) sent")
    terminal.on_judge_event(snapshot_json(call_event("call", 9.0, "activate", True)))
    assert shown == ['[sim   9.00 s] $ ros2 service call /activate std_srvs/srv/SetBool "{data: true}"',
                     "[sim   9.00 s] requester: making request: std_srvs.srv.SetBool_Request(data=True)"]
