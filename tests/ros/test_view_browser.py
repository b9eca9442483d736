"""The browser view in a real browser, live from a running sim, and ``bt-nav record`` of the same graph.

One simulated mission (``bt-nav sim-run --profile eval``: simulator, executive, referee) serves both
tests. The browser is Debian's ``chromium`` driven by Playwright (``executable_path``; no browser is
ever downloaded); a missing chromium fails the test with the install command: it is never skipped
(``make test`` and ``.ci/run`` install it).
"""

from __future__ import annotations

import re
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from simtools import REPO, Proc

from bt_nav.media.bag import ANNOUNCEMENTS, COLLISIONS, TOPICS, WALKERS
from bt_nav.media.bagread import read_bag
from bt_nav.testing import wait_until

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]
RECORD_S = 30.0  # wall seconds of recording: past the referee's first arming (5 s of sim time)


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """sim-run (eval: the referee arms the robot), a recorder and the view server, all on this test's domain."""
    out = tmp_path_factory.mktemp("live")
    sim = Proc("sim-run", "--profile", "eval", "--maneuver", "C", "--seed", "1", "--rtf", "1")
    recorder = Proc("record", str(out / "bag"), "--duration", str(RECORD_S))
    view = Proc("view", "--port", "0")
    try:
        wait_until(lambda: any("http://" in line for line in view.stdout), 60, "the view server's URL",
                   view.output)
        url = re.search(r"http://\S+", next(line for line in view.stdout if "http://" in line))[0]
        yield {"url": url, "out": out, "sim": sim, "recorder": recorder, "view": view}
    finally:
        for proc in (view, recorder, sim):
            proc.stop()


def test_page_shows_tree_and_moving_robot(live: dict) -> None:
    from playwright.sync_api import sync_playwright

    assert Path(CHROMIUM).is_file(), ("Debian's chromium is missing: apt-get install -y chromium "
                                      "(make test and .ci/run install it)")
    shot = live["out"] / "view.png"
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(live["url"])
            page.wait_for_function("document.querySelectorAll('#tree .row').length > 10", timeout=90_000)
            assert page.locator("#tree .row").first.inner_text().startswith("Mission")
            assert page.locator("#tree .row.active").count() >= 2  # the running path is highlighted

            def robot() -> tuple[str, str]:
                r = page.locator("#robot")
                return r.get_attribute("data-px") or "", r.get_attribute("data-py") or ""

            page.wait_for_function("document.getElementById('robot').dataset.px !== ''", timeout=60_000)
            first = robot()
            deadline = time.monotonic() + 90
            while robot() == first and time.monotonic() < deadline:
                page.wait_for_timeout(500)
            moved = robot()
            page.screenshot(path=str(shot))
        finally:
            browser.close()
    shutil.copy(shot, REPO / "runs" / "view_browser.png") if (REPO / "runs").is_dir() else None
    assert moved != first, f"the robot's drawn position did not change ({first}); screenshot {shot}"
    assert shot.stat().st_size > 10_000


def test_record_writes_every_topic_of_the_live_graph(live: dict) -> None:
    assert live["recorder"].wait(RECORD_S + 60) == 0, live["recorder"].output()
    rec = read_bag(live["out"] / "bag")
    for topic in TOPICS:
        if topic not in (COLLISIONS, WALKERS, ANNOUNCEMENTS):  # stage_4: no collision, no people, no maneuver yet
            assert rec.counts.get(topic, 0) > 0, f"{topic}: {rec.counts}\n{live['recorder'].output()}"
    assert rec.trees and all(snapshot["format"] == "bt_nav.tree/1" for _, snapshot in rec.trees)
    assert rec.mission.get("world") == "stage_4"  # asked from the simulator's parameters
    # sim-time stamps, not wall time (0 is sim time too: the first /clock, and what came before it)
    assert not rec.truncated and 0 <= rec.start < rec.end < 200
    assert any("armed" in text for _, text in rec.events), rec.events[:20]
