"""``bt-nav lockstep --robots 2 --bag B --video V.mp4``: one bag with each robot under its namespace, and a
film with each robot in its own colour (issue #16's last part)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import imageio_ffmpeg
import numpy as np
import pytest
from rosbags.rosbag2 import Reader

from bt_nav.cli.lockstep import main
from bt_nav.media.bag import ROBOT_TOPICS, TOPICS, split_namespace
from bt_nav.media.bagread import MissionRecord, read_bag
from bt_nav.media.plot import robot_colour
from bt_nav.media.video import MAP_H, MAP_W, TracksRenderer, VideoRenderer, renderer_for, world_of

DURATION, FPS = 12.0, 5.0  # past the first arming at 5 s, so every robot topic has messages
ROBOTS = ("robot1", "robot2")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """One 2-robot lock-step run (stage_4, maneuver C) with --bag, --video and --json."""
    tmp = tmp_path_factory.mktemp("two")
    bag, video, results = tmp / "bag", tmp / "two.mp4", tmp / "two.json"
    code = main(["--robots", "2", "--maneuver", "C", "--seed", "1", "--duration", str(DURATION), "--bag", str(bag),
                 "--video", str(video), "--fps", str(FPS), "--json", str(results)])
    assert code in (0, 1)
    return {"bag": bag, "video": video, "results": json.loads(results.read_text()), "record": read_bag(bag)}


def test_one_bag_holds_every_robot_under_its_namespace(run: dict[str, Any]) -> None:
    with Reader(run["bag"]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    for name in ROBOTS:
        for topic in ROBOT_TOPICS:
            if topic not in ("/collisions", "/walkers", "/bt_nav_executive/events"):  # none here: no collision, no
                # people, no maneuver in this short run
                assert counts.get(f"/{name}{topic}", 0) > 0, f"/{name}{topic}"
    assert counts["/clock"] > 0 and counts["/bt_nav/mission"] == 1
    assert not set(counts) & set(ROBOT_TOPICS), "a robot topic at the root"
    assert all(t in ("/clock", "/bt_nav/mission") or split_namespace(t)[0] in ("/robot1", "/robot2") for t in counts)
    assert counts["/robot1/ground_truth_odom"] == counts["/robot2/ground_truth_odom"]  # one clock for both


def test_each_robots_ground_truth_is_its_own_trajectory(run: dict[str, Any]) -> None:
    record: MissionRecord = run["record"]
    assert list(record.robots) == list(ROBOTS)
    for name in ROBOTS:
        traj, truth = run["results"]["robots"][name]["trajectory"], record.robots[name].truth
        np.testing.assert_allclose(truth.t, traj["t"], atol=1e-9)
        np.testing.assert_allclose(truth.x, traj["x"], atol=1e-12)
        np.testing.assert_allclose(truth.y, traj["y"], atol=1e-12)
    one, two = record.robots["robot1"].truth, record.robots["robot2"].truth
    assert np.hypot(one.x - two.x, one.y - two.y).min() > 0.2  # two robots, not one twice
    assert record.robots["robot2"].events[-1][1].startswith("verdict: ")
    np.testing.assert_array_equal(record.truth.x, one.x)  # one-robot readers (view, replay) see robot1


def test_the_video_has_one_frame_per_step(run: dict[str, Any]) -> None:
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(run["video"]))
    assert frames == round(DURATION * FPS)


def _pixels(img: Any, rgb: tuple[int, int, int]) -> int:
    """Pixels of exactly ``rgb`` in the map panel below the caption."""
    a = np.asarray(img)[50:MAP_H, :MAP_W]
    return int(np.all(a == np.asarray(rgb, dtype=np.uint8), axis=-1).sum())


def test_each_robot_is_drawn_in_its_own_colour(run: dict[str, Any]) -> None:
    record: MissionRecord = run["record"]
    renderer = renderer_for(record, world_of(record))
    assert isinstance(renderer, TracksRenderer)
    expected = {name: tuple(int(robot_colour(i)[k:k + 2], 16) for k in (1, 3, 5)) for i, name in enumerate(ROBOTS)}
    assert renderer.colours == expected and len(set(expected.values())) == 2
    img = None
    for t in np.arange(record.start, record.end, 0.5):  # rising t, as the film does
        img = renderer.frame(float(t))
    for name, rgb in expected.items():
        assert _pixels(img, rgb) > 150, f"{name}'s path is not drawn in {rgb}"


def test_a_one_robot_bag_is_filmed_as_before(mission_bag: Path) -> None:
    record = read_bag(mission_bag)
    assert record.robots == {}
    assert type(renderer_for(record)) is VideoRenderer
    assert set(record.counts) <= set(TOPICS)


def test_split_namespace() -> None:
    assert split_namespace("/robot1/scan") == ("/robot1", "/scan")
    assert split_namespace("/fleet/a/bt_nav_executive/tree") == ("/fleet/a", "/bt_nav_executive/tree")
    assert split_namespace("/robot1/ground_truth_odom") == ("/robot1", "/ground_truth_odom")
    for root in ("/scan", "/bt_nav_executive/tree", "/bt_nav/events", "/clock", "/bt_nav/mission"):
        assert split_namespace(root) == ("", root)


def test_trace_records_every_robot(tmp_path: Path) -> None:
    """--trace with several robots writes one trace per robot (t_robot1.jsonl, t_robot2.jsonl), each its
    own tree's ticks (the robots start apart, so their poses differ)."""
    import json

    main(["--robots", "2", "--duration", "1", "--trace", str(tmp_path / "t.jsonl")])
    traces = [[json.loads(line) for line in (tmp_path / f"t_{name}.jsonl").read_text().splitlines()]
              for name in ("robot1", "robot2")]
    assert all(len(t) >= 9 for t in traces)
    assert traces[0][-1]["pose"] != traces[1][-1]["pose"]
