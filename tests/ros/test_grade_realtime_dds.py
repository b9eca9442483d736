"""A node that keeps time by the wall clock is right on a robot and wrong in a faster simulation: the grader checks
a failure at 1x before it stands, so such a node passes (with a finding), while a real mistake still fails.

A class of two over real DDS, one run each at the default 5x: the lab's correct node with its turn timed by
``time.monotonic`` (``--timing wall``: 450 deg at the default 5x) and the half-angle mistake (45 deg at any speed).
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

from bt_nav.cli import grade

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
LAB = f"{sys.executable} {FIXTURES / 'lab_student_node.py'} --choice C"


@pytest.mark.slow
def test_a_wall_clock_node_passes_at_real_time_and_a_mistake_still_fails(tmp_path: Path) -> None:
    manifest = tmp_path / "class.yaml"
    manifest.write_text(f"wall_clock: {LAB} --timing wall\nhalf_angle: {LAB} --mistake half_angle\n")
    out = tmp_path / "class"
    code = grade.main(["--class", str(manifest), "--profile", "lab", "--maneuvers", "C", "--worlds", "lab_object",
                       "--lidars", "lds01", "--seeds", "1", "--jobs", "2", "--record", "off", "--progress", "off",
                       "--out", str(out)])
    wall = json.loads((out / "wall_clock" / "grade.json").read_text())["runs"]
    half = json.loads((out / "half_angle" / "grade.json").read_text())["runs"]
    assert code == 1  # the half-angle node failed
    assert len(wall) == 1 and wall[0]["passed"], wall
    assert "/realtime/" in wall[0]["run_dir"], wall[0]["run_dir"]
    assert wall[0]["realtime"]["rtf"] == 5.0 and not wall[0]["realtime"]["passed"]
    turned = re.search(r"turned (\d+) deg", wall[0]["realtime"]["reason"])
    assert turned and int(turned.group(1)) > 300, wall[0]["realtime"]  # 90 deg of wall time, many times over
    assert any("keeps time by the wall clock" in f for f in wall[0]["findings"]), wall[0]["findings"]
    assert len(half) == 1 and not half[0]["passed"] and "/realtime/" not in half[0]["run_dir"], half
    assert "turned 4" in half[0]["reason"] and "the Smart Pivot needs 90 +- 10 deg" in half[0]["reason"]
    assert half[0]["realtime_probe"]["passed"] is False, half[0]
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert page["wall_clock"]["passed"] == 1 and page["half_angle"]["passed"] == 0, page
