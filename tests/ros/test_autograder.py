"""The Gradescope autograder's ``run_autograder`` (``autograder/``, docs/autograder.md) run as Gradescope runs it,
against a submission folder (the right lab node as ``reactive_navigator.py`` with ``# CHOICE: C``, and its launch
file), every path redirected to a temporary directory, this venv's bt-nav instead of setup.sh's, the grid kept to one
run; the results.json it writes must validate against Gradescope's documented keys and score the hand-in. And one
node graded with ``bt-nav grade --exe ... --gradescope ... --junit ...``."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

from bt_nav.cli import grade
from tests.gradescope_schema import gradescope_problems
from tests.grading.test_formats import unopenable

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "tests" / "fixtures"


def _submission(folder: Path) -> Path:
    folder.mkdir(parents=True)
    source = (FIXTURES / "lab_student_node.py").read_text()
    (folder / "reactive_navigator.py").write_text(
        re.sub(r"^# CHOICE: given on the command line.*$", "# CHOICE: C", source, count=1, flags=re.M))
    shutil.copy(FIXTURES / "autograder_submission" / "turtlebot_bringup.launch.py", folder)
    return folder


ONE_RUN = "--worlds lab_object --lidars lds01 --seeds 1 --record off --jobs 1"


def _run_autograder(tmp_path: Path, submission: Path, args: str = ONE_RUN,
                    **more: str) -> tuple[subprocess.CompletedProcess, Path]:
    source = tmp_path / "source"  # the autograder zip's folder: an instructor's weights.yaml
    source.mkdir()
    (source / "weights.yaml").write_text("total: 10\nlaunch_share: 0.3\n")
    env = {**os.environ, "BT_NAV_AUTOGRADER_SUBMISSION": str(submission),
           "BT_NAV_AUTOGRADER_RESULTS": str(tmp_path / "results"), "BT_NAV_AUTOGRADER_WORK": str(tmp_path / "work"),
           "BT_NAV_AUTOGRADER_SOURCE": str(source), "BT_NAV_AUTOGRADER_BT_NAV": str(Path(sys.executable).parent
                                                                                    / "bt-nav"),
           "BT_NAV_AUTOGRADER_ARGS": args, **more}
    env.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)  # the script sets it itself
    done = subprocess.run(["bash", str(REPO / "autograder" / "run_autograder")], env=env, capture_output=True,
                          text=True, timeout=400, cwd=tmp_path)
    return done, tmp_path / "results" / "results.json"


def test_run_autograder_grades_a_submission_into_results_json(tmp_path: Path) -> None:
    done, results = _run_autograder(tmp_path, _submission(tmp_path / "submission"))
    said = done.stdout + done.stderr
    assert done.returncode == 0, said
    assert "run_autograder: bt-nav grade exited 0" in done.stdout, said
    doc = json.loads(results.read_text())
    assert gradescope_problems(doc) == [], doc
    names = [t["name"] for t in doc["tests"]]
    assert names == ["run lab_object C lds01 seed 0", "launch file: starts the node",
                     "launch file: declares safety_distance (default 0.5)",
                     "launch file: passes safety_distance to the node"], doc
    assert all(t["status"] == "passed" for t in doc["tests"]), doc
    assert doc["score"] == 10 and doc["tests"][0]["max_score"] == 7, doc  # the zip's weights.yaml: 10 points, 0.3
    assert (tmp_path / "work" / "submission" / "grade.json").is_file(), said


def test_a_failing_submission_reads_on_gradescope(tmp_path: Path) -> None:
    """The fixture submission (tests/fixtures/autograder_submission: its Smart Pivot turns 45 deg, its launch file is
    the sheet's) graded by run_autograder as Gradescope runs it, Python unbuffered (the way lines of stdout and stderr
    used to run together): the failed test says the failure's words and how to fix it, nothing names a file the
    student cannot open there, execution_time is the grade's wall time (not the runs' sum), one message a line."""
    started = time.monotonic()
    done, results = _run_autograder(tmp_path, FIXTURES / "autograder_submission", PYTHONUNBUFFERED="1")
    wall = time.monotonic() - started
    said = done.stdout + done.stderr
    assert done.returncode == 0 and "run_autograder: bt-nav grade exited 1" in done.stdout, said
    doc = json.loads(results.read_text())
    assert gradescope_problems(doc) == [] and doc["output_format"] == doc["test_output_format"] == "md", doc
    failed = [t for t in doc["tests"] if t.get("status") == "failed"]
    assert [t["name"] for t in failed] == ["run lab_object C lds01 seed 0"], doc
    for test in failed:
        assert re.search(r"\n- maneuver 1 turned 4\d deg (left|right); the Smart Pivot needs 90 \+- 10 deg either "
                         r"side \(readings at the start", test["output"]), test["output"]
        assert "**How to fix:** Turn by 90 +- 10 deg. Any way of measuring the turn passes" in test["output"], \
            test["output"]
    assert doc["score"] == 3, doc  # the launch file's 3 of the zip's 10 points (launch_share 0.3)
    assert unopenable(json.dumps(doc)) == [], doc
    assert abs(doc["execution_time"] - wall) <= 0.1 * wall, (doc["execution_time"], wall)
    assert not list((tmp_path / "work").rglob("*.mp4")), "a film nobody on Gradescope can open (--videos off)"
    for line in said.splitlines():  # each message on a line of its own
        for mark in (r"run_autograder:", r"bt-nav grade:", r"class of 1 in [\d.]+ s wall"):
            assert not re.search(mark, line) or re.match(mark, line.lstrip()), line


#: A stand-in for bt-nav: half a line on stdout, a whole one on stderr, the rest of the first; then, as bt-nav grade
#: does for a hand-in with runs not graded, autograder_error.md and no results.json.
FAKE_BT_NAV = """#!{python}
import os, sys, time
from pathlib import Path
work = Path(sys.argv[sys.argv.index("--out") + 1])
os.write(1, b"bt-nav grade: a class of 1 (1 run)")
time.sleep(0.2)
os.write(2, b"not checked off there: lab_object B\\n")
time.sleep(0.2)
os.write(1, b"\\n")
(work / "_gradescope" / "submission").mkdir(parents=True)
(work / "_gradescope" / "submission" / "autograder_error.md").write_text("The autograder could not grade this "
    "submission: 1 of 1 run(s) not graded (another program is on ROS_DOMAIN_ID 7).\\n")
sys.exit(3)
"""


def test_runs_not_graded_are_an_autograder_error_and_lines_stay_whole(tmp_path: Path) -> None:
    """Without DDS (a stand-in for bt-nav): a line written in two parts around a line on stderr comes out whole,
    each message on its own line; a hand-in with runs not graded leaves no results.json and run_autograder exits 1,
    so Gradescope shows an autograder error (never 0, never full marks), its output saying why."""
    fake = tmp_path / "bin" / "bt-nav"
    fake.parent.mkdir()
    fake.write_text(FAKE_BT_NAV.format(python=sys.executable))
    fake.chmod(0o755)
    submission = _submission(tmp_path / "submission")
    env = {**os.environ, "BT_NAV_AUTOGRADER_SUBMISSION": str(submission),
           "BT_NAV_AUTOGRADER_RESULTS": str(tmp_path / "results"), "BT_NAV_AUTOGRADER_WORK": str(tmp_path / "work"),
           "BT_NAV_AUTOGRADER_SOURCE": str(tmp_path), "BT_NAV_AUTOGRADER_BT_NAV": str(fake)}
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "results.json").write_text('{"score": 100}')  # an old one must not stand
    done = subprocess.run(["bash", str(REPO / "autograder" / "run_autograder")], env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=60, cwd=tmp_path)
    lines = done.stdout.splitlines()
    assert "bt-nav grade: a class of 1 (1 run)" in lines and "not checked off there: lab_object B" in lines, lines
    assert done.returncode == 1 and not (tmp_path / "results" / "results.json").exists(), done.stdout
    assert "The autograder could not grade this submission: 1 of 1 run(s) not graded" in done.stdout, lines
    assert lines[-1].startswith("run_autograder: no results.json: not graded"), lines


def test_run_autograder_says_why_when_nothing_could_be_graded(tmp_path: Path) -> None:
    """A submission without any Python file: no DDS run; Gradescope still gets a results.json, scored 0, saying why."""
    empty = tmp_path / "submission"
    empty.mkdir()
    (empty / "notes.txt").write_text("forgot the code\n")
    done, results = _run_autograder(tmp_path, empty)
    assert done.returncode == 0, done.stdout + done.stderr
    doc = json.loads(results.read_text())
    assert gradescope_problems(doc) == [] and doc["score"] == 0, doc
    assert doc["output"].startswith("**Not run**: no reactive\\_navigator.py"), doc  # Markdown: _ escaped
    assert "Launch file: 0/3 checks passed." in doc["output"], doc


def test_run_autograder_writes_a_result_when_bt_nav_grade_refuses(tmp_path: Path) -> None:
    """bt-nav grade refusing its options (exit 2, nothing graded): the results.json says so with bt-nav's words."""
    done, results = _run_autograder(tmp_path, _submission(tmp_path / "submission"), "--worlds nowhere")
    assert done.returncode == 0 and "bt-nav grade exited 2" in done.stdout, done.stdout + done.stderr
    doc = json.loads(results.read_text())
    assert gradescope_problems(doc) == [] and doc["score"] == 0 and doc["tests"] == [], doc
    assert doc["output"].startswith("The autograder could not grade this submission (bt-nav grade exited 2)"), doc
    assert "bt-nav grade: error: unknown world 'nowhere'" in doc["output"] and "usage:" not in doc["output"], doc


def test_grade_exe_writes_results_json_and_junit(tmp_path: Path) -> None:
    """One node graded with ``--exe``: its results.json validates, the JUnit XML has its one run as one testcase."""
    node = _submission(tmp_path / "hand-in") / "reactive_navigator.py"
    code = grade.main(["--exe", f"{sys.executable} {node}", "--profile", "lab", *ONE_RUN.split(), "--progress", "off",
                       "--out", str(tmp_path / "grade"), "--gradescope", str(tmp_path / "results.json"),
                       "--junit", str(tmp_path / "report.xml")])
    assert code == 0
    doc = json.loads((tmp_path / "results.json").read_text())
    assert gradescope_problems(doc) == [] and doc["score"] == 100, doc
    assert [t["name"] for t in doc["tests"]] == ["run lab_object C lds01 seed 0"], doc  # no launch file with --exe
    (suite,) = ET.parse(tmp_path / "report.xml").getroot().findall("testsuite")
    assert [c.get("name") for c in suite.findall("testcase")] == ["lab_object C lds01 seed 0"]
    assert suite.get("failures") == "0" and suite.get("name") == f"{sys.executable} {node}"
