"""Issue 52: the fork server and its client take either end going at any time, without a traceback. Seen: a grade with
a re-run closed a server before its hello (an empty pool), and the server's ``BrokenPipeError`` and the reader thread's
``EBADF`` reached the user's terminal; a grid's end closed the server its probe's runs still used (SIGTERM to their
simulators). Real processes, no DDS."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_nav.ros import forkserver
from bt_nav.ros.forkserver import ForkServer, ForkServerError
from bt_nav.testing import wait_until

REPO = Path(__file__).resolve().parents[1]
TARGET = "tests.forkserver_target:main"
ENV = {"PATH": os.environ["PATH"]}


@pytest.fixture
def thread_errors(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[str]]:
    """What any thread raised (the reader thread's EBADF was one)."""
    seen: list[str] = []
    monkeypatch.setattr(threading, "excepthook", lambda args: seen.append(repr(args.exc_value)))
    yield seen


@pytest.fixture
def gated(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """The gate a server's imports wait behind (``tests.forkserver_gate``), not open yet."""
    monkeypatch.chdir(REPO)
    gate = tmp_path / "open"
    monkeypatch.setenv("BT_NAV_TEST_GATE", str(gate))
    return gate


def test_a_server_closed_before_its_hello_ends_at_once_and_quietly(gated: Path, thread_errors: list[str]) -> None:
    server = ForkServer(preload=("tests.forkserver_gate",))
    time.sleep(0.3)  # importing, behind the gate
    began = time.monotonic()
    server.close()
    assert time.monotonic() - began < 3.0 and server.proc.poll() is not None  # killed: it had forked nothing
    server.close()  # a second close does nothing (the socket is closed once)
    assert not thread_errors and not server.usable and "closed before its hello" in server.refusal
    with pytest.raises(ForkServerError, match="closed before its hello"):
        server.spawn(["say", "0"], ENV, str(REPO), target=TARGET)


def test_a_server_whose_client_went_before_its_hello_exits_0_without_a_word() -> None:
    mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    mine.close()  # the grade is gone before the server could say hello
    done = subprocess.run([sys.executable, "-m", "bt_nav.ros.forkserver", str(theirs.fileno()), "bt_nav.cli"],
                          pass_fds=(theirs.fileno(),), capture_output=True, text=True, timeout=120, cwd=REPO)
    theirs.close()
    assert done.returncode == 0 and done.stderr == "", done.stderr


def test_a_server_that_never_says_hello_is_given_up_by_a_spawn(gated: Path, thread_errors: list[str]) -> None:
    server = ForkServer(preload=("tests.forkserver_gate",))
    try:
        began = time.monotonic()
        with pytest.raises(ForkServerError, match="given up: no hello after 1 s"):
            server.spawn(["say", "0"], ENV, str(REPO), target=TARGET, hello_wait=1.0)
        assert time.monotonic() - began < 5.0
        wait_until(lambda: server.proc.poll() is not None, 5.0, "the silent server to be ended")
        gated.touch()  # too late: it is not asked again
        assert not server.usable and forkserver.current() is None
    finally:
        server.close()
    assert not thread_errors


def test_a_server_killed_during_its_hello_refuses_spawns(gated: Path, thread_errors: list[str]) -> None:
    server = ForkServer(preload=("tests.forkserver_gate",))
    try:
        server.proc.kill()
        assert not server.ready(30) and "ended before its hello" in server.refusal
        with pytest.raises(ForkServerError, match="not ready"):
            server.spawn(["say", "0"], ENV, str(REPO), target=TARGET)
    finally:
        server.close()
    assert not thread_errors


def test_a_child_of_a_server_whose_socket_closed_is_lost_with_its_cause(monkeypatch: pytest.MonkeyPatch,
                                                                       thread_errors: list[str]) -> None:
    monkeypatch.chdir(REPO)
    server = ForkServer(preload=("bt_nav.cli",))
    sleeper = server.spawn(["sleep", "60"], ENV, str(REPO), target=TARGET)
    assert sleeper.stdout.readline().strip() == "sleeping"
    server.close()
    assert sleeper.wait(5) < 0 and "the fork server it was forked from is gone (closed by its grade)" in sleeper.lost
    server.close()
    assert not thread_errors


def test_serving_ends_the_server_with_its_last_block_in_any_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """A grid's block ending while another thread's block (its probe's runs) still forks from the server must not
    end it: their simulators got SIGTERM from its end."""
    monkeypatch.chdir(REPO)
    opened, release, child = threading.Event(), threading.Event(), []

    def probe() -> None:
        with forkserver.serving() as server:
            assert server is not None
            opened.set()
            release.wait(30)
            child.append(server.spawn(["sleep", "30"], ENV, str(REPO), target=TARGET))
            assert child[0].stdout.readline().strip() == "sleeping"
            os.kill(child[0].pid, 15)
            assert child[0].wait(10) == -15  # its own end, reported by the server that still runs

    with forkserver.serving() as grid:
        thread = threading.Thread(target=probe)
        thread.start()
        assert opened.wait(30)
    assert grid is not None and grid.proc.poll() is None and forkserver.current() is grid  # the probe holds it
    release.set()
    thread.join(60)
    assert child and grid.proc.wait(10) is not None and forkserver.current() is None
