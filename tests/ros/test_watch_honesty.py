"""``bt-nav watch`` tells the truth: each snapshot with its age, and a clear line when no executive publishes."""

from __future__ import annotations

import time
from collections.abc import Callable

from simtools import Proc

from bt_nav.testing import wait_until


def test_says_so_when_no_executive_publishes() -> None:
    watch = Proc("watch", "--grace", "1", "--timeout", "8")
    started = time.monotonic()
    wait_until(lambda: any("no executive is publishing" in line for line in watch.stderr), 6,
               "watch to say that nobody publishes", watch.output)
    assert time.monotonic() - started < 6
    assert watch.wait(15) == 1


def test_snapshot_age_and_the_executive_going_away(start_executive: Callable) -> None:
    executive = start_executive(sim_time=False)  # ticks on wall time: publishes ~/tree at once
    watch = Proc("watch", "--grace", "1", "--status-period", "1")
    try:
        wait_until(lambda: any("(snapshot 1, " in line for line in watch.stdout), 40, "the first snapshot",
                   lambda: watch.output() + executive.tail())
        wait_until(lambda: any(line.strip().startswith("[o] Priorities [") for line in watch.stdout), 10,
                   "the snapshot drawn as py_trees' tree", watch.output)  # the art, drawn from the JSON document
        wait_until(lambda: any("last snapshot" in line and "ago" in line for line in watch.stdout), 20,
                   "a status line with the snapshot's age", watch.output)
        executive.stop()
        wait_until(lambda: any("no executive is publishing" in line for line in watch.stderr), 15,
                   "watch to notice the executive is gone", watch.output)
    finally:
        watch.stop()
