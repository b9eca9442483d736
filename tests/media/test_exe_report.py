"""``report.html`` of an ``--exe`` grid, from made-up rows around a real bag (lock-step; no DDS, no node).

Three runs: one passed and one failed, each with a copy of the session's mission bag, and one whose node crashed
before a bag was recorded (it gets a picture of its world alone, saying why). The grid is reported with
``record="failures"``, as ``bt-nav grade --exe --record failures`` would: the passed run's bag goes once its
picture exists, the failed run keeps its bag and gets a video.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.html import rate_colour
from bt_nav.grading.media import FPS, balanced, distance_histogram, travelled_requirement, turns_figure
from bt_nav.grading.report import write_exe_report
from bt_nav.media.bagread import read_bag
from tests.media.reportkit import broken_links, mp4_frames, page_links

T0 = 5.0  # the made-up judge's t0 (sim s): the failed run's video starts there
COMMAND = "python3 my_node.py <fast>"  # a command with HTML in it


def _verdict(passed: bool, travelled: float) -> dict[str, Any]:
    return {"passed": passed, "travelled": travelled, "t0_sim": T0, "collisions": 0, "collision_events": [],
            "checks": [{"name": "minimum travelled distance", "passed": passed, "value": travelled, "required": 8.0},
                       {"name": "no collision", "passed": True, "value": 0, "required": 0}]}


def _row(out: Path, bag: Path | None, seed: int, passed: bool, verdict: dict[str, Any] | None,
         reason: str) -> dict[str, Any]:
    run_dir = out / f"stage_4_none_seed{seed}"
    run_dir.mkdir(parents=True)
    for name in ("node.log", "sim.log", "referee.log", "record.log"):
        (run_dir / name).write_text(f"{name} of seed {seed}\n")
    if verdict is not None:
        (run_dir / "verdict.json").write_text(json.dumps(verdict))
    if bag is not None:
        shutil.copytree(bag, run_dir / "bag")
    row = {"job": f"stage_4|none|{seed}", "world": "stage_4", "maneuver": "none", "seed": seed, "passed": passed,
           "outcome": "verdict" if verdict else "node exited", "reason": reason, "verdict": verdict,
           "run_dir": str(run_dir), "wall_time": 14.2, "bag": "bag" if bag else None,
           "bag_bytes": 1 if bag else 0}
    (run_dir / "result.json").write_text(json.dumps(row))
    return row


@pytest.fixture(scope="module")
def grid(mission_bag: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The three runs reported once (``record="failures"``, ``videos="failures"``)."""
    out = tmp_path_factory.mktemp("exe") / "grid"
    rows = [_row(out, mission_bag, 0, True, _verdict(True, 8.6), "passed"),
            {**_row(out, mission_bag, 1, False, _verdict(False, 7.4), "failed: minimum travelled distance"),
             "bag_after_t0_s": 2.5},
            _row(out, None, 2, False, None, "the node exited with code 1 after 1.2 s wall, before the verdict")]
    settings = ExeSettings(COMMAND, "homework", out, limit=150.0, rtf=5.0, record="failures", videos="failures")
    write_exe_report(rows, settings, workers=2)
    doc = json.loads((out / "grade.json").read_text())
    return {"out": out, "rows": rows, "settings": settings, "doc": doc,
            "media": {r["seed"]: r["media"] for r in doc["runs"]}, "page": out / "report.html"}


def test_every_link_of_the_page_is_relative_and_resolves(grid: dict[str, Any]) -> None:
    page = grid["page"]
    assert not broken_links(page), broken_links(page)
    links = page_links(page)
    assert "distance.png" in links
    for seed in (0, 1, 2):
        run = f"stage_4_none_seed{seed}"
        assert {f"{run}/node.log", f"{run}/result.json"} <= set(links), f"{run}'s files are not linked"
    assert "stage_4_none_seed1/bag" in links and "stage_4_none_seed0/bag" not in links, "only the failure's bag"


def test_the_page_moves_with_its_directory(grid: dict[str, Any], tmp_path: Path) -> None:
    """Zipped and unpacked elsewhere (here: copied), every link still resolves."""
    copy = tmp_path / "unzipped"
    shutil.copytree(grid["out"], copy)
    assert not broken_links(copy / "report.html")
    assert len(page_links(copy / "report.html")) == len(page_links(grid["page"]))


def test_the_page_says_the_grade(grid: dict[str, Any]) -> None:
    text = grid["page"].read_text()
    assert "1/3 passed (33.3 %)" in text
    assert "python3 my_node.py &lt;fast&gt;" in text and "<fast>" not in text, "the command is escaped"
    assert "homework" in text and "5x" in text and "150 s wall" in text
    assert f'background: {rate_colour(1, 3)}' in text and "1/3 (33 %)" in text, "the coloured pass-rate cell"
    assert text.count('class="FAILED"') == 2 and text.count('class="PASSED"') == 1
    assert "failed: minimum travelled distance" in text and 'href="#stage_4_none_seed1"' in text
    assert "no bag: the node ended before the simulator recorded; the world only" in text, \
        "the crashed run says why its picture has no path"
    assert text.count("bag from t0 + ") == 1 and "bag from t0 + 2.5 s" in text, "a late bag says so"


def test_each_run_with_a_bag_has_its_picture_and_only_failures_a_video(grid: dict[str, Any]) -> None:
    out, media = grid["out"], grid["media"]
    for seed in (0, 1):
        png = out / f"stage_4_none_seed{seed}" / "trajectory.png"
        assert media[seed]["picture"] == "trajectory.png" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert png.stat().st_size > 20_000, "a picture of the world and a path, not an empty canvas"
    assert media[0]["video"] is None and not (out / "stage_4_none_seed0" / "video.mp4").exists()
    crashed = media[2]
    assert crashed["picture"] == "trajectory.png" and crashed["video"] is None, crashed
    assert crashed["note"].startswith("no bag: the node ended before the simulator recorded"), crashed
    assert (out / "stage_4_none_seed2" / "trajectory.png").stat().st_size > 10_000, "the world, drawn"


def test_the_failed_run_s_video_starts_at_the_judge_s_t0(grid: dict[str, Any], mission_bag: Path) -> None:
    video = grid["out"] / "stage_4_none_seed1" / "video.mp4"
    frames, size = mp4_frames(video)
    record = read_bag(mission_bag)
    assert size == (1280, 720)
    assert frames == grid["media"][1]["frames"] == round((record.end - T0) * FPS), \
        "one frame per 1/FPS s from t0 to the bag's end (not from its first message)"
    assert frames < round((record.end - record.origin) * FPS)


def test_record_failures_keeps_only_the_failed_runs_bags(grid: dict[str, Any]) -> None:
    assert not (grid["out"] / "stage_4_none_seed0" / "bag").exists()
    assert (grid["out"] / "stage_4_none_seed1" / "bag" / "metadata.yaml").is_file()


def test_a_report_made_again_draws_nothing_again(grid: dict[str, Any]) -> None:
    video = grid["out"] / "stage_4_none_seed1" / "video.mp4"
    before = video.stat().st_mtime_ns
    write_exe_report(grid["rows"], grid["settings"])
    again = {r["seed"]: r["media"] for r in json.loads((grid["out"] / "grade.json").read_text())["runs"]}
    assert again[0]["note"] == again[1]["note"] == "drawn before"
    assert again[0]["picture"] == "trajectory.png" and again[1]["video"] == "video.mp4"
    assert video.stat().st_mtime_ns == before


def test_the_histogram_marks_the_judge_s_requirement(grid: dict[str, Any], tmp_path: Path) -> None:
    rows = grid["rows"]
    assert travelled_requirement(rows) == 8.0
    assert travelled_requirement([rows[2]]) is None, "a run without a verdict requires nothing"
    assert distance_histogram([rows[2]], tmp_path / "none.png") is None and not (tmp_path / "none.png").exists()
    assert (grid["out"] / "distance.png").stat().st_size > 10_000
    assert grid["doc"]["figures"] == ["distance.png"], "no lab turns figure for the homework"


def test_the_lab_gets_its_turns_figure(tmp_path: Path) -> None:
    turns = [{"passed": True}, {"passed": False}, {"passed": True}]
    row = {"world": "lab_object", "maneuver": "A", "seed": 0, "passed": False,
           "verdict": {"passed": False, "travelled": 3.0, "maneuvers": turns, "checks": []}}
    assert turns_figure([row], tmp_path / "turns.png") == tmp_path / "turns.png"
    assert (tmp_path / "turns.png").stat().st_size > 5_000
    assert turns_figure([{**row, "verdict": _verdict(True, 8.0)}], tmp_path / "no.png") is None


def test_recording_off_says_so(tmp_path: Path) -> None:
    out = tmp_path / "grid"
    row = _row(out, None, 0, True, _verdict(True, 8.6), "passed")
    del row["bag_bytes"]
    write_exe_report([row], ExeSettings("node", "homework", out, record="off", videos="off"))
    assert "no picture: no bag (recording off)" in (out / "report.html").read_text()
    assert not broken_links(out / "report.html")


def test_an_unreadable_bag_leaves_a_note_not_a_broken_report(grid: dict[str, Any], tmp_path: Path) -> None:
    out = tmp_path / "grid"
    rows = [_row(out, grid["out"] / "stage_4_none_seed1" / "bag", 0, False, _verdict(False, 7.0), "failed"),
            _row(out, grid["out"] / "stage_4_none_seed1" / "bag", 1, False, _verdict(False, 7.0), "failed")]
    for mcap in (out / "stage_4_none_seed1" / "bag").glob("*.mcap"):
        mcap.write_bytes(b"not a bag at all")
    write_exe_report(rows, ExeSettings("node", "homework", out), workers=2)  # two drawing processes
    media = {r["seed"]: r["media"] for r in json.loads((out / "grade.json").read_text())["runs"]}
    assert media[0]["picture"] == "trajectory.png" and media[0]["video"] == "video.mp4"
    assert media[1]["picture"] is None and media[1]["note"].startswith("bag unreadable"), media[1]
    assert "no picture: bag unreadable" in (out / "report.html").read_text()
    assert not broken_links(out / "report.html")


def test_pass_rate_colours_run_from_red_to_green() -> None:
    assert rate_colour(0, 4) == "hsl(0, 65%, 82%)"
    assert rate_colour(4, 4) == "hsl(120, 65%, 82%)"
    assert rate_colour(1, 2) == "hsl(60, 65%, 82%)"


def test_a_browser_shows_every_picture_and_plays_the_video(grid: dict[str, Any]) -> None:
    """Debian's chromium (as tests/ros/test_view_browser.py drives it) opens the page from disk: no broken image,
    and the failed run's video decodes (duration and size known)."""
    from playwright.sync_api import sync_playwright

    chromium = "/usr/bin/chromium"
    assert Path(chromium).is_file(), "Debian's chromium is missing: apt-get install -y chromium (make test does)"
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium, headless=True,
                                     args=["--headless", "--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page()
            page.goto(grid["page"].as_uri())
            page.evaluate("document.querySelectorAll('img').forEach(i => i.loading = 'eager');"
                          "document.querySelectorAll('video').forEach(v => { v.preload = 'auto'; v.load(); })")
            page.wait_for_function("Array.from(document.images).every(i => i.complete)"
                                   " && Array.from(document.querySelectorAll('video')).every(v => v.readyState >= 1"
                                   " || v.error)", timeout=60_000)
            images = page.evaluate("Array.from(document.images).map(i => [i.getAttribute('src'), i.naturalWidth])")
            videos = page.evaluate("Array.from(document.querySelectorAll('video')).map(v => [v.getAttribute('src'),"
                                   " v.videoWidth, v.duration, v.error && v.error.code])")
        finally:
            browser.close()
    assert len(images) == 4 and all(width > 0 for _, width in images), images  # histogram + three thumbnails
    assert [(src, width, err) for src, width, _, err in videos] == [("stage_4_none_seed1/video.mp4", 1280, None)]
    assert videos[0][2] == pytest.approx(grid["media"][1]["frames"] / FPS, abs=0.2)


def test_the_videos_are_shared_out_between_the_drawing_processes() -> None:
    tasks = [({"job": str(k)}, k in (0, 2), True) for k in range(6)]  # two films among six runs
    chunks = balanced(tasks, 2)
    assert sorted(len([t for t in c if t[1]]) for c in chunks) == [1, 1], "one film per process"
    assert sorted(t[0]["job"] for c in chunks for t in c) == [str(k) for k in range(6)]
    assert balanced(tasks[:1], 2) == [[tasks[0]]], "no empty process"


def test_the_drawer_draws_ended_runs_while_the_grid_runs(mission_bag: Path, tmp_path: Path) -> None:
    """A :class:`Drawer` draws a passed run's picture in its worker (a failed run to be filmed is left to the report),
    then the grid's figures; the report takes both as they are and draws only the rest."""
    from bt_nav.grading.media import PICTURE, Drawer

    out = tmp_path / "grid"
    passed = _row(out, mission_bag, 0, True, _verdict(True, 8.6), "passed")
    failed = _row(out, mission_bag, 1, False, _verdict(False, 7.4), "failed: minimum travelled distance")
    # a stall far beyond any machine's load: this test is the flow; a starved worker is the next test's
    drawer = Drawer(videos="failures", record="failures", stall=600.0)
    drawer.submit(passed)
    drawer.submit(failed)
    assert drawer.sent == 1, "the run to be filmed waits for the report"
    drawn = drawer.finish(figures=([passed, failed], out))
    assert drawn[passed["job"]]["picture"] == PICTURE and drawn[passed["job"]]["picture_s"] > 0
    assert not (Path(passed["run_dir"]) / "bag").exists(), "record=failures: a passed run's bag goes with its picture"
    assert drawn["figures"]["names"] == ["distance.png"] and (out / "distance.png").is_file()
    assert not (Path(failed["run_dir"]) / PICTURE).exists()
    settings = ExeSettings(COMMAND, "homework", out, limit=150.0, rtf=5.0, record="failures", videos="failures")
    write_exe_report([passed, failed], settings, workers=1, drawn=drawn)
    media = {r["seed"]: r["media"] for r in json.loads((out / "grade.json").read_text())["runs"]}
    assert media[0] == drawn[passed["job"]], "the drawer's picture is the report's"
    assert media[1]["picture"] == PICTURE and media[1]["video"], "the report drew and filmed the failure"


def test_a_starved_drawer_never_holds_the_grid_and_the_report_draws_the_rest(mission_bag: Path,
                                                                               tmp_path: Path) -> None:
    """A worker that gets no CPU (stopped here, as nice 19 is under two busy loops) holds neither the grid's threads
    (a submit returns at once, more than a pipe's worth of tasks included) nor the report for longer than ``stall``
    seconds; the report then draws every picture itself."""
    import signal
    import time

    from bt_nav.grading.media import PICTURE, Drawer

    out = tmp_path / "grid"
    rows = [_row(out, mission_bag, seed, True, _verdict(True, 8.6), "passed") for seed in range(2)]
    drawer = Drawer(videos="failures", record="on", stall=0.5)
    drawer.submit(rows[0])
    assert drawer.proc is not None
    os.kill(drawer.proc.pid, signal.SIGSTOP)
    bulky = {**rows[1], "padding": "x" * 200_000}  # more than a pipe holds: a blocking write would hang here
    began = time.monotonic()
    drawer.submit(bulky)
    drawer.submit(rows[1])
    assert time.monotonic() - began < 0.5, "submit waited for the worker"
    drawn = drawer.finish(figures=(rows, out))
    assert time.monotonic() - began < 5.0, "finish waited for a starved worker"
    assert drawn == {} and drawer.proc.poll() is not None, "the starved worker was stopped, nothing taken from it"
    settings = ExeSettings(COMMAND, "homework", out, limit=150.0, rtf=5.0, record="on", videos="failures")
    write_exe_report(rows, settings, workers=1, drawn=drawn)
    for row in rows:
        assert (Path(row["run_dir"]) / PICTURE).stat().st_size > 1000, "the report drew it, whole"
    assert not list(out.rglob("*.partial")), "no half-written picture left"


@pytest.mark.parametrize(("name", "written"), [("t.svg", "t.svg"), ("t", "t.png"), ("t.", "t.png"), ("t.eps", "t.eps")])
def test_a_figure_is_written_whole_under_its_name(name: str, written: str, tmp_path: Path) -> None:
    """save_figure writes through a temporary name: the format from the suffix (none: matplotlib's default, added to
    the name, as matplotlib does), no temporary file or name left behind."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bt_nav.media.plot import save_figure

    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    try:
        assert save_figure(fig, tmp_path / "d" / name) == tmp_path / "d" / written
    finally:
        plt.close(fig)
    assert [p.name for p in (tmp_path / "d").iterdir()] == [written]
    assert b"partial" not in (tmp_path / "d" / written).read_bytes()
