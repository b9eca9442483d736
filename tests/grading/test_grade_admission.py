"""``--jobs auto`` for ``--exe`` grids (bt_nav.grading.admission): every place at once on idle cores, else one run
per core; a place more only while the cores stay idle (one per gap), a place less when other programs take the
cores (never for the grade's own busy cores); a plain number is exactly that many. The meter and the clock are stand-ins
(the real grids run in tests/ros and in the bench)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from bt_nav.cli.options import jobs_arg
from bt_nav.grading.admission import Admission, AutoJobs, IdleMeter, cpu_times, describe, tree_cpu


class Meter:
    """An idle share the test sets (the opening look sees ``opening`` free, by default a busy machine)."""

    def __init__(self, share: float | None, opening: float | None = 0.5) -> None:
        self.share = share
        self.opening = opening
        self.fresh = True  # the share's window began after the runs started up
        self.foreign: float | None = 0.0  # the share other programs took

    def idle_share(self) -> float | None:
        return self.share

    def foreign_share(self) -> float | None:
        return self.foreign

    def free_over(self, seconds: float) -> float | None:
        return self.opening

    def fresh_since(self, when: float) -> bool:
        return self.fresh


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _admission(meter: Meter, clock: Clock, base: int = 2, limit: int = 4) -> Admission:
    return Admission(base, limit, meter=meter, clock=clock, gap=3.0, idle_needed=0.4, poll=0.01)


def test_base_runs_start_at_once_then_extra_ones_wait_for_idle_cores_and_the_gap() -> None:
    meter, clock = Meter(0.9), Clock()
    gate = _admission(meter, clock)
    assert gate._may_start() and gate.enter() and gate.enter()  # one per core, whatever the load
    assert not gate._may_start(), "the second start was just now: the gap holds the third"
    clock.now = 3.0
    meter.share = 0.2
    assert not gate._may_start(), "80 % busy: no third run"
    meter.share = 0.6
    assert gate.enter() and gate.running == 3
    clock.now = 6.0
    assert gate.enter() and gate.running == 4
    clock.now = 9.0
    assert not gate._may_start(), "the limit: two per core"
    gate.leave()
    assert gate._may_start() and gate.places == 4, "an earned place is taken again at once"


def test_idle_cores_at_the_start_open_every_place_and_other_programs_take_places_away() -> None:
    meter, clock = Meter(0.3, opening=0.95), Clock()
    gate = _admission(meter, clock)
    assert all(gate.enter() for _ in range(4)) and gate.places == 4, "a quiet machine: four runs at once"
    meter.share, clock.now = 0.0, 3.0
    gate.leave()
    assert gate._may_start() and gate.places == 4, "the grade's own runs fill the cores: they slow down, no place less"
    assert gate.enter() and gate.running == 4
    meter.foreign, clock.now = 0.5, 5.0
    gate.leave()
    assert gate._may_start() and gate.places == 4, "a run started 2 s ago: the share may be of its start-up"
    meter.fresh, clock.now = False, 6.5
    assert gate._may_start() and gate.places == 4, "a share whose window began during the start-ups says nothing"
    meter.fresh = True
    assert not gate._may_start() and gate.places == 3, "another program takes half the cores: a place less"
    clock.now = 7.5
    gate.leave()
    assert gate._may_start() and gate.places == 3, "one place less per gap"
    assert gate.enter() and gate.running == 3
    clock.now = 11.0
    gate.leave()
    assert not gate._may_start() and gate.places == 2, "and down to one per core ..."
    clock.now = 20.0
    assert not gate._may_start() and gate.places == 2 and gate.running == 2, "... no further"
    meter.foreign = 0.0
    meter.share = 0.6
    assert gate._may_start() and gate.places == 3, "the program gone and the cores idle: a place again"


def test_an_unknown_share_of_other_programs_takes_no_place_away() -> None:
    meter, clock = Meter(0.0, opening=0.95), Clock()
    gate = _admission(meter, clock)
    assert all(gate.enter() for _ in range(4))
    meter.foreign, clock.now = None, 10.0
    gate.leave()
    assert gate._may_start() and gate.places == 4


def test_a_busy_machine_at_the_start_opens_one_place_per_core() -> None:
    gate = _admission(Meter(0.9, opening=0.5), Clock())
    assert gate.enter() and gate.enter() and gate.places == 2 and not gate._may_start()
    assert _admission(Meter(0.9, opening=None), Clock())._may_start(), "an unknown share: one per core"


def test_an_unknown_idle_share_gives_no_extra_place() -> None:
    gate = _admission(Meter(None), Clock())
    gate.enter()
    gate.enter()
    gate.clock.now = 10.0
    assert not gate._may_start()


def test_a_waiting_run_starts_when_a_place_frees_and_gives_up_on_a_stop() -> None:
    gate = Admission(1, 1, meter=Meter(1.0), poll=0.01)
    assert gate.enter()
    started = threading.Event()
    threading.Thread(target=lambda: gate.enter() and started.set(), daemon=True).start()
    time.sleep(0.05)
    assert not started.is_set(), "the only place is taken"
    gate.leave()
    assert started.wait(2.0)

    class Stop:
        requested = True

    assert gate.enter(Stop()) is False and gate.running == 1, "a stop starts nothing"


def test_only_auto_adapts(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("bt_nav.grading.admission.usable_cores", lambda: 2)
    assert Admission.for_jobs(3) is None, "--jobs 3 is three runs, no more"
    gate = Admission.for_jobs(AutoJobs(2))
    assert (gate.base, gate.limit) == (2, 6)
    assert describe(AutoJobs(2)) == "2 at a time, up to 6 while the cores stay idle"
    assert describe(3) == "3 at a time"
    assert isinstance(jobs_arg("auto"), AutoJobs) and type(jobs_arg("2")) is int


def test_the_idle_share_is_read_from_proc_stat(tmp_path: Path) -> None:
    stat = tmp_path / "stat"
    stat.write_text("cpu  30 0 10 60 0 0 0 0 0 0\ncpu0 20 0 5 25 0 0 0 0 0 0\ncpu1 10 0 5 35 0 0 0 0 0 0\nintr 1\n")
    assert cpu_times(path=str(stat)) == (60.0, 100.0), "the per-core lines, not the total line twice"
    assert cpu_times([0], path=str(stat)) == (25.0, 50.0)
    assert cpu_times(path=str(tmp_path / "missing")) is None
    readings = iter([(0.0, 100.0), (30.0, 200.0)])
    clock = Clock()
    meter = IdleMeter(read=lambda: next(readings), window=1.0, clock=clock)
    assert meter.idle_share() is None, "no reading a window apart yet"
    clock.now = 1.0
    assert meter.idle_share() == pytest.approx(0.3)
    assert meter.fresh_since(0.0) and not meter.fresh_since(0.5), "the share's window began at 0"
    assert cpu_times() is not None, "this machine's /proc/stat reads"
    looks = iter([(0.0, 100.0), (50.0, 100.0), (50.0, 100.0)])
    assert IdleMeter(read=lambda: next(looks), clock=clock, own=lambda: 0.0).free_over(0.0) is None, \
        "no time between the two looks"
    looks = iter([(10.0, 100.0), (10.0, 100.0), (90.0, 200.0)])
    owns = iter([0.0, 0.0, 15.0])
    meter = IdleMeter(read=lambda: next(looks), clock=clock, own=lambda: next(owns))
    assert meter.free_over(0.0) == pytest.approx(0.95), "80 of 100 jiffies idle, 15 the grade's own start-up"
    assert IdleMeter(read=lambda: (0.0, 1.0), clock=clock, own=lambda: None).free_over(0.0) is None, \
        "the grade's own time unknown: so is what is free"


def test_other_programs_share_is_the_busy_share_less_the_grade_s_own() -> None:
    clock = Clock()
    readings = iter([(0.0, 100.0), (30.0, 200.0), (30.0, 300.0)])
    owns = iter([5.0, 45.0, None])
    meter = IdleMeter(read=lambda: next(readings), clock=clock, own=lambda: next(owns))
    clock.now = 1.0
    assert meter.foreign_share() == pytest.approx(0.3), "70 of 100 jiffies busy, 40 of them the grade's"
    assert meter.idle_share() == pytest.approx(0.3)
    clock.now = 2.0
    assert meter.foreign_share() is None, "the grade's own time unknown: so is the rest"
    assert meter.idle_share() == pytest.approx(0.0)


def _stat(pid: int, ppid: int, utime: int, stime: int, cutime: int = 0, cstime: int = 0, name: str = "py thon") -> str:
    rest = ["S", str(ppid)] + ["0"] * 9 + [str(utime), str(stime), str(cutime), str(cstime)] + ["0"] * 10
    return f"{pid} ({name}) " + " ".join(rest) + "\n"


def test_the_grade_s_own_cpu_is_its_process_tree_s(tmp_path: Path) -> None:
    for pid, line in {10: _stat(10, 1, 5, 1, cutime=7, cstime=1), 11: _stat(11, 10, 20, 2, name="a) b"),
                      12: _stat(12, 11, 3, 0), 13: _stat(13, 1, 50, 50)}.items():
        (tmp_path / str(pid)).mkdir()
        (tmp_path / str(pid) / "stat").write_text(line)
    (tmp_path / "self").mkdir()
    assert tree_cpu(10, proc=str(tmp_path)) == 39.0, "10 with its reaped children, 11 and 12; not the stranger 13"
    assert tree_cpu(12, proc=str(tmp_path)) == 3.0
    assert tree_cpu(99, proc=str(tmp_path)) is None, "not running"
    assert tree_cpu(proc=str(tmp_path / "missing")) is None
    assert (tree_cpu() or 0.0) >= 0.0 and tree_cpu() is not None, "this machine's /proc reads"


def test_1x_places_are_the_machines_shared_by_every_grade_on_it(tmp_path: Path) -> None:
    """Two grades on one machine (two MachineSlots over one directory) share its places: the second waits for one
    the first gives back, and a place held by a process that died is free again (the kernel drops its flock)."""
    import subprocess
    import sys

    from bt_nav.grading.admission import MachineSlots

    first, second = MachineSlots(2, str(tmp_path)), MachineSlots(2, str(tmp_path))
    assert first.take() and second.take() and not first.take() and not second.take()
    first.give_back()
    assert second.take() and not first.take()
    second.give_back()
    second.give_back()
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; sys.path[:0] = [sys.argv[1]]; "
                               "from bt_nav.grading.admission import MachineSlots as M; s = M(2, sys.argv[2]); "
                               "s.take(); s.take(); print('held', flush=True); time.sleep(60)",
                               str(Path(__file__).resolve().parents[2]), str(tmp_path)],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        assert not first.take()
    finally:
        holder.kill()
        holder.wait()
    assert first.take() and first.take()


def test_a_run_that_fell_behind_calms_every_grade_on_the_machine(tmp_path: Path) -> None:
    """Once a run of any grade fell behind, new runs of every grade on the machine (another MachineSlots over the
    same directory) take only half of the places for CALM_S; runs holding the other half go on; then all again."""
    import time

    from bt_nav.grading.admission import CALM_S, MachineSlots

    mine, other = MachineSlots(4, str(tmp_path)), MachineSlots(4, str(tmp_path))
    assert mine.take() and other.take() and other.take()  # three of four places held
    assert other.usable() == 4
    mine.calm()
    assert other.usable() == 2 and not other.take(), "the first half is held: the re-run waits"
    other.give_back()  # its newest place (the third): still none of the first half free
    assert not mine.take()
    other.give_back()
    assert mine.take() and not mine.take(), "one of the first half again, never the third or fourth"
    assert other.usable(now=time.time() + CALM_S + 1.0) == 4


def test_fell_behind_calms_the_machine(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Admission.fell_behind at 1x calms the machine's places (every grade's) for a while and keeps its own: cut
    for good, they once left a class graded one run at a time."""
    from bt_nav.grading.admission import SLOTS_ENV

    monkeypatch.setenv(SLOTS_ENV, str(tmp_path))
    admission = Admission.for_jobs(AutoJobs(2), real_time=True)
    assert admission is not None and admission.slots is not None
    count = admission.slots.count
    assert admission.slots.usable() == count
    for _ in range(3):
        assert admission.enter()
    admission.fell_behind()
    assert admission.slots.usable() == max(1, count // 2)
    assert admission.places == admission.limit == count, "its own places stay"
    assert admission.enter(), "a place of the first half is free: the re-run starts"
    for _ in range(4):
        admission.leave()


def test_a_1x_grade_opens_every_place_then_starts_runs_only_while_the_cores_carry_them(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """At 1x the opening wave takes every place at once (a grid of 18 runs at once); after it, beyond one run per
    core, a freed place is taken only REALTIME_GAP after the last start and while the cores were REALTIME_IDLE idle."""
    from bt_nav.grading.admission import REALTIME_GAP, REALTIME_IDLE, MachineSlots

    monkeypatch.setattr("bt_nav.grading.admission.usable_cores", lambda: 2)

    class Stop:
        requested = True

    meter, clock = Meter(0.0, opening=1.0), Clock()
    gate = Admission(6, 6, meter=meter, clock=clock, gap=3.0, poll=0.01)
    gate.slots = MachineSlots(6, str(tmp_path))
    assert all(gate.enter() for _ in range(6)), "the opening wave: every place, however busy the cores"
    clock.now = 10.0
    gate.leave()
    assert gate.enter(Stop()) is False, "the cores are busy (0 % idle): the freed place waits"
    meter.share = REALTIME_IDLE
    assert gate.enter(Stop()) is True, "idle enough: it starts"
    gate.leave()
    clock.now += REALTIME_GAP / 2
    assert gate.enter(Stop()) is False, "too soon after the last start"
    clock.now += REALTIME_GAP
    for _ in range(5):
        gate.leave()
    meter.share = 0.0
    assert gate.enter(Stop()) and gate.enter(Stop()), "one run per core starts whatever the load"
    assert gate.enter(Stop()) is False


def test_a_1x_admission_takes_a_machine_place_per_run() -> None:
    admission = Admission.for_jobs(AutoJobs(2), real_time=True)
    assert admission is not None and admission.slots is not None and admission.base == admission.limit
    assert Admission.for_jobs(AutoJobs(2)) is not None and Admission.for_jobs(AutoJobs(2)).slots is None
