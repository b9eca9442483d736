"""Gradescope's results.json and JUnit XML written from real grades (``tests/fixtures/grades/lab_class``: a class of
three graded over DDS with ``bt-nav grade --class`` on lab_object, LDS-01, one seed: ann right, bob turning half
the angle, cy refused; trimmed of the verdicts' samples) and from the real launch-file checker.

The results.json is checked against Gradescope's documented keys and types (:mod:`tests.gradescope_schema`), the XML
parsed with ``xml.etree``.
"""

from __future__ import annotations

import argparse
import copy
import csv
import json
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from bt_nav.cli import grade
from bt_nav.cli.grade.formats import write_class_formats, write_exe_formats
from bt_nav.grading.exe.grid import error_row
from bt_nav.grading.formats import (
    WEIGHTS_FILE,
    Weights,
    class_records,
    gradescope_results,
    junit_xml,
    load_weights,
    not_graded_reason,
    read_record,
)
from bt_nav.grading.grid import Job
from bt_nav.grading.hints import student_words
from bt_nav.grading.launch import check_launch
from tests.gradescope_schema import gradescope_problems
from tests.grading.classfixture import make_class

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
CLASS = FIXTURES / "grades" / "lab_class"
#: What a student on Gradescope cannot open: the grader's files and folders, an absolute path.
GRADER_FILES = re.compile(r"[\w.-]+\.(?:log|json|html|md|png|mp4|mcap|db3)\b|grade's directory|\bbag/"
                          r"|(?<![\w.])/[\w.-]+/")


def unopenable(text: str) -> list[str]:
    """The names in ``text`` a student reading it on Gradescope could not open."""
    return GRADER_FILES.findall(text)


def record(name: str) -> dict[str, Any]:
    return read_record(CLASS / name)


def launch(file: str) -> dict[str, Any]:
    return check_launch(FIXTURES / "launch" / file, Path("reactive_navigator.py")).to_dict()


def test_one_node_s_results_json_validates_and_scores_its_runs() -> None:
    right, wrong = gradescope_results(record("ann")), gradescope_results(record("bob"))
    for doc in (right, wrong):
        assert gradescope_problems(doc) == [], doc
        assert len(doc["tests"]) == 1 and sum(t["max_score"] for t in doc["tests"]) == 100, doc
    assert right["score"] == 100 and right["tests"][0]["status"] == "passed", right
    assert wrong["score"] == 0 and wrong["tests"][0]["status"] == "failed", wrong
    run = record("bob")["runs"][0]
    first = next(c for c in run["verdict"]["checks"] if not c["passed"])  # maneuver 1 turned 44 deg right; ...
    output = wrong["tests"][0]["output"]
    assert wrong["tests"][0]["name"] == "run lab_object C lds01 seed 0", wrong
    assert output.startswith("**FAILED**: 21 of 27 checks failed\n") and f"\n- {first['reason']}\n" in output, output
    assert "**How to fix:** Turn by 90 +- 10 deg. Any way of measuring the turn passes" in output, output
    assert "a turn timed at the rate you command" in output and "rather than timed" not in output, output
    assert run["reason"].removeprefix("failed: ") in wrong["output"], wrong["output"]
    assert right["tests"][0]["output"] == "**PASSED**", right
    said = ("In the preview (at 9.3x) it failed (failed: maneuver 1 turned 45 deg right; the Smart Pivot needs 90 +- "
            "10 deg either side (readings at the start: front 0.32 m, left 1.93 m, right 2.07 m) (and 20 more "
            "maneuvers failed)); graded again at 1x real time it failed.")
    assert output.endswith(f"\n\n{said}"), output
    for doc in (right, wrong):  # Gradescope shows Markdown, and nothing the student cannot open there
        assert doc["output_format"] == doc["test_output_format"] == "md", doc
        assert all(t["output_format"] == "md" for t in doc["tests"]), doc
        assert unopenable(json.dumps(doc)) == [], doc
        assert "execution_time" not in doc  # not known from a grade's files: the runs ran in parallel


def test_the_launch_file_checks_take_their_share() -> None:
    """A right node whose launch file forgets safety_distance: the runs' 80 points, and one of the three checks'
    20/3 (it starts the node); a check is a test that says why it failed and on which line."""
    doc = gradescope_results({**record("ann"), "launch": launch("forgets_safety.launch.py")})
    assert gradescope_problems(doc) == [], doc
    checks = [t for t in doc["tests"] if t["name"].startswith("launch file: ")]
    assert [t["status"] for t in checks] == ["passed", "failed", "failed"], checks
    assert sum(t["max_score"] for t in checks) == pytest.approx(20) and doc["score"] == pytest.approx(80 + 20 / 3)
    assert "Launch file: 1/3 checks passed." in doc["output"], doc["output"]
    assert all(t["output"].startswith("**FAILED**: ") for t in checks[1:]), checks
    assert "**How to fix:** The file declares no launch argument `safety_distance`: add " \
        "`DeclareLaunchArgument('safety_distance', default_value='0.5')`" in checks[1]["output"], checks[1]
    assert "How to fix" not in checks[0]["output"], checks[0]


def test_a_bt_nav_error_is_not_the_node_s_and_scores_nothing() -> None:
    doc = record("ann")
    doc["runs"].append(error_row(Job("lab_object", "C", 1, "lab"), "disk full"))
    out = gradescope_results(doc)
    assert gradescope_problems(out) == [], out
    run, error = out["tests"]
    assert (run["score"], run["max_score"]) == (100, 100) and (error["score"], error["max_score"]) == (0, 0), out
    assert "status" not in error and "not your node's failure" in error["output"], error


def test_the_weights_file_an_instructor_changes() -> None:
    assert load_weights() == Weights()  # the shipped file says what the code's defaults say
    assert WEIGHTS_FILE.is_file()


def test_an_instructor_s_weights(tmp_path: Path) -> None:
    mine = tmp_path / "weights.yaml"
    mine.write_text("total: 10\nworlds: {lab_object: 3}\nvisibility: after_published\n")
    weights = load_weights(mine)
    assert (weights.total, weights.launch_share, weights.worlds) == (10, 0.2, {"lab_object": 3.0})
    doc = record("ann")
    doc["runs"] = [doc["runs"][0], {**doc["runs"][0], "world": "lab_side", "passed": False, "reason": "failed: x"}]
    out = gradescope_results(doc, weights)
    assert [t["max_score"] for t in out["tests"]] == [7.5, 2.5] and out["score"] == 7.5, out
    assert out["visibility"] == "after_published" and gradescope_problems(out) == [], out
    for bad, said in (("totl: 3\n", "unknown key(s) totl"), ("visibility: students\n", "visibility is 'students'"),
                      ("launch_share: 2\n", "launch_share within 0..1"), ("- 1\n", "a YAML mapping")):
        mine.write_text(bad)
        with pytest.raises(ValueError, match=said.replace("(", r"\(").replace(")", r"\)")):
            load_weights(mine)


def junit_cases(xml: str) -> dict[str, list[ET.Element]]:
    root = ET.fromstring(xml)
    assert root.tag == "testsuites"
    return {suite.get("name"): suite.findall("testcase") for suite in root.findall("testsuite")}


def test_junit_has_a_testcase_per_run_and_the_reason_as_failure_message() -> None:
    doc = record("bob")
    doc["runs"] = [doc["runs"][0], {**record("ann")["runs"][0], "seed": 1}]
    xml = junit_xml([("bob", doc)])
    (cases,) = junit_cases(xml).values()
    assert [c.get("name") for c in cases] == ["lab_object C lds01 seed 0", "lab_object C lds01 seed 1"]
    assert cases[0].find("failure").get("message") == doc["runs"][0]["reason"] and cases[1].find("failure") is None
    suite = ET.fromstring(xml).find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("2", "1", "0")


def test_a_class_as_junit_and_gradescope(tmp_path: Path) -> None:
    """The class: a testsuite per student (a refused one fails with its reason), each student's results.json in the
    class directory, and the launch-file checks a folder of hand-ins puts on each student's class.json line."""
    out = tmp_path / "class"
    shutil.copytree(CLASS, out)
    page = json.loads((out / "class.json").read_text())
    page["students"][0]["handin"] = {"launch": launch("sheet.launch.py")}
    (out / "class.json").write_text(json.dumps(page))
    args = argparse.Namespace(gradescope=str(tmp_path / "results.json"), junit=str(tmp_path / "report.xml"),
                              weights=None, exe=None, klass=str(out))
    written = write_class_formats(args, out)
    assert [p.relative_to(tmp_path).as_posix() for p in written] == [
        "class/_gradescope/ann/results.json", "class/_gradescope/bob/results.json", "class/_gradescope/cy/results.json",
        "report.xml"]
    results = {n: json.loads((out / "_gradescope" / n / "results.json").read_text()) for n in ("ann", "bob", "cy")}
    assert not (tmp_path / "results.json").exists()  # several students: no dict of them no platform reads
    assert all(gradescope_problems(doc) == [] for doc in results.values()), results
    assert [results[n]["score"] for n in ("ann", "bob", "cy")] == [100, 0, 0], results
    assert len(results["ann"]["tests"]) == 4 and results["cy"]["output"].startswith("**Not run**: nothere.py"), results
    cases = junit_cases((tmp_path / "report.xml").read_text())
    assert list(cases) == ["ann", "bob", "cy"]
    assert [c.get("classname") for c in cases["ann"]] == ["ann.lab_object.C.lds01", *["ann.launch_file"] * 3]
    assert len(cases["bob"]) == 1 and cases["bob"][0].find("failure") is not None
    assert cases["cy"][0].find("failure").get("message") == "nothere.py does not exist"


def test_a_class_of_one_writes_its_results_json_where_the_option_says(tmp_path: Path) -> None:
    out = tmp_path / "class"
    shutil.copytree(CLASS / "ann", out / "ann")
    page = json.loads((CLASS / "class.json").read_text())
    page["students"] = page["students"][:1]
    (out / "class.json").write_text(json.dumps(page))
    args = argparse.Namespace(gradescope=str(tmp_path / "r.json"), junit=None, weights=None, exe=None, klass="x")
    write_class_formats(args, out)
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc == gradescope_results(class_records(out)[0][1], wall_time=doc["execution_time"])
    assert doc["execution_time"] >= 1, doc  # this process's wall time so far: a class of one is the command


def test_one_node_s_formats_from_its_grade_directory(tmp_path: Path) -> None:
    args = argparse.Namespace(gradescope=str(tmp_path / "g" / "results.json"), junit=str(tmp_path / "r.xml"),
                              weights=None, exe="python3 ann.py", klass=None)
    assert write_exe_formats(args, CLASS / "bob") == [tmp_path / "g" / "results.json", tmp_path / "r.xml"]
    assert gradescope_problems(json.loads((tmp_path / "g" / "results.json").read_text())) == []
    assert list(junit_cases((tmp_path / "r.xml").read_text())) == ["python3 ann.py --mistake half_angle"]


def test_bad_format_options_refuse_the_grade_before_any_run(tmp_path: Path,
                                                           capsys: pytest.CaptureFixture) -> None:
    bad = tmp_path / "w.yaml"
    bad.write_text("totl: 3\n")
    for argv, said in ((["--exe", "python3 x.py", "--gradescope", "r.json", "--weights", str(bad)], "unknown key"),
                       (["--junit", "r.xml"], "written for --exe or --class"),
                       (["--exe", "python3 x.py", "--weights", str(bad)], "--csv or a class page: give one"),
                      (["--exe", "python3 x.py", "--csv", "s.csv"], "--csv is written for --class")):
        with pytest.raises(SystemExit) as exit_:
            grade.main(argv)
        assert exit_.value.code == 2 and said in capsys.readouterr().err, argv


def test_records_are_not_changed_by_writing_them() -> None:
    doc = {**record("bob"), "launch": launch("sheet.launch.py")}
    before = copy.deepcopy(doc)
    gradescope_results(doc)
    junit_xml([("bob", doc)])
    assert doc == before


def test_each_failed_test_says_what_failed_the_rule_and_the_fix_in_words_a_student_can_read(tmp_path: Path) -> None:
    """The fixture class (tests/grading/classfixture.py): a crash quotes the node's last output (not "see
    node.log"), a launch-file check a TA must look at scores as passed and says so, a refused hand-in says why; no
    output names a file or folder the student cannot open on Gradescope."""
    records = dict(class_records(make_class(tmp_path / "class")))
    crash = gradescope_results(records["cy"])["tests"][0]
    assert crash["status"] == "failed" and crash["output"].startswith(
        "**FAILED**: the node crashed after 3.2 s wall: ValueError: min() arg is an empty sequence "
        "(reactive\\_navigator.py:57 in scan\\_cb)\n"), crash
    assert "**How to fix:** Your node raised the exception quoted here" in crash["output"], crash
    assert '  File "reactive_navigator.py", line 57, in scan_cb\n' in crash["output"], crash  # its traceback
    dee = gradescope_results(records["dee"])
    ta = dee["tests"][-1]
    assert dee["score"] == 100 and ta["status"] == "passed" and ta["score"] == ta["max_score"], dee
    assert ta["output"].startswith("**NOT CHECKED: a TA will look**: a `Command` substitution"), ta
    for name, record in records.items():
        doc = gradescope_results(record)
        assert gradescope_problems(doc) == [] and unopenable(json.dumps(doc)) == [], (name, doc)
        for test in doc["tests"]:
            if test.get("status") == "failed" and test["name"].startswith("run "):
                assert "**How to fix:**" in test["output"] and test["output"].startswith("**FAILED**: "), test


def test_a_hand_in_with_a_run_not_graded_is_an_autograder_error_never_a_score(tmp_path: Path) -> None:
    """fay's run was not graded (another program on its domain): no results.json (Gradescope shows an autograder
    error: never 0, never full marks), autograder_error.md saying why; the CSV leaves her score empty."""
    out = make_class(tmp_path / "class")
    for name in ("fay", "ann"):  # a class of one, as Gradescope's submission is
        one = tmp_path / name
        shutil.copytree(out / name, one / name)
        page = json.loads((out / "class.json").read_text())
        page["students"] = [s for s in page["students"] if s["name"] == name]
        (one / "class.json").write_text(json.dumps(page))
        target = tmp_path / f"{name}-results" / "results.json"
        target.parent.mkdir()
        target.write_text("{}")  # an old one must not stay
        args = argparse.Namespace(gradescope=str(target), junit=None, csv=None, weights=None, exe=None, klass="x")
        written = write_class_formats(args, one)
        if name == "fay":
            assert not target.exists() and written == [one / "_gradescope" / "fay" / "autograder_error.md"], written
            text = written[0].read_text()
            assert text.startswith("The autograder could not grade this submission: 1 of 1 run(s) not graded (not "
                                   "graded: another program is on ROS_DOMAIN_ID 7"), text
            assert "not a failure of your code" in text and "pid 4242" in text, text
        else:
            assert json.loads(target.read_text())["score"] == pytest.approx(80 + 20 / 3)
    assert not_graded_reason(dict(class_records(out))["fay"]) is not None


def test_a_failed_run_beside_one_not_graded_is_a_failure() -> None:
    """A run the node failed at 1x is its verdict: another run left without one (not its doing) cannot make the
    hand-in pass, so it is FAILED, not NOT GRADED (its score still waits: not_graded_reason); with no failure, NOT
    GRADED."""
    from bt_nav.grading.scores import handin_verdict

    failed = {"passed": False, "outcome": "verdict", "reason": "failed: maneuver 1 turned 44 deg"}
    behind = {"passed": False, "outcome": "error", "not_graded": "not graded: its simulator fell behind"}
    passed = {"passed": True, "outcome": "verdict", "reason": "passed"}
    assert handin_verdict({"runs": [failed, behind]}) == "FAILED"
    assert not_graded_reason({"runs": [failed, behind]}) is not None
    assert handin_verdict({"runs": [passed, behind]}) == "NOT GRADED"
    assert handin_verdict({"runs": [passed, passed]}) == "PASSED"


def test_the_gradebook_csv_has_a_row_per_student(tmp_path: Path) -> None:
    out = make_class(tmp_path / "class")
    weights = tmp_path / "w.yaml"
    weights.write_text("total: 10\n")
    args = argparse.Namespace(gradescope=None, junit=None, csv=str(tmp_path / "scores.csv"), weights=str(weights),
                              exe=None, klass=str(out))
    assert write_class_formats(args, out) == [tmp_path / "scores.csv"]
    rows = list(csv.DictReader((tmp_path / "scores.csv").open()))
    got = {r["student"]: (r["score"], r["max_score"], r["verdict"]) for r in rows}
    assert got == {"ann": ("8.6667", "10", "FAILED"), "bob": ("2", "10", "FAILED"), "cy": ("2", "10", "FAILED"),
                   "dee": ("10", "10", "PASSED"), "eve": ("0", "10", "FAILED"), "fay": ("", "10", "NOT GRADED")}, got
    ann, dee = rows[0], rows[3]
    assert ann["run lab_object C lds01 seed 0"] == "passed" and \
        ann["launch file: declares safety_distance (default 0.5)"] == "failed", ann
    assert dee["launch file: passes safety_distance to the node"] == "not checked", dee
    assert "10 / 10" in (out / "class.html").read_text()  # the class page written again with the weights


def test_student_words_drop_the_grader_s_files() -> None:
    assert student_words("failed (see node.log)") == "failed"
    assert student_words("ValueError: x (node.py:3 in cb; see node.log)") == "ValueError: x (node.py:3 in cb)"
    assert student_words("/autograder/submission/pkg/reactive_navigator.py does not exist") == \
        "reactive_navigator.py does not exist"
    assert student_words("no call of /reactive_control/evaluate_mission") == \
        "no call of /reactive_control/evaluate_mission"  # a ROS name is no file
