"""SimClock: sim time at a wall instant from /clock's (source wall time, sim time) pairs; the bag's stamp rule."""

from __future__ import annotations

import struct

from bt_nav.media.bag import message_time_ns, own_stamp_ns
from bt_nav.ros.simclock import SimClock

MS = 1_000_000


def test_interpolates_between_clock_samples_and_never_guesses_ahead() -> None:
    clock = SimClock()
    assert clock.sim_at(5 * MS) is None and clock.latest() is None
    for k in range(11):  # 20x real time: 10 ms of sim per 0.5 ms of wall
        clock.add(1000 * MS + k * MS // 2, k * 10 * MS)
    assert clock.sim_at(999 * MS) is None  # before the map: the caller keeps what it had
    assert clock.sim_at(1000 * MS + MS // 4) == 5 * MS
    assert clock.sim_at(1005 * MS) == 100 * MS
    assert clock.sim_at(1006 * MS) == 100 * MS  # after the newest: held there (the sim may be held)
    seen = [clock.sim_at(1004 * MS)]
    clock.add(1007 * MS, 101 * MS)  # the sim slowed down: what came later is still not earlier
    seen += [clock.sim_at(1006 * MS), clock.sim_at(1008 * MS)]
    assert seen == sorted(seen)


def test_a_clock_that_goes_back_starts_afresh() -> None:
    clock = SimClock()
    clock.add(1 * MS, 50 * MS)
    clock.add(2 * MS, 60 * MS)
    clock.add(3 * MS, 0)  # another simulator
    assert len(clock) == 1 and clock.sim_at(1 * MS) is None and clock.latest() == 0


def test_own_stamps_are_read_from_the_bytes() -> None:
    header = b"\x00\x01\x00\x00" + struct.pack("<iI", 12, 500_000_000)
    assert own_stamp_ns("nav_msgs/msg/Odometry", header + b"\x00" * 40) == 12_500_000_000
    assert own_stamp_ns("rosgraph_msgs/msg/Clock", header) == 12_500_000_000
    assert own_stamp_ns("geometry_msgs/msg/Twist", header + b"\x00" * 40) is None
    assert own_stamp_ns("rcl_interfaces/msg/Log", header + b"\x00" * 40) is None  # its stamp is wall time
    big_endian = b"\x00\x00\x00\x00" + struct.pack(">iI", 3, 0)
    assert own_stamp_ns("sensor_msgs/msg/LaserScan", big_endian + b"\x00" * 40) == 3_000_000_000


def test_a_stamp_on_another_clock_is_not_taken() -> None:
    assert message_time_ns(10_000 * MS, 13_000 * MS) == 10_000 * MS  # 3 s behind the bag: a backlog
    assert message_time_ns(None, 13_000 * MS) == 13_000 * MS
    assert message_time_ns(1_700_000_000 * 1000 * MS, 13_000 * MS) == 13_000 * MS  # wall time in a sim graph


def test_a_line_waits_for_the_clock_that_covers_it() -> None:
    """A line stamped after the newest /clock read so far waits for its own sample (the reader lags), and does not
    wait at all once the clock has stopped (nothing more will come)."""
    import threading
    import time

    clock = SimClock()
    now = time.time_ns()
    clock.add(now, 10_000_000_000)
    line = now + 50_000_000  # logged 50 ms after the newest sample read
    assert clock.sim_at(line) == 10_000_000_000  # held at the newest: early by the lag

    def later() -> None:
        time.sleep(0.1)
        clock.add(now + 60_000_000, 10_300_000_000)  # the sample that covers the line arrives late

    threading.Thread(target=later).start()
    assert clock.wait_cover(line, timeout=2.0)
    assert clock.sim_at(line) == 10_250_000_000  # interpolated, not the stale newest
    stopped = SimClock()
    stopped.add(now - 3_000_000_000, 5)  # the last /clock 3 s ago: the simulator has ended
    started = time.monotonic()
    assert not stopped.wait_cover(now, timeout=2.0) and time.monotonic() - started < 0.1
