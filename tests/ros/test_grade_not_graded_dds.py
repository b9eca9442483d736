"""Issue 44 over real DDS: another program on the only domain a grade may take (``BT_NAV_DOMAIN_RANGE`` of one
domain) leaves the run not graded, never failed. The guard names the program; the run does not claim to have moved
("another domain" when it was the same one); it is not re-run at 1x; the grade counts it apart (not 0/1 passed) and
exits 3 (runs without a verdict, ``--resume`` runs them). A grade whose only domain another run holds waits for it, then
is not graded either: it never takes a domain it did not claim."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from ros_harness import DOMAIN_ID

from bt_nav.ros.supervise import claim_domain_id, release_domain_id

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
RUN = "lab_object C lds01 seed 0"


@pytest.mark.slow
def test_a_foreign_program_on_the_only_domain_leaves_the_run_not_graded(tmp_path: Path) -> None:
    domain = claim_domain_id(215, 232, wait=120.0)  # one of this test's own, besides the harness's
    foreign = subprocess.Popen([sys.executable, str(FIXTURES / "noservice_node.py"), "--drive", "0.1"],
                               env={**os.environ, "ROS_DOMAIN_ID": str(domain)}, start_new_session=True)
    out = tmp_path / "grid"
    release_domain_id(domain)  # for the grade to claim (the foreign program sets it, as a fixed ROS_DOMAIN_ID does)
    try:
        done = subprocess.run([sys.executable, "-m", "bt_nav.cli", "grade", "--profile", "lab", "--exe",
                               f"{sys.executable} {FIXTURES / 'lab_student_node.py'} --choice C",
                               "--worlds", "lab_object", "--maneuvers", "C", "--lidars", "lds01", "--seeds", "1",
                               "--record", "off", "--progress", "off", "--out", str(out)],
                              env={**os.environ, "BT_NAV_DOMAIN_RANGE": f"{domain}-{domain}"},
                              capture_output=True, text=True, check=False, timeout=300)
    finally:
        foreign.terminate()
        foreign.wait(10)
    print(done.stdout, done.stderr)
    [row] = json.loads((out / "grade.json").read_text())["runs"]
    said = row.get("not_graded") or ""
    assert said.startswith(f"not graded: another program is on ROS_DOMAIN_ID {domain}: ") and \
        f"of pid {foreign.pid} (python noservice_node.py --drive 0.1)" in said, row["reason"]
    assert said.endswith(f"no other domain was free to move to (tried ROS_DOMAIN_ID {domain}; BT_NAV_DOMAIN_RANGE "
                         f"{domain}-{domain}): not the node's failure, --resume runs it again"), said
    assert not row["passed"] and row["outcome"] == "bt_nav error" and row["domains"] == [domain]
    assert "another domain" not in done.stdout + json.dumps(row) and "started again" not in done.stdout
    assert not (out / "realtime").exists() and not (out / "rerun").exists()  # never re-run: it is no failure
    assert f"{RUN}: NOT GRADED (not graded: another program" in done.stdout, done.stdout
    assert "0/0 passed, 1 without a verdict apart (not the node's: not graded" in done.stdout, done.stdout
    assert done.returncode == 3, done.stdout
    assert "not graded (not yours)" in (out / "feedback.md").read_text()


@pytest.mark.slow
def test_a_grade_whose_only_domain_another_run_holds_waits_then_is_not_graded(tmp_path: Path) -> None:
    """``BT_NAV_DOMAIN_RANGE`` of one domain, held by this test process all along (the harness's claim): the grade
    waits for it (``--timeout 4``: 4 s and the shutdown margin, :func:`bt_nav.grading.exe.run.domain_wait`), starts
    nothing, and says why."""
    out = tmp_path / "grid"
    done = subprocess.run([sys.executable, "-m", "bt_nav.cli", "grade", "--profile", "lab", "--exe",
                           f"{sys.executable} {FIXTURES / 'lab_student_node.py'} --choice C", "--worlds", "lab_object",
                           "--maneuvers", "C", "--lidars", "lds01", "--seeds", "1", "--record", "off", "--progress",
                           "off", "--timeout", "4", "--out", str(out)],
                          env={**os.environ, "BT_NAV_DOMAIN_RANGE": f"{DOMAIN_ID}-{DOMAIN_ID}"},
                          capture_output=True, text=True, check=False, timeout=300)
    print(done.stdout, done.stderr)
    [row] = json.loads((out / "grade.json").read_text())["runs"]
    said = row["not_graded"]
    assert said.startswith(f"not graded: no free ROS_DOMAIN_ID in BT_NAV_DOMAIN_RANGE {DOMAIN_ID}-{DOMAIN_ID} (each "
                           "one is claimed by another run on this machine; waited 34."), said
    assert row["outcome"] == "bt_nav error" and row["run_dir"] == "" and row["domains"] == []
    assert f"{RUN}: NOT GRADED (not graded: no free ROS_DOMAIN_ID in BT_NAV_DOMAIN_RANGE" in done.stdout, done.stdout
    assert done.returncode == 3, done.stdout
