"""``--jobs auto`` for ``--exe`` grids (bt_nav.grading.admission): every place at once on idle cores, else one run
per core; a place more only while the cores stay idle (one per gap), a place less when they are saturated; a plain
number is exactly that many. The meter and the clock are stand-ins
(the real grids run in tests/ros and in the bench)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from bt_nav.cli.options import jobs_arg
from bt_nav.grading.admission import Admission, AutoJobs, IdleMeter, cpu_times, describe


class Meter:
    """An idle share the test sets (the opening look sees ``opening``, by default a busy machine)."""

    def __init__(self, share: float | None, opening: float | None = 0.5) -> None:
        self.share = share
        self.opening = opening
        self.fresh = True  # the share's window began after the runs started up

    def idle_share(self) -> float | None:
        return self.share

    def share_over(self, seconds: float) -> float | None:
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


def test_idle_cores_at_the_start_open_every_place_and_saturated_ones_take_places_away() -> None:
    meter, clock = Meter(0.3, opening=0.95), Clock()
    gate = _admission(meter, clock)
    assert all(gate.enter() for _ in range(4)) and gate.places == 4, "a quiet machine: four runs at once"
    meter.share = 0.05
    clock.now = 2.0
    gate.leave()
    assert gate._may_start() and gate.places == 4, "a run started 2 s ago: its start-up, not the runs, fills the cores"
    clock.now = 3.0
    meter.fresh = False
    assert gate._may_start() and gate.places == 4, "a share whose window began during the start-ups says nothing"
    meter.fresh = True
    assert not gate._may_start() and gate.places == 3, "the runs in flight leave the cores 95 % busy: a place less"
    clock.now = 4.0
    gate.leave()
    assert gate._may_start() and gate.places == 3, "one place less per gap"
    clock.now = 6.0
    gate.leave()
    assert gate.places == 3 and gate._may_start() and gate.places == 2, "and down to one per core, no further"
    clock.now = 20.0
    assert gate._may_start() and gate.places == 2


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
    assert (gate.base, gate.limit) == (2, 4)
    assert describe(AutoJobs(2)) == "2 at a time, up to 4 while the cores stay idle"
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
    assert IdleMeter(read=lambda: next(looks), clock=clock).share_over(0.0) is None, "no time between the two looks"
    looks = iter([(10.0, 100.0), (10.0, 100.0), (90.0, 200.0)])
    meter = IdleMeter(read=lambda: next(looks), clock=clock)
    assert meter.share_over(0.0) == pytest.approx(0.8)
