"""Who else is on a run's domain (bt_nav.ros.domain_guard), on a stand-in /proc: a process is the run's by its
mark, whatever its node is called; another program's is foreign; what cannot be traced is blamed on nobody."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from bt_nav.ros.domain_guard import RUN_MARK_ENV, DomainGuard, gid_pid16, run_mark

MARK = "4242:150"


def _proc(tmp_path: Path, processes: dict[int, str | None]) -> Path:
    """A /proc with ``pid -> mark`` (None: no mark in its environment)."""
    for pid, mark in processes.items():
        (tmp_path / str(pid)).mkdir()
        env = [b"PATH=/usr/bin"] + ([f"{RUN_MARK_ENV}={mark}".encode()] if mark is not None else [])
        (tmp_path / str(pid) / "environ").write_bytes(b"\0".join(env) + b"\0")
        (tmp_path / str(pid) / "cmdline").write_bytes(b"python3\0talker.py\0")
    return tmp_path


def _endpoint(pid: int, node: str = "n", vendor: bytes = b"\x01\x0f") -> SimpleNamespace:
    gid = vendor + b"\x78\xfd" + (pid & 0xFFFF).to_bytes(2, "little") + b"\x25\x3b" + bytes(8)
    return SimpleNamespace(endpoint_gid=list(gid), node_name=node)


def test_a_fast_dds_gid_carries_the_low_bits_of_the_pid() -> None:
    assert gid_pid16(bytes.fromhex("010f78fdcd58253b0000000000001303")) == 22733
    assert gid_pid16(bytes.fromhex("01100000cd58253b0000000000001303")) is None  # another vendor's GUID


def test_the_runs_own_processes_are_its_own_whatever_their_node_names(tmp_path: Path) -> None:
    guard = DomainGuard(MARK, _proc(tmp_path, {300: MARK, 301: MARK}))
    for endpoint in (_endpoint(300, "reactive_navigator"), _endpoint(301, "bt_nav_sim")):
        guard.see(endpoint)
    assert guard.finding("150") is None


def test_another_program_on_the_domain_is_named_with_its_process(tmp_path: Path) -> None:
    guard = DomainGuard(MARK, _proc(tmp_path, {300: MARK, 400: None, 500: "9999:150"}))
    for pid in (300, 400, 500):
        guard.see(_endpoint(pid, f"node{pid}"))
    finding = guard.finding("150")
    assert finding is not None and finding.startswith("another program is on ROS_DOMAIN_ID 150: ")
    assert "node node400 of pid 400 (python3 talker.py)" in finding and "node500 of pid 500" in finding
    assert "node300" not in finding


def test_what_cannot_be_traced_is_blamed_on_nobody(tmp_path: Path) -> None:
    guard = DomainGuard(MARK, _proc(tmp_path, {300: MARK}))
    guard.see(_endpoint(777))  # no such process (it left)
    guard.see(_endpoint(400, vendor=b"\x01\x10"))  # another vendor
    guard.see(_endpoint(400, "_ros2cli_daemon_150_abc"))  # the ros2 CLI's daemon only watches
    assert guard.finding("150") is None
    assert not DomainGuard("", tmp_path).active  # no mark (a judge started by hand): the guard is off


def test_a_launchers_mark_names_it_and_the_domain() -> None:
    assert run_mark(150, launcher_pid=4242) == MARK


def test_a_foreign_program_is_named_by_its_file_however_deep_its_folder(tmp_path: Path) -> None:
    _proc(tmp_path, {400: None})
    deep = "/" + "/".join(["a_rather_long_folder_name"] * 8)
    words = [f"{deep}/bin/python", f"{deep}/noservice_node.py", "--drive", "0.3"]
    (tmp_path / "400" / "cmdline").write_bytes("\0".join(words).encode() + b"\0")
    guard = DomainGuard(MARK, tmp_path)
    guard.see(_endpoint(400, "wanderer"))
    assert "node wanderer of pid 400 (python noservice_node.py --drive 0.3)" in (guard.finding("150") or "")


def _stat(proc: Path, pid: int, parent: int) -> None:
    (proc / str(pid) / "stat").write_text(f"{pid} (python3 my node) S {parent} {pid} {pid} 0 -1\n")


def test_the_nodes_children_are_the_nodes_whatever_environment_it_gave_them(tmp_path: Path) -> None:
    """Issue 44: a run is not graded only for a program that is neither the node nor one of its children. A child
    the node started with an environment of its own (no mark) is the node's; a program without the mark whose
    ancestors carry none is foreign, even one the launcher's own process started (a test's talker)."""
    proc = _proc(tmp_path, {300: MARK, 310: None, 320: None, 400: None, 4242: None})
    _stat(proc, 300, 1)
    _stat(proc, 310, 300)  # the node's child, env={}
    _stat(proc, 320, 310)  # and its grandchild
    _stat(proc, 400, 4242)  # started by the launcher's process, not by the run's mark
    _stat(proc, 4242, 1)
    guard = DomainGuard(MARK, proc)
    for pid in (310, 320, 400):
        guard.see(_endpoint(pid, f"node{pid}"))
    finding = guard.finding("150") or ""
    assert "node400 of pid 400" in finding and "node310" not in finding and "node320" not in finding, finding
