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
