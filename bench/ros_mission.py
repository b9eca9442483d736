"""One whole homework mission over DDS, as ``bt-nav demo`` runs it: its speed and its processes' memory.

The ``eval`` graph of :func:`bt_nav.run.rosmission.mission_graph` (the simulator with ``real_time_factor`` 0
hosting the referee in its process, the executive with ``config/homework.yaml``) runs as subprocesses in a domain
of its own, through :class:`~bt_nav.run.rosmission.RosMission` on a :class:`~bt_nav.run.session.MissionSession`
(as ``bt-nav demo`` does, with the one verdict wait), whose recorder node in
this process records ground truth with its wall arrival time, which gives the real-time factor over exactly the
referee's mission (from its t0 to its report): simulated seconds / wall seconds. Start-up (Python imports, DDS
discovery) is reported apart, because it is a fixed cost, not a speed.

Memory: ``VmHWM`` (peak resident set) and ``VmRSS`` of the executive and the simulator are read from
``/proc/<pid>/status`` once the referee has given its verdict, while both still run, so the peak
covers the whole mission. The executive's own tick statistics (those of its exit log line, written as JSON to its
``stats_path``: :func:`executive_stats`) come along.

CPU: what each process spent (user + system, ``/proc/<pid>/stat``) from the moment this process's recorder sees
the robot to the referee's verdict file, next to the wall time of that span: on a small machine the real-time factor
is bounded by the CPU the processes need per simulated second, and this says which process needs it. "sim" is the
simulator with the referee it hosts; "recorder" is this process (the demo's recorder node). With ``profile_to``,
the executive runs under ``python -m cProfile`` (its one thread is the whole node) and writes its
profile there; such a run is slower and only says where the executive's time goes.
"""

from __future__ import annotations

import os
import resource
import tempfile
import time
from collections import deque
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from bt_nav.ros.bringup import NodeSpec
from bt_nav.ros.rosutil import dds_env
from bt_nav.ros.tick_stats import read_final_stats
from bt_nav.run.session import VERDICT, MissionSession, files_written

#: Wall seconds the referee may take (its own timeout), and extra wall time before this gives up.
REFEREE_TIMEOUT = 120.0
GRACE = 15.0
#: Wall seconds to wait for ground truth and the executive's first commands before measuring.
STARTUP = 45.0
#: The executive's exit statistics (its ``stats_path``), in the run's temporary directory.
EXECUTIVE_STATS = "executive_stats.json"


#: What the executive wrote into its ``stats_path`` on its way out: read beside its writer.
executive_stats = read_final_stats


def proc_status(pid: int) -> dict[str, int]:
    """``VmHWM`` and ``VmRSS`` (kB) of a running process; empty when it is gone."""
    out: dict[str, int] = {}
    try:
        with open(f"/proc/{pid}/status", encoding="utf-8") as stream:
            for line in stream:
                key, _, value = line.partition(":")
                if key in ("VmHWM", "VmRSS"):
                    out[f"{key}_kb"] = int(value.split()[0])
    except (OSError, ValueError, IndexError):
        return {}
    return out


def proc_cpu(pid: int) -> float | None:
    """User + system CPU seconds of a running process (None when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as stream:
            fields = stream.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _self_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


@dataclass
class ProfiledSpec(NodeSpec):
    """A node started under ``python -m cProfile -o <profile_out>`` (same arguments otherwise)."""

    profile_out: str = ""

    def command(self, python: str | None = None) -> list[str]:
        """``python -m cProfile -o <out> -m bt_nav.cli <executable> ...``."""
        base = super().command(python)
        return [base[0], "-m", "cProfile", "-o", self.profile_out, *base[1:]]


def _mission_window(t: list[float], wall: list[float], results: dict[str, Any]) -> tuple[float, float] | None:
    """(simulated s, wall s) between the referee's t0 and its report, from the recorded samples."""
    times = results.get("times") or {}
    t0, report = times.get("t0"), times.get("report")
    if t0 is None or report is None:
        return None
    inside = [i for i, stamp in enumerate(t) if t0 <= stamp <= t0 + report]
    if len(inside) < 2:
        return None
    first, last = inside[0], inside[-1]
    return t[last] - t[first], wall[last] - wall[first]


def _wait_verdict(session: MissionSession, verdict: Path) -> Any:
    """Wait for the hosted judge's verdict file (True), or the first child to exit (that child; None: timeout):
    :meth:`bt_nav.run.session.MissionSession.wait`, polled every 20 ms."""
    outcome, child = session.wait(REFEREE_TIMEOUT + GRACE, files_written([verdict]), interval=0.02)
    return True if outcome == VERDICT else child


def _measure_verdict(session: MissionSession, verdict: Path, out: dict[str, Any]
                     ) -> tuple[Any, dict[str, dict[str, int]]]:
    """Wait for the verdict (:func:`_wait_verdict`), measuring each process's CPU over that span into ``out``.

    Returns what :func:`_wait_verdict` returned and the memory of the processes still running.
    """
    children = session.children
    span_start = time.monotonic()
    cpu_start = {c.name: proc_cpu(c.popen.pid) for c in children}
    self_start = _self_cpu()
    ended = _wait_verdict(session, verdict)
    span = time.monotonic() - span_start
    memory = {c.name: proc_status(c.popen.pid) for c in children if c.poll() is None}
    cpu: dict[str, float | None] = {}
    for c in children:
        now, before = proc_cpu(c.popen.pid), cpu_start.get(c.name)
        cpu[c.name] = None if now is None or before is None else round(now - before, 3)
    cpu["recorder"] = round(_self_cpu() - self_start, 3)
    out["cpu_s"] = cpu
    out["cpu_span_wall_s"] = round(span, 3)
    return ended, memory


def _summarise(out: dict[str, Any], rec: Any, results: dict[str, Any], logs: dict[str, deque[str]],
               stats: dict[str, Any]) -> None:
    """Add the real-time factor over the referee's mission, the executive's tick statistics (``stats``:
    :func:`executive_stats`) and the failed checks to ``out`` (and the logs' tails when something went wrong)."""
    window = _mission_window(rec.t, rec.wall, results)
    if window is not None:
        sim_s, wall_s = window
        out.update({"mission_sim_s": round(sim_s, 3), "mission_wall_s": round(wall_s, 3),
                    "rtf": round(sim_s / wall_s, 3) if wall_s > 0 else None})
    else:
        out.update({"mission_sim_s": None, "mission_wall_s": None, "rtf": None})
        out.setdefault("error", "no mission window (referee results or ground truth missing)")
    out["executive_tick_stats"] = stats.get("tick_stats")
    out["executive_ticks"] = stats.get("durations")
    checks = results.get("checks") or []
    out["failed_checks"] = [c.get("name") for c in checks if not c.get("passed")]
    if "error" in out:
        out["log_tail"] = {name: list(lines)[-15:] for name, lines in logs.items()}


def run_mission(domain: int, seed: int = 0, world: str = "stage_4", log_lines: int = 400,
                profile_to: str | Path | None = None) -> dict[str, Any]:
    """Run one mission; returns its real-time factor, verdict, timings, CPU and memory.

    The DDS environment of this process is set to ``domain`` (the recorder node lives here).
    """
    from bt_nav.run.rosmission import RosMission, mission_graph
    from bt_nav.run.session import read_verdict
    from bt_nav.run.settings import profile_maneuver

    os.environ.update(dds_env(domain))
    logs: dict[str, deque[str]] = {}

    def sink(name: str, line: str) -> None:
        logs.setdefault(name, deque(maxlen=log_lines)).append(line)

    with tempfile.TemporaryDirectory(prefix="bt_nav_bench_") as tmp:
        results_path = Path(tmp) / "results.json"
        stats_path = Path(tmp) / EXECUTIVE_STATS
        specs = mission_graph(["robot1"], {"robot1": str(results_path)}, world=world, seed=seed, rtf=0.0,
                              referee={"timeout": REFEREE_TIMEOUT})
        specs = [replace(s, parameters={**s.parameters, "stats_path": str(stats_path)}) if s.executable == "executive"
                 else s for s in specs]
        if profile_to is not None:
            specs = [ProfiledSpec(**vars(s), profile_out=str(profile_to)) if s.executable == "executive" else s
                     for s in specs]
        out: dict[str, Any] = {"world": world, "maneuver": profile_maneuver("homework"), "seed": seed,
                               "domain": domain}
        wall0 = time.monotonic()
        session = MissionSession(domain, sink=sink)
        mission = RosMission(specs, ["robot1"], session, verdicts=[str(results_path)])
        referee_code: int | None = None
        memory: dict[str, dict[str, int]] = {}
        try:
            mission.start_graph()
            mission.wait_ready(STARTUP)
            out["startup_wall_s"] = round(time.monotonic() - wall0, 3)
            ended, memory = _measure_verdict(session, results_path, out)
            if ended is True:
                referee_code = mission.referee_code()
            elif ended is not None:
                out["error"] = f"{ended.name} exited with {ended.poll()} before the verdict"
            else:
                out["error"] = "no verdict in time"
        finally:
            rec = mission.close()["robot1"]
        out["total_wall_s"] = round(time.monotonic() - wall0, 3)
        results = read_verdict(results_path) or {}
        stats = executive_stats(stats_path)

    out["referee_exit"] = referee_code
    out["passed"] = referee_code == 0
    out["memory"] = memory
    _summarise(out, rec, results, logs, stats)
    return out
