"""The bag of one ``--exe`` run: ``bt-nav record`` as one more child of the run's :class:`Launcher`.

Why a child of the run's launcher: it lives in the run's ROS domain, its output goes to ``record.log`` like every
other process's, and the launcher stops it with the rest (and kills it, should the grid die). It gets its SIGINT
(:meth:`RecorderWatch.stop`) once the graded node has stopped, as the simulator and the judge get theirs: the bag
then holds what the node sent on its way out (bt_nav's executive: its three last zero twists; stopped before the node,
the recorder missed them). A recorder that SIGINT closes writes ``metadata.yaml``, one that had to be killed still
leaves a readable ``.mcap`` up to its last second.

Why it starts with the others, not before the simulator: the judge's schedule begins at t0 (the node's service
found, ``/clock`` running) and activates the robot seconds of sim time later (the homework: 5 s, one wall second at
5x), so the recorder must have found the simulator by then, and it looks for its topics every half second. Holding
the simulator until the recorder printed ``recording ...`` made every run's start-up the recorder's plus the
simulator's, and in a grid the runs start in bursts of two per core, where a Python process takes a wall second or
two to come up. Started together (measured over 48 runs, four at once on two cores), the bags began 0-2.1 sim s
after t0, always seconds before the first activation, and an 8-run grid went from 14.0 to 14.6 runs a minute,
back to back. When the recorder's first ground truth arrived (its note in the bag,
:func:`bt_nav.run.bagrecorder.first_messages`) goes into the row (``bag_truth_from``, ``bag_after_t0_s``), so a bag
that started late says so. With Fast DDS's default profile two participants that miss
each other's start-up announcements (seen on a loaded 2-core machine) meet only at the next periodic one, 3 s (15 s
of sim time) later: every process bt_nav starts announces itself every 0.25 s instead
(:data:`bt_nav.ros.supervise.DISCOVERY_PROFILE`).

The recorder spins rclpy's events executor (half the CPU of the default one) and records only what the report draws
(:data:`RUN_TOPICS`). The pictures and videos are drawn from the bags after the grid, in the report step
(:mod:`bt_nav.grading.media`), so they cost the timed runs nothing.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bt_nav.media.bag import CMD, COLLISIONS, ROSOUT, SCAN, TREE, TRUTH, WALKERS
from bt_nav.run.bagrecorder import FIRST_MESSAGES, first_messages

#: The bag's directory name inside the run directory.
BAG = "bag"
#: Wall seconds a recorder gets to close its bag after SIGINT before it is killed. It takes a fifth of a second; the
#: ROS teardown of its EventsExecutor hung once in ~16 graded runs on a loaded machine, spinning a core until killed,
#: and the launcher's own grace is 5 s (7 s to SIGKILL): CPU the other runs' nodes need.
RECORDER_GRACE = 1.5
#: What a run's bag records: what the pictures and videos draw (ground truth, scans, commands, collisions, the judge's
#: log lines as events, a bt_nav executive's tree). Not ``/clock`` (every message is stamped with its sim time
#: anyway, and at 5x real time it is the busiest topic) nor ``/odom`` (what the node sees; the pictures use ground
#: truth): fewer messages, less of the recorder's CPU taken from the run.
RUN_TOPICS = (SCAN, TRUTH, CMD, COLLISIONS, ROSOUT, TREE, WALKERS)
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
    profile: str = "homework"
    executable: str = "record"

    def command(self, python: str | None = None) -> list[str]:
        """``python -m bt_nav.cli record BAG --world W --seed S --no-ask --events-executor --topics ...``
        (:data:`RUN_TOPICS`); the discovery profile comes with the run launcher's environment
        (:func:`bt_nav.ros.supervise.child_env`), as for every process of the run."""
        return [python or sys.executable, "-m", "bt_nav.cli", "record",
                str(self.bag), "--world", self.world, "--seed", str(self.seed), "--profile", self.profile, "--no-ask",
                "--events-executor",
                "--topics", *RUN_TOPICS]


class RecorderWatch:
    """The run's recorder process: stopped when the graded node has stopped (:meth:`stop`)."""

    def __init__(self) -> None:
        self.child: Any = None  # the recorder's Child, once started

    def stop(self, grace: float = RECORDER_GRACE) -> None:
        """SIGINT the recorder now (it closes its bag); one still running ``grace`` s later is killed (its ``.mcap`` is
        readable up to its last flush), sooner than the launcher's own ladder would."""
        child = self.child
        if child is None or child.poll() is not None:
            return
        child.signal_group(signal.SIGINT)

        def kill_late() -> None:
            try:
                child.popen.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                child.signal_group(signal.SIGKILL)

        threading.Thread(target=kill_late, name="recorder-stop", daemon=True).start()


def start_recorder(session: Any, sink: Callable[[str, str], None], run_dir: Path, world: str,
                   seed: int, profile: str = "homework") -> RecorderWatch:
    """Start the run's recorder (``run_dir/bag``) in ``session`` (the run's :class:`bt_nav.run.session.MissionSession`,
    with the run's other processes: see the module docstring)."""
    watch = RecorderWatch()
    watch.child = session.start(RecordSpec(run_dir / BAG, world, seed, profile), sink=sink)
    return watch


def bag_row(run_dir: Path, watch: RecorderWatch | None, t0: float | None) -> dict[str, Any]:
    """What the run's row says of its bag: its directory (relative to the run directory), size, the sim time of its
    first ground truth and by how much that came after the judge's t0 (0.0: the bag holds t0; None: unknown)."""
    if watch is None:
        return {"bag": None}
    bag = run_dir / BAG
    size = sum(p.stat().st_size for p in bag.rglob("*") if p.is_file() and p.name != FIRST_MESSAGES) \
        if bag.is_dir() else 0
    truth_from = first_messages(bag).get(TRUTH)
    truth_from = None if truth_from is None else round(truth_from, 2)
    late = None if truth_from is None or t0 is None else round(max(0.0, truth_from - t0), 2)
    return {"bag": BAG if size else None, "bag_bytes": size, "bag_truth_from": truth_from, "bag_after_t0_s": late}
