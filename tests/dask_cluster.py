"""A Dask cluster started as a user would, from the command line (``dask scheduler``, ``dask worker``), for the
tests that grade on a cluster (lock-step and ``--exe``). Everything listens on 127.0.0.1 only, without
dashboards; every process is in a session of its own and is killed by :meth:`DaskProcesses.close`."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

from bt_nav.testing import wait_until

REPO = Path(__file__).resolve().parents[1]
DASK = Path(sys.executable).with_name("dask")


class DaskProcesses:
    """``dask scheduler`` (its address in :attr:`file`) and ``workers`` ``dask worker`` of ``nthreads`` threads
    each, without nannies (a killed worker stays dead), all started in ``cwd`` with ``env``."""

    def __init__(self, tmp: Path, workers: int = 2, nthreads: int = 1, *, cwd: Path = REPO,
                 env: Mapping[str, str] | None = None) -> None:
        self.file = tmp / "scheduler.json"
        self.cwd, self.env = cwd, dict(os.environ if env is None else env)
        self.procs: list[subprocess.Popen[bytes]] = []
        self._start("scheduler", "--scheduler-file", str(self.file), "--host", "127.0.0.1", "--port", "0",
                    "--no-dashboard")
        wait_until(self.file.exists, 30, "the dask scheduler to write its file", interval=0.1)
        self.workers = [self._start("worker", "--scheduler-file", str(self.file), "--nthreads", str(nthreads),
                                    "--no-nanny", "--no-dashboard", "--host", "127.0.0.1") for _ in range(workers)]

    def _start(self, *args: str) -> subprocess.Popen[bytes]:
        proc = subprocess.Popen([str(DASK), *args], cwd=self.cwd, env=self.env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        self.procs.append(proc)
        return proc

    def close(self) -> None:
        """Kill every process of the cluster (each one's whole session group)."""
        for proc in self.procs:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)


def marked(variable: str, mark: str) -> list:
    """Every live process whose environment carries ``variable=mark`` (a test's own children, wherever they run)."""
    import psutil

    found = []
    for proc in psutil.process_iter():
        try:
            if proc.environ().get(variable) == mark and proc.status() != psutil.STATUS_ZOMBIE:
                found.append(proc)
        except (psutil.Error, OSError):
            continue
    return found
