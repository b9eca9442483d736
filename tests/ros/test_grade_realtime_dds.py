"""A failed run is run again at the grade's speed and at 1x before it stands, and the grade says how each re-run
ended (issues 41 and 44). A class of three over real DDS, one run each at the default 5x, maneuver A:

- ``wall_clock``: the lab's right node with its turn timed by ``time.monotonic`` (``--timing wall``: five times its
  angle at 5x): passes at 1x, graded there, its finding names the wall clock;
- ``draw``: a Randomizer whose first run draws its angle outside 90-180 deg (``tests/fixtures/varying_node.py --odd
  draw``): its re-runs draw other angles; the failure stands and the words say the runs differed, never the load;
- ``stall``: the right node, not scheduled for 3 s of wall time mid-turn in its first run (``--odd stall``: SIGSTOP,
  as a loaded machine starves a process): the simulator stopped waiting for it inside the failed turn; its re-run
  passes, and the failure is put down to the load.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

from bt_nav.cli import grade

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
LAB = f"{sys.executable} {FIXTURES / 'lab_student_node.py'} --choice A --seed 1"
VARYING = f"{sys.executable} {FIXTURES / 'varying_node.py'}"
RUN = "lab_object A lds01 seed 0"


@pytest.mark.slow
@pytest.mark.suite
def test_reruns_tell_the_wall_clock_the_load_and_a_node_whose_runs_differed(tmp_path: Path,
                                                                             capsys: pytest.CaptureFixture) -> None:
    manifest = tmp_path / "class.yaml"
    manifest.write_text(f"wall_clock: {LAB} --timing wall\n"
                        f"draw: {VARYING} --count {tmp_path / 'draw.count'} --odd draw\n"
                        f"stall: {VARYING} --count {tmp_path / 'stall.count'} --odd stall --stall 3 --choice A "
                        "--seed 1\n")
    out = tmp_path / "class"
    code = grade.main(["--class", str(manifest), "--profile", "lab", "--maneuvers", "A", "--worlds", "lab_object",
                       "--lidars", "lds01", "--seeds", "1", "--jobs", "2", "--record", "off", "--progress", "off",
                       "--out", str(out)])
    said = capsys.readouterr().out
    print(said)
    runs = {name: json.loads((out / name / "grade.json").read_text())["runs"] for name in ("wall_clock", "draw",
                                                                                          "stall")}
    assert code == 1  # the draw's failure stands

    [wall] = runs["wall_clock"]
    assert wall["passed"] and "/realtime/" in wall["run_dir"] and wall["rerun"]["decision"] == "wall clock", wall
    turned = re.search(r"turned (\d+) deg", wall["realtime"]["reason"])
    assert turned and int(turned.group(1)) > 300, wall["realtime"]  # its angle of wall time, many times over
    assert any("keeps time by the wall clock" in f for f in wall["findings"]), wall["findings"]

    [draw] = runs["draw"]
    assert not draw["passed"] and "/rerun/" not in draw["run_dir"] and draw["rerun"]["decision"] == "stands", draw
    assert re.search(r"maneuver 1 turned [5-7]\d deg", draw["reason"]), draw["reason"]  # drawn from 50-70
    words = draw["rerun"]["said"]
    assert "the runs differed (maneuver 1 turned" in words and words.endswith("the failure stands"), words
    assert "load" not in words and f"  draw: {RUN}: {words}" in said.splitlines()  # the class terminal says it

    [stall] = runs["stall"]
    assert stall["passed"] and stall["rerun"]["decision"] == "load", stall["rerun"]
    assert re.search(r"the simulator stopped waiting for the node's commands at t=[\d.]+ s, inside maneuver 1, "
                     r"which failed .*the failure is put down to the machine's load, not to the node", stall["reason"])

    feedback = (out / "draw" / "feedback.md").read_text()
    assert f"  - run again: {words}" in feedback.splitlines()  # and so does the student's feedback
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert page["wall_clock"]["passed"] == 1 and page["stall"]["passed"] == 1 and page["draw"]["passed"] == 0, page
