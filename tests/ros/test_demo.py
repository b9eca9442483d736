"""``bt-nav demo`` end to end: simulator, executive and referee over real DDS in sim time, once."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import pytest
from simtools import Proc

WALL_LIMIT = 60.0


@pytest.mark.slow
def test_demo_passes_and_writes_its_files(tmp_path: Path) -> None:
    started = time.monotonic()
    demo = Proc("demo", "--out", str(tmp_path), "--name", "run", "--quiet", "--timeout", "50")
    code = demo.wait(WALL_LIMIT + 30.0)
    wall = time.monotonic() - started
    assert code == 0, demo.output() + "\n".join(
        f"--- {p.name}\n{p.read_text()}" for p in sorted((tmp_path / "run").glob("*.log")))
    assert "overall: PASSED" in demo.stdout
    verdict = [line for line in demo.stdout if not line.startswith("bt-nav demo:")]
    assert len(verdict) == 8 and all(line.endswith(": PASSED") for line in verdict), demo.output()
    assert wall < WALL_LIMIT, f"the demo took {wall:.1f} s wall"

    run = tmp_path / "run"
    results = json.loads((run / "results.json").read_text())
    assert results["passed"] is True and results["report_lines"] == verdict
    for name in ("trajectory.json", "trajectory.png", "tree.dot", "sim.log", "executive.log", "referee.log"):
        assert (run / name).is_file() and (run / name).stat().st_size > 0, name
    if shutil.which("dot"):
        assert (run / "tree.svg").read_text().lstrip().startswith("<?xml")
    trajectory = json.loads((run / "trajectory.json").read_text())
    assert len(trajectory["t"]) > 1000  # ~57 s of ground truth at 30 Hz
    assert {"FullSpeed", "TurnAway"} <= set(trajectory["branch"])  # the tip was read from ~/tree
    assert trajectory["branch"][-1] == "Stopped"
    assert (run / "trajectory.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the demo reports the speed of the mission
    assert any("x real time" in line for line in demo.stdout), demo.output()
