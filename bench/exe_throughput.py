"""Benchmark 7: grading throughput over DDS: missions per minute of ``bt-nav grade --exe "<bt-nav executive>"
--jobs auto``, as a user runs it (a subprocess, the venv's console script), and where each run's wall time goes.

Why: a grade of a foreign node is N missions of three Python processes each (simulator, node, judge) at
``--rtf`` sim seconds per wall second; on a 2-core machine its throughput is bounded by the mission's sim
length over the rtf (about 60 sim s from the judge's t0 to its report), by the processes' start-up and
shutdown around it, and by the CPU the six processes of two runs need. The section says which.

Per run (from its run directory): start-up (run start to the judge's t0, ``t0_wall`` in its verdict: the three
processes are up and the judge found the node's arm service), the mission (t0 to the verdict file),
the shutdown (verdict to ``result.json``), and the rtf the simulator reached over the mission (the verdict's
report time, in sim s from t0, over the mission's wall s). CPU: every
process of the grade, exactly (user + system of the grade's waited-for descendants, ``RUSAGE_CHILDREN``), and
split by process kind from samples every 0.25 s (a process's last 0.25 s can be missed).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bt_nav.grading.report import read_grade

from .common import DOMAIN_RANGE, REPO, Target, at_least, median, usable_cores

TARGET_PER_MINUTE = 15.0
JOBS = "auto"
#: Process kinds by their command line, first match wins: the simulator hosting its judge (``--judge``) is one.
KINDS = ((" --judge ", "sim+judge"), (" sim ", "sim"), ("referee", "referee"), ("checkoff", "judge"),
         ("executive", "node"))


def _kind(cmdline: list[str]) -> str:
    text = " " + " ".join(cmdline) + " "
    return next((kind for needle, kind in KINDS if needle in text), "grade")


def _phases(row: dict[str, Any]) -> dict[str, Any]:
    """Where one run's wall time went (see the module docstring); None where the verdict does not say."""
    from bt_nav.run.session import read_verdict

    run_dir = Path(row["run_dir"])
    try:
        end = (run_dir / "result.json").stat().st_mtime
        written = (run_dir / "verdict.json").stat().st_mtime
    except OSError:
        return {"wall_s": row.get("wall_time")}
    start = end - float(row["wall_time"])
    verdict = read_verdict(run_dir / "verdict.json") or {}
    t0, report = verdict.get("t0_wall"), (verdict.get("times") or {}).get("report")
    mission = None if t0 is None else written - t0
    return {"wall_s": row["wall_time"], "startup_s": None if t0 is None else round(t0 - start, 2),
            "mission_s": None if mission is None else round(mission, 2), "shutdown_s": round(end - written, 2),
            "sim_rtf": round(report / mission, 2) if report is not None and mission else None}


def _sample(procs: dict[int, tuple[str, float]], root: int) -> None:
    """Record the CPU seconds of every descendant of ``root`` by pid (kind, latest reading)."""
    import psutil

    try:
        children = psutil.Process(root).children(recursive=True)
    except psutil.Error:
        return
    for child in children:
        try:
            times = child.cpu_times()
            procs[child.pid] = (_kind(child.cmdline()), times.user + times.system)  # after exec: its own name
        except psutil.Error:
            continue


def grade_once(seeds: int, rtf: float | None = None, jobs: str = JOBS, world: str = "stage_4") -> dict[str, Any]:
    """One ``bt-nav grade --exe`` of bt_nav's executive over ``seeds`` seeds; its throughput and breakdown."""
    bt_nav = str(Path(sys.executable).with_name("bt-nav"))
    out = Path(tempfile.mkdtemp(prefix="bench-exe-")) / "grade"
    argv = [bt_nav, "grade", "--exe", f"{bt_nav} executive", "--worlds", world, "--lidars", "profile", "--seeds",
            str(seeds), "--jobs",
            str(jobs), "--out", str(out), "--progress", "off", *(["--rtf", f"{rtf:g}"] if rtf else [])]
    env = {**os.environ, "BT_NAV_DOMAIN_RANGE": f"{DOMAIN_RANGE[0]}-{DOMAIN_RANGE[1]}",
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.monotonic()
    log = out.with_name("grade.log")
    with open(log, "w", encoding="utf-8") as stream:
        proc = subprocess.Popen(argv, cwd=REPO, env=env, stdout=stream, stderr=subprocess.STDOUT)
        procs: dict[int, tuple[str, float]] = {}
        while proc.poll() is None:
            _sample(procs, proc.pid)
            time.sleep(0.25)
    wall = time.monotonic() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    output = log.read_text(encoding="utf-8", errors="replace")
    try:
        rows = (read_grade(out) or {"runs": []})["runs"]
    except (OSError, ValueError, KeyError):
        return {"error": f"bt-nav grade exited with {proc.returncode}: {output[-2000:]}", "argv": argv}
    by_kind: dict[str, float] = {}
    for kind, seconds in procs.values():
        by_kind[kind] = round(by_kind.get(kind, 0.0) + seconds, 2)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    phases = [_phases(row) for row in rows]
    medians = {key: median([p[key] for p in phases if p.get(key) is not None])
               for key in ("wall_s", "startup_s", "mission_s", "shutdown_s", "sim_rtf")}
    return {"argv": argv, "rtf": rtf or 5.0, "jobs": jobs, "world": world, "runs": len(rows),
            "passed": sum(1 for row in rows if row["passed"]),
            "reasons": sorted({row["reason"] for row in rows if not row["passed"]}), "wall_s": round(wall, 1),
            "missions_per_min": round(60.0 * len(rows) / wall, 2), "cpu_s": round(cpu, 1),
            "cpu_s_per_mission": round(cpu / max(1, len(rows)), 2), "cpu_share_of_cores": round(cpu / wall / (
                os.cpu_count() or 1), 2), "cpu_by_kind_s": by_kind, "per_run": phases,
            "phases_median": medians, "returncode": proc.returncode,
            # what --jobs runs at a time could reach if start-up and shutdown took no time at all
            "mission_bound_per_min": round(60.0 * _workers(jobs) / medians["mission_s"], 2) if medians["mission_s"]
            else None}


def run(quick: bool = False, rtfs: tuple[float, ...] | None = None) -> dict[str, Any]:
    """A grade at a fixed ``--rtf 5`` (issue 27's default; today's default, as fast as the node keeps up and at most
    5x, is :mod:`bench.grade_speed`'s) over 8 seeds (2 when quick), then the same at the other ``rtfs``, for the
    speed-versus-verdicts trade."""
    seeds = 2 if quick else 8
    grades = []
    for rtf in (5.0, *(rtfs if rtfs is not None else (() if quick else (8.0,)))):
        print(f"  bt-nav grade --exe 'bt-nav executive' --jobs {JOBS} --seeds {seeds} --rtf {rtf:g} ...", flush=True)
        result = grade_once(seeds, rtf)
        print(f"    {result.get('missions_per_min')} missions/min, {result.get('passed')}/{result.get('runs')} passed, "
              f"{result.get('cpu_s_per_mission')} CPU s per mission", flush=True)
        grades.append(result)
    return {"seeds": seeds, "jobs": JOBS, "grades": grades}


def _workers(jobs: str) -> int:
    """How many runs ``--jobs`` lets run at once here at most (auto: PER_CORE per core while the cores stay idle)."""
    from bt_nav.grading.admission import PER_CORE

    return PER_CORE * usable_cores() if str(jobs) == "auto" else int(jobs)


def targets(result: dict[str, Any]) -> list[Target]:
    """Issue 27's aim: >= 15 missions per minute with --jobs auto, at the default rtf."""
    main = result["grades"][0] if result.get("grades") else {}
    value = main.get("missions_per_min")
    return [Target("exe_missions_per_min", "exe", f"bt-nav grade --exe 'bt-nav executive' --jobs {JOBS}, rtf "
                   f"{main.get('rtf', 5.0):g}: missions per minute ({main.get('passed')}/{main.get('runs')} passed)",
                   f">= {TARGET_PER_MINUTE:g}", value, "missions/min", at_least(value, TARGET_PER_MINUTE))]
