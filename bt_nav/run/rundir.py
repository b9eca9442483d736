"""Where a mission over DDS writes: its run directory and one log file per node, with one time base.

Log lines carry ``sim <t> s [wall <t> s]``: the sim time at which the node logged the line and wall seconds
since the run started. The nodes print each line with the wall time of its log call (:data:`LOG_FORMAT`'s
``{time_as_nanoseconds}``; rcutils takes the system clock for it, whatever the node's clock) and the demo's
recorder maps it to sim time with ``/clock`` (:class:`bt_nav.ros.simclock.SimClock`), so a line is stamped with
when it happened, not with when this process read it: at 22x real time a busy demo process read the
executive's lines up to 6.5 s of sim time late. A line without that stamp (a ``print``) gets the sim time now.
The referee's report lines are its own: their times are seconds from the referee's t0 (its results say so
under ``time_base``).
"""

from __future__ import annotations

import re
import threading
import time
from pathlib import Path
from typing import IO, Any

from bt_nav.ros.bringup import JUDGE_NODE_NAMES, JUDGES
from bt_nav.ros.simclock import SimClock

#: rcutils' line format for the nodes: the log call's wall time (ns since the epoch) in front, which
#: :func:`split_stamp` takes off again (the run prefixes sim and wall time itself).
LOG_FORMAT = "@{time_as_nanoseconds} [{severity}] [{name}]: {message}"
_STAMPED = re.compile(r"^@(\d+) (?=\[)")
#: Wall s a line may wait for the /clock sample that covers its stamp (the demo's recorder lags on a loaded machine).
CLOCK_WAIT = 2.0


#: The node of an rcutils log line, in our format (its stamp taken off) or the default one: ``[INFO] [name]: ...``.
_LOG_NODE = re.compile(r"^\[[A-Z]+\] (?:\[\d+\.\d+\] )?\[([^\]]+)\]: ")


def judge_line(name: str, line: str) -> str | None:
    """Whose ``line`` of process ``name`` is, if a judge's: ``"report"`` (its plain lines: the report, the verdict),
    ``"log"`` (its log lines) or None. A judge runs as a process of its own (``referee``, ``checkoff``, in a robot's
    namespace ``robot1_referee``) or hosted by the simulator (``sim``: only the log lines of the judge's node, named in
    :data:`bt_nav.ros.bringup.JUDGE_NODE_NAMES`, and the plain lines, which the simulator itself never prints)."""
    kind = name.rsplit("_", 1)[-1]
    if kind not in (*JUDGES, "sim"):
        return None
    match = _LOG_NODE.match(line)
    if match is None:
        return None if line.startswith("[") else "report"
    return "log" if kind in JUDGES or match[1].rsplit(".", 1)[-1] in JUDGE_NODE_NAMES else None


def split_stamp(line: str) -> tuple[int | None, str]:
    """``"@1712345678123456789 [INFO] [x]: hi"`` -> (1712345678123456789, ``"[INFO] [x]: hi"``); a line without
    the stamp -> (None, line)."""
    match = _STAMPED.match(line)
    if match is None:
        return None, line
    return int(match[1]), line[match.end():]


def make_run_dir(out: Path, name: str) -> Path:
    """A new directory ``out/name`` (``-2``, ``-3`` ... appended while taken): a run never overwrites
    another's files, however many run at once (``mkdir`` is atomic)."""
    out.mkdir(parents=True, exist_ok=True)
    for n in range(1, 1000):
        path = out / (name if n == 1 else f"{name}-{n}")
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path
    raise FileExistsError(f"{out / name}: 999 runs of that name already")


class LogFiles:
    """One log file per process of a run, ``<name>.log``, opened on its first line (a launcher's sink)."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.files: dict[str, IO[str]] = {}
        self._lock = threading.Lock()

    def _stream(self, name: str) -> IO[str]:
        """``name``'s file (opened now if this is its first line); the caller holds the lock."""
        stream = self.files.get(name)
        if stream is None:
            stream = self.files[name] = open(self.directory / f"{name}.log", "w", encoding="utf-8")  # noqa: SIM115
        return stream

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: the line into ``name``'s file, flushed (a run cut short keeps what it logged)."""
        with self._lock:
            stream = self._stream(name)
            stream.write(line + "\n")
            stream.flush()

    def close(self) -> None:
        """Close every log file."""
        with self._lock:
            for stream in self.files.values():
                stream.close()


class Logs(LogFiles):
    """Per-node log files; a judge's report lines (anything not an rcutils log line) go to stdout.

    Every log line is prefixed with one time base: ``sim 37.65 s [wall 3.2 s]`` (the newest ground
    truth the recorder saw, and wall seconds since the demo started); report lines stay as the
    referee prints them. After the verdict nothing is echoed any more: the shutdown's own lines go
    to the files only, so the verdict is the last thing the user reads.
    """

    def __init__(self, directory: Path, echo_logs: bool, sim_time: Any = None, clock: SimClock | None = None) -> None:
        super().__init__(directory)
        self.echo_logs = echo_logs
        self.sim_time = sim_time or (lambda: None)
        self.clock = clock  # the demo's recorder's map of /clock (None: sim_time() alone)
        self.wall0 = time.monotonic()
        self.verdict: list[str] = []
        self.quiet_from_now = False

    def line_time(self, wall_ns: int | None = None) -> float | None:
        """Sim seconds at wall instant ``wall_ns`` (a log line's stamp; None: now), from :attr:`clock`; else the
        newest ground truth (:attr:`sim_time`); None before either."""
        if self.clock is not None:
            if wall_ns is not None:  # a line from another process: its /clock may not have been read yet
                self.clock.wait_cover(wall_ns, CLOCK_WAIT)
            sim = self.clock.sim_at(time.time_ns() if wall_ns is None else wall_ns)
            if sim is not None:
                return sim * 1e-9
        return self.sim_time()

    def stamp(self, t: float | None = None) -> str:
        """``sim 37.65 s [wall 3.2 s]`` at sim time ``t`` (None: now; sim ``-`` before the first clock)."""
        t = self.line_time() if t is None else t
        sim = f"{t:7.2f} s" if t is not None else "      - s"
        return f"sim {sim} [wall {time.monotonic() - self.wall0:5.1f} s]"

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: log file always; stdout for report lines (and warnings, unless quiet)."""
        wall_ns, line = split_stamp(line)
        stamp = self.stamp(self.line_time(wall_ns))
        with self._lock:
            stream = self._stream(name)
            is_log = line.startswith("[")
            stream.write((f"{stamp} {line}" if is_log else line) + "\n")
            judge = judge_line(name, line)
            if judge == "report":
                self.verdict.append(line)
                print(line, flush=True)
            elif self.echo_logs and not self.quiet_from_now and (
                    judge == "log" or any(lvl in line for lvl in ("[WARN]", "[ERROR]", "[FATAL]"))):
                print(f"  {stamp} [{name}] {line}", flush=True)
