"""The demo's recorder times the tree's branch and the command by when they were sent, not by when they arrived.

Its one executor takes one message per ready topic per round, so at 10-20x real time the ground truth (30 a sim
second) queues up behind the rare tree snapshots: labelled on arrival, a README demo drew the last ~1.6 m before the
deadline as Stopped and the path FullSpeed 2 s before arming. Here the recorder's callbacks get a mission in that
order (ground truth 3 s of sim time late), without DDS.
"""

from __future__ import annotations

import threading
from types import SimpleNamespace
from typing import Any

import pytest

from bt_nav.mission.snapshot import snapshot_json
from bt_nav.run.recorder import Recorder, Recording, held_at

RTF = 10.0  # sim seconds per wall second
WALL0 = 1_000_000_000_000  # ns
ARM, DEADLINE, END = 5.0, 8.0, 10.0  # sim s: FullSpeed from ARM, EvaluateMission (and a stop) from DEADLINE
LAG = 3.0  # sim s: how far the ground truth arrives behind the tree and the commands


def _wall(t: float) -> int:
    return WALL0 + round(t / RTF * 1e9)


def _bare_recorder() -> Recorder:
    """A Recorder's state and callbacks without its node."""
    rec = object.__new__(Recorder)
    rec.data, rec.lock = Recording(), threading.Lock()
    rec.clock = SimpleNamespace(add=lambda wall, sim: None)
    rec._truth = "subscribed"
    return rec


def _truth(t: float) -> Any:
    stamp = SimpleNamespace(sec=int(t), nanosec=round((t - int(t)) * 1e9))
    pose = SimpleNamespace(position=SimpleNamespace(x=0.22 * max(0.0, min(t, DEADLINE) - ARM), y=0.0),
                           orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0))
    return SimpleNamespace(header=SimpleNamespace(stamp=stamp), pose=SimpleNamespace(pose=pose))


def _tree(t: float, tip: str) -> Any:
    return SimpleNamespace(data=snapshot_json({"format": "bt_nav.tree/1", "tick": round(t * 20), "t": t,
                                               "maneuver": "C", "tip": tip, "path": [], "nodes": [],
                                               "blackboard": {}}))


def _cmd(v: float) -> Any:
    return SimpleNamespace(linear=SimpleNamespace(x=v), angular=SimpleNamespace(z=0.0))


def _lagging_mission(rec: Recorder) -> None:
    """Feed the callbacks in arrival order: tree and commands at once, the ground truth ``LAG`` late."""
    arrivals: list[tuple[float, int, Any]] = []
    for k in range(round(END * 30) + 1):  # ground truth, 30 a sim second
        t = k / 30
        info = {"source_timestamp": _wall(t), "publication_sequence_number": k + 1}
        arrivals.append((t + LAG, 0, lambda t=t, info=info: rec._on_truth(_truth(t), info)))
    arrivals += [(0.0, 1, lambda: rec._on_tree(_tree(0.0, "StopDisarmed"))),
                 (ARM, 1, lambda: rec._on_tree(_tree(ARM, "FullSpeed"))),
                 (DEADLINE, 1, lambda: rec._on_tree(_tree(DEADLINE, "EvaluateMission")))]
    for k in range(round(END * 20) + 1):  # commands, 20 a sim second, sent just after their tick's truth
        t = k / 20
        v = 0.22 if ARM <= t < DEADLINE else 0.0
        arrivals.append((t, 2, lambda t=t, v=v: rec._on_cmd(_cmd(v), {"source_timestamp": _wall(t) + 1000})))
    for _, _, deliver in sorted(arrivals, key=lambda a: (a[0], a[1])):
        deliver()


def test_branch_and_command_are_those_sent_at_each_samples_time() -> None:
    rec = _bare_recorder()
    _lagging_mission(rec)
    traj, data = rec.data.mission_trajectory({})
    assert len(traj) == round(END * 30) + 1 and data["tree_messages"] == 3 and data["commands"] == 201
    for t, branch, tip, v in zip(data["t"], data["branch"], data["tip"], data["cmd_linear"], strict=True):
        if t < ARM:
            assert (branch, tip, v) == ("Stopped", "StopDisarmed", 0.0), t
        elif ARM + 0.01 < t < DEADLINE:
            assert (branch, tip, v) == ("FullSpeed", "FullSpeed", 0.22), t
        elif t > DEADLINE + 0.01:
            assert (branch, tip, v) == ("Stopped", "EvaluateMission", 0.0), t


def test_a_snapshot_without_its_time_is_timed_by_arrival() -> None:
    """An older executive's snapshot without ``t``: the newest ground truth read when it came (as before)."""
    rec = _bare_recorder()
    rec._on_truth(_truth(1.0), {"source_timestamp": _wall(1.0)})
    rec._on_tree(SimpleNamespace(data='{"format": "bt_nav.tree/1", "tip": "FullSpeed"}'))
    rec._on_truth(_truth(1.1), {"source_timestamp": _wall(1.1)})
    assert rec.data.trees == [(1.0, "FullSpeed")]
    assert rec.data.mission_trajectory({})[1]["tip"] == ["FullSpeed", "FullSpeed"]


@pytest.mark.parametrize(("times", "expected"), [([0.5, 1.0, 1.5, 2.0, 3.0], ["-", "a", "a", "b", "c"])])
def test_held_at_takes_the_last_value_sent_at_or_before(times: list[float], expected: list[str]) -> None:
    assert held_at(times, [1.0, 2.0, 2.0, 2.5], ["a", "x", "b", "c"], "-") == expected
    assert held_at(times, [2.5, 1.0], ["c", "a"], "-") == ["-", "a", "a", "a", "c"]  # sorted by time


def test_ground_truth_is_read_only_once_the_executive_is_heard() -> None:
    """The judge's t0 waits for this node's ground-truth subscription (``truth_readers``): made on the first tree
    snapshot (latched: it comes as soon as the executive matches), once, so no leg of the mission goes unlabelled."""
    rec = _bare_recorder()
    made: list[str] = []
    rec._truth, rec._subscribe_truth = None, lambda: made.append("ground_truth_odom") or "subscription"
    rec._on_cmd(_cmd(0.0), None)
    assert not made
    rec._on_tree(_tree(0.05, "StopDisarmed"))
    rec._on_tree(_tree(5.0, "FullSpeed"))
    assert made == ["ground_truth_odom"] and rec._truth == "subscription"
