"""The bag of one ``--exe`` run: ``bt-nav record`` as one more child of the run's :class:`Launcher`.

Why a child of the run's launcher: it lives in the run's ROS domain, its output goes to ``record.log`` like every
other process's, and it is stopped last (the launcher stops in reverse start order and it starts first), so the
bag holds the whole run up to the judge's verdict and the shutdown; a recorder that SIGINT closes writes
``metadata.yaml``, and one that had to be killed still leaves a readable ``.mcap`` up to its last second.

Why the judge waits: the judge's schedule begins at t0 (the node's service found, ``/clock`` running) and activates
the robot seconds of sim time later, but a recorder started with the simulator has been seen to get its first
message up to 3 s of wall time (15 s of sim time at 5x) after the simulator's start (DDS discovery on a loaded
machine). So the run starts the judge only once the recorder printed ``first /ground_truth_odom`` (at most
:data:`READY_TIMEOUT` s, and not after the node exited): every bag then holds the run from before t0, at the cost
of the judge's own start, which no longer overlaps the simulator's. The pictures and videos are drawn from the
bags after the grid, in the report step (:mod:`bt_nav.run.exemedia`), so they cost the timed runs nothing.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_nav.media.bag import CMD, COLLISIONS, ROSOUT, SCAN, TREE, TRUTH

#: The bag's directory name inside the run directory.
BAG = "bag"
#: Wall seconds the run waits for each of the recorder's lines (listening, ground truth) before going on anyway.
READY_TIMEOUT = 10.0
#: What a run's bag records: what the pictures and videos draw (ground truth, scans, commands, collisions, the judge's
#: log lines as events, a bt_nav executive's tree). Not ``/clock`` (every message is stamped with its sim time
#: anyway, and at 5x real time it is the busiest topic) nor ``/odom`` (what the node sees; the pictures use ground
#: truth): fewer messages, less of the recorder's CPU taken from the run.
RUN_TOPICS = (SCAN, TRUTH, CMD, COLLISIONS, ROSOUT, TREE)
#: What ``--record`` accepts: every run's bag kept, only the failed runs' (the passed runs' deleted once their
#: trajectory picture is drawn), or no bag at all (a benchmark; no pictures, no videos).
RECORD_MODES = ("on", "failures", "off")


@dataclass(frozen=True)
class RecordSpec:
    """``bt-nav record BAG`` as a :class:`bt_nav.ros.supervise.Startable` (named ``record``).

    The world and seed are given (``--no-ask``): the bag's ``/bt_nav/mission`` then names the run's world without
    a parameter request to the simulator, which may not be up yet.
    """

    bag: Path
    world: str
    seed: int
    executable: str = "record"

    def command(self, python: str | None = None) -> list[str]:
        """``python -m bt_nav.cli record BAG --world W --seed S --no-ask --topics ...`` (:data:`RUN_TOPICS`)."""
        return [python or sys.executable, "-m", "bt_nav.cli", "record", str(self.bag), "--world", self.world,
                "--seed", str(self.seed), "--no-ask", "--topics", *RUN_TOPICS]


class RecorderWatch:
    """The recorder's line sink: every line to the run's log sink; events once it listens (``recording ...``) and
    once the simulator's ground truth reaches it (``first /ground_truth_odom ...``)."""

    def __init__(self, sink: Callable[[str, str], None]) -> None:
        self.forward = sink
        self.listening = threading.Event()
        self.covering = threading.Event()
        self.child: Any = None  # the recorder's Child, once started

    def sink(self, name: str, line: str) -> None:
        """Launcher sink of the recorder process."""
        if line.startswith("recording "):
            self.listening.set()
        elif line.startswith(f"first {TRUTH} "):
            self.covering.set()
        self.forward(name, line)

    def wait(self, event: threading.Event, timeout: float = READY_TIMEOUT,
             alive: Callable[[], bool] = lambda: True) -> bool:
        """Wait for ``event`` (False: not within ``timeout``, the recorder exited, or ``alive()`` turned False: the
        run goes on, with a bag that may miss its first seconds, rather than fail for it)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if event.wait(0.05):
                return True
            if (self.child is not None and self.child.poll() is not None) or not alive():
                break
        return event.is_set()

    def before_judge(self, node: Any) -> bool:
        """Wait until the ground truth reaches the bag (see the module docstring); False: it did not."""
        return self.wait(self.covering, alive=lambda: node.poll() is None)


def start_recorder(launcher: Any, sink: Callable[[str, str], None], run_dir: Path, world: str,
                   seed: int) -> RecorderWatch:
    """Start the run's recorder (``run_dir/bag``) on ``launcher``; wait on the returned watch before the judge."""
    watch = RecorderWatch(sink)
    watch.child = launcher.start(RecordSpec(run_dir / BAG, world, seed), sink=watch.sink)
    return watch


def bag_row(run_dir: Path, watch: RecorderWatch | None) -> dict[str, Any]:
    """What the run's row says of its bag: its directory (relative to the run directory) and size, or none."""
    if watch is None:
        return {"bag": None}
    bag = run_dir / BAG
    size = sum(p.stat().st_size for p in bag.rglob("*") if p.is_file()) if bag.is_dir() else 0
    return {"bag": BAG if size else None, "bag_bytes": size, "bag_from_start": watch.covering.is_set()}
