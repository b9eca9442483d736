"""Tick statistics of the executive: how long ticks take, how often they overrun, what went wrong.

Pure Python (no rclpy), so it is tested without a node. The executive records one duration per tick
(wall clock, ``perf_counter``) and logs :meth:`TickStats.describe` every ``stats_period`` and at exit.
"""

from __future__ import annotations

import json
import math
from collections import deque
from collections.abc import Iterable
from pathlib import Path
from typing import Any


class TickStats:
    """Tick durations and counters, summarised for the log.

    ``overruns`` counts ticks that took longer than the tick period: the timer cannot keep its rate
    then. The window (since the last periodic line) and a bounded history (for the exit line) are
    kept separately so a long run's exit line does not need every sample.
    """

    def __init__(self, period: float, history: int = 100_000) -> None:
        self.period = float(period)
        self.ticks = 0
        self.overruns = 0
        self.exceptions = 0
        self.vetoed = 0
        self.window: list[float] = []
        self.history: deque[float] = deque(maxlen=history)
        self._window_since: float | None = None  # mission-clock start of the window

    def record(self, duration: float) -> None:
        """One tick took ``duration`` seconds."""
        self.ticks += 1
        if duration > self.period:
            self.overruns += 1
        self.window.append(duration)
        self.history.append(duration)

    @staticmethod
    def describe(durations: Iterable[float]) -> str:
        """``min/mean/p99/max`` in milliseconds (``no ticks`` when empty)."""
        values = sorted(durations)
        if not values:
            return "no ticks"
        p99 = values[max(0, math.ceil(0.99 * len(values)) - 1)]
        mean = sum(values) / len(values)
        return (f"tick ms min/mean/p99/max {values[0] * 1e3:.2f}/{mean * 1e3:.2f}/{p99 * 1e3:.2f}/"
                f"{values[-1] * 1e3:.2f} over {len(values)}")

    def counters(self, faults: int) -> str:
        """The counters as one phrase (``faults``: exceptions the core caught inside the tree)."""
        return (f"ticks {self.ticks}, overruns {self.overruns} (period {self.period * 1e3:.1f} ms), "
                f"exceptions {faults + self.exceptions}, vetoed commands {self.vetoed}")

    def take_window(self) -> list[float]:
        """The durations since the last call, and start a new window."""
        window, self.window = self.window, []
        return window

    def periodic_line(self, now: float, period: float, faults: int) -> str | None:
        """The window's log line when ``period`` mission-clock seconds have passed since the last one
        (0: never), else None. A clock that jumps back starts a new window."""
        if self._window_since is None or now < self._window_since:  # first tick, or the clock jumped back
            self._window_since = now
            return None
        if period <= 0.0 or now - self._window_since < period:
            return None
        self._window_since = now
        return f"stats: {self.describe(self.take_window())}; {self.counters(faults)}"

    def final_line(self, faults: int) -> str:
        """The exit line's statistics over the whole (bounded) history."""
        return f"final stats: {self.describe(self.history)}; {self.counters(faults)}"

    def final_record(self, faults: int) -> dict[str, Any]:
        """The exit line's statistics as data (the executive's ``stats_path``): ``tick_stats`` its words
        (:meth:`describe` of the history), ``durations`` how many ticks that covers, and the counters."""
        return {"tick_stats": self.describe(self.history), "durations": len(self.history), "ticks": self.ticks,
                "overruns": self.overruns, "period_ms": round(self.period * 1e3, 3),
                "exceptions": faults + self.exceptions, "vetoed_commands": self.vetoed}


def read_final_stats(path: Path) -> dict[str, Any]:
    """What the executive wrote into its ``stats_path`` on its way out (:meth:`TickStats.final_record` and its
    counters); empty when it wrote nothing (it was killed) or the file cannot be read."""
    try:
        stats = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return stats if isinstance(stats, dict) else {}
