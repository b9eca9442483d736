"""``bt-nav lockstep --bag B --video V.mp4``: a bag both readers open with every topic, and a film of it; for one
robot and for two (each robot's topics under its namespace)."""

from __future__ import annotations

from pathlib import Path

import imageio_ffmpeg
import pytest
from bt_nav_sim.multi import robot_names
from mcap.reader import make_reader
from rosbags.rosbag2 import Reader

from bt_nav.cli.lockstep import main
from bt_nav.media.bag import ROBOT_TOPICS, TOPICS, split_namespace


@pytest.mark.parametrize("robots", [1, 2], ids=["1robot", "2robots"])
def test_lockstep_writes_a_bag_and_films_it(robots: int, tmp_path: Path, capsys) -> None:
    bag, video = tmp_path / "B", tmp_path / "V.mp4"
    main(["--maneuver", "C", "--seed", "1", "--duration", "8", "--bag", str(bag), "--video", str(video),
          "--fps", "5", "--robots", str(robots)])
    out = capsys.readouterr().out
    assert f"bag: {bag}" in out and "video:" in out
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    (mcap_file,) = bag.glob("*.mcap")
    with open(mcap_file, "rb") as stream:
        summary = make_reader(stream).get_summary()
    mcap_counts = {ch.topic: summary.statistics.channel_message_counts[cid] for cid, ch in summary.channels.items()}
    assert counts == mcap_counts
    namespaces = [""] if robots == 1 else [f"/{name}" for name in robot_names(robots)]
    for topic in ("/clock", "/scan", "/odom", "/ground_truth_odom", "/cmd_vel", "/bt_nav/events"):
        for ns in namespaces if topic in ROBOT_TOPICS else [""]:
            assert counts.get(ns + topic, 0) > 0, ns + topic
    assert {split_namespace(topic)[1] for topic in counts} <= set(TOPICS) | {"/bt_nav_executive/tree",
                                                                            "/bt_nav/mission"}
    assert all(split_namespace(topic)[0] in ("", *namespaces) for topic in counts)  # one robot: all at the root
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(video))
    assert frames == round(8.0 * 5)
