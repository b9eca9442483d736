"""``bt-nav record`` notes when each topic's first message arrived in a file of the bag
(:data:`bt_nav.run.bagrecorder.FIRST_MESSAGES`), and ``bt-nav grade --exe`` reads the bag's start from it, not from
the recorder's output lines. Without DDS: the recorder's write callback is fed by hand."""

from __future__ import annotations

import json
import threading
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from bt_nav.grading.exe.bag import BAG, bag_row
from bt_nav.media.bag import SCAN, TRUTH
from bt_nav.run.bagrecorder import FIRST_MESSAGES, BagRecorder, first_messages


def _recorder(bag: Path) -> BagRecorder:
    """A BagRecorder whose bag only counts what it is given (no ROS node, no MCAP file)."""
    bag.mkdir(parents=True)
    (bag / "bag_0.mcap").write_bytes(b"x" * 100)
    counts: dict[str, int] = {}

    def write_raw(topic: str, *_: Any) -> None:
        counts[topic] = counts.get(topic, 0) + 1

    recorder = BagRecorder.__new__(BagRecorder)
    recorder.bag = SimpleNamespace(path=bag, closed=False, counts=counts, write_raw=write_raw)
    recorder.lock = threading.Lock()
    recorder.first = {}
    recorder._first_lock = threading.Lock()
    return recorder


def test_the_first_messages_are_noted_in_the_bag_and_the_row_reads_them(tmp_path: Path, capsys: Any) -> None:
    recorder = _recorder(tmp_path / BAG)
    recorder._write(SCAN, "sensor_msgs/msg/LaserScan", 11_200_000_000, b"", None)
    recorder._write(TRUTH, "nav_msgs/msg/Odometry", 12_345_678_900, b"", None)
    recorder._write(TRUTH, "nav_msgs/msg/Odometry", 13_000_000_000, b"", None)  # not the first: no change
    assert json.loads((tmp_path / BAG / FIRST_MESSAGES).read_text()) == {SCAN: 11.2, TRUTH: 12.3456789}
    # the lines for people are printed as before
    assert capsys.readouterr().out.splitlines() == [f"first {SCAN} at sim 11.20 s", f"first {TRUTH} at sim 12.35 s"]
    row = bag_row(tmp_path, True, 10.0)
    assert row == {"bag": BAG, "bag_bytes": 100, "bag_truth_from": 12.35, "bag_after_t0_s": 2.35}


def test_a_bag_without_its_note_says_unknown(tmp_path: Path) -> None:
    """No note (the recorder heard no ground truth, or was killed before its first message), or one cut short."""
    recorder = _recorder(tmp_path / BAG)
    recorder._write(SCAN, "sensor_msgs/msg/LaserScan", 11_200_000_000, b"", None)
    assert bag_row(tmp_path, True, 10.0)["bag_truth_from"] is None
    (tmp_path / BAG / FIRST_MESSAGES).write_text('{"/ground_truth_odom": 1')
    assert first_messages(tmp_path / BAG) == {}
    assert bag_row(tmp_path, False, 10.0) == {"bag": None}
