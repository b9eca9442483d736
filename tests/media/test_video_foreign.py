"""The video of a robot node that is not bt_nav's (no tree): the caption says what the robot does, the side panel
shows its command and its own log lines."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bt_nav.media.bag import MissionBag
from bt_nav.media.bagread import read_bag
from bt_nav.media.video import VideoRenderer, motion_text, node_lines


def _pivot_bag(path: Path) -> None:
    """A node drives 5 s, stops, then pivots left for 3 s; it logs its own lines, the judge logs one."""
    with MissionBag(path, mission={"world": "lab_object", "profile": "lab"}) as bag:
        yaw = 0.0
        for k in range(240):
            t = k * 0.05
            v, w = (0.1, 0.0) if t < 5 else ((0.0, 0.5) if t < 8 else (0.0, 0.0))
            yaw += w * 0.05
            bag.clock(t)
            bag.ground_truth(t, 0.1 * min(t, 5.0), 0.0, yaw, v, w)
            bag.cmd(t, v, w)
            if k == 100:
                bag.event(t, "[INFO] lab_node: obstacle at 0.30 m: turning left 90 deg")
                bag.event(t, "[INFO] checkoff: sim 5.00 s: toggle_navigation(true) sent")


def test_caption_and_panel_of_a_node_without_a_tree(tmp_path: Path) -> None:
    _pivot_bag(tmp_path / "bag")
    renderer = VideoRenderer(read_bag(tmp_path / "bag"))
    assert renderer.text(2.0).lines()[1] == "robot driving 0.10 m/s; cmd_vel driving 0.10 m/s"
    assert renderer.text(6.5).lines()[1] == "robot turning left 0.50 rad/s; cmd_vel turning left 0.50 rad/s"
    assert "Stopped" not in renderer.text(6.5).lines()[1]
    assert renderer.text(10.0).lines()[1] == "robot stopped; cmd_vel stopped"
    assert [text for _, text in node_lines(renderer.rec.events)] == [
        "[INFO] lab_node: obstacle at 0.30 m: turning left 90 deg"]  # the judge's line is not the node's
    before, during = (np.asarray(renderer._tree_panel(t)) for t in (4.0, 6.5))
    assert not np.array_equal(before, during)  # the panel follows the command and the node's lines
    assert renderer._tree_panel(6.5) is renderer._tree_panel(6.5)  # cached while nothing changes


def test_motion_in_words() -> None:
    assert motion_text(0.0, -0.3) == "turning right 0.30 rad/s"
    assert motion_text(0.05, 0.3) == "driving 0.05 m/s, turning left 0.30 rad/s"
    assert motion_text(-0.1, 0.0) == "reversing 0.10 m/s"
    assert motion_text(0.001, 0.002) == "stopped"
