"""Benchmark ``testquick``: the wall time of ``make test-quick``, the contributor's edit-test loop.

``make test-quick`` runs the tests that need no DDS (the pure core, the simulator and the judges' rules, the grading
logic, the media: the folders the Makefile's ``QUICK_TESTS`` names, ``-m "not ros and not slow"``); ``make test``
stays the whole suite. It exists to be quick, so its time is measured here, where a suite that grows slower shows
as a change between runs (``latest.md``), and the number docs/developing.md states comes from here.

Target: at most :data:`LIMIT_S` on this machine (minutes, not the whole suite's tens of minutes).
"""

from __future__ import annotations

import os
import re
import subprocess
import time
from typing import Any

from .common import REPO, Target, at_most

#: Wall seconds ``make test-quick`` may take (a contributor runs it after every edit).
LIMIT_S = 300.0
_COUNTS = re.compile(r"(\d+) (passed|failed|error|errors|skipped|deselected)")


def run(quick: bool = False) -> dict[str, Any]:
    """Time one ``make test-quick`` (``quick`` changes nothing: the loop is what it is), with the CPU time its
    processes used (on a loaded machine the wall time is mostly waiting) and the tests that did not pass."""
    before = os.times()
    started = time.perf_counter()
    done = subprocess.run(["make", "--no-print-directory", "test-quick"], cwd=REPO, capture_output=True, text=True,
                          check=False)
    wall = time.perf_counter() - started
    after = os.times()
    lines = done.stdout.strip().splitlines() or [""]
    counts = {kind.rstrip("s") if kind == "errors" else kind: int(n) for n, kind in _COUNTS.findall(lines[-1])}
    cpu = (after.children_user + after.children_system) - (before.children_user + before.children_system)
    print(f"  make test-quick: {wall:.0f} s wall, {cpu:.0f} s CPU, exit {done.returncode}: {lines[-1]}", flush=True)
    return {"wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "exit_code": done.returncode, "summary": lines[-1],
            "not_passed": [line.split(" - ")[0] for line in lines if line.startswith(("FAILED ", "ERROR "))],
            **counts}


def targets(result: dict[str, Any]) -> list[Target]:
    """The loop's wall time; met or missed only when every test passed (a failing run's time is reported, not held
    to the target: a test that fails early may end sooner)."""
    value = result["wall_s"]
    met = at_most(value, LIMIT_S) if result.get("exit_code") == 0 else None
    return [Target("test_quick_wall", "testquick", "make test-quick (the tests that need no DDS), wall time",
                   f"<= {LIMIT_S:g} s", value, "s", met)]
