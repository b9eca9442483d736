"""The film of the two real TurtleBot3 recordings (Jacopo-oranneZ/SESASR-LAB, lab03_pkg/recordings/) checked frame by
frame from the texts each frame draws (:meth:`RobotFilmRenderer.texts`, what ``--console-log`` writes), and the
verdict card's layout against the frame's size. The bags are read where they lie (``BT_NAV_REALBAGS``; in CI a
missing folder fails, on a user's clone it skips), as in tests/media/test_realbags.py."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from bt_nav.media.console import ROW_CHARS
from bt_nav.media.robotfilm import (
    CARD_HOLD,
    CARD_MARGIN,
    HEIGHT,
    WIDTH,
    RobotFilmRenderer,
    card_layout,
    film_frames,
)
from bt_nav.media.robotrun import COMMAND_STALE, RobotRun, load_robot_run
from tests.media.test_realbags import ROOT

FPS = 5.0


def _run(name: str) -> RobotRun:
    path = ROOT / name
    if not path.is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"{path}: the real recordings are missing (CI has ../shared/realbags; set BT_NAV_REALBAGS)")
        pytest.skip(f"{path}: no real recordings here (set BT_NAV_REALBAGS)")
    return load_robot_run(Path(path), "C")


def _frames(run: RobotRun) -> tuple[RobotFilmRenderer, list[tuple[float, bool, list[str]]]]:
    """Each frame's time (s since t=0), whether it is the card, and every text it draws."""
    renderer = RobotFilmRenderer(run)
    return renderer, [(t - run.origin, card, renderer.texts(t, card)) for t, card in film_frames(run, FPS)]


@pytest.mark.parametrize(("name", "overall"), [("sesasr_tb3_lab03_1653", "FAILED"),
                                               ("sesasr_tb3_lab03_1700", "PASSED")])
def test_the_film_ends_on_the_whole_verdict_held_3_s(name: str, overall: str) -> None:
    run = _run(name)
    renderer, frames = _frames(run)
    held = [f for f in frames if f[1]]
    assert len(held) / FPS >= 3.0 and len(held) == round(CARD_HOLD * FPS) and frames[-len(held):] == held
    assert not any(r.startswith("overall:") for _, card, rows in frames if not card for r in rows[:-9])
    for _, _, rows in held:  # every line of the report, in the terminal's order, the overall verdict last
        body = [r.strip() for r in rows]
        assert body[1].startswith(f"{run.source}; t=0: the first /odom, /scan or /cmd_vel message")
        assert body[0].endswith(f": overall: {overall}") and body[-1] == f"overall: {overall}"
        joined = " ".join(body)
        assert all(" ".join(line.split()) in " ".join(joined.split()) for line in run.report)
    rows, size = card_layout(run, renderer._char_width)  # noqa: SLF001 - the font's own metrics
    mono = renderer._mono(size)  # noqa: SLF001
    assert rows[-1].text == f"overall: {overall}" and rows[-1].y + size + 4 <= HEIGHT - CARD_MARGIN
    assert all(mono.getlength(row.text) <= WIDTH - 2 * CARD_MARGIN for row in rows if not row.big)
    img = np.asarray(renderer.frame(run.end, card=True))  # the overall row is drawn, in the frame, in its colour
    band = img[rows[-1].y:rows[-1].y + size + 2, CARD_MARGIN:CARD_MARGIN + 140].astype(int)
    assert (np.abs(band - (30, 140, 50) if overall == "PASSED" else band - (200, 40, 40)).max(axis=2) < 60).sum() > 30


def test_1700_each_verdict_from_when_it_is_decided_and_each_event_as_it_happens() -> None:
    run = _run("sesasr_tb3_lab03_1700")
    _, frames = _frames(run)
    t0 = run.verdict["feed"]["t0"] - run.origin
    for number, e in enumerate(run.verdict["maneuvers"], 1):
        decided = t0 + e["settled"]
        name = f"maneuver {number}"
        shown = [t for t, card, rows in frames if not card and any(name in r for r in rows if "] " + name in r)]
        assert shown and abs(shown[0] - decided) <= 1.0 / FPS + 1e-6, (name, shown[:1], decided)
        assert shown == [t for t, card, _ in frames if not card and t >= decided - 1e-6]  # and it stays
    # the stall and the hands: a banner with the judge's words while each happens, and none when nothing does
    for event in run.verdict["events"]:
        during = [rows for t, card, rows in frames if not card and event["start"] <= t <= event["end"]]
        assert during and all(f"{event['kind'].upper()}: {event['text']}" in rows for rows in during), event
    quiet = [rows for t, card, rows in frames if not card and not any(e["start"] <= t <= e["end"]
                                                                          for e in run.verdict["events"])]
    assert quiet and not any(r.startswith(("STUCK:", "MOVED BY HAND:", "GAP:")) for rows in quiet for r in rows)
    at_23 = next(rows for t, _, rows in frames if t >= 23.0)
    assert "STUCK: stuck from t=20.2 s: 10 deg in 6.6 s while commanded -0.22 rad/s" in at_23
    assert "cmd v +0.00 m/s  w -0.22 rad/s" in at_23[1]


@pytest.mark.parametrize("name", ["sesasr_tb3_lab03_1653", "sesasr_tb3_lab03_1700"])
def test_the_caption_the_scale_and_the_nodes_lines(name: str) -> None:
    run = _run(name)
    _, frames = _frames(run)
    frames = [f for f in frames if not f[1]]  # the run's frames (the card covers its caption)
    last_command = run.rec.commands[-1][0] - run.origin
    for t, _, rows in frames:
        caption = rows[1]
        if t < run.rec.commands[0][0] - run.origin:
            assert "no command yet" in caption
        elif t - last_command > COMMAND_STALE + 1e-6:  # the node stopped sending: never its last command as current
            assert f"no command for {t - last_command:.1f} s (last: " in caption and "   cmd v" not in caption
        assert any(r == "scale: 1 m" for r in rows), rows
    assert f"no command for {run.end - run.origin - last_command:.1f} s" in frames[-1][2][1]
    console = [r for _, _, rows in frames for r in rows if r.startswith("[") and "[controller]" in r]
    assert console and all(len(r) <= ROW_CHARS for r in console)
    assert any(r.endswith(")") and " (x" in r for r in console), "the per-scan chatter is folded with a count"
    assert any(r.endswith("Turning right") for r in console) and any(r.endswith("Wall detected") for r in console)
