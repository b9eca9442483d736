"""bt_nav.run.session: the one layer that starts, watches and stops a mission over DDS (domain lease, run directory
log files, launcher, verdict wait), and the paths that run a mission all go through it."""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import pytest

from bt_nav.ros.supervise import NoFreeDomainError, StopRequest
from bt_nav.run.session import EXITED, STOPPED, TIMEOUT, VERDICT, DomainLease, MissionSession, files_written

ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Script:
    """A tiny process for a session: ``python -c CODE``, named ``executable``."""

    code: str
    executable: str = "node"

    def command(self, python: str | None = None) -> list[str]:
        return [sys.executable, "-c", self.code]


@pytest.fixture
def lock_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Domain claims in a directory of this test's own, from a range of four."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", "150-153")
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    return tmp_path


def test_a_lease_keeps_the_users_domain_and_claims_one_otherwise(lock_dir: Path,
                                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    assert DomainLease(42).claim() == 42
    monkeypatch.setenv("ROS_DOMAIN_ID", "7")
    assert DomainLease().claim() == 7  # the user's choice (demo, sim-run)
    lease = DomainLease(start=0, user_env=False)  # a graded run: a domain of its own, whatever the shell says
    first, second = lease.claim(), lease.claim()
    assert (first, second) == (150, 151) and lease.held == [150, 151]  # the shared one is still held
    assert DomainLease(start=0, user_env=False).claim() == 152  # nobody else gets a held one
    lease.release()
    assert lease.held == [] and DomainLease(start=0, user_env=False).claim() == 150


def test_a_lease_never_hands_out_a_domain_it_did_not_claim(lock_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``BT_NAV_DOMAIN_RANGE`` of one domain, held by another run: a claim that may not wait fails at once with the
    range in its words; one that waits gets the domain as soon as the other run hands it back."""
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", "150-150")
    other = DomainLease(user_env=False)
    assert other.claim() == 150
    with pytest.raises(NoFreeDomainError, match=r"^no free ROS_DOMAIN_ID in BT_NAV_DOMAIN_RANGE 150-150 \(each one "
                                                r"is claimed by another run on this machine\)$"):
        DomainLease(user_env=False).claim()
    waiting = DomainLease(user_env=False)
    got: list[tuple[int, float]] = []
    began = time.monotonic()
    thread = threading.Thread(target=lambda: got.append((waiting.claim(wait=20.0), time.monotonic() - began)))
    thread.start()
    time.sleep(0.5)
    assert not got and thread.is_alive()  # waiting, not sharing
    other.release()
    thread.join(10.0)
    assert got and got[0][0] == 150 and 0.5 <= got[0][1] < 1.5 and waiting.held == [150], got
    waiting.release()


def test_a_claim_waits_for_another_process_and_its_wait_is_bounded(lock_dir: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """Another process's claim is seen to end by polling; with nothing handed back the wait ends at its bound, and
    a stop request ends it early."""
    monkeypatch.setenv("BT_NAV_DOMAIN_RANGE", "151-151")
    lock = lock_dir / "bt_nav_ros_domains" / "domain-151.lock"
    lock.parent.mkdir(parents=True, exist_ok=True)
    holder = subprocess.Popen([sys.executable, "-c", f"import fcntl, sys, time; f = open({str(lock)!r}, 'a+'); "
                               "fcntl.flock(f, fcntl.LOCK_EX); print('held', flush=True); time.sleep(1.5)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        began = time.monotonic()
        with pytest.raises(NoFreeDomainError, match=r"BT_NAV_DOMAIN_RANGE 151-151 \(.*; waited 0\.[67] s\)$"):
            DomainLease(user_env=False).claim(wait=0.6)
        assert 0.6 <= time.monotonic() - began < 1.4
        stop = StopRequest()
        stop.signum = 2
        began = time.monotonic()
        with pytest.raises(NoFreeDomainError):
            DomainLease(user_env=False).claim(wait=30.0, stop=stop)
        assert time.monotonic() - began < 1.0
        lease = DomainLease(user_env=False)
        assert lease.claim(wait=30.0) == 151 and holder.poll() is not None  # the holder's exit freed it
        lease.release()
    finally:
        holder.kill()
        holder.wait()


def test_a_session_logs_each_process_and_waits_for_the_verdict(tmp_path: Path) -> None:
    verdict = tmp_path / "verdict.json"
    seen: list[tuple[str, str]] = []
    session = MissionSession(123, run_dir=tmp_path, tee=lambda name, line: seen.append((name, line)))
    assert session.env["ROS_DOMAIN_ID"] == "123" and session.env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    session.start(Script(f"import time; print('hi', flush=True); time.sleep(0.3); open({str(verdict)!r}, 'w')"
                         ".write('{{}}'); time.sleep(30)", "judge"))
    try:
        assert session.wait(20.0, files_written([verdict])) == (VERDICT, None)
    finally:
        session.close(1.0)
    assert (tmp_path / "judge.log").read_text().startswith("hi\n") and seen[0] == ("judge", "hi")
    assert session.children[0].poll() is not None  # stopped by close


def test_a_session_says_which_process_ended_first_or_that_it_was_stopped(tmp_path: Path) -> None:
    stop = StopRequest()
    session = MissionSession(123, stop=stop, sink=lambda name, line: None)
    never = files_written([tmp_path / "none.json"])
    session.start(Script("import time; time.sleep(30)", "sim"))
    ends = session.start(Script("raise SystemExit(3)"))
    try:
        assert session.wait(0.2, never, watched=lambda c: c is not ends) == (TIMEOUT, None)
        outcome, child = session.wait(20.0, never)
        assert (outcome, child) == (EXITED, ends) and child is not None and child.poll() == 3
        stop.signum = 2
        assert session.wait(20.0, never, watched=lambda c: c is not ends) == (STOPPED, None)
    finally:
        session.close(1.0)


#: The paths that run a mission over DDS (grade --exe, demo and its lab and --exe runs, sim-run, the ROS bench).
MISSION_PATHS = ("bt_nav/grading/exe/run.py", "bt_nav/cli/demo/__init__.py", "bt_nav/cli/demo/lab.py",
                 "bt_nav/cli/demo/exe.py", "bt_nav/cli/sim_run.py", "bt_nav/run/rosmission.py", "bench/ros_mission.py")


def test_every_mission_path_starts_and_waits_through_the_session() -> None:
    """No path makes its own launcher, claims its own domain or writes its own wait loop for a verdict."""
    own = re.compile(r"\bLauncher\(|claim_domain_id\(|choose_domain_id\(|release_domain_id\(|LogFiles\(|"
                     r"\.is_file\(\) for|time\.sleep\(")
    found = {path: own.findall((ROOT / path).read_text(encoding="utf-8")) for path in MISSION_PATHS}
    assert not {path: hits for path, hits in found.items() if hits}, found
