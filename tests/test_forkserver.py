"""The fork server starts a child as a launcher's Popen would: its own arguments, environment, directory, session,
output and watchdog descriptor; its exit code or signal; gone with the server. Real processes, real signals."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_nav.ros import forkserver
from bt_nav.ros.forkserver import ForkedProcess, ForkServer, ForkServerError
from bt_nav.ros.supervise import WATCHDOG_ENV, Launcher, child_env, choose_domain_id
from bt_nav.testing import wait_until

REPO = Path(__file__).resolve().parents[1]
TARGET = "tests.forkserver_target:main"


@pytest.fixture
def server(monkeypatch: pytest.MonkeyPatch) -> Iterator[ForkServer]:
    """A fork server started from the repository (so ``tests`` imports) with a variable its children must not see."""
    monkeypatch.chdir(REPO)
    monkeypatch.setenv("ONLY_THE_SERVER_HAS_THIS", "1")
    started = ForkServer(preload=("bt_nav.cli",))
    yield started
    started.close()


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return state[state.rindex(")") + 2] != "Z"


def test_a_child_gets_its_arguments_environment_directory_session_and_descriptor(server: ForkServer,
                                                                                 tmp_path: Path) -> None:
    read, write = os.pipe()
    os.write(write, b"hello")
    try:
        child = server.spawn(["say", "3"], {"SOME_VAR": "mine", "PATH": os.environ["PATH"], "PYTHONUNBUFFERED": "1"},
                             str(tmp_path), {"SOME_FD": read}, target=TARGET)
    finally:
        os.close(read)
        os.close(write)
    output = child.stdout.read().splitlines()
    assert child.wait(10) == 3 and child.poll() == 3
    assert output[:6] == ["argv=['say', '3']", "env=mine leaked=None", f"cwd={tmp_path}", "own_session=True",
                          "fd_readable=hello", "sys_argv=['say', '3']"], output
    assert output[6] == "to stderr"  # where stdout goes, in order: PYTHONUNBUFFERED is honoured as at a start


def test_signals_end_a_child_as_they_end_a_started_process(server: ForkServer) -> None:
    env = {"PATH": os.environ["PATH"]}
    sleeper = server.spawn(["sleep", "30"], env, str(REPO), target=TARGET)
    assert sleeper.stdout.readline().strip() == "sleeping"
    title = Path(f"/proc/{sleeper.pid}/cmdline").read_text().replace("\0", " ").strip()
    assert title == f"{sys.executable} -m bt_nav.cli sleep 30", title  # what ps shows: the command it runs
    with pytest.raises(subprocess.TimeoutExpired):
        sleeper.wait(0.2)
    assert sleeper.poll() is None
    os.killpg(sleeper.pid, signal.SIGTERM)  # its group is its own
    assert sleeper.wait(10) == -signal.SIGTERM
    interrupted = server.spawn(["sleep", "30"], env, str(REPO), target=TARGET)
    assert interrupted.stdout.readline().strip() == "sleeping"
    os.killpg(interrupted.pid, signal.SIGINT)  # KeyboardInterrupt: a traceback, then the end by SIGINT
    assert interrupted.wait(10) == -signal.SIGINT
    assert "KeyboardInterrupt" in interrupted.stdout.read()


def test_a_retitled_child_names_its_ros_log_after_its_executable(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """rcutils names a log file after glibc's program name, which pointed into the retitled command line: the file was
    named after the title's tail, and rclpy refused to start once that passed 255 bytes (a long server command line
    leaves room for such a title)."""
    monkeypatch.chdir(REPO)
    started = ForkServer(preload=("bt_nav.cli",) * 40)  # a command line with room for a title of 400 characters
    try:
        env = {**child_env(choose_domain_id(), {"PATH": os.environ["PATH"]}), "ROS_LOG_DIR": str(tmp_path)}
        child = started.spawn(["ros", "--option", "x" * 300], env, str(tmp_path), target=TARGET)
        output = child.stdout.read()
        assert child.wait(30) == 0, output
    finally:
        started.close()
    names = eval(output.splitlines()[-1])  # noqa: S307 (the child's own repr of a list of str)
    assert len(names) == 1 and names[0].startswith(f"{Path(sys.executable).name}_{child.pid}_"), names


def test_a_target_that_raises_exits_with_1_and_its_traceback(server: ForkServer) -> None:
    child = server.spawn(["say"], {"PATH": os.environ["PATH"]}, str(REPO), target=TARGET)  # no exit code: IndexError
    assert child.wait(10) == 1
    assert "IndexError" in child.stdout.read()


def test_children_end_with_the_server(server: ForkServer) -> None:
    sleeper = server.spawn(["sleep", "60"], {"PATH": os.environ["PATH"]}, str(REPO), target=TARGET)
    assert sleeper.stdout.readline().strip() == "sleeping"
    server.close()
    wait_until(lambda: not _alive(sleeper.pid), 5.0, "the child to end with its fork server")
    assert sleeper.wait(5) == -signal.SIGTERM
    with pytest.raises(ForkServerError):
        server.spawn(["say", "0"], {}, str(REPO), target=TARGET)


def test_a_server_is_usable_at_once_and_forks_once_it_is_ready(monkeypatch: pytest.MonkeyPatch,
                                                                tmp_path: Path) -> None:
    """The server imports while its owner goes on (a grade starts its first nodes meanwhile); a spawn waits for it."""
    monkeypatch.chdir(REPO)
    gate = tmp_path / "open"
    monkeypatch.setenv("BT_NAV_TEST_GATE", str(gate))
    started = ForkServer(preload=("tests.forkserver_gate",))
    try:
        assert started.usable and not started.settled and not started.ready(0.2)  # still importing, behind the gate
        gate.touch()
        child = started.spawn(["say", "0"], {"PATH": os.environ["PATH"]}, str(tmp_path), target=TARGET)
        assert child.wait(10) == 0 and started.settled and started.alive
    finally:
        started.close()


def test_a_server_that_never_becomes_ready_is_passed_over(monkeypatch: pytest.MonkeyPatch) -> None:
    """Its preload fails: spawns raise, the launcher starts the command the usual way, current() offers it no more."""
    monkeypatch.chdir(REPO)
    broken = ForkServer(preload=("bt_nav_no_such_module",))
    try:
        assert not broken.ready(30) and not broken.usable
        with pytest.raises(ForkServerError, match="not ready"):
            broken.spawn(["say", "0"], {}, str(REPO), target=TARGET)
        launcher = Launcher({"PATH": os.environ["PATH"]}, sink=lambda n, line: None, forker=broken)
        child = launcher.start(_Spec("bt-nav", [sys.executable, "-m", "bt_nav.cli", "help"]))
        assert isinstance(child.popen, subprocess.Popen) and child.popen.wait(30) == 0
    finally:
        broken.close()


class _Spec:
    """What a launcher starts (:class:`bt_nav.ros.supervise.Startable`)."""

    def __init__(self, executable: str, command: list[str]) -> None:
        self.executable, self._command = executable, command

    def command(self) -> list[str]:
        return self._command


def test_a_launcher_forks_bt_nav_commands_and_starts_the_rest(server: ForkServer) -> None:
    lines: list[tuple[str, str]] = []
    launcher = Launcher({"PATH": os.environ["PATH"], "SOME_VAR": "x"}, sink=lambda n, line: lines.append((n, line)),
                        forker=server)
    ours = launcher.start(_Spec("bt-nav", [sys.executable, "-m", "bt_nav.cli", "help"]))
    theirs = launcher.start(_Spec("echo", ["/bin/echo", "not ours"]))
    assert isinstance(ours.popen, ForkedProcess) and isinstance(theirs.popen, subprocess.Popen)
    assert ours.popen.wait(10) == 0 and theirs.popen.wait(10) == 0
    launcher.shutdown(grace=1.0)
    assert ("echo", "not ours") in lines
    assert any(name == "bt-nav" and line.startswith("usage: bt-nav") for name, line in lines), lines[:3]


def test_a_forked_child_stops_when_its_launchers_watchdog_pipe_closes(server: ForkServer) -> None:
    """The launcher's watchdog pipe reaches the child under its own number: a forked node stops when its launcher
    dies (:func:`bt_nav.ros.supervise.watch_parent_pipe`), as a started one does."""
    read, write = os.pipe()
    child = server.spawn(["watch", "60"], {"PATH": os.environ["PATH"]}, str(REPO), {WATCHDOG_ENV: read},
                         target=TARGET)
    os.close(read)
    assert child.stdout.readline().strip() == "watching"
    os.close(write)  # what the kernel does when the launcher dies
    assert child.wait(10) == -signal.SIGTERM


def test_serving_shares_one_server_and_is_switched_off_by_the_environment() -> None:
    assert forkserver.current() is None
    with forkserver.serving() as outer:
        assert outer is not None and forkserver.current() is outer
        with forkserver.serving() as inner:
            assert inner is outer
        assert forkserver.current() is outer  # the inner block does not end the outer one's server
    assert forkserver.current() is None and outer.proc.poll() is not None
    with forkserver.serving(False) as none:
        assert none is None and forkserver.current() is None
    assert not forkserver.wanted({forkserver.SWITCH_ENV: "off"}) and not forkserver.wanted({forkserver.SWITCH_ENV: "0"})
    assert forkserver.wanted({}) and forkserver.wanted({forkserver.SWITCH_ENV: "on"})
