"""Sim time at a wall-clock instant, learnt from ``/clock``: what a message's source time was in sim time.

Why: a process that records or prints what happens on a graph running 10-20x faster than real time gets each
message some wall milliseconds after it was sent, and more when its queue backs up (a Python recorder on a
loaded two-core machine: up to 2.8 s of sim time, measured on a lab demo at 11x). Stamping with the newest
``/clock`` *on arrival* shifts everything by that lag: a turn is drawn seconds late, then snaps. What is known
at the source is a wall time: DDS stamps every sample with its writer's wall clock (rmw's
``source_timestamp``), and an rcutils log line, on the console (``{time}``) and on ``/rosout`` alike, carries
the system time of the log call, never the node's ROS clock (``rcutils_log`` takes
``rcutils_system_time_now``: ros2/rcutils, src/logging.c). The simulator publishes ``/clock`` on every
physics step (100 per sim second), so the (source wall time, sim time) pairs of ``/clock`` map any such wall
instant on this machine to sim time within a step.

Pure: no rclpy. :class:`SimClock` is fed by :class:`bt_nav.ros.graphtap.GraphTap` (``bt-nav record``, the
bags of ``demo`` and ``grade --exe``) and by the demo's recorder node (the terminal's and the logs' times).
"""

from __future__ import annotations

import bisect
import threading
import time
from collections import deque


class SimClock:
    """Pairs (wall ns at the source, sim ns) of ``/clock``; :meth:`sim_at` maps a wall instant to sim time.

    Thread-safe (fed from an executor thread, read from others). Keeps the last ``keep`` pairs: at 100 steps a
    sim second and 20x real time that is 4 wall seconds, more than any backlog a recorder survives.
    """

    def __init__(self, keep: int = 8192) -> None:
        self._wall: deque[int] = deque(maxlen=keep)
        self._sim: deque[int] = deque(maxlen=keep)
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._wall)

    def add(self, wall_ns: int, sim_ns: int) -> None:
        """One ``/clock`` sample: its source (wall) timestamp and its value. A clock that goes back (a new
        simulator in the domain) starts the map afresh; a sample older than the newest is dropped."""
        with self._lock:
            if self._sim and sim_ns < self._sim[-1]:
                self._wall.clear()
                self._sim.clear()
            elif self._wall and wall_ns <= self._wall[-1]:
                return
            self._wall.append(int(wall_ns))
            self._sim.append(int(sim_ns))

    def newest_wall(self) -> int | None:
        """The source wall time of the newest sample (None before the first)."""
        with self._lock:
            return self._wall[-1] if self._wall else None

    def covers(self, wall_ns: int) -> bool:
        """Whether a sample at or after wall instant ``wall_ns`` has been seen: :meth:`sim_at` is then exact there
        (before it, it holds at the newest sample, which a reader that lags behind the graph has not got yet)."""
        with self._lock:
            return bool(self._wall) and self._wall[-1] >= wall_ns

    def wait_cover(self, wall_ns: int, timeout: float, alive: float = 1.0) -> bool:
        """Wait (at most ``timeout`` wall seconds) until a sample covers ``wall_ns``; not at all when the newest
        sample is more than ``alive`` s older than now (the simulator has stopped: none will come). Returns
        :meth:`covers`. A line logged while this process's reader lags waits for its own /clock instead of taking
        the newest one read so far, which is early by the lag (seconds of sim time on a loaded machine)."""
        deadline = time.monotonic() + timeout
        while not self.covers(wall_ns):
            newest = self.newest_wall()
            if newest is None or time.time_ns() - newest > alive * 1e9 or time.monotonic() >= deadline:
                return False
            time.sleep(0.005)
        return True

    def latest(self) -> int | None:
        """The newest sim time seen (None before the first /clock)."""
        with self._lock:
            return self._sim[-1] if self._sim else None

    def sim_at(self, wall_ns: int) -> int | None:
        """Sim ns at wall instant ``wall_ns``: interpolated between the /clock samples around it, the newest one's
        after it; None before the first sample (the caller falls back to what it had).

        Why not extrapolate past the newest: the simulator may be holding (waiting for a follower), and a guess
        that a later sample corrects downwards would put two lines sent in order into the bag out of order
        (measured on the lab demo's terminal lines). Held at the newest sample, the map only ever grows with
        wall time, and a line is at most one /clock sample (10 ms of sim time) early.
        """
        with self._lock:
            if not self._wall or wall_ns < self._wall[0]:
                return None
            k = bisect.bisect_right(self._wall, wall_ns) - 1
            w0, s0 = self._wall[k], self._sim[k]
            if k + 1 < len(self._wall):
                w1, s1 = self._wall[k + 1], self._sim[k + 1]
                return s0 + (s1 - s0) * (wall_ns - w0) // max(1, w1 - w0)
            return s0
