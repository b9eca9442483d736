"""``bt-nav lockstep --bag B --video V.mp4``: a bag both readers open with every topic, and a film of it."""

from __future__ import annotations

from pathlib import Path

import imageio_ffmpeg
from mcap.reader import make_reader
from rosbags.rosbag2 import Reader

from bt_nav.cli.lockstep import main
from bt_nav.media.bag import TOPICS


def test_lockstep_writes_a_bag_and_films_it(tmp_path: Path, capsys) -> None:
    bag, video = tmp_path / "B", tmp_path / "V.mp4"
    main(["--maneuver", "C", "--seed", "1", "--duration", "8", "--bag", str(bag), "--video", str(video),
          "--fps", "5"])
    out = capsys.readouterr().out
    assert f"bag: {bag}" in out and "video:" in out
    with Reader(bag) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    (mcap_file,) = bag.glob("*.mcap")
    with open(mcap_file, "rb") as stream:
        summary = make_reader(stream).get_summary()
    mcap_counts = {ch.topic: summary.statistics.channel_message_counts[cid] for cid, ch in summary.channels.items()}
    assert counts == mcap_counts
    for topic in ("/clock", "/scan", "/odom", "/ground_truth_odom", "/cmd_vel", "/bt_nav/events"):
        assert counts.get(topic, 0) > 0, topic
    assert set(counts) <= set(TOPICS) | {"/bt_nav_executive/tree", "/bt_nav/mission"}
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(video))
    assert frames == round(8.0 * 5)
