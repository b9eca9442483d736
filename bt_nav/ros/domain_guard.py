"""Who else is on a run's ROS domain: a participant that is not the run's own is found, never blamed on the node.

A run claims a ROS domain of its own (:func:`bt_nav.ros.supervise.claim_domain_id`), but a program that picks its
domain another way (a fixed ``ROS_DOMAIN_ID`` in someone's shell, a second grader told the same id) can join it. Its
service may answer the judge's calls and its commands drive the robot: a node that offers no service was once told
"(the node offers std_srvs/srv/SetBool as /toggle_navigation)", with 1672 commands counted against ~460 in sibling
runs. The graph audit cannot tell that program from the student's by its node names.

What tells them apart is the process. Every process a bt_nav launcher starts carries :data:`RUN_MARK_ENV` (the
launcher's pid and the run's domain: :func:`run_mark`) in its environment, and its children inherit it. A Fast DDS
endpoint's GUID carries the low 16 bits of its process id (GUID prefix bytes 4-5, little-endian; vendor 0x010f). A
process on this machine with that pid whose environment carries another mark, or none, is foreign (unless one of its
ancestors is the run's: the node's own children are the node's, whatever environment it gave them); so is one whose
pid is none of ours. Endpoints of another DDS vendor, and pids no process has any more, are left alone (never blamed
on anyone). Linux only (``/proc``); elsewhere the guard sees nothing.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

#: The environment variable that marks a process as one of a run's (set by :func:`bt_nav.ros.supervise.child_env`).
RUN_MARK_ENV = "BT_NAV_RUN"
#: Node names of passive observers any run may meet on its domain: the ros2 CLI's daemon (started by the first
#: ``ros2`` command on a domain, it outlives that run and only watches the graph).
PASSIVE_PREFIX = "_ros2cli"
#: rclpy's name of an endpoint whose node is not discovered yet.
UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"
#: Fast DDS's vendor id, the first two bytes of every GUID it makes.
FAST_DDS_VENDOR = b"\x01\x0f"


def run_mark(domain_id: int, launcher_pid: int | None = None) -> str:
    """The mark of the run a launcher (this process) starts on ``domain_id``: ``<launcher pid>:<domain>``."""
    return f"{os.getpid() if launcher_pid is None else launcher_pid}:{int(domain_id)}"


def gid_pid16(gid: bytes | Iterable[int]) -> int | None:
    """The low 16 bits of the process id in a Fast DDS endpoint GUID (None: another vendor's GUID)."""
    raw = bytes(gid)
    if len(raw) < 6 or raw[:2] != FAST_DDS_VENDOR:
        return None
    return int.from_bytes(raw[4:6], "little")


def _environ_mark(pid: int, proc: Path) -> str | None:
    """``pid``'s run mark ('' when it has none), None when it cannot be read (gone, or not ours to read)."""
    try:
        fields = (proc / str(pid) / "environ").read_bytes().split(b"\0")
    except OSError:
        return None
    key = RUN_MARK_ENV.encode() + b"="
    return next((f[len(key):].decode(errors="replace") for f in fields if f.startswith(key)), "")


def _cmdline(pid: int, proc: Path, limit: int = 120) -> str:
    """The process's command line as a reader knows it: paths by their file names, at most ``limit`` characters.

    File names rather than whole paths, so that the program's own name survives however deep its folder lies.
    """
    try:
        words = (proc / str(pid) / "cmdline").read_bytes().split(b"\0")
    except OSError:
        return "?"
    text = " ".join(Path(w.decode(errors="replace")).name if b"/" in w else w.decode(errors="replace")
                    for w in words if w)
    return text if len(text) <= limit else text[:limit - 1] + "…"


class DomainGuard:
    """The endpoints of a run's domain, sorted into the run's own and foreign ones by their processes.

    Args:
        mark: this run's mark (default: this process's :data:`RUN_MARK_ENV`; none: the guard is off, as when a
            user starts a judge by hand on a domain of their choosing).
        proc: the ``/proc`` to read (a test's stand-in).
    """

    def __init__(self, mark: str | None = None, proc: str | os.PathLike[str] = "/proc") -> None:
        self.mark = os.environ.get(RUN_MARK_ENV) if mark is None else mark
        self.proc = Path(proc)
        launcher = (self.mark or "").partition(":")[0]
        self.own_pids = {os.getpid(), *([int(launcher)] if launcher.isdigit() else [])}
        self._known: dict[int, bool] = {}  # pid16 -> foreign (classified once: a process keeps its environment)
        self.foreign: dict[int, str] = {}  # pid16 -> what the foreign process is

    @property
    def active(self) -> bool:
        return bool(self.mark) and self.proc.is_dir()

    def see(self, endpoint: Any) -> None:
        """One endpoint of the graph (rclpy's TopicEndpointInfo: ``endpoint_gid``, ``node_name``)."""
        if not self.active or str(endpoint.node_name).startswith(PASSIVE_PREFIX):
            return
        pid16 = gid_pid16(endpoint.endpoint_gid)
        if pid16 is None or pid16 in self._known:
            return
        verdict = self._classify(pid16)
        if verdict is None:
            return  # no such process (any more): ask again at the next sighting
        self._known[pid16] = verdict[0]
        if verdict[0]:
            pid, name = verdict[1], str(endpoint.node_name or "")
            who = f"node {name}" if name and name != UNKNOWN_NODE else "a participant"  # named at a later sighting
            self.foreign[pid16] = f"{who} of pid {pid} ({_cmdline(pid, self.proc)})"

    def _classify(self, pid16: int) -> tuple[bool, int] | None:
        """(foreign, pid) of the process behind ``pid16``; None when no process here has that pid."""
        candidates = [int(name) for name in os.listdir(self.proc) if name.isdigit() and int(name) & 0xFFFF == pid16]
        if not candidates:
            return None
        for pid in candidates:
            # the launcher itself by its pid; below it only what carries the run's mark and what that started (a
            # program the launcher's process started by other means, as a test does, is not the run's)
            if pid in self.own_pids or any(_environ_mark(p, self.proc) == self.mark for p in self._lineage(pid)):
                return False, pid
        readable = [pid for pid in candidates if _environ_mark(pid, self.proc) is not None]
        return (True, readable[0]) if readable else None

    def _lineage(self, pid: int, depth: int = 32) -> list[int]:
        """``pid`` and its ancestors (nearest first, up to ``depth``): a child the node starts with an environment
        of its own (``subprocess`` with ``env={...}``) has no mark, but it is still the node's, never foreign."""
        chain = [pid]
        while len(chain) <= depth:
            try:
                stat = (self.proc / str(chain[-1]) / "stat").read_text()
                parent = int(stat.rpartition(")")[2].split()[1])  # after the command name, which may hold spaces
            except (OSError, ValueError, IndexError):
                break
            if parent <= 1 or parent in chain:
                break
            chain.append(parent)
        return chain

    def finding(self, domain: str) -> str | None:
        """The run's domain is shared: with what (None: only the run's own processes were seen)."""
        if not self.foreign:
            return None
        return (f"another program is on ROS_DOMAIN_ID {domain}: " + "; ".join(sorted(self.foreign.values()))
                + " (not the run's, not the node's)")
