"""The issue's class over real DDS: four hand-ins (node + launch file each; one launch file forgets
``safety_distance``, one student hands in none) graded in one command: four verdicts with the launch-file lines.
Each node is the right C fixture node under the lab's name, so the runs pass and the launch file decides."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from bt_nav.cli import grade

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


@pytest.mark.slow
def test_four_hand_ins_get_four_verdicts_with_their_launch_lines(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture) -> None:
    source = re.sub(r"^# CHOICE: given on the command line.*$", "# CHOICE: C",
                    (FIXTURES / "lab_student_node.py").read_text(), count=1, flags=re.M)
    klass = tmp_path / "hand-ins"
    for name, launch in (("ann", "sheet"), ("bob", "variables_add_action"), ("cy", "forgets_safety"),
                         ("dee", None)):
        (klass / name).mkdir(parents=True)
        (klass / name / "reactive_navigator.py").write_text(source)
        if launch is not None:
            shutil.copy(FIXTURES / "launch" / f"{launch}.launch.py", klass / name / "turtlebot_bringup.launch.py")
    out = tmp_path / "class"
    code = grade.main(["--class", str(klass), "--profile", "lab", "--worlds", "lab_object", "--lidars", "lds01",
                       "--seeds", "1", "--jobs", "2", "--record", "off", "--progress", "off", "--out", str(out)])
    stdout = capsys.readouterr().out
    assert code == 1, stdout  # cy and dee fail their hand-in
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert {n: (s["passed"], s["runs"]) for n, s in page.items()} == {n: (1, 1) for n in ("ann", "bob", "cy", "dee")}
    assert {n: s["verdict"] for n, s in page.items()} == {"ann": "PASSED", "bob": "PASSED", "cy": "FAILED",
                                                         "dee": "FAILED"}
    lines = {n: s["handin"]["lines"] for n, s in page.items()}
    assert "launch file: declares safety_distance (default 0.5): FAILED (no DeclareLaunchArgument(" \
           "'safety_distance', default_value='0.5'))" in lines["cy"]
    assert lines["dee"][0] == "launch file: FAILED (no launch file handed in (expected turtlebot_bringup.launch.py))"
    assert all(": PASSED (turtlebot_bringup.launch.py:" in line for line in lines["ann"][:3]), lines["ann"]
    md = (out / "class.md").read_text()
    assert "| [cy](cy/report.html) | FAILED | 1/3 | 1/1 |" in md, md
    for name in page:
        feedback = (out / name / "feedback.md").read_text()
        assert feedback.startswith(f"# {name}: {page[name]['verdict']}\n"), feedback
        assert "- **lab_object C lds01 seed 0: PASSED** (passed)" in feedback, feedback
    assert "  dee: hand-in FAILED (launch file: starts the node, declares safety_distance (default 0.5), passes " \
           "safety_distance to the node failed)" in stdout.splitlines(), stdout
