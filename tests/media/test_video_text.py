"""A lab video's frames against the bag they were made from (issue 20, item 6): each frame's text is the bag's
own at that instant on one time base, scans are placed from the pose at their stamp, and the console shows the
lab terminal's lines without diagnostics."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_nav.cli.video import main as video_main
from bt_nav.media.bag import MissionBag
from bt_nav.media.bagread import MissionRecord, read_bag
from bt_nav.media.console import console_shows
from bt_nav.media.video import (
    MAP_W,
    TIME_BASE,
    VideoRenderer,
    live_feedback,
    shown_feedback,
    world_of,
)
from bt_nav.mission.snapshot import DEADLINE_LEFT, TO_GO, SnapshotNode, snapshot_nodes
from bt_nav.run.lockstep import run_mission

LAB = {"world": "lab_object", "maneuver": "C", "seed": 0, "profile": "lab"}
DURATION = 22.0  # sim s: armed at 5 s, maneuver C fires near 18 s in front of the object and ends near 20 s


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """A short lock-step lab run (lab_object, C) written into a bag, read back."""
    path = tmp_path_factory.mktemp("lab") / "bag"
    with MissionBag(path, mission=LAB) as bag:
        result = run_mission(LAB["world"], LAB["maneuver"], LAB["seed"], profile=LAB["profile"], duration=DURATION,
                             sink=bag)
        bag.event(result.sim_time, "verdict: end of the test's window")
    rec = read_bag(path)
    return {"path": path, "rec": rec, "world": world_of(rec)}


def _maneuver(rec: MissionRecord) -> tuple[float, float]:
    """Start and end (bag time) of the first maneuver, from the tree snapshots: SmartPivot RUNNING."""
    running = [t for t, snap in rec.trees if any(n.name == "SmartPivot" and n.status == "RUNNING"
                                                 for n in snapshot_nodes(snap))]
    assert running, "maneuver C never ran in the lab run"
    after = [t for t, _ in rec.trees if t > running[0] and t not in running]
    return running[0], after[0] if after else rec.end


def _expected(rec: MissionRecord, t: float) -> tuple[str, str, str]:
    """(branch, tip, tip's feedback as written) of the bag's last snapshot at or before ``t``, read directly."""
    snapshot = [s for st, s in rec.trees if st <= t][-1]
    rows, path = snapshot_nodes(snapshot), snapshot["path"]
    priorities = next(i for i in path if rows[i].name == "Priorities")
    branch = rows[path[path.index(priorities) + 1]].name
    tip = rows[path[-1]]
    return branch, tip.name, tip.feedback if tip.status != "INVALID" else ""


def test_frame_text_is_the_bags_at_that_instant(lab: dict) -> None:
    rec: MissionRecord = lab["rec"]
    start, end = _maneuver(rec)
    renderer = VideoRenderer(rec, lab["world"])
    seen = set()
    for clock in (1.0, 10.0, start + 0.05, (start + end) / 2, end - 0.1, end + 0.5, DURATION - 0.5):  # armed at 2 s
        text = renderer.text(rec.origin + clock)
        branch, tip, feedback = _expected(rec, rec.origin + clock)
        assert text.clock == pytest.approx(clock)
        assert (text.branch, text.tip, text.feedback) == (branch, tip, feedback), clock
        assert text.deadline == "no deadline" and "left" not in " ".join(text.lines())  # the lab has no deadline
        head, detail = text.lines()
        assert head.startswith(f"t = {clock:.2f} s {TIME_BASE}")
        assert detail.startswith(tip if branch.endswith(tip) else f"{branch} > {tip}")
        assert not feedback or f": {feedback}" in detail
        seen.add(branch)
    assert {"Disarmed", "Lab", "ManeuverC_SmartPivot"} <= seen
    mid = renderer.text(rec.origin + (start + end) / 2)
    assert mid.turned is not None and abs(mid.turned) > 10  # live, from ground truth, during the turn
    assert renderer.text(rec.origin + end + 0.5).turned is None  # over: no turn is shown any more
    assert "SmartPivot" not in renderer.text(rec.origin + end + 0.5).lines()[1]  # no stale maneuver text


def _caption(renderer: VideoRenderer, lines: tuple[str, str]) -> np.ndarray:
    """The caption strip drawn from ``lines`` alone, as the frame draws it."""
    from PIL import Image, ImageDraw

    img = Image.new("RGB", (MAP_W + 1, 47), (255, 255, 255))
    d = ImageDraw.Draw(img)
    d.text((10, 4), lines[0], font=renderer.font, fill=(30, 30, 30))
    d.text((10, 25), lines[1][:90], font=renderer.mono, fill=(70, 70, 90))
    return np.asarray(img)


def test_the_still_at_t_shows_t_and_draws_that_text(lab: dict, tmp_path: Path) -> None:
    """``--still --at T`` is the frame whose clock reads T; its caption is exactly the text computed for T."""
    from PIL import Image

    rec: MissionRecord = lab["rec"]
    start, end = _maneuver(rec)
    clock = round((start + end) / 2 - rec.origin, 2)
    still = tmp_path / "still.png"
    assert video_main([str(lab["path"]), "--no-video", "--still", str(still), "--at", str(clock)]) == 0
    picture = np.asarray(Image.open(still).convert("RGB"))
    renderer = VideoRenderer(rec, lab["world"])
    text = renderer.text(rec.origin + clock)
    assert text.clock == pytest.approx(clock)
    np.testing.assert_array_equal(picture[:47, :MAP_W + 1], _caption(renderer, text.lines()))
    other = renderer.text(rec.origin + clock + 1.0).lines()
    assert not np.array_equal(picture[:47, :MAP_W + 1], _caption(renderer, other))  # the comparison can fail


def _distance_to_world(world, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Each point's distance to the nearest wall segment or circle of ``world``."""
    p = np.column_stack([xs, ys])[:, None, :]
    seg = np.asarray(world.segments, dtype=float)
    a, b = seg[None, :, :2], seg[None, :, 2:]
    ab = b - a
    u = np.clip(((p - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
    best = np.linalg.norm(p - (a + u[..., None] * ab), axis=-1).min(axis=1)
    for cx, cy, r in np.asarray(world.circles, dtype=float).reshape(-1, 3):
        best = np.minimum(best, np.abs(np.hypot(xs - cx, ys - cy) - r))
    return best


def test_scan_points_land_on_the_walls_during_a_spin(lab: dict) -> None:
    """Drawn from the pose at the scan's stamp, the returns sit on the walls while the robot spins; drawn from the
    pose of a frame 0.15 s later (what the video did) a good share of them misses."""
    rec: MissionRecord = lab["rec"]
    world, truth = lab["world"], rec.truth
    spinning = [t for t in rec.scans.t if abs(np.interp(t, truth.t, truth.w)) > 0.8]
    assert len(spinning) >= 3, "no scan taken while the robot spun"
    on, off = [], []
    for stamp in spinning:
        _, xs, ys = rec.scan_at(float(stamp))
        on.append(np.mean(_distance_to_world(world, xs, ys) < 0.05))
        later = truth.at(float(stamp) + 0.15)  # the frame's pose, not the scan's
        k = int(np.searchsorted(rec.scans.t, stamp, side="right")) - 1
        r = rec.scans.ranges[k]
        ok = np.isfinite(r) & (r < rec.scans.range_max)
        a = rec.scans.angles[ok] + later[2]
        off.append(np.mean(_distance_to_world(world, later[0] + r[ok] * np.cos(a), later[1] + r[ok] * np.sin(a))
                           < 0.05))
    assert min(on) > 0.9, on
    assert np.mean(off) < np.mean(on) - 0.2, (on, off)


@pytest.mark.parametrize(("line", "shown"), [
    ("[INFO] Randomizer: front 0.49 m: turning right 143 deg", True),
    ("[INFO] Randomizer: done: turned -142.6 deg", True),
    ("[WARN] AEB: path blocked 0.12 m ahead: emergency stop", True),
    ("[INFO] referee: activate(true) -> True: armed at t=5.00 s", True),
    ("[INFO] ros2 service call /toggle_navigation std_srvs/srv/SetBool '{data: true}'", True),
    ("[INFO] [launch]: All log files can be found below /root/.ros/log", True),
    ("verdict: PASSED", True),
    ("[INFO] stats: tick ms mean 0.41 p99 1.2 max 3.0; faults 0", False),
    ("[INFO] final stats: tick ms mean 0.41; faults 0", False),
    ("[INFO] ProcessScan: ok — scan usable again", False),
    ("[WARN] ProcessScan: front sector unknown (3 of 40 beams)", False),
    ("[DEBUG] anything at all", False),
    ("[INFO] [bt_nav_executive]: Randomizer: front 0.49 m: turning right 143 deg", True),
    ("[WARN] [bt_nav_executive]: AEB: path blocked 0.12 m ahead: emergency stop", True),
    ("[INFO] [bt_nav_executive]: stats: tick ms mean 0.41 p99 1.2 max 3.0; faults 0", False),
    ("[INFO] [bt_nav_executive]: ProcessScan: ok — scan usable again", False),
])
def test_console_rule(line: str, shown: bool) -> None:
    assert console_shows(line) is shown


def test_the_lab_console_keeps_the_terminals_lines(lab: dict) -> None:
    rec: MissionRecord = lab["rec"]
    shown = [text for _, text in VideoRenderer(rec, lab["world"]).events]
    assert any("SmartPivot:" in line and "turning" in line for line in shown)
    assert any("activate(true)" in line for line in shown) and shown[-1].startswith("verdict")
    assert any("ProcessScan" in text for _, text in rec.events)  # in the bag, not on the console
    assert not any("ProcessScan" in line for line in shown)


def _row(feedback: str, data: dict | None = None, status: str = "RUNNING") -> SnapshotNode:
    return SnapshotNode("Leaf", "leaf", status, feedback, 3, 2, data or {})


def test_feedback_rules() -> None:
    """Countdowns are counted from the figures the leaf put in the snapshot (``data``), never from the words."""
    assert live_feedback(_row("16.2 s left", {DEADLINE_LEFT: 16.2}), 0.5, 0.0) == "15.7 s left"
    assert live_feedback(_row("3.0 s left", {DEADLINE_LEFT: 3.0}), 5.0, 0.0) == "0.0 s left"
    assert live_feedback(_row("+158 deg to go", {TO_GO: 158.0}), 0.5, 60.0) == "+98 deg to go"
    assert live_feedback(_row("-90 deg to go", {TO_GO: -90.0}), 0.5, -30.0) == "-60 deg to go"
    assert live_feedback(_row("creeping at 0.05 m/s"), 9.0, 40.0) == "creeping at 0.05 m/s"
    assert live_feedback(_row("+158 deg to go"), 0.5, 60.0) == "+158 deg to go", "words alone are not a figure"
    assert live_feedback(_row("+158 deg to go", {TO_GO: 158.0}, "INVALID"), 0.5, 60.0) == ""
    finished = SnapshotNode("SmartPivot", "leaf", "INVALID", "+158 deg to go", 3, 2)
    assert shown_feedback(finished) == ""
    assert shown_feedback(SnapshotNode("SmartPivot", "leaf", "RUNNING", "+158 deg to go", 3, 2)) == "+158 deg to go"
    assert shown_feedback(SnapshotNode("DeadlineReached?", "leaf", "FAILURE", "16.2 s left", 3, 2)) == "16.2 s left"


def test_a_lockstep_bag_holds_the_maneuvers_events(lab: dict) -> None:
    """The engine writes the executive's ``~/events`` too: each maneuver with its fields, at its sim time."""
    rec: MissionRecord = lab["rec"]
    assert rec.announcements, "maneuver C ran: its event is in the bag"
    starts = [(t, record) for t, record in rec.announcements if record["event"] == "maneuver"]
    assert starts and all(t == pytest.approx(record["t"]) for t, record in rec.announcements)
    for _, record in starts:
        assert record["leaf"] == "SmartPivot" and record["maneuver"] == "C"
        assert record["angle_deg"] == 90.0 and record["side"] in ("left", "right")
