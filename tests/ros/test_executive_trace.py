"""``trace_path``: the executive writes the lock-step runner's JSONL trace, and ``bt-nav replay`` reads it."""

from __future__ import annotations

import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from ros_harness import REPO, Harness

from bt_nav.mission.trace import read_trace
from bt_nav.testing import front_scan, laserscan_msg


def test_trace_path_writes_a_trace_that_replay_reads(executive: Callable[..., Harness], tmp_path: Path) -> None:
    trace = tmp_path / "runs" / "executive.jsonl"  # a folder that does not exist yet
    h = executive("-p", f"trace_path:={trace}", "-p", "maneuver:=A", "-p", "trigger_at_arming:=true",
                  "-p", "random_seed:=7")
    assert h.arm(True).success
    driving = h.ticks(3, scan=laserscan_msg(front_scan()))
    turning = h.ticks(3, scan=laserscan_msg(front_scan(front=0.4)))
    assert driving[-1].linear > 0.0 and turning[-1].linear == 0.0 and turning[-1].angular != 0.0
    h.process.proc.send_signal(signal.SIGINT)
    assert h.process.wait_exit(10.0, step=h.spin) == 0

    header, ticks = read_trace(trace)
    assert header["maneuver"] == "A" and header["params"]["trace_path"] == str(trace)
    assert len(ticks) >= 6, "one line per tick"
    assert [line["tick"] for line in ticks] == list(range(1, len(ticks) + 1))
    commands = [(line["cmd"]["linear"], line["cmd"]["angular"]) for line in ticks]
    for published in (driving[-1], turning[-1]):
        assert (round(published.linear, 6), round(published.angular, 6)) in commands, \
            "the trace holds the commands that were published (rounded to 6 decimals)"
    assert any("Randomizer" in line["tip"] for line in ticks), "the maneuver's ticks are in the trace"

    replay = subprocess.run([sys.executable, "-m", "bt_nav.cli", "replay", str(trace), "--compact"], cwd=REPO,
                            capture_output=True, text=True, timeout=60)
    assert replay.returncode == 0, replay.stderr
    shown = replay.stdout.splitlines()
    events = sum(len(line.get("events", [])) for line in ticks)  # each announcement printed before its tick
    assert events >= 1, "the Randomizer announced itself in the trace"
    assert len(shown) == len(ticks) + events and "Randomizer" in replay.stdout
    assert sum(1 for text in shown if text.startswith("tick ")) == len(ticks)


def test_an_unwritable_trace_path_refuses_to_start(start_executive: Callable[..., object], tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    process = start_executive("-p", f"trace_path:={blocker / 'trace.jsonl'}", sim_time=False)
    assert process.wait_exit(20.0) == 2
    assert any("refusing to start" in line for line in process.lines), process.tail()
