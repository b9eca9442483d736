"""How many ``--exe`` runs at once with ``--jobs auto``: one per usable core, and more while the cores stay idle.

Why not simply one per core: a run over DDS is three processes that spend much of a mission waiting for each
other (sim time waits for the node's answer), so one run alone leaves most of a core idle. Why not a fixed larger
number: a run whose processes lack CPU answers late in sim time, so its verdict could change with the load
(docs/grading.md).

So :class:`Admission` keeps a number of *places* and lets a run start whenever one is free:

- at the grid's start it looks at the cores for :data:`OPENING` wall seconds: nearly free of other programs
  (``burst_idle``: idle, or used by the grade itself) they get every place up to ``limit`` at once (twelve runs
  in two waves of six, not a ramp whose last wave starts late), otherwise ``base`` places (one per core);
- a place is added, up to ``limit``, when the cores this process may use were at least ``idle_needed`` idle
  since the last look and the last start was ``gap`` wall seconds ago (a run's start-up is its busiest part, and
  the next look should see it running);
- a place is taken away, down to ``base``, when *other programs* took more than ``foreign_max`` of the cores
  while no run was starting up (no start for ``gap`` s): runs in flight go on, the next ones wait.

Why other programs' share and not the idle share: at ``--rtf 0`` the simulator keeps just behind its node
(:class:`bt_nav_sim.pacing.StayBehind`), so the grade's own runs take whatever CPU is free and leave the cores
busy however many places there are; a node short of CPU slows its simulator down rather than answering late. Read
as "saturated", that busy share took places away mid-grid, and the second wave started run by run (the right C
node's default grid: 55 s with up to six places, 49.6 s with six throughout). A program beside the grade does not
slow down for it: that is the load to make room for. The grade's own share is its process tree's CPU time
(:func:`tree_cpu`); the idle share comes from ``/proc/stat`` (Linux: what ROS 2 Jazzy runs on). Where either
cannot be read, no place beyond ``base`` is given, and none is taken away. That is a preview's admission (``--rtf``
0 or above 1), whose failures are graded again at 1x anyway.

At 1x (the grade) every place opens at once (:func:`auto_bounds`): a 1x run waits for the wall clock most of the
time, and each run also takes one of the machine's places (:class:`MachineSlots`), which every grade on the machine
shares; a run whose simulator fell behind real time takes a place away (:meth:`Admission.fell_behind`).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Sequence

from bt_nav.ros.supervise import StopRequest, usable_cores

#: Runs at most per usable core, with ``--jobs auto``. Three since the simulator keeps just behind its node: six
#: at once on 2 cores (2026-11-28, quiet, 12 runs each, the default lab grid) ran each at 3.4-4.0x, and the right
#: nodes most sensitive to lag stayed on the rule, ``c_no_aeb_fast`` (a 1.5 rad/s pivot closed loop on odometry)
#: 12/12 at 89.1-90.4 deg and ``b_fast_spin`` (2 rad/s on a 50 Hz loop) 6/6 at 179.4-180.8 deg; the right C node's
#: grade took 49.6 s against 75-80 s with four. Eight took as long (49-51 s); twelve starved the nodes at ~2x
#: (``c_no_aeb_fast`` 112 deg once). Before :class:`bt_nav_sim.pacing.StayBehind`, six overshot that pivot to
#: 103-121 deg in 4-5 of 8 runs (the simulator ran at the bound of the node's lead).
PER_CORE = 3
#: The idle share of the cores an extra run needs (beyond the opening look).
IDLE_NEEDED = 0.4
#: Above this share of the cores taken by other programs, with no run starting up, a place is taken away.
FOREIGN_MAX = 0.25
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


def tree_cpu(root: int | None = None, proc: str = "/proc") -> float | None:
    """CPU jiffies (user and system, with those of its reaped children) that process ``root`` (None: this one) and
    its live descendants used so far; None when ``proc`` cannot be listed or ``root`` is not in it.

    A run's processes that ended were reaped by their parent in the tree (the grade, a launcher), whose
    reaped-children times then hold theirs: the sum does not drop when they go."""
    root = os.getpid() if root is None else int(root)
    try:
        names = os.listdir(proc)
    except OSError:
        return None
    children: dict[int, list[int]] = {}
    used: dict[int, float] = {}
    for name in names:
        if not name.isdigit():
            continue
        try:
            with open(f"{proc}/{name}/stat", encoding="ascii", errors="replace") as stream:
                fields = stream.read().rpartition(")")[2].split()
            used[int(name)] = sum(float(v) for v in fields[11:15])  # utime stime cutime cstime
            children.setdefault(int(fields[1]), []).append(int(name))
        except (OSError, ValueError, IndexError):
            continue  # it ended meanwhile (its parent's reaped-children times will say it)
    if root not in used:
        return None
    total, todo = 0.0, [root]
    while todo:
        pid = todo.pop()
        total += used.get(pid, 0.0)
        todo += children.get(pid, [])
    return total


class IdleMeter:
    """The idle share of this process's cores over the last ``window`` wall seconds or more, and the share other
    programs than this process and its descendants took (None: unknown).

    Args:
        read: (idle, total) jiffies of the cores since boot (:func:`cpu_times` of this process's cores).
        own: jiffies this process tree used so far (:func:`tree_cpu`).
    """

    def __init__(self, read: Callable[[], tuple[float, float] | None] | None = None, window: float = 1.0,
                 clock: Callable[[], float] = time.monotonic,
                 own: Callable[[], float | None] | None = None) -> None:
        try:
            cores: Sequence[int] | None = sorted(os.sched_getaffinity(0))
        except (AttributeError, OSError):
            cores = None
        self._read = read or (lambda: cpu_times(cores))
        self._own = own or tree_cpu
        self.window, self.clock = window, clock
        self._last, self._last_own, self._at = self._read(), self._own(), clock()
        self._share: float | None = None
        self._foreign: float | None = None
        self._share_from = -float("inf")  # when the window of the current share began

    def idle_share(self) -> float | None:
        """Idle share between the last two readings at least ``window`` apart (a reading is taken when the last is
        that old: a share over a few milliseconds says nothing)."""
        if self.clock() - self._at < self.window:
            return self._share
        now, own = self._read(), self._own()
        last, self._last = self._last, now
        last_own, self._last_own = self._last_own, own
        self._share_from, self._at = self._at, self.clock()
        self._share = self._foreign = None
        if now is not None and last is not None and now[1] > last[1]:
            total = now[1] - last[1]
            self._share = (now[0] - last[0]) / total
            if own is not None and last_own is not None:
                busy = total - (now[0] - last[0])
                self._foreign = min(1.0, max(0.0, (busy - (own - last_own)) / total))
        return self._share

    def foreign_share(self) -> float | None:
        """The share of the cores other programs took over the window of :meth:`idle_share` (read afresh when that
        is ``window`` old): busy less what this process tree used."""
        self.idle_share()
        return self._foreign

    def fresh_since(self, when: float) -> bool:
        """Whether the window of the last :meth:`idle_share` began at or after ``when`` (it says nothing of before)."""
        return self._share_from >= when

    def free_over(self, seconds: float) -> float | None:
        """The share of the cores other programs left over the next ``seconds`` (blocks that long; None: unknown): the
        idle share plus what this process tree used meanwhile (a grade's start-up, its fork server's imports, is its
        own and leaves the cores free for its runs)."""
        first, first_own = self._read(), self._own()
        time.sleep(seconds)
        last, last_own = self._read(), self._own()
        if first is None or last is None or first_own is None or last_own is None or last[1] <= first[1]:
            return None
        return min(1.0, (last[0] - first[0] + last_own - first_own) / (last[1] - first[1]))


#: Runs at most per usable core at 1x (the default grade): a 1x lab run uses about a tenth of a core (six cells took
#: 43.8 CPU s over 74 s wall, 2026-11-28), so a whole grid (12 runs; C's 18) runs at once on 2 cores.
REALTIME_PER_CORE = 10
#: MiB a run takes (the node, a forked simulator with its judge and bag writer): the memory bound on runs at once.
RUN_MEMORY_MIB = 400


def available_mib(path: str = "/proc/meminfo") -> float | None:
    """MiB of memory available to new processes (``MemAvailable``), or None when it cannot be read."""
    try:
        with open(path, encoding="ascii") as stream:
            for line in stream:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        return None
    return None


def auto_bounds(jobs: int, real_time: bool = False) -> tuple[int, int] | None:
    """(runs started at once, most runs at once) of ``--jobs auto``; None for a plain number (exactly that many). At
    1x (``real_time``) every place opens at once, up to :data:`REALTIME_PER_CORE` per core and the memory's bound:
    a 1x run waits for the wall clock most of the time, and one that fell behind says so itself (its place is then
    taken away, :meth:`Admission.fell_behind`)."""
    if not isinstance(jobs, AutoJobs):
        return None
    if real_time:
        memory = available_mib()
        most = REALTIME_PER_CORE * max(int(jobs), usable_cores())
        if memory is not None:
            most = max(1, min(most, int(memory // RUN_MEMORY_MIB)))
        return most, most
    return int(jobs), PER_CORE * max(int(jobs), usable_cores())


def describe(jobs: int, real_time: bool = False) -> str:
    """What ``--jobs`` means for a grid's first line: ``2 at a time``, ``up to 16 at once`` (1x), or ``2 at a time,
    up to 6 while the cores stay idle``."""
    bounds = auto_bounds(jobs, real_time)
    if bounds is not None and real_time:
        return f"up to {bounds[1]} at once"
    if bounds is None or bounds[0] == bounds[1]:
        return f"{int(jobs)} at a time"
    return f"{bounds[0]} at a time, up to {bounds[1]} while the cores stay idle"


#: At 1x, after the opening wave (the grade's first ``gap`` s, every place at once) and beyond one run per core, a run
#: starts only this long after the last start (wall s) ...
REALTIME_GAP = 1.0
#: ... and while the cores were at least this idle over the last second. Why: a class keeps every place busy, and
#: each run's start-up (imports, discovery: some 3 CPU s) lands on runs being judged; a class of 10 (180 runs) with
#: every place taken as soon as free ran at load 10 on 2 cores and one run in ten fell behind real time.
REALTIME_IDLE = 0.1

#: Where the machine's real-time places are (a lock file each, in the temporary directory unless set).
SLOTS_ENV = "BT_NAV_SLOTS_DIR"
#: Wall seconds after a 1x run fell behind anywhere on the machine during which new runs, of every grade on it, take
#: only the first half of its places (:meth:`MachineSlots.calm`).
CALM_S = 60.0


class MachineSlots:
    """The 1x runs this machine carries at once, shared by every grade on it: ``count`` places, each an exclusive
    ``flock`` on ``<dir>/slot-<k>.lock`` held for a run's life (the kernel drops it when the holder dies).

    Why: a 1x run costs about a tenth of a core, and its simulator keeps real time only if the cores carry every
    run at once; three grades of 18 runs started together (54 runs on 2 cores, two CPU hogs beside them) fell
    behind in every run, and a third of their cells ended NOT GRADED after the second try. With the places shared,
    the second and third grade wait for places as the first one's runs end.

    A run that fell behind says the machine carries fewer runs than it was given (:meth:`calm`): for
    :data:`CALM_S` every grade's new runs, its own re-run among them, take only the first half of the places, so
    the re-run starts once the machine runs at most half as many. Why machine-wide: four classes graded at once
    (the grader suite) each took a place away from their own admission only, the others filled it at once, and
    long runs (a node that never creeps, 66 s) fell behind twice and ended NOT GRADED."""

    def __init__(self, count: int, directory: str | None = None) -> None:
        import tempfile

        self.count = max(1, int(count))
        root = directory or os.environ.get(SLOTS_ENV) or tempfile.gettempdir()
        self.directory = os.path.join(root, "bt_nav_realtime_slots")
        os.makedirs(self.directory, exist_ok=True)
        self._held: list[object] = []

    @property
    def _calm_marker(self) -> str:
        return os.path.join(self.directory, "fell-behind")

    def calm(self) -> None:
        """A run fell behind real time: only the first half of the places are taken for :data:`CALM_S` s."""
        with open(self._calm_marker, "a"):
            pass
        os.utime(self._calm_marker)

    def usable(self, now: float | None = None) -> int:
        """How many of the places a new run may take now: half of them within :data:`CALM_S` of :meth:`calm`."""
        try:
            age = (time.time() if now is None else now) - os.stat(self._calm_marker).st_mtime
        except OSError:
            return self.count
        return max(1, self.count // 2) if 0.0 <= age < CALM_S else self.count

    def take(self) -> bool:
        """Take a free place among those :meth:`usable` now (True), or none is free (False, at once)."""
        import fcntl

        for k in range(self.usable()):
            handle = open(os.path.join(self.directory, f"slot-{k}.lock"), "a+")  # noqa: SIM115 - held: the place
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.close()
                continue
            self._held.append(handle)
            return True
        return False

    def give_back(self) -> None:
        """Give back one place this process holds (closing the file drops the lock)."""
        if self._held:
            self._held.pop().close()  # type: ignore[attr-defined]


class Admission:
    """Lets runs start while a place is free: ``base`` to ``limit`` places, by how idle the cores are (module
    docstring); at 1x also a place of the machine's (:class:`MachineSlots`), shared with the other grades on it."""

    def __init__(self, base: int, limit: int, *, idle_needed: float = IDLE_NEEDED, foreign_max: float = FOREIGN_MAX,
                 burst_idle: float = BURST_IDLE, gap: float = GAP, meter: IdleMeter | None = None,
                 clock: Callable[[], float] = time.monotonic, poll: float = 0.5, opening: float = OPENING) -> None:
        self.base, self.limit = max(1, base), max(1, base, limit)
        self.idle_needed, self.foreign_max, self.burst_idle = idle_needed, foreign_max, burst_idle
        self.gap, self.poll, self.opening = gap, poll, opening
        self.meter = meter or IdleMeter()
        self.clock = clock
        self.running = 0
        self.places: int | None = None  # decided by the opening look, at the first start
        self.slots: MachineSlots | None = None  # at 1x: the machine's places, shared by its grades
        self._last_start = self._last_change = -float("inf")
        self._wave_ends = -float("inf")  # at 1x: the end of the opening wave (every place at once)
        self._cond = threading.Condition()

    @classmethod
    def for_jobs(cls, jobs: int, real_time: bool = False) -> Admission | None:
        """The admission of ``--jobs`` (None for a plain number: that many run, no more); ``real_time``: of 1x runs
        (:func:`auto_bounds`)."""
        bounds = auto_bounds(jobs, real_time)
        if bounds is None:
            return None
        admission = cls(*bounds)
        if real_time:
            admission.slots = MachineSlots(bounds[1])
        return admission

    def fell_behind(self) -> None:
        """A run's simulator fell behind real time: the machine carries fewer runs than are running.

        At 1x the machine's places calm down (:meth:`MachineSlots.calm`: every grade's new runs, this one's re-run
        among them, take half of them for :data:`CALM_S` s), and this grade's own places stay: cutting them to one
        fewer than were running at each such run, as before, never gave them back, and a class of 180 runs ended
        graded one run at a time (three times the wall of the same class's first ten minutes). A preview's places
        (no machine places): one fewer than are running now (never below one), grown again while the cores idle."""
        if self.slots is not None:
            self.slots.calm()
            return
        with self._cond:
            self.base = max(1, min(self.base, self.running - 1))
            self.places = max(1, min(self.places if self.places is not None else self.running, self.running - 1))
            self.limit = max(self.base, self.places)

    def _open(self) -> int:
        """The places at the start: all of them when other programs leave the cores nearly free, else ``base``.

        Free, not idle: the grade's own start-up (its fork server imports for about a CPU second) is no other
        program's load; read as busy, it opened two places instead of six and the right C node's grade took 42-50 s
        instead of about 35."""
        if self.limit == self.base:
            return self.base
        free = self.meter.free_over(self.opening)
        return self.limit if free is not None and free >= self.burst_idle else self.base

    def _quiet_from(self) -> float:
        """When the runs in flight were last settled: ``gap`` s after the last start or change of places."""
        return max(self._last_start, self._last_change) + self.gap

    def _settled(self, now: float) -> bool:
        """No start and no change of places for ``gap`` s: the idle share now says what the runs in flight use."""
        return now >= self._quiet_from()

    def _may_start_1x(self) -> bool:
        """At 1x: every free place in the opening wave; after it, beyond one run per core, a run starts
        :data:`REALTIME_GAP` s after the last and only while the cores were :data:`REALTIME_IDLE` idle (a measured
        load the runs in flight leave room in; unknown: no hold)."""
        now = self.clock()
        if self.places is None:
            self.places, self._wave_ends = self._open(), now + self.gap
        if self.running >= self.places:
            return False
        if now <= self._wave_ends or self.running < usable_cores():
            return True
        if now - self._last_start < REALTIME_GAP:
            return False
        idle = self.meter.idle_share()
        return idle is None or idle >= REALTIME_IDLE

    def _may_start(self) -> bool:
        if self.slots is not None:
            return self._may_start_1x()
        if self.places is None:
            self.places = self._open()
        now = self.clock()
        if self.places > self.base and self._settled(now):
            foreign = self.meter.foreign_share()
            # The window must begin after the runs started up: a start-up is the busiest part of a run (and a
            # run's processes are the grade's own only once started).
            if foreign is not None and foreign > self.foreign_max and self.meter.fresh_since(self._quiet_from()):
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
            while not (self._may_start() and (self.slots is None or self.slots.take())):
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
            if self.slots is not None:
                self.slots.give_back()
            self._cond.notify_all()
