"""The bag of one ``--exe`` run: written by the simulator's own process (``bt-nav sim --record``,
:mod:`bt_nav.ros.nodes.hosted_bag`), one more argument of the run's simulator.

Why there and not a ``bt-nav record`` process of its own: that recorder was a Python interpreter and a DDS participant
per run that subscribed to what the simulator had just published and followed ``/clock`` to stamp it, about a fifth
of a graded run's CPU on two cores (1.5-2.3 of 6-9 CPU s, measured), taken from the node being graded; and its bag
began whenever its discovery had found the topics (0-2.1 sim s after t0 over 48 runs). The simulator knows every
message it publishes at the instant it publishes it: the bag now holds the run from its first step, every message at
the exact sim time of its step, the node's commands at the sim time they arrived (when the physics took them), and
the graph's ``/rosout`` lines as mission events. The simulator is stopped after the graded node (the node first,
:mod:`bt_nav.grading.exe.run`), so the bag holds what the node sent on its way out (bt_nav's executive: its last zero
twists). A simulator that had to be killed leaves a readable ``.mcap`` up to its last flush (every sim second).

The bag records only what the report draws (:data:`RUN_TOPICS`). The pictures and videos are drawn from the bags
after the grid, in the report step (:mod:`bt_nav.grading.media`), so they cost the timed runs nothing. When the
first ground truth went into the bag (:data:`bt_nav.media.bag.FIRST_MESSAGES`) goes into the row
(``bag_truth_from``, ``bag_after_t0_s``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav.media.bag import CMD, COLLISIONS, FIRST_MESSAGES, ROSOUT, SCAN, TREE, TRUTH, WALKERS
from bt_nav.run.bagrecorder import first_messages

#: The bag's directory name inside the run directory.
BAG = "bag"
#: What a run's bag records: what the pictures and videos draw (ground truth, scans, commands, collisions, the judge's
#: log lines as events, a bt_nav executive's tree). Not ``/clock`` (every message is stamped with its sim time
#: anyway) nor ``/odom`` (what the node sees; the pictures use ground truth).
RUN_TOPICS = (SCAN, TRUTH, CMD, COLLISIONS, ROSOUT, TREE, WALKERS)
#: What ``--record`` accepts: every run's bag kept, only the failed runs' (the passed runs' deleted once their
#: trajectory picture is drawn), or no bag at all (a benchmark; no pictures, no videos).
RECORD_MODES = ("on", "failures", "off")


def record_args(run_dir: Path) -> list[str]:
    """The simulator's arguments that make it write the run's bag into ``run_dir/bag`` (:data:`RUN_TOPICS`, read when
    called: a benchmark may record more)."""
    return ["--record", str(run_dir / BAG), "--record-topics", ",".join(RUN_TOPICS)]


def bag_row(run_dir: Path, recorded: bool, t0: float | None) -> dict[str, Any]:
    """What the run's row says of its bag: its directory (relative to the run directory), size, the sim time of its
    first ground truth and by how much that came after the judge's t0 (0.0: the bag holds t0; None: unknown)."""
    if not recorded:
        return {"bag": None}
    bag = run_dir / BAG
    size = sum(p.stat().st_size for p in bag.rglob("*") if p.is_file() and p.name != FIRST_MESSAGES) \
        if bag.is_dir() else 0
    truth_from = first_messages(bag).get(TRUTH)
    truth_from = None if truth_from is None else round(truth_from, 2)
    late = None if truth_from is None or t0 is None else round(max(0.0, truth_from - t0), 2)
    return {"bag": BAG if size else None, "bag_bytes": size, "bag_truth_from": truth_from, "bag_after_t0_s": late}
