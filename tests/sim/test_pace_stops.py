"""The simulator's record of its pace stops (:class:`bt_nav_sim.pacing.PaceStops`): when sim time stopped waiting
for a follower and when it waited again, as the data a grade reads (``pace.json``), never the log's words."""

from __future__ import annotations

import json
from pathlib import Path

from bt_nav_sim.pacing import PACE_FILE, Followers, PaceStop, PaceStops, read_pace_stops

MS = 1_000_000


def test_a_stop_is_closed_by_the_followers_next_message_only() -> None:
    stops = PaceStops()
    stops.resumed("cmd_vel", 1.0)  # a first message (joining) ends no stop
    stops.stopped("cmd_vel", 19.45, holding=False)
    stops.stopped("referee", 20.0, holding=True)
    stops.resumed("cmd_vel", 19.7)
    stops.resumed("cmd_vel", 19.9)  # already following again: the stop keeps its first resumption
    stops.stopped("cmd_vel", 65.65, holding=False)
    assert stops.stops == [PaceStop("cmd_vel", 19.45, "silent", 19.7), PaceStop("referee", 20.0, "holding"),
                           PaceStop("cmd_vel", 65.65, "silent")]
    record = stops.record(t_end=70.0)
    assert set(record["followed"]) == {"cmd_vel"}
    assert {k: v for k, v in record.items() if k != "followed"} == {"t_end": 70.0, "stops": [
        {"who": "cmd_vel", "t": 19.45, "why": "silent", "resumed": 19.7},
        {"who": "referee", "t": 20.0, "why": "holding", "resumed": None},
        {"who": "cmd_vel", "t": 65.65, "why": "silent", "resumed": None}]}


def test_the_followers_drops_become_stops_as_the_node_records_them() -> None:
    """The node's bookkeeping in its order: :meth:`Followers.blocking` drops a silent follower, its next message
    (``report`` says it rejoined) resumes it."""
    followers, stops = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0), PaceStops()
    followers.report("cmd_vel", 1000 * MS, False, wall=0.0)
    _, dropped = followers.blocking(1100 * MS, wall=1.5)
    for who in dropped:
        stops.stopped(who, 1.09, followers.members[who].hold)
    if followers.report("cmd_vel", 1090 * MS, False, wall=2.0):
        stops.resumed("cmd_vel", 1.09)
    assert stops.stops == [PaceStop("cmd_vel", 1.09, "silent", 1.09)]


def test_the_pace_file_reads_back_and_a_missing_or_broken_one_is_none(tmp_path: Path) -> None:
    stops = PaceStops()
    stops.stopped("cmd_vel", 3.5, holding=False)
    (tmp_path / PACE_FILE).write_text(json.dumps(stops.record(t_end=9.0)), encoding="utf-8")
    assert read_pace_stops(tmp_path / PACE_FILE) == [PaceStop("cmd_vel", 3.5, "silent")]
    assert read_pace_stops(tmp_path / "missing.json") is None
    (tmp_path / "broken.json").write_text('{"stops": [{"who": "cmd_vel"}]}', encoding="utf-8")
    assert read_pace_stops(tmp_path / "broken.json") is None


class _Clock:
    """A wall clock the test sets."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _joined_at_sim_2_wall_1() -> tuple[_Clock, Followers, PaceStops]:
    """A node followed (silence 1 s wall) from its first command at sim 2 s, wall 1 s."""
    clock = _Clock()
    followers, stops = Followers(max_lag_ns=50 * MS, silence_s=1.0, hold_s=5.0), PaceStops(clock)
    clock.now = 1.0
    followers.report("cmd_vel", 2000 * MS, False, wall=clock.now)
    stops.resumed("cmd_vel", 2.0)
    return clock, followers, stops


def test_followed_counts_sim_and_wall_seconds_less_the_silence_that_dropped_the_follower() -> None:
    """The node joins at sim 2 s (wall 1 s), keeps up until sim 12 s (wall 3 s), falls silent: the drop comes a
    silence (1 s wall) later, at wall 4 s, and is not counted. It speaks again at sim 12.1 s (wall 5 s) and its latest
    message, at sim 30 s and wall 7 s, ends the open span: 10.1 + 17.9 sim s in 2 + 2 wall s."""
    clock, followers, stops = _joined_at_sim_2_wall_1()
    followers.report("cmd_vel", 11900 * MS, False, wall=2.9)
    followers.report("cmd_vel", 12000 * MS, False, wall=3.0)
    clock.now = 4.0
    _, dropped = followers.blocking(12200 * MS, wall=clock.now + 0.01)
    assert dropped == ["cmd_vel"]
    stops.stopped("cmd_vel", 12.1, holding=False)
    clock.now = 5.0
    assert followers.report("cmd_vel", 12100 * MS, False, wall=clock.now)
    stops.resumed("cmd_vel", 12.1)
    followers.report("cmd_vel", 30000 * MS, False, wall=7.0)
    clock.now = 9.0  # the simulator's exit: the node said nothing more
    assert stops.followed(followers, t_end=31.0) == {"cmd_vel": {"sim_s": 28.0, "wall_s": 4.0}}
    assert stops.record(followers, t_end=31.0, wall_s=10.0)["followed"] == {"cmd_vel": {"sim_s": 28.0, "wall_s": 4.0}}


def test_a_drop_after_a_shorter_silence_takes_off_that_silence_only() -> None:
    """A disarmed node standing still is dropped after a tenth of a second (Followers.disarmed): the span ends at its
    latest message, not a whole follower timeout before the drop."""
    clock, followers, stops = _joined_at_sim_2_wall_1()
    followers.report("cmd_vel", 12000 * MS, False, wall=3.0)
    clock.now = 3.1
    stops.stopped("cmd_vel", 12.1, holding=False, quiet_s=0.1)
    assert stops.followed(followers, t_end=31.0) == {"cmd_vel": {"sim_s": 10.1, "wall_s": 2.0}}


def test_a_span_without_the_followers_bookkeeping_ends_at_the_end() -> None:
    clock = _Clock()
    stops = PaceStops(clock)
    stops.resumed("cmd_vel", 1.0)
    clock.now = 2.0
    assert stops.followed(t_end=11.0) == {"cmd_vel": {"sim_s": 10.0, "wall_s": 2.0}}
    assert stops.followed() == {}  # no end known: nothing counted
