"""Mission bags: lock-step writes a real rosbag2 (MCAP) bag that rosbags and mcap both read; bad bags fail clearly.

What a bag must be for any number of robots is checked on ``robots_bag``: one robot and two."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
import yaml

from bt_nav.media.bag import (
    ANNOUNCEMENTS,
    CLOCK,
    COLLISIONS,
    EVENTS,
    ROBOT_TOPICS,
    SCAN,
    TOPICS,
    TREE,
    WALKERS,
    BagError,
    MissionBag,
)
from bt_nav.media.bagread import read_bag

if TYPE_CHECKING:
    from conftest import RobotsBag  # tests/media/conftest.py

#: No collision, no people here, and no maneuver in the first 12 s (so no event on /bt_nav_executive/events).
EXPECTED = [topic for topic in TOPICS if topic not in (COLLISIONS, WALKERS, ANNOUNCEMENTS)]


def test_rosbags_reader_counts_every_topic(robots_bag: RobotsBag) -> None:
    from rosbags.rosbag2 import Reader

    with Reader(robots_bag.path) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        types = {c.topic: c.msgtype for c in reader.connections}
    expected = [(topic, name) for name in EXPECTED for topic in robots_bag.topics(name)]
    assert len(expected) == len(EXPECTED) + (robots_bag.robots - 1) * (len(ROBOT_TOPICS) - 3)
    for topic, name in expected:
        assert counts.get(topic, 0) > 0, topic
        assert types[topic] == TOPICS[name].msgtype
    assert set(counts) == {topic for topic, _ in expected}, "a topic where it does not belong"


def test_mcap_reader_agrees(robots_bag: RobotsBag) -> None:
    from mcap.reader import make_reader

    (file,) = robots_bag.path.glob("*.mcap")
    with file.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    counts = {ch.topic: summary.statistics.channel_message_counts[cid] for cid, ch in summary.channels.items()}
    assert counts == read_bag(robots_bag.path).counts
    schemas = {summary.schemas[ch.schema_id].encoding for ch in summary.channels.values()}
    assert schemas == {"ros2msg"}


def test_metadata_has_mcap_storage_and_qos(robots_bag: RobotsBag) -> None:
    meta = yaml.safe_load((robots_bag.path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap"
    qos = {t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"]
           for t in meta["topics_with_message_count"]}
    for scan, tree in zip(robots_bag.topics(SCAN), robots_bag.topics(TREE), strict=True):
        assert "reliability: 2" in str(qos[scan]) or "best_effort" in str(qos[scan])  # scans are best effort
        assert qos[tree]  # every topic carries its offered QoS


def test_timestamps_are_sim_time(robots_bag: RobotsBag) -> None:
    rec = read_bag(robots_bag.path)
    assert rec.start == pytest.approx(0.0, abs=0.02)
    assert rec.end == pytest.approx(12.0, abs=0.1)
    assert rec.mission["world"] == "stage_4" and not rec.truncated
    each = [rec] if robots_bag.robots == 1 else [rec.robots[ns.strip("/")] for ns in robots_bag.namespaces]
    def statuses(snapshot: dict) -> tuple:
        return [(n["name"], n["status"]) for n in snapshot["nodes"]], snapshot["tip"]

    for robot in each:
        assert robot.truth.t[-1] <= rec.end and robot.scans.t.size > 10
        assert any("armed" in text for _, text in robot.events)
        assert all(statuses(a[1]) != statuses(b[1]) for a, b in zip(robot.trees, robot.trees[1:], strict=False)), \
            "tree written when a status or the tip changes only"


def test_cut_bag_reads_up_to_the_cut(robots_bag: RobotsBag, tmp_path: Path) -> None:
    (file,) = robots_bag.path.glob("*.mcap")
    data = file.read_bytes()
    cut = tmp_path / "cut"
    cut.mkdir()
    (cut / "cut.mcap").write_bytes(data[: len(data) * 2 // 3])  # no summary, no metadata.yaml
    rec = read_bag(cut)
    full = read_bag(robots_bag.path)
    assert rec.truncated
    assert 0 < rec.counts[CLOCK] < full.counts[CLOCK]
    assert 0 < rec.duration < full.duration


@pytest.mark.parametrize("content", [b"", b"\x89MCAP0\r\n" + b"\x00" * 7, b"not a bag at all" * 20])
def test_corrupt_bag_names_the_file(tmp_path: Path, content: bytes) -> None:
    file = tmp_path / "broken.mcap"
    file.write_bytes(content)
    with pytest.raises(BagError, match="broken.mcap"):
        read_bag(file)


def test_missing_bag_names_the_path(tmp_path: Path) -> None:
    with pytest.raises(BagError, match="nowhere"):
        read_bag(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(BagError, match="empty"):
        read_bag(tmp_path / "empty")


def test_killed_writer_leaves_a_readable_bag(tmp_path: Path) -> None:
    """A writer that dies without close() (os._exit, as after SIGKILL) keeps what flush() put on disk."""
    bag = tmp_path / "killed"
    code = (f"import os\nfrom bt_nav.media.bag import MissionBag\nb = MissionBag({str(bag)!r}, flush_every=0)\n"
            "for i in range(50):\n    b.clock(i * 0.1)\n    b.event(i * 0.1, f'line {i}')\n"
            "b.flush()\nb.clock(99.0)\nos._exit(0)\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
    assert not (bag / "metadata.yaml").exists()
    rec = read_bag(bag)
    assert rec.truncated and rec.counts[CLOCK] == 50 and rec.counts[EVENTS] == 50
    assert rec.end == pytest.approx(4.9)


def test_existing_directory_is_refused(tmp_path: Path) -> None:
    with pytest.raises(BagError, match="exists"):
        MissionBag(tmp_path)


def test_people_walking_are_recorded_and_filmed(tmp_path: Path) -> None:
    """A lock-step bag of a world with people holds /walkers as the simulator node publishes it; the record
    gives where they were at any time, and a video frame draws them (the pink of their disks)."""
    import numpy as np

    from bt_nav.media.video import renderer_for
    from bt_nav.run.lockstep import run_mission

    with MissionBag(tmp_path / "bag", mission={"world": "lab_passerby", "profile": "lab"}) as bag:
        run_mission("lab_passerby", "A", 0, profile="lab", duration=8.0, sink=bag)
    record = read_bag(tmp_path / "bag")
    assert record.counts[WALKERS] == record.counts["/ground_truth_odom"]
    early, late = record.walkers_at(1.0), record.walkers_at(7.0)
    assert early.shape == (3, 3) and np.all(early[:, 2] == 0.2) and not np.allclose(early, late)
    assert record.walkers_at(-1.0) is None
    frame = np.asarray(renderer_for(record).frame(7.0))
    assert np.any(np.all(frame == (240, 170, 215), axis=-1)), "the people are drawn"


def test_a_tree_snapshot_is_read_at_the_time_it_was_taken(tmp_path: Path) -> None:
    """``ros2 bag record`` holds a String at its receive time, seconds late when the recorder lagged; the snapshot's
    own ``t`` (the executive's tick) times the branch, where it is on the bag's clock (the header-stamp rule)."""
    def snap(t: float, tip: str) -> dict:
        return {"format": "bt_nav.tree/1", "tick": 1, "t": t, "maneuver": "C", "tip": tip, "path": [], "nodes": [],
                "blackboard": {}}

    with MissionBag(tmp_path / "bag") as bag:
        bag.clock(0.1)
        bag.tree(8.5, snap(5.0, "FullSpeed"))  # received 3.5 s of sim time after its tick
        bag.tree(9.0, snap(7.5, "EvaluateMission"))
        bag.tree(9.5, snap(900.0, "StopDisarmed"))  # not on the bag's clock: its bag time
    trees = read_bag(tmp_path / "bag").trees
    assert [doc["tip"] for _, doc in trees] == ["FullSpeed", "EvaluateMission", "StopDisarmed"]
    assert [t for t, _ in trees] == pytest.approx([5.0, 7.5, 9.5])
