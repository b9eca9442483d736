"""The mission video: an H.264 yuv420p MP4 with duration x fps frames, and frames that show the mission."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_nav.cli.video import main as video_main
from bt_nav.media.bagread import read_bag
from bt_nav.media.video import MAP_H, MAP_W, VideoRenderer, frame_times, world_of


def test_mp4_is_h264_yuv420p_with_duration_times_fps_frames(mission_bag: Path, tmp_path: Path) -> None:
    import imageio_ffmpeg

    out = tmp_path / "mission.mp4"
    assert video_main([str(mission_bag), "-o", str(out), "--fps", "5"]) == 0
    rec = read_bag(mission_bag)
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == round(rec.duration * 5) == len(frame_times(rec, 5))
    reader = imageio_ffmpeg.read_frames(str(out))
    meta = next(reader)
    reader.close()
    assert meta["codec"].startswith("h264") and meta["pix_fmt"].startswith("yuv420p")
    assert tuple(meta["size"]) == (1280, 720)


def test_robot_moves_between_frames_and_panels_change(mission_bag: Path) -> None:
    rec = read_bag(mission_bag)
    renderer = VideoRenderer(rec, world_of(rec))
    early = np.asarray(renderer.frame(2.0))
    late = np.asarray(renderer.frame(11.0))
    map_diff = np.abs(early[46:MAP_H, :MAP_W].astype(int) - late[46:MAP_H, :MAP_W]).sum(axis=2) > 0
    assert map_diff.sum() > 500  # the robot, its scan and the trail moved
    console_early, console_late = early[MAP_H:], late[MAP_H:]
    assert not np.array_equal(console_early, console_late)  # the arm lines appeared at 5 s
    assert not np.array_equal(early[:MAP_H, MAP_W + 2:], late[:MAP_H, MAP_W + 2:])  # the tree changed


def test_still_and_plot_from_a_bag(mission_bag: Path, tmp_path: Path) -> None:
    still, plot = tmp_path / "still.png", tmp_path / "plot.png"
    assert video_main([str(mission_bag), "--no-video", "--still", str(still), "--at", "8", "--plot", str(plot)]) == 0
    assert still.stat().st_size > 10_000 and plot.stat().st_size > 10_000


@pytest.mark.parametrize("content", [b"", b"garbage" * 100])
def test_bad_bag_exits_2_naming_the_file(tmp_path: Path, content: bytes, capsys: pytest.CaptureFixture) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(content)
    assert video_main([str(bad), "-o", str(tmp_path / "x.mp4")]) == 2
    assert "bad.mcap" in capsys.readouterr().err
    assert not (tmp_path / "x.mp4").exists()


def test_a_scripted_console_is_drawn_and_recorded_frame_by_frame(mission_bag: Path, tmp_path: Path) -> None:
    """A hand-in's console (a script: pinned head, lines in time order on the sim clock): the sidecar lists, per frame
    of the MP4, the rows drawn; each frame read back has ink in its console and the simulation label."""
    import imageio_ffmpeg

    from bt_nav.media.console import ConsoleScript, console_log_path, read_console_log
    from bt_nav.media.video import CONSOLE_BG, CONSOLE_Y, write_video

    rec = read_bag(mission_bag)
    script = ConsoleScript(("$ python3 node.py --ros-args -p maneuver:=C", "# stands in for: ros2 launch p f.py"),
                           ((6.0, "[INFO] [node]: later"), (1.0, "[INFO] [node]: started")))
    out = tmp_path / "handin.mp4"
    stats = write_video(rec, out, 5.0, world_of(rec), script=script, console_log=console_log_path(out))
    frames = read_console_log(tmp_path / "handin.console.json")
    assert len(frames) == stats.frames == imageio_ffmpeg.count_frames_and_secs(str(out))[0]
    assert all(rows[:2] == list(script.head) for _, rows in frames)
    assert [rows[2:] for t, rows in frames if t >= 6.0][0] == ["[sim   1.00 s] [INFO] [node]: started",
                                                               "[sim   6.00 s] [INFO] [node]: later"]
    assert all(len(rows) == 2 for t, rows in frames if t < 1.0)
    reader = imageio_ffmpeg.read_frames(str(out))
    width, height = next(reader)["size"]
    for raw in reader:
        img = np.frombuffer(raw, np.uint8).reshape(height, width, 3).astype(int)
        assert (np.abs(img[CONSOLE_Y:] - CONSOLE_BG).sum(axis=2) > 120).mean() > 0.005  # text in the console
        label = img[MAP_H - 26:MAP_H - 2, 4:170]
        assert (label.sum(axis=2) < 450).mean() > 0.02  # "simulation (bt_nav)" in dark ink on its white box
