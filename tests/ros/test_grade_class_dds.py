"""A class with bad entries over real DDS: each bad entry fails its student with the reason naming the file, and the
rest of the class is graded (one run: a right C node whose file declares ``# CHOICE: C``)."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import pytest

from bt_nav.cli import grade

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"


def test_a_bad_entry_fails_its_student_and_the_class_is_graded(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture) -> None:
    source = (FIXTURES / "lab_student_node.py").read_text()
    good, plain = tmp_path / "ann.py", tmp_path / "cy.py"
    good.write_text(re.sub(r"^# CHOICE: given on the command line.*$", "# CHOICE: C", source, count=1, flags=re.M))
    plain.write_text(source)  # no choice of its own: '# CHOICE: given on the command line'
    manifest = tmp_path / "class.yaml"
    manifest.write_text(f"ann: {sys.executable} {good} --variant c_stands_05\nbob: {sys.executable} "
                        f"{tmp_path / 'bob.py'}\ncy: {sys.executable} {plain}\n")
    out = tmp_path / "class"
    code = grade.main(["--class", str(manifest), "--profile", "lab", "--worlds", "lab_object", "--lidars", "lds01",
                       "--seeds", "1", "--jobs", "1", "--record", "off", "--progress", "off", "--out", str(out)])
    stdout = capsys.readouterr().out
    assert code == 1, stdout  # two students failed
    assert f"  bob: FAILED (not run: {tmp_path / 'bob.py'} does not exist)" in stdout.splitlines(), stdout
    assert f"  cy: FAILED (not run: {plain} declares no maneuver" in stdout, stdout
    page = {s["name"]: s for s in json.loads((out / "class.json").read_text())["students"]}
    assert (page["ann"]["passed"], page["ann"]["runs"]) == (1, 1), page["ann"]
    assert page["bob"]["refused"] == f"{tmp_path / 'bob.py'} does not exist", page["bob"]
    assert page["cy"]["refused"].startswith(f"{plain} declares no maneuver"), page["cy"]
    assert not (out / "bob" / "grade.json").exists() and not (out / "cy" / "grade.json").exists()
    assert "Not run: " in (out / "bob" / "feedback.md").read_text()  # a refused student hears why
