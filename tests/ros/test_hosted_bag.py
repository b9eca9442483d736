"""``bt-nav sim --record BAG``: the simulator's own process writes the run's bag (bt_nav.ros.nodes.hosted_bag), over
real DDS for what it does not publish itself (the robot's commands, the graph's log lines).

What must hold for the grader's pictures, videos and bag judge to read it as they read a recorder's bag: every
message the simulator published is in it from its first step, at the sim time of that step (the stamp the message
carries); a command is in it at the sim time the simulator took it, and the robot moved from then on; the topics not
asked for are left out; the graph's log lines are mission events; and the bag is closed whole on SIGINT.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from simtools import Probe, Proc, wait_until

from bt_nav.media.bag import CMD, EVENTS, FIRST_MESSAGES, ODOM, SCAN, TRUTH
from bt_nav.media.bagread import read_bag


def test_the_simulator_writes_its_bag(ros_context: Any, tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    probe = Probe(ros_context)
    proc = Proc("sim", "--profile", "lab", "--world", "lab_object", "--record", str(bag),
                "--record-topics", ",".join((SCAN, TRUTH, CMD, "/rosout")))
    try:
        wait_until(lambda: probe.now() > 1.0, 20.0, "the simulator's clock", proc.output)
        start = probe.last_truth().pose.pose.position
        probe.command = (0.1, 0.0)  # forward at 0.1 m/s, sent at 20 Hz while set

        def moved() -> float:
            here = probe.last_truth().pose.pose.position
            return float(np.hypot(here.x - start.x, here.y - start.y))

        wait_until(lambda: moved() > 0.05, 20.0, "the robot moving", proc.output)
        probe.command = None
        probe.wait_sim_time(probe.now() + 0.5)
    finally:
        code = proc.stop()
        probe.close()
    assert code == 0, proc.output()
    assert (bag / "metadata.yaml").is_file(), "SIGINT closes the bag whole"
    record = read_bag(bag)
    assert set(record.counts) == {SCAN, TRUTH, CMD, EVENTS, "/bt_nav/mission"}, record.counts
    assert ODOM not in record.counts, "a topic not asked for is left out"
    assert record.truth.t[0] == 0.0 and record.scans.t[0] == 0.0, "from the simulator's first step"
    assert np.all(np.diff(record.truth.t) > 0.0), "one ground truth per step it was published in, in order"
    first = json.loads((bag / FIRST_MESSAGES).read_text())
    assert first[TRUTH] == 0.0 and first[CMD] > 1.0
    cmd = record.cmd
    assert len(cmd) > 5 and np.allclose(cmd[:, 1], 0.1) and np.allclose(cmd[:, 2], 0.0), cmd[:5]
    moving = record.truth.t[1:][np.hypot(np.diff(record.truth.x), np.diff(record.truth.y)) > 1e-6]  # moved by then
    assert moving[0] >= cmd[0, 0] - 1e-9, "the robot moved only once the first command was in (its arrival time)"
    assert moving[0] - cmd[0, 0] < 0.1, "... and from then on (the command's time is when the physics took it)"
    said = [text for _, text in record.events]
    assert any(text.startswith("[INFO] sim: world lab_object") for text in said), said[:5]
