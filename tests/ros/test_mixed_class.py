"""Issue 54's class of four hand-ins (``tests/fixtures/handins_mixed``: a right C, a right A, a B whose trigger is
left OR right, a right C whose launch file passes ``safety_dist``), graded over DDS as an instructor grades a folder
of hand-ins, and read where a student and an instructor read: Gradescope's tests, ``feedback.md``, the class page in
Chromium at 1280 x 800.

Its subject is the words, not the timing, so it grades one cell each (``--worlds lab_beside,lab_hallway``: A and C
in ``lab_beside``, B in ``lab_hallway``, whose wall on the left only fires a left OR right trigger at once), one
LiDAR, one seed, in the preview (``PREVIEW``, as the mutation tests do); ``tests/grader_suite.py --only mixed``
grades the same class on its default grid at 1x.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import grade
from bt_nav.grading.formats import class_records, gradescope_results
from bt_nav.grading.hints import check_kinds, check_rule

FOLDER = Path(__file__).resolve().parents[1] / "fixtures" / "handins_mixed"
PREVIEW = ("--rtf", "0", "--realtime-check", "off")
#: Advice that tells a student to stop timing turns (the sheet prescribes no way of measuring one).
AGAINST_TIMING = re.compile(r"rather than tim|instead of tim|not tim|never tim|don't tim|avoid tim|stop tim|"
                            r"measured from odometry", re.IGNORECASE)


def _outputs(doc: dict[str, Any]) -> list[str]:
    return [doc["output"], *(t["output"] for t in doc["tests"])]


@pytest.mark.slow
def test_a_mixed_class_reads_right_for_students_and_instructors(tmp_path: Path) -> None:
    out = tmp_path / "class"
    code = grade.main(["--class", str(FOLDER), "--profile", "lab", "--worlds", "lab_beside,lab_hallway",
                       "--lidars", "lds01", "--seeds", "1", "--jobs", "2", "--record", "off", "--progress", "off",
                       "--out", str(out), *PREVIEW])
    assert code == 1
    records = dict(class_records(out))
    runs = {name: record["runs"] for name, record in records.items()}
    assert {name: [r["world"] for r in rows] for name, rows in runs.items()} == {
        "right_c": ["lab_beside"], "right_a": ["lab_beside"], "b_left_or_right": ["lab_hallway"],
        "c_safety_dist": ["lab_beside"]}, "one cell each"
    for name in ("right_c", "right_a", "c_safety_dist"):
        assert all(r["passed"] for r in runs[name]), [r["reason"] for r in runs[name]]

    # the OR trigger: its failure's rule and advice are the trigger's, not the angle's
    [run] = runs["b_left_or_right"]
    failed = [c for c in run["verdict"]["checks"] if not c["passed"]]
    first = next(c for c in failed if c["name"].startswith("maneuver "))
    assert check_kinds(first)[0] == "trigger" and "trigger did not hold" in first["reason"], first
    assert check_rule(first).startswith("held: left and right < 0.5 m"), first
    b_doc = gradescope_results(records["b_left_or_right"])
    [b_test] = [t for t in b_doc["tests"] if t.get("status") == "failed"]
    line = next(x for x in b_test["output"].splitlines() if x.startswith("- maneuver 1 turned although"))
    assert "(the rule: held: left and right \\< 0.5 m" in line and "needs 180" not in line.split("(the rule:")[1], line
    advice = b_test["output"].split("**How to fix:** ", 1)[1]
    assert advice.startswith("Turn only when the sheet's trigger holds: the left sector AND the right sector"), advice

    # the launch typo costs one check, and its fix names what the file holds
    checks = records["c_safety_dist"]["launch"]["checks"]
    assert [c["passed"] for c in checks] == [True, True, False], checks
    c_doc = gradescope_results(records["c_safety_dist"])
    failed_tests = [t for t in c_doc["tests"] if t.get("status") == "failed"]
    assert [t["name"] for t in failed_tests] == ["launch file: passes safety_distance to the node"], failed_tests
    assert "`{'safety_dist': LaunchConfiguration('safety_distance')}`" in failed_tests[0]["output"], failed_tests
    assert "the parameter is `safety_distance`" in failed_tests[0]["output"]
    assert "safety_dist" in (out / "c_safety_dist" / "feedback.md").read_text()

    # no advice anywhere tells a student to stop timing turns
    said = [text for name in records for text in _outputs(gradescope_results(records[name]))]
    said += [(out / name / "feedback.md").read_text() for name in records]
    assert not [m.group(0) for text in said for m in [AGAINST_TIMING.search(text)] if m]

    # the page counts runs: each row's count is its runs passed of its runs, said as runs
    page = (out / "class.html").read_text()
    for name, rows in runs.items():
        row = page.split(f'data-name="{name}"', 1)[1].split("</tr>", 1)[0]
        assert f'<td class="num">{sum(r["passed"] for r in rows)}/{len(rows)} runs</td>' in row, row
    doc = json.loads((out / "class.json").read_text())
    assert {s["name"]: s["runs"] for s in doc["students"]} == {n: len(r) for n, r in runs.items()}
    _in_chromium(out / "class.html")


def _in_chromium(page_file: Path) -> None:
    """The page at 1280 x 800: nothing wider than the window but the folded matrix; each failed row's reason in
    view (:func:`tests.grading.test_class_page_browser.fits_the_window`)."""
    from playwright.sync_api import sync_playwright

    from tests.grading.test_class_page_browser import CHROMIUM, CHROMIUM_ARGS, WINDOW, fits_the_window

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            page = browser.new_page(viewport=WINDOW)
            page.goto(page_file.as_uri())
            reasons = {r["name"]: r["text"] for r in fits_the_window(page)}
        finally:
            browser.close()
    assert set(reasons) == {"b_left_or_right", "c_safety_dist"}, reasons
    assert "trigger did not hold" in reasons["b_left_or_right"] and "safety_dist" in reasons["c_safety_dist"], reasons
