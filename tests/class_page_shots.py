"""The class page's screenshots in docs/grading.md (``make class-page-shots``): issue 54's mixed class of four
hand-ins (``tests/fixtures/handins_mixed``) graded as an instructor grades a folder, at 1x on each choice's default
cells (one LiDAR, one seed: 10 runs, about a minute), its ``class.html`` shot in Debian's chromium at 1280 x 800:
as it opens (every student folded) and with the failed B student opened::

    python tests/class_page_shots.py --out runs/class-page-shots --docs docs

Writes ``class_page.png`` and ``class_page_open.png`` into ``--docs``; the grade stays in ``--out``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FOLDER = REPO / "tests" / "fixtures" / "handins_mixed"
CHROMIUM = "/usr/bin/chromium"
WINDOW = {"width": 1280, "height": 800}
#: The student opened in the second shot.
OPENED = "b_left_or_right"


def grade(out: Path) -> int:
    """Grade the class into ``out`` with ``bt-nav grade --class`` (its exit code: 1, two hand-ins fail)."""
    argv = [sys.executable, "-m", "bt_nav.cli", "grade", "--class", str(FOLDER), "--profile", "lab", "--lidars",
            "lds01", "--seeds", "1", "--record", "off", "--progress", "off", "--out", str(out)]
    return subprocess.run(argv, check=False).returncode


def shoot(page_file: Path, docs: Path) -> list[Path]:
    """The two screenshots of ``page_file`` at 1280 x 800, into ``docs``."""
    from playwright.sync_api import sync_playwright

    shots = [docs / "class_page.png", docs / "class_page_open.png"]
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True,
                                     args=["--headless", "--no-sandbox", "--disable-gpu"])
        try:
            page = browser.new_page(viewport=WINDOW)
            page.goto(page_file.resolve().as_uri())
            page.screenshot(path=str(shots[0]))
            page.locator(f'tr[data-name="{OPENED}"] details summary').click()
            page.screenshot(path=str(shots[1]))
        finally:
            browser.close()
    return shots


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "runs" / "class-page-shots")
    parser.add_argument("--docs", type=Path, default=REPO / "docs")
    parser.add_argument("--page-only", action="store_true", help="no grade: write the class page of the grade in "
                        "--out again (this checkout's page) and shoot it")
    args = parser.parse_args(argv)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if args.page_only:
        from bt_nav.grading.classroom import write_class_html

        write_class_html(args.out)
        code = 0
    else:
        import shutil

        shutil.rmtree(args.out, ignore_errors=True)  # this script's own grade: a new one each time, never a stale one
        code = grade(args.out)
    page = args.out / "class.html"
    if not page.is_file():
        print(f"class_page_shots: no {page} (bt-nav grade exited {code})", file=sys.stderr)
        return 1
    for shot in shoot(page, args.docs):
        print(f"class_page_shots: wrote {shot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
