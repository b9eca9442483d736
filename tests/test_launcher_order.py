"""Launcher.shutdown's ``first``: that child is stopped while the others still run (a graded node's world goes on
until it has stopped), then the rest together. Plain Python children, no ROS."""

from __future__ import annotations

import os
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from bt_nav.ros.supervise import Launcher

#: A child that, on SIGINT, notes the wall time it got it and ``delay`` s later exits (its stop takes that long).
SCRIPT = """
import signal, sys, time
out, delay, lose = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
def stop(*_):
    global lose
    if lose:  # this SIGINT is lost, as one can be inside rclpy
        lose -= 1
        return
    with open(out, "w") as f:
        f.write(repr(time.time()))
    time.sleep(delay)
    sys.exit(0)
signal.signal(signal.SIGINT, stop)
print("up", flush=True)
while True:
    time.sleep(0.01)
"""


@dataclass
class _Spec:
    """A named child running SCRIPT."""

    executable: str
    script: Path
    out: Path
    delay: float
    lose: int = 0

    def command(self, python: str | None = None) -> list[str]:
        return [python or sys.executable, str(self.script), str(self.out), str(self.delay), str(self.lose)]


def _started(tmp_path: Path, lose: int = 0) -> tuple[Launcher, dict[str, Path]]:
    script = tmp_path / "child.py"
    script.write_text(SCRIPT)
    launcher = Launcher(dict(os.environ), sink=lambda name, line: None, driver="node")
    outs = {}
    for name, delay in (("world", 0.0), ("node", 0.4), ("judge", 0.0)):
        outs[name] = tmp_path / f"{name}.sigint"
        launcher.start(_Spec(name, script, outs[name], delay, lose if name == "node" else 0))
    time.sleep(1.0)  # every child has its handler
    return launcher, outs


def test_the_first_child_stops_before_the_others_get_sigint(tmp_path: Path) -> None:
    launcher, outs = _started(tmp_path)
    node = next(c for c in launcher.children if c.name == "node")
    launcher.shutdown(grace=3.0, together=True, first=node)
    got = {name: float(path.read_text()) for name, path in outs.items()}
    assert got["world"] - got["node"] >= 0.35 and got["judge"] - got["node"] >= 0.35, got  # after its 0.4 s stop
    assert abs(got["world"] - got["judge"]) < 0.3, got  # the rest together
    assert all(c.poll() == 0 and c.stopped_by == signal.SIGINT for c in launcher.children)


def test_after_first_comes_between_the_first_child_and_the_others(tmp_path: Path) -> None:
    """A grade's recorder is told to stop once the node has stopped, before the world and the judge get SIGINT."""
    launcher, outs = _started(tmp_path)
    node = next(c for c in launcher.children if c.name == "node")
    called: list[tuple[float, bool]] = []
    launcher.shutdown(grace=3.0, together=True, first=node,
                      after_first=lambda: called.append((time.time(), node.poll() is not None)))
    got = {name: float(path.read_text()) for name, path in outs.items()}
    assert len(called) == 1 and called[0][1], "called once, the node ended"
    assert got["node"] < called[0][0] <= min(got["world"], got["judge"]), (got, called)


def test_a_failing_after_first_keeps_no_child_running(tmp_path: Path) -> None:
    launcher, _ = _started(tmp_path)
    node = next(c for c in launcher.children if c.name == "node")

    def broken() -> None:
        raise RuntimeError("the hook failed")

    launcher.shutdown(grace=3.0, together=True, first=node, after_first=broken)
    assert all(c.poll() is not None and c.stopped_by == signal.SIGINT for c in launcher.children)


def test_without_first_they_stop_together(tmp_path: Path) -> None:
    launcher, outs = _started(tmp_path)
    launcher.shutdown(grace=3.0, together=True)
    got = [float(path.read_text()) for path in outs.values()]
    assert max(got) - min(got) < 0.3, got


def test_the_first_child_gets_a_second_sigint_when_the_first_is_lost(tmp_path: Path) -> None:
    launcher, outs = _started(tmp_path, lose=1)
    node = next(c for c in launcher.children if c.name == "node")
    launcher.shutdown(grace=3.0, together=True, first=node)
    assert node.stopped_by == signal.SIGINT and node.sigints == 2 and 1.5 <= node.stop_seconds < 3.0
    got = {name: float(path.read_text()) for name, path in outs.items()}
    assert got["world"] > got["node"]  # the others after it, still
    others = [c for c in launcher.children if c is not node]
    assert all(c.sigints == 1 and c.stopped_by == signal.SIGINT for c in others)
