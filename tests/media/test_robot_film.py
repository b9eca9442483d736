"""``bt-nav video BAG`` of a robot's bag (no ground truth, no world file): a SIMULATED real-robot bag
(tests/media/robotsynth.py) filmed to an MP4 whose frames, decoded back, show the room built up from the scans, the
odometry path and the check-off's lines at their times, each frame saying where its data came from; and the
simulator's bag reader opening sqlite3 and ROS 1 bags through the one reader of those formats."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_nav.cli.video import main as video_main
from bt_nav.media.bagread import read_bag
from bt_nav.media.console import SIM_LABEL, read_console_log
from bt_nav.media.robotfilm import MAP_H, MAP_W, card_frames
from bt_nav.media.robotrun import (
    CLOCK_LABEL,
    GAZEBO_LABEL,
    REAL_LABEL,
    SYNTHETIC_LABEL,
    load_robot_run,
    source_label,
)
from tests.media.robotsynth import Effects, simulate, write_rosbag1, write_rosbag2

FPS = 5


@pytest.fixture(scope="module")
def synth_bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One simulated run (a 120 deg right turn: maneuver A's range) in the three formats."""
    root = tmp_path_factory.mktemp("robotfilm")
    run = simulate(effects=Effects(service_events=True))
    return {"sqlite3": write_rosbag2(run, root / "db3", "sqlite3", Effects(service_events=True)),
            "mcap": write_rosbag2(run, root / "mcap", "mcap", Effects(service_events=True)),
            "ros1": write_rosbag1(run, root / "run.bag")}


def _frames(path: Path) -> list[np.ndarray]:
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    w, h = meta["size"]
    frames = [np.frombuffer(f, dtype=np.uint8).reshape(h, w, 3) for f in reader]
    return frames


def _count(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 40) -> int:
    """Pixels of the map panel within ``tol`` of ``rgb`` in every channel."""
    region = img[46:MAP_H - 30, :MAP_W].astype(int)
    return int((np.abs(region - np.asarray(rgb)).max(axis=2) <= tol).sum())


def test_a_robot_bag_is_filmed_with_the_room_the_path_and_the_checkoff_lines(synth_bags: dict[str, Path],
                                                                             tmp_path: Path) -> None:
    out = tmp_path / "run.mp4"
    assert video_main([str(synth_bags["sqlite3"]), "-o", str(out), "--fps", str(FPS), "--maneuver", "A",
                       "--console-log"]) == 0
    frames = _frames(out)
    log = read_console_log(tmp_path / "run.console.json")
    assert len(frames) == len(log) > 100
    run = load_robot_run(synth_bags["sqlite3"], "A")
    # every frame says where its data came from
    assert all(rows[0] == SYNTHETIC_LABEL or rows[1].startswith(SYNTHETIC_LABEL + "; ")  # the card: its 2nd line
               for _, rows in log)
    # the maneuver's line appears when its turn settled, never before; the verdict only at the end
    settled = run.verdict["feed"]["t0"] + run.verdict["maneuvers"][0]["settled"] - run.origin
    assert run.verdict["maneuvers"][0]["passed"], run.lines
    first = [t for t, rows in log if any("maneuver 1 (" in r and r.endswith("PASSED") for r in rows)]
    assert first and settled - 1.0 / FPS <= first[0] <= settled + 1.0 / FPS
    held = card_frames(FPS)  # the verdict card: the film's last CARD_HOLD s, the verdict decided at its first
    assert held >= 3 * FPS
    assert not any("overall:" in r for _, rows in log[:-held - 1] for r in rows)
    assert all(any(r == "overall: PASSED" for r in rows) for _, rows in log[-held:])
    early, late = frames[2], frames[-held - 1]
    # the room grows from the scans (grey returns), the scan (red) is drawn, the path (blue) appears after moving
    assert _count(late, (150, 150, 150), 25) > 2 * _count(early, (150, 150, 150), 25) > 0
    assert _count(early, (230, 40, 40)) > 100 and _count(late, (230, 40, 40)) > 100
    assert _count(early, (31, 119, 180)) < 20 < 100 < _count(late, (31, 119, 180))
    # the check-off panel: empty of verdict colours before the maneuver ended, green lines after
    k_before, k_after = int((settled - 1.0) * FPS), int((settled + 1.0) * FPS)
    green = (30, 140, 50)
    panel = [f[40:MAP_H, MAP_W + 4:].astype(int) for f in (frames[k_before], frames[k_after])]
    counts = [int((np.abs(p - np.asarray(green)).max(axis=2) <= 40).sum()) for p in panel]
    assert counts[0] == 0 < 50 < counts[1]


@pytest.mark.parametrize("fmt", ["mcap", "ros1"])
def test_every_format_films_the_same_run(synth_bags: dict[str, Path], tmp_path: Path, fmt: str) -> None:
    still = tmp_path / "still.png"
    assert video_main([str(synth_bags[fmt]), "--no-video", "--still", str(still), "--at", "20"]) == 0
    from PIL import Image

    img = np.asarray(Image.open(still).convert("RGB"))
    assert _count(img, (31, 119, 180), 10) > 100 and _count(img, (150, 150, 150), 10) > 300


def test_the_source_label_and_the_simulators_reader_of_other_formats(synth_bags: dict[str, Path]) -> None:
    assert source_label({"/odom": "nav_msgs/msg/Odometry"}, None) == REAL_LABEL
    assert source_label({"/ground_truth_odom": "nav_msgs/msg/Odometry"}, None) == SIM_LABEL
    assert source_label({"/synthetic": "std_msgs/msg/String"}, "simulated") == SYNTHETIC_LABEL
    gazebo = {"/odom": "nav_msgs/msg/Odometry", "/clock": "rosgraph_msgs/msg/Clock",
              "/gazebo/model_states": "gazebo_msgs/msg/ModelStates"}
    assert source_label(gazebo, None) == GAZEBO_LABEL
    assert source_label({"/odom": "nav_msgs/msg/Odometry", "/clock": "rosgraph_msgs/msg/Clock"}, None) == CLOCK_LABEL
    counts = [read_bag(synth_bags[fmt]).counts for fmt in ("mcap", "sqlite3", "ros1")]
    for topic in ("/odom", "/scan", "/cmd_vel"):
        assert counts[0][topic] == counts[1][topic] == counts[2][topic] > 10


def test_a_maneuver_for_a_simulators_bag_and_an_unreadable_bag_are_refused(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture) -> None:
    (tmp_path / "junk.bag").write_bytes(b"not a bag")
    assert video_main([str(tmp_path / "junk.bag"), "-o", str(tmp_path / "x.mp4")]) == 2
    assert "junk.bag" in capsys.readouterr().err


def test_the_browser_view_plays_a_robot_bag_back(synth_bags: dict[str, Path]) -> None:
    """``bt-nav view --bag``'s scene of a robot's bag: the room as scanned is the page's world, the robot moves on
    its odometry, the source is the first log line and the check-off's lines appear once decided."""
    import http.client
    import json

    from bt_nav.cli.view import _bag
    from bt_nav.media.view import ViewServer

    args = type("Args", (), {"bag": str(synth_bags["ros1"]), "maneuver": "A", "node": None, "world": None,
                             "seed": None})()
    scene = _bag(args, [])
    srv = ViewServer(scene, "127.0.0.1", 0)
    srv.start()

    def call(method: str, path: str, body: bytes | None = None) -> dict:
        conn = http.client.HTTPConnection(*srv.server_address[:2], timeout=5)
        try:
            conn.request(method, path, body=body)
            return json.loads(conn.getresponse().read())
        finally:
            conn.close()

    try:
        world = call("GET", "/world")
        assert world["name"].startswith("the room as scanned") and len(world["circles"]) > 300
        start = scene.run.origin
        call("POST", "/control", json.dumps({"t": start + 2.0}).encode())
        early = call("GET", "/state")
        call("POST", "/control", json.dumps({"t": scene.run.end}).encode())
        late = call("GET", "/state")
    finally:
        srv.close()
        scene.close()
    assert early["events"][0] == late["events"][0] == SYNTHETIC_LABEL
    assert early["pose"] != late["pose"] and len(late["trail"]) > len(early["trail"]) and late["scan"]
    assert not any("check-off:" in e for e in early["events"])
    assert any("check-off: overall: PASSED" in e for e in late["events"])


def test_the_nodes_lines_at_info_and_above_repeats_folded_and_the_command_current_or_how_long_none() -> None:
    from bt_nav.judge.recorded import Recording
    from bt_nav.media.robotfilm import RobotFilmRenderer
    from bt_nav.media.robotrun import RobotRun
    from bt_nav.mission.scan import Scan

    scan = Scan(0.0, 6.0, 0.1, 0.0, 10.0, np.full(61, 1.0, dtype=np.float32))
    cycle = ["Getting front cone. angle=0.13rad", "Front cone indices: [{k}, 0, 1]"]
    log = [(0.1, 10, "node", "a DEBUG line")]
    log += [(0.2 + 0.1 * k, 20, "node", line.format(k=k)) for k in range(6) for line in cycle]
    log += [(1.0, 30, "node", "Wall detected"), (1.1, 20, "node", "Front cone indices: [9, 0, 1]")]
    rec = Recording([(t, 0.0, 0.0, 0.0) for t in np.arange(0.0, 5.0, 0.05)], [(0.0, scan), (4.9, scan)],
                    [(0.5, 0.1, 0.0), (1.0, 0.0, -0.3)], log=log)
    renderer = RobotFilmRenderer(RobotRun(Path("x"), rec, "real robot bag"))
    assert renderer.console_rows(1.2) == ["[   0.70] [node]: Getting front cone. angle=0.13rad (x6)",
                                          "[   1.00] [node]: Wall detected",
                                          "[   1.10] [node]: Front cone indices: [9, 0, 1] (x7)"]
    assert not any("DEBUG" in r for t in (0.15, 3.0) for r in renderer.console_rows(t))
    assert renderer.caption(0.2).endswith("no command yet")
    assert renderer.caption(1.3).endswith("cmd v +0.00 m/s  w -0.30 rad/s")
    assert renderer.caption(3.1).endswith("no command for 2.1 s (last: v +0.00 m/s  w -0.30 rad/s)")
    assert renderer.run.current_command(3.1) is None  # the robot is drawn with no command arrow
    assert "scale: 1 m" in renderer.texts(1.0) or "scale: 0.5 m" in renderer.texts(1.0)
