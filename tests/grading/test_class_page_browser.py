"""``class.html`` in a real browser: the fixture class (:mod:`tests.grading.classfixture`: a hand-in failed by its
launch file, a failed run, a crash, a TA's note, a refused student, a run not graded) opened from disk in Debian's
``chromium`` driven by Playwright (``executable_path``; no browser is ever downloaded; a missing chromium fails the
test with the install command). What is read is what an instructor sees: the rows' computed colours and their order,
the filters and the sorting at work, code shown as code, nothing loaded from the network. The screenshot is kept
beside the page (``class.png`` in the test's tmp directory, and ``runs/class_page.png`` when ``runs/`` exists): an
artefact to look at, not compared pixel by pixel."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from tests.grading.classfixture import make_class

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run"]
REPO = Path(__file__).resolve().parents[2]
#: The computed colours of the verdict cells and of each row's left edge (classpage.PAGE_STYLE).
RED, AMBER, GREEN = "rgb(246, 214, 214)", "rgb(253, 233, 184)", "rgb(216, 240, 216)"
EDGE = {"FAILED": "rgb(192, 57, 43)", "NOT GRADED": "rgb(212, 160, 23)", "PASSED": "rgb(46, 139, 87)"}

#: A laptop's window: the class page must fit it (issue 54).
WINDOW = {"width": 1280, "height": 800}
#: What sticks out of the window: every element wider than it or reaching past its right edge, but those inside a
#: folded <details> (not rendered) and the folded matrix itself.
WIDE_JS = """() => Array.from(document.querySelectorAll('body *')).filter(e => {
  const r = e.getBoundingClientRect();
  return r.width > 0 && (r.right > window.innerWidth + 0.5 || r.width > window.innerWidth)
    && !e.closest('details:not([open])');
}).map(e => e.tagName + '.' + e.className + ': ' + Math.round(e.getBoundingClientRect().right))"""
#: Each failed row's first reason: its box, and whether it is rendered (not inside a folded <details>).
REASONS_JS = """() => Array.from(document.querySelectorAll('#students > tbody > tr'))
  .filter(r => r.dataset.verdict !== 'PASSED')
  .map(r => { const f = r.querySelector('td.reason .first'); const b = f ? f.getBoundingClientRect() : null;
    return {name: r.dataset.name, text: f ? f.innerText : '', left: b ? b.left : -1, right: b ? b.right : -1,
            width: b ? b.width : 0, folded: f ? !!f.closest('details:not([open])') : true}; })"""


def fits_the_window(page: Any) -> list[dict[str, Any]]:
    """Assert the class page shown in ``page`` (a 1280 px window) is no wider than the window, but for what is folded,
    and that every failed row's first reason is in view (rendered, inside the window, not folded); its reasons."""
    assert page.evaluate("document.documentElement.scrollWidth") <= WINDOW["width"], page.evaluate(WIDE_JS)
    assert page.evaluate(WIDE_JS) == []
    reasons = page.evaluate(REASONS_JS)
    for reason in reasons:
        assert reason["text"] and not reason["folded"], reason
        assert 0 <= reason["left"] and reason["right"] <= WINDOW["width"] and reason["width"] >= 300, reason
    assert all(not d for d in page.evaluate("Array.from(document.querySelectorAll('#students details'))"
                                            ".map(d => d.open)")), "every student's details start folded"
    return reasons


ROWS_JS = """() => Array.from(document.querySelectorAll('#students > tbody > tr'))
  .filter(r => !r.classList.contains('hidden')).map(r => ({name: r.dataset.name, verdict: r.cells[1].textContent,
              cell: getComputedStyle(r.cells[1]).backgroundColor,
              edge: getComputedStyle(r.cells[0]).borderLeftColor, score: r.cells[2].textContent}))"""


def test_the_class_page_in_chromium(tmp_path: Path) -> None:
    from playwright.sync_api import sync_playwright

    assert Path(CHROMIUM).is_file(), ("Debian's chromium is missing: apt-get install -y chromium "
                                      "(make test and .ci/run install it)")
    out = make_class(tmp_path / "class")
    page_file = out / "class.html"
    shot = tmp_path / "class.png"
    requests: list[str] = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            page = browser.new_page(viewport=WINDOW)
            errors: list[str] = []
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.on("request", lambda req: requests.append(req.url))
            page.goto(page_file.as_uri())
            rows = page.evaluate(ROWS_JS)
            page.screenshot(path=str(shot), full_page=True)
            reasons = {r["name"]: r["text"] for r in fits_the_window(page)}
            assert "turned 44 deg right" in reasons["bob"] and "ValueError" in reasons["cy"], reasons
            assert page.locator('tr[data-name="bob"] .num').nth(1).inner_text() == "0/1 runs"  # counts say what
            assert page.locator('tr[data-name="bob"] .num').nth(2).inner_text() == "3/3 checks"
            assert page.locator('tr[data-name="bob"] td.man').inner_text() == "C"
            page.locator('tr[data-name="bob"] details summary').click()  # one student opened: its matrix shows
            assert page.locator('tr[data-name="bob"] table.matrix').is_visible()
            assert page.locator('tr[data-name="bob"] table.matrix').inner_text().split() == \
                ["runs", "passed", "per", "arena", "and", "LiDAR", "arena", "lds01", "lab_object", "0/1"]
            assert not page.locator('tr[data-name="ann"] table.matrix').is_visible()  # the others stay folded
            page.locator('tr[data-name="bob"] details summary').click()

            # failures first (lowest score first), then not graded, then passed
            assert [r["name"] for r in rows] == ["eve", "bob", "cy", "ann", "fay", "dee"], rows
            colour = {"FAILED": RED, "NOT GRADED": AMBER, "PASSED": GREEN}
            for row in rows:
                assert row["cell"] == colour[row["verdict"]] and row["edge"] == EDGE[row["verdict"]], row
            ann = next(r for r in rows if r["name"] == "ann")  # every run passed, the launch file did not
            assert ann["verdict"] == "FAILED" and ann["cell"] == RED and ann["score"] == "86.7 / 100", ann
            assert next(r for r in rows if r["name"] == "fay")["score"] == "- / 100"  # not graded: no score

            ann_row = page.locator('tr[data-name="ann"]')
            assert "launch file: declares safety_distance (default 0.5): FAILED (no DeclareLaunchArgument(" in \
                ann_row.inner_text()
            assert not ann_row.locator("details").evaluate("d => d.open")  # what passed is folded
            assert "launch file: starts the node: PASSED" in ann_row.locator("details").text_content()
            bob = page.locator('tr[data-name="bob"]').inner_text()
            assert "arena lab_object, LiDAR lds01, maneuver C, seed 0" in bob and "turned 44 deg right" in bob, bob
            assert "TA: look at the launch file" in page.locator('tr[data-name="dee"]').inner_text()
            assert page.locator('tr[data-name="bob"] div.first .where a').get_attribute("href") == \
                "bob/report.html#lab_object_C_lds01_seed0"  # each failure links to its run in the report
            eve = page.locator('tr[data-name="eve"]').text_content()  # three checks failed alike: said once
            assert eve.count("no launch file handed in") == 1 and "not run: no reactive_navigator.py" in eve, eve
            assert "launch file: FAILED (no launch file handed in)" in eve, eve
            assert "not graded (not the node's; not scored): another program" in \
                page.locator('tr[data-name="fay"]').text_content()
            # the note every hand-in shares is said once, as code, not on every row
            assert page.locator("p.note code").first.inner_text() == "python3 reactive_navigator.py"
            assert "read statically" not in page.locator("#students").inner_text()
            assert "`" not in page.locator("body").inner_text()  # no raw backticks anywhere
            assert page.locator('tr[data-name="ann"] a').first.get_attribute("href") == "ann/report.html"

            page.select_option("#f-verdict", "PASSED")
            assert [r["name"] for r in page.evaluate(ROWS_JS)] == ["dee"]
            page.select_option("#f-verdict", "")
            page.select_option("#f-reason", "node crashed")
            assert [r["name"] for r in page.evaluate(ROWS_JS)] == ["cy"]
            page.select_option("#f-reason", "launch file: declares safety_distance (default 0.5)")
            assert [r["name"] for r in page.evaluate(ROWS_JS)] == ["ann", "eve"] or \
                sorted(r["name"] for r in page.evaluate(ROWS_JS)) == ["ann", "eve"]
            page.select_option("#f-reason", "")
            page.fill("#f-name", "fa")
            assert [r["name"] for r in page.evaluate(ROWS_JS)] == ["fay"]
            page.fill("#f-name", "")
            page.click('th[data-key="score"]')
            scores = [r["score"] for r in page.evaluate(ROWS_JS)]
            assert scores[0] == "- / 100" and scores[-1] == "100 / 100", scores
            page.click('th[data-key="name"]')
            assert [r["name"] for r in page.evaluate(ROWS_JS)] == ["ann", "bob", "cy", "dee", "eve", "fay"]
            assert errors == [], errors
        finally:
            browser.close()
    assert requests == [page_file.as_uri()], requests  # one file: no script, style or font from anywhere
    assert shot.stat().st_size > 10_000
    if (REPO / "runs").is_dir():
        shutil.copy(shot, REPO / "runs" / "class_page.png")
