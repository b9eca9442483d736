"""Test-only: ``python grader_faults.py FAULT ARGS...`` runs ``bt-nav ARGS...`` with one failure of the grader's own
injected (issue 52), as it was seen on busy machines, so a test can check that it never decides a grade.

Why a wrapper: the faults are in the grade's own process (its fork server, its launcher); product code knows nothing of
this module (as :mod:`faulty_executive` for the executive). The faults:

- ``server-killed-in-hello``: the fork server is SIGKILLed while it imports (held behind ``tests.forkserver_gate``);
- ``server-socket-closed``: the fork server's socket is closed under the runs once it has forked a simulator (what a
  sibling's ``serving`` block did when it ended first);
- ``server-never-hello``: the fork server never says hello (held behind the gate; ``HELLO_WAIT`` 2 s);
- ``sim-killed``: the first run's simulator gets SIGTERM from outside the run 1 s after its start (a sibling's stop);
- ``sim-killed-always``: every simulator does: the cell cannot be graded.
"""

from __future__ import annotations

import os
import signal
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
FAULTS = ("server-killed-in-hello", "server-socket-closed", "server-never-hello", "sim-killed", "sim-killed-always")
#: Wall seconds after its start a simulator gets the sibling's SIGTERM.
KILL_AFTER = 1.0


def _gated_server(on_start: Any = None) -> None:
    """Fork servers that wait behind a gate never opened (``tests.forkserver_gate``); ``on_start(server)`` after each
    starts."""
    from bt_nav.ros import forkserver

    os.environ["BT_NAV_TEST_GATE"] = str(Path(tempfile.mkdtemp(prefix="bt_nav_gate_")) / "never")
    original = forkserver.ForkServer.__init__

    def start(self: Any, preload: Any = forkserver.PRELOAD, timeout: float = forkserver.READY_TIMEOUT) -> None:
        original(self, ("tests.forkserver_gate", *preload), timeout)
        if on_start is not None:
            on_start(self)

    forkserver.ForkServer.__init__ = start  # type: ignore[method-assign]


def _close_after_first_spawn() -> None:
    """The server's socket closed by someone else once it has forked a child."""
    from bt_nav.ros import forkserver

    original = forkserver.ForkServer.spawn
    done = threading.Event()

    def spawn(self: Any, *args: Any, **kwargs: Any) -> Any:
        child = original(self, *args, **kwargs)
        if not done.is_set():
            done.set()
            threading.Timer(KILL_AFTER, self.close).start()
        return child

    forkserver.ForkServer.spawn = spawn  # type: ignore[method-assign]


def _kill_simulators(every: bool) -> None:
    """SIGTERM to a simulator's group :data:`KILL_AFTER` s after its start: the first one, or ``every`` one."""
    from bt_nav.ros import supervise

    original = supervise.Launcher.start
    killed = threading.Event()

    def start(self: Any, spec: Any, *args: Any, **kwargs: Any) -> Any:
        child = original(self, spec, *args, **kwargs)
        if child.name == "sim" and (every or not killed.is_set()):
            killed.set()
            threading.Timer(KILL_AFTER, lambda: child.signal_group(signal.SIGTERM)).start()
        return child

    supervise.Launcher.start = start  # type: ignore[method-assign]


def arm(fault: str) -> None:
    """Inject ``fault`` (one of :data:`FAULTS`) into this process."""
    from bt_nav.ros import forkserver

    if fault == "server-killed-in-hello":
        _gated_server(lambda server: threading.Timer(0.5, server.proc.kill).start())
    elif fault == "server-socket-closed":
        _close_after_first_spawn()
    elif fault == "server-never-hello":
        forkserver.HELLO_WAIT = 2.0
        _gated_server()
    elif fault in ("sim-killed", "sim-killed-always"):
        _kill_simulators(every=fault == "sim-killed-always")
    else:
        raise SystemExit(f"grader_faults.py: unknown fault {fault!r} (one of {', '.join(FAULTS)})")


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    arm(sys.argv[1])
    from bt_nav.cli import main

    sys.exit(main(sys.argv[2:]))
