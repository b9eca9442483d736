"""How many ``--exe`` runs at once with ``--jobs auto``: one per usable core, and more while the cores stay idle.

Why not simply one per core: a run over DDS is three processes that spend most of a mission waiting for sim
time, so at the default ``--rtf 5`` one run keeps about a third of a core busy (measured on this project's 2-core
machine: 6.1 CPU s per 14 s run, the cores 39 % busy with two runs at once). Why not a fixed larger number: a run
whose processes lack CPU answers late in sim time, so its verdict would change with the load (docs/grading.md).

So :class:`Admission` keeps a number of *places* and lets a run start whenever one is free:

- at the grid's start it looks at the cores for :data:`OPENING` wall seconds: nearly idle (``burst_idle``) they
  get every place up to ``limit`` at once (eight runs in two waves of four, not a ramp whose last wave starts
  late), otherwise ``base`` places (one per core);
- a place is added, up to ``limit``, when the cores this process may use were at least ``idle_needed`` idle
  since the last look and the last start was ``gap`` wall seconds ago (a run's start-up is its busiest part, and
  the next look should see it running);
- a place is taken away, down to ``base``, when the cores were less than ``idle_floor`` idle while no run was
  starting up (no start for ``gap`` s): the runs in flight use more CPU than their places assumed, and a run
  whose processes lack CPU answers late. Runs in flight go on; the next ones wait.

A machine busy with something else (another grade, a build) sees no extra place; one whose runs use more CPU
than bt_nav's own nodes loses them. The idle share comes from ``/proc/stat`` (Linux: what ROS 2 Jazzy runs on);
where it cannot be read, no place beyond ``base`` is given. And a run that fails at ``--rtf`` above 1 is run
again at 1x before its failure stands (:mod:`bt_nav.grading.realtime`), so a load that slipped through costs
time, not a verdict.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Sequence

from bt_nav.ros.supervise import StopRequest, usable_cores

#: Runs at most per usable core, with ``--jobs auto``. Not three: the right C node's default lab grade (12 runs, 2
#: cores, 2026-11-27) took 55.4 s with up to six runs at once and 62.7 s with four, but six starve the nodes (each
#: kept up 3.3-4.4x) and a right node turning at 1.5 rad/s closed loop on odometry (the grader suite's
#: ``c_no_aeb_fast``) then overshot its 90 deg pivot to 103-121 deg in 4-5 of 8 runs; two at once passed 8 of 8 in
#: the same 75 s wall.
PER_CORE = 2
#: The idle share of the cores an extra run needs: a run at the default rtf takes about a third of a core.
IDLE_NEEDED = 0.4
#: Below this idle share, with no run starting up, a place is taken away.
IDLE_FLOOR = 0.1
#: The idle share at the grid's start that opens every place at once.
BURST_IDLE = 0.8
#: Wall seconds of the opening look at the cores.
OPENING = 0.25
#: Wall seconds between a start and the next extra one (a run's start-up, imports and discovery, takes ~2 s).
GAP = 3.0


class AutoJobs(int):
    """``--jobs auto``: counts as one run per usable core, and lets an ``--exe`` grid add runs while the cores stay
    idle (:class:`Admission`). A plain number of jobs is exactly that many."""


def cpu_times(cores: Sequence[int] | None = None, path: str = "/proc/stat") -> tuple[float, float] | None:
    """(idle, total) jiffies of ``cores`` (all when None) since boot, or None when ``path`` cannot be read."""
    wanted = None if cores is None else {f"cpu{i}" for i in cores}
    idle = total = 0.0
    try:
        with open(path, encoding="ascii") as stream:
            for line in stream:
                name, _, rest = line.partition(" ")
                if not name.startswith("cpu") or name == "cpu" or (wanted is not None and name not in wanted):
                    continue
                fields = [float(v) for v in rest.split()]
                idle += fields[3] + (fields[4] if len(fields) > 4 else 0.0)  # idle + iowait
                total += sum(fields[:8])  # user nice system idle iowait irq softirq steal (guest is in user)
    except (OSError, ValueError, IndexError):
        return None
    return (idle, total) if total > 0 else None


class IdleMeter:
    """The idle share of this process's cores over the last ``window`` wall seconds or more (None: unknown)."""

    def __init__(self, read: Callable[[], tuple[float, float] | None] | None = None, window: float = 1.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        try:
            cores: Sequence[int] | None = sorted(os.sched_getaffinity(0))
        except (AttributeError, OSError):
            cores = None
        self._read = read or (lambda: cpu_times(cores))
        self.window, self.clock = window, clock
        self._last, self._at = self._read(), clock()
        self._share: float | None = None
        self._share_from = -float("inf")  # when the window of the current share began

    def idle_share(self) -> float | None:
        """Idle share between the last two readings at least ``window`` apart (a reading is taken when the last is
        that old: a share over a few milliseconds says nothing)."""
        if self.clock() - self._at < self.window:
            return self._share
        now = self._read()
        last, self._last = self._last, now
        self._share_from, self._at = self._at, self.clock()
        if now is None or last is None or now[1] <= last[1]:
            self._share = None
        else:
            self._share = (now[0] - last[0]) / (now[1] - last[1])
        return self._share

    def fresh_since(self, when: float) -> bool:
        """Whether the window of the last :meth:`idle_share` began at or after ``when`` (it says nothing of before)."""
        return self._share_from >= when

    def share_over(self, seconds: float) -> float | None:
        """The idle share over the next ``seconds`` (blocks that long; None: unknown)."""
        first = self._read()
        time.sleep(seconds)
        last = self._read()
        if first is None or last is None or last[1] <= first[1]:
            return None
        return (last[0] - first[0]) / (last[1] - first[1])


def auto_bounds(jobs: int) -> tuple[int, int] | None:
    """(runs started at once, most runs at once) of ``--jobs auto``; None for a plain number (exactly that many)."""
    if not isinstance(jobs, AutoJobs):
        return None
    return int(jobs), PER_CORE * max(int(jobs), usable_cores())


def describe(jobs: int) -> str:
    """What ``--jobs`` means for a grid's first line: ``2 at a time`` or ``2 at a time, up to 4 while idle``."""
    bounds = auto_bounds(jobs)
    if bounds is None or bounds[0] == bounds[1]:
        return f"{int(jobs)} at a time"
    return f"{bounds[0]} at a time, up to {bounds[1]} while the cores stay idle"


class Admission:
    """Lets runs start while a place is free: ``base`` to ``limit`` places, by how idle the cores are (module
    docstring)."""

    def __init__(self, base: int, limit: int, *, idle_needed: float = IDLE_NEEDED, idle_floor: float = IDLE_FLOOR,
                 burst_idle: float = BURST_IDLE, gap: float = GAP, meter: IdleMeter | None = None,
                 clock: Callable[[], float] = time.monotonic, poll: float = 0.5, opening: float = OPENING) -> None:
        self.base, self.limit = max(1, base), max(1, base, limit)
        self.idle_needed, self.idle_floor, self.burst_idle = idle_needed, idle_floor, burst_idle
        self.gap, self.poll, self.opening = gap, poll, opening
        self.meter = meter or IdleMeter()
        self.clock = clock
        self.running = 0
        self.places: int | None = None  # decided by the opening look, at the first start
        self._last_start = self._last_change = -float("inf")
        self._cond = threading.Condition()

    @classmethod
    def for_jobs(cls, jobs: int) -> Admission | None:
        """The admission of ``--jobs`` (None for a plain number: that many run, no more)."""
        bounds = auto_bounds(jobs)
        return None if bounds is None else cls(*bounds)

    def _open(self) -> int:
        """The places at the start: all of them when the cores are nearly idle, else ``base``."""
        if self.limit == self.base:
            return self.base
        idle = self.meter.share_over(self.opening)
        return self.limit if idle is not None and idle >= self.burst_idle else self.base

    def _quiet_from(self) -> float:
        """When the runs in flight were last settled: ``gap`` s after the last start or change of places."""
        return max(self._last_start, self._last_change) + self.gap

    def _settled(self, now: float) -> bool:
        """No start and no change of places for ``gap`` s: the idle share now says what the runs in flight use."""
        return now >= self._quiet_from()

    def _may_start(self) -> bool:
        if self.places is None:
            self.places = self._open()
        now = self.clock()
        if self.places > self.base and self._settled(now):
            idle = self.meter.idle_share()
            # The window must begin after the runs started up: four runs starting at once on two cores keep them
            # busy for ~3 s, longer than the gap.
            if idle is not None and idle < self.idle_floor and self.meter.fresh_since(self._quiet_from()):
                self.places -= 1
                self._last_change = now
        if self.running < self.places:
            return True
        if self.running >= self.limit or not self._settled(now):
            return False
        idle = self.meter.idle_share()
        if idle is None or idle < self.idle_needed:
            return False
        self.places = self.running + 1
        return True

    def enter(self, stop: StopRequest | None = None) -> bool:
        """Wait until a run may start (True), or until ``stop`` is requested (False: start nothing)."""
        with self._cond:
            while not self._may_start():
                if stop is not None and stop.requested:
                    return False
                self._cond.wait(self.poll)
            self.running += 1
            self._last_start = self.clock()
            return True

    def leave(self) -> None:
        """A run ended: its place is free."""
        with self._cond:
            self.running -= 1
            self._cond.notify_all()
