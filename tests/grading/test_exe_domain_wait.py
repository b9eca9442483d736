"""A graded run's ROS domain when the range runs out (:func:`bt_nav.grading.exe.run.run_exe_job`, its processes
replaced by a stand-in that holds the domain a while): a run never takes a domain it did not claim; with more
workers than domains it waits for one, and with none coming free it is not graded, in words that name the range."""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pytest

from bt_nav.grading.exe import grid as exe_grid
from bt_nav.grading.exe import run
from bt_nav.grading.exe.run import ExeSettings
from bt_nav.grading.grid import make_jobs
from bt_nav.ros.supervise import StopRequest, claim_domain_id, release_domain_id

DOMAIN = 160
JOBS = make_jobs(["stage_4"], ["none"], 3)


@pytest.fixture
def one_domain(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[tuple[int, float, float]]:
    """``BT_NAV_DOMAIN_RANGE`` of one domain (lock files of this test's own); each attempt holds its domain 0.4 s and
    passes. Returns the attempts as (domain, wall start, wall end)."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", f"{DOMAIN}-{DOMAIN}")
    attempts: list[tuple[int, float, float]] = []

    def attempt(job: Any, settings: ExeSettings, domain: int, *rest: Any) -> dict[str, Any]:
        began = time.monotonic()
        time.sleep(0.4)
        attempts.append((domain, began, time.monotonic()))
        return {"passed": True, "outcome": "verdict", "reason": "passed", "verdict": None, "job": job.key,
                "run_dir": str(settings.out / f"seed{job.seed}"), "domain": domain}

    monkeypatch.setattr(run, "_attempt", attempt)
    return attempts


def _settings(out: Path, limit: float = 150.0) -> ExeSettings:
    return ExeSettings(f"{sys.executable} node.py", "homework", out, limit=limit)


def test_more_workers_than_domains_wait_their_turn(tmp_path: Path, one_domain: list) -> None:
    rows = [row for _, row in exe_grid.run_pool([(job, _settings(tmp_path)) for job in JOBS], 3, None)]
    assert [row["outcome"] for row in rows] == ["verdict"] * 3 and all(row["passed"] for row in rows), rows
    spans = sorted((began, ended) for _, began, ended in one_domain)
    assert [domain for domain, _, _ in one_domain] == [DOMAIN] * 3
    assert all(ended <= began for (_, ended), (began, _) in zip(spans, spans[1:], strict=False)), \
        f"two runs on ROS_DOMAIN_ID {DOMAIN} at once: {spans}"


def test_a_run_whose_only_domain_stays_taken_is_not_graded(tmp_path: Path, one_domain: list,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(run, "DOMAIN_WAIT_MARGIN", 0.0)
    assert claim_domain_id(DOMAIN, DOMAIN, range_name="held by the test") == DOMAIN  # another run holds it
    try:
        began = time.monotonic()
        row = run.run_exe_job(JOBS[0], _settings(tmp_path, limit=0.5))
        waited = time.monotonic() - began
        stop = StopRequest()
        stop.signum = 2
        stopped = run.run_exe_job(JOBS[1], _settings(tmp_path, limit=60.0), stop)
    finally:
        release_domain_id(DOMAIN)
    assert one_domain == [] and 0.5 <= waited < 2.0  # nothing ran, and the wait was bounded
    said = row["not_graded"]
    assert said.startswith(f"not graded: no free ROS_DOMAIN_ID in BT_NAV_DOMAIN_RANGE {DOMAIN}-{DOMAIN} (each one "
                           "is claimed by another run on this machine; waited 0."), said
    assert said.endswith("): not the node's failure, --resume runs it again") and row["reason"] == said
    assert (row["outcome"], row["passed"], row["run_dir"], row["domains"]) == ("bt_nav error", False, "", [])
    assert stopped["outcome"] == "stopped" and "not_graded" not in stopped and stopped["reason"] == (
        "stopped by SIGINT while waiting for a free ROS domain")


def test_a_shared_domain_with_none_free_to_move_to_is_not_graded(tmp_path: Path, one_domain: list,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """The run's domain had another program on it and the range has no other: the run does not move (onto a domain
    it did not claim), it is not graded."""
    def shared(job: Any, settings: ExeSettings, domain: int, *rest: Any) -> dict[str, Any]:
        run_dir = settings.out / "run"
        run_dir.mkdir(parents=True, exist_ok=True)
        return {"passed": False, "outcome": run.SHARED_DOMAIN, "reason": "no verdict: another program is on it",
                "verdict": None, "run_dir": str(run_dir)}

    monkeypatch.setattr(run, "_attempt", shared)
    row = run.run_exe_job(JOBS[0], _settings(tmp_path))
    assert row["domains"] == [DOMAIN] and row["not_graded"].endswith(
        f"no other domain was free to move to (tried ROS_DOMAIN_ID {DOMAIN}; BT_NAV_DOMAIN_RANGE {DOMAIN}-{DOMAIN}): "
        "not the node's failure, --resume runs it again"), row
