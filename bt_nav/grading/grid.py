"""Grading grids: lock-step missions over worlds x maneuvers x seeds, where they run (local worker processes
or a Dask distributed cluster) and their summary figures.

Each grid cell is a :class:`Job`: one deterministic lock-step mission. Both executors yield
``(job, summary)`` pairs as missions finish, so ``bt-nav grade`` can show progress and save partial
results; which executor ran a job never changes its summary (only ``wall_time``).

Dask (``--scheduler tcp://HOST:PORT``): the grid is submitted to an existing scheduler, whose workers
run :func:`run_job`. A worker that dies mid-grid loses only its running tasks, which the scheduler
reruns elsewhere; results are collected per job key, so every job is counted exactly once. Each tree
owns its blackboard, but py_trees keeps the live one in process-wide dicts that two threads would share,
so missions in one worker process are serialised by a lock: start workers with ``--nthreads 1`` and as
many ``--nworkers`` as cores to use them all.
"""

from __future__ import annotations

import statistics
import sys
import threading
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from tqdm import tqdm

from bt_nav.mission.params import normalise_maneuver
from bt_nav.run.settings import DEFAULT_JITTER

#: One mission at a time per process: the live py_trees blackboard is one set of dicts per process.
_MISSION_LOCK = threading.Lock()


@dataclass(frozen=True)
class Job:
    """One grid cell: everything that determines a lock-step mission."""

    world: str
    maneuver: str
    seed: int
    profile: str = "homework"
    kinematics: str = ""
    jitter: tuple[float, float] | None = None
    overrides: dict[str, Any] | None = field(default=None, hash=False, compare=False)
    sim_params: tuple[tuple[str, Any], ...] = ()  # simulator settings (--sim-param), e.g. actuation_latency
    # the graded node's parameters in this cell (-p NAME:=VALUE, over --node-param's; its judge is given the
    # trigger distances among them): a default grid's cell that checks the node applies its safety_distance
    node_params: tuple[tuple[str, Any], ...] = ()

    @property
    def key(self) -> str:
        """A stable name of the job (results files and Dask keys use it)."""
        jitter = "exact" if not self.jitter else f"{self.jitter[0]:g}m{self.jitter[1]:g}deg"
        sim = "".join(f"|{name}={value}" for name, value in self.sim_params)
        node = "".join(f"|p:{name}={value}" for name, value in self.node_params)
        return f"{self.world}|{self.maneuver}|{self.seed}|{self.profile}|{self.kinematics or '-'}|{jitter}{sim}{node}"

    @property
    def lidar(self) -> str:
        """The real LiDAR of the run (``lidar`` among its simulator settings); empty: the profile's own."""
        return str(dict(self.sim_params).get("lidar", ""))

    @property
    def cell(self) -> tuple[str, str, str]:
        """The grid cell the job belongs to: world, maneuver, LiDAR (empty: the profile's)."""
        return self.world, self.maneuver, self.lidar

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return asdict(self)

    def params_over(self, given: Sequence[tuple[str, Any]] = ()) -> tuple[tuple[str, Any], ...]:
        """The node's parameters in this run: ``given`` (``--node-param``, the whole grid's) with this cell's own
        over them, in order (what ``-p`` gives the node and what its judge is configured by)."""
        merged = dict(given)
        merged.update(self.node_params)
        return tuple(merged.items())


def params_text(params: Mapping[str, Any] | Sequence[tuple[str, Any]] | None) -> str:
    """A cell's parameters as its label shows them, ``safety_distance=0.7`` (empty: none)."""
    pairs = params.items() if isinstance(params, Mapping) else (params or ())
    return " ".join(f"{name}={value:g}" if isinstance(value, float) else f"{name}={value}" for name, value in pairs)


def run_job(job: Job) -> dict[str, Any]:
    """One mission's summary; a mission that raises is reported as a failed run, never lost."""
    from bt_nav.run.lockstep import run_mission

    with _MISSION_LOCK:
        try:
            summary = run_mission(job.world, job.maneuver, job.seed, job.overrides, job.profile, jitter=job.jitter,
                                  kinematics=job.kinematics, sim_params=dict(job.sim_params)).summary()
        except Exception as exc:  # one broken mission must not sink the whole grade
            summary = {"world": job.world, "maneuver": job.maneuver, "seed": job.seed, "profile": job.profile,
                       "kinematics": job.kinematics, "passed": False, "error": repr(exc), "travelled": 0.0,
                       "efficiency": 0.0, "collisions": 0, "failed_checks": ["error"], "wall_time": 0.0}
    summary["job"] = job.key
    summary["lidar"] = job.lidar
    return summary


def run_local(jobs: Sequence[Job], processes: int) -> Iterator[tuple[Job, dict[str, Any]]]:
    """Run the jobs in this process (``processes <= 1``) or in a pool of worker processes."""
    if processes <= 1:
        for job in jobs:
            yield job, run_job(job)
        return
    with ProcessPoolExecutor(max_workers=processes) as pool:
        futures = {pool.submit(run_job, job): job for job in jobs}
        for future in as_completed(futures):
            yield futures[future], future.result()


def run_dask(jobs: Sequence[Job], scheduler: str, retries: int = 3) -> Iterator[tuple[Job, dict[str, Any]]]:
    """Run the jobs on the Dask cluster whose scheduler listens at ``scheduler`` (tcp://host:port or a
    scheduler file). Tasks lost with a dying worker are rerun by the scheduler (``retries`` covers jobs
    that raise in a worker, e.g. when it runs out of memory)."""
    from distributed import Client
    from distributed import as_completed as dask_completed

    kwargs = {"scheduler_file": scheduler} if scheduler.endswith(".json") else {"address": scheduler}
    if "scheduler_file" in kwargs and not Path(scheduler).is_file():  # Client would wait for it forever
        raise ValueError(f"--scheduler {scheduler}: no such scheduler file (dask scheduler --scheduler-file writes it)")
    try:
        client = Client(**kwargs, timeout="30s")
    except OSError as exc:  # never a traceback, never a silent local run
        raise ValueError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc}); start it with 'dask "
                         "scheduler', or leave --scheduler out to grade on this machine") from None
    with client:
        futures = [client.submit(run_job, job, key=f"bt-nav-grade-{job.key}", pure=False, retries=retries)
                   for job in jobs]
        by_key = {future.key: job for future, job in zip(futures, jobs, strict=True)}
        for future in dask_completed(futures):  # each future once, whichever worker finished it
            yield by_key[future.key], future.result()


def seed_list(seeds: int | Iterable[int]) -> list[int]:
    """``20`` means seeds 0..19; an iterable is taken as is."""
    return list(range(seeds)) if isinstance(seeds, int) else [int(s) for s in seeds]


def make_jobs(worlds: Sequence[str], maneuvers: Sequence[str], seeds: int | Iterable[int],
              overrides: dict[str, Any] | None = None, profile: str = "homework",
              jitter: tuple[float, float] | None = DEFAULT_JITTER, kinematics: str = "",
              sim_params: dict[str, Any] | None = None, lidars: Sequence[str] = ("",),
              node_params: Sequence[tuple[str, Any]] = ()) -> list[Job]:
    """The grid in its canonical order: worlds, then maneuvers, then LiDARs (``""``: the profile's own, or
    ``lidar`` of ``sim_params``), then seeds; every job with the cell's ``node_params``."""
    base = dict(sim_params or {})
    sims = [tuple(sorted({**base, **({"lidar": lidar} if lidar else {})}.items())) for lidar in lidars or ("",)]
    return [Job(w, normalise_maneuver(m), s, profile, kinematics, jitter, overrides, sim, tuple(node_params))
            for w in worlds for m in maneuvers for sim in sims for s in seed_list(seeds)]


def parse_lidars(text: str | None) -> list[str]:
    """``--lidars``: comma-separated names of bt_nav_sim.lidar.LIDARS; ``profile`` (or nothing) is the profile's
    own LiDAR (ValueError naming an unknown one)."""
    from bt_nav_sim.lidar import LIDARS

    names = [n.strip() for n in (text or "").split(",") if n.strip()] or ["profile"]
    for name in names:
        if name != "profile" and name not in LIDARS:
            raise ValueError(f"unknown lidar {name!r}; choose among profile, {', '.join(LIDARS)}")
    return ["" if n == "profile" else n for n in names]


def lidar_label(name: str) -> str:
    """What a report calls a LiDAR of the grid (the profile's own when ``name`` is empty)."""
    from bt_nav_sim.lidar import LIDARS

    return LIDARS[name].label if name in LIDARS else "the profile's LiDAR"


def progress_bar(total: int, initial: int, enabled: bool, unit: str) -> tqdm:
    """The grids' progress bar (lock-step and ``--exe``): on stderr, so stdout keeps only results; a disabled
    one draws nothing. Lines printed while it shows go through ``tqdm.write`` so it is redrawn below them."""
    return tqdm(total=total, initial=initial, disable=not enabled, unit=unit, dynamic_ncols=True, file=sys.stderr)


def run_grid(jobs: Sequence[Job], processes: int = 2, scheduler: str | None = None,
             done: dict[str, dict[str, Any]] | None = None, progress: bool = False,
             on_result: Callable[[dict[str, dict[str, Any]]], None] | None = None) -> list[dict[str, Any]]:
    """Run the jobs not in ``done`` (job key -> summary); returns every summary in grid order.

    ``on_result`` sees the growing ``done`` after each mission (``bt-nav grade`` saves it).
    """
    results = dict(done or {})
    todo = [job for job in jobs if job.key not in results]
    stream = run_dask(todo, scheduler) if scheduler else run_local(todo, processes)
    with progress_bar(len(jobs), len(jobs) - len(todo), progress, "mission") as bar:
        for job, summary in stream:
            results[job.key] = summary
            bar.update(1)
            if on_result is not None:
                on_result(results)
    return [results[job.key] for job in jobs]


def grade(worlds: Sequence[str], maneuvers: Sequence[str], seeds: int | Iterable[int], jobs: int = 2,
          overrides: dict[str, Any] | None = None, profile: str = "homework",
          jitter: tuple[float, float] | None = DEFAULT_JITTER, kinematics: str = "",
          scheduler: str | None = None) -> list[dict[str, Any]]:
    """Run every (world, maneuver, seed); returns one summary dict per mission, in grid order."""
    grid = make_jobs(worlds, maneuvers, seeds, overrides, profile, jitter, kinematics)
    return run_grid(grid, jobs, scheduler)


def _median(values: list[float]) -> float:
    return statistics.median(values) if values else float("nan")


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One line per (world, maneuver, LiDAR): pass rate, collisions, distances, efficiency, failures, time."""
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault((row["world"], row["maneuver"], row.get("lidar", "")), []).append(row)
    out = []
    for (world, maneuver, lidar), runs in groups.items():
        travelled = [r["travelled"] for r in runs]
        efficiency = [r["efficiency"] for r in runs]
        failures = Counter(name for r in runs for name in r.get("failed_checks", ()))
        out.append({
            "world": world, "maneuver": maneuver, "lidar": lidar, "runs": len(runs),
            "passed": sum(1 for r in runs if r["passed"]),
            "pass_rate": sum(1 for r in runs if r["passed"]) / len(runs),
            "collisions": sum(r["collisions"] for r in runs),
            "runs_with_collisions": sum(1 for r in runs if r["collisions"]),
            "travelled_median": _median(travelled), "travelled_min": min(travelled),
            "efficiency_median": _median(efficiency), "efficiency_worst": min(efficiency),
            "failed_checks": dict(failures.most_common()),
            "failed_seeds": [r["seed"] for r in runs if not r["passed"]],
            "wall_time_mean": statistics.fmean(r.get("wall_time", 0.0) for r in runs),
            **_checkoff_cell(runs),
        })
    return out


def _checkoff_cell(runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The lab check-off's figures of a cell (nothing for homework runs): maneuvers judged, how many obeyed
    their rule, recovery turns, and the largest miss of an announced angle (degrees)."""
    cells = [r["checkoff"] for r in runs if "checkoff" in r]
    if not cells:
        return {}
    errors = [abs(e) for c in cells for e in c["angle_errors"]]
    return {"turns": sum(c["maneuvers"] for c in cells), "turns_ok": sum(c["angles_ok"] for c in cells),
            "recoveries": sum(c["recoveries"] for c in cells), "angle_error_max": max(errors, default=0.0),
            "runs_without_maneuver": sum(1 for c in cells if c["maneuvers"] == 0)}


def overall(rows: Sequence[dict[str, Any]], summary: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The grid's headline figures: what the homework targets are stated in."""
    efficiency = [r["efficiency"] for r in rows]
    worst_cell = min(summary, key=lambda s: s["pass_rate"], default=None)
    return {
        "runs": len(rows), "passed": sum(1 for r in rows if r["passed"]),
        "pass_rate": sum(1 for r in rows if r["passed"]) / len(rows) if rows else float("nan"),
        "collisions": sum(r["collisions"] for r in rows),
        "runs_with_collisions": sum(1 for r in rows if r["collisions"]),
        "efficiency_median": _median(efficiency), "efficiency_worst": min(efficiency, default=float("nan")),
        "worst_cell": (f"{worst_cell['world']} {worst_cell['maneuver']} {worst_cell['passed']}/{worst_cell['runs']}"
                       if worst_cell else ""),
        **_checkoff_cell(rows),
    }


def per_lidar(rows: Sequence[dict[str, Any]]) -> dict[str, tuple[int, int]]:
    """Passed and judged runs per LiDAR of the grid (empty name: the profile's own); bt_nav's own errors are no
    run of the student's and do not count."""
    out: dict[str, list[int]] = {}
    for row in rows:
        if row.get("outcome") == "bt_nav error":
            continue
        cell = out.setdefault(row.get("lidar", ""), [0, 0])
        cell[0] += bool(row.get("passed"))
        cell[1] += 1
    return {k: (v[0], v[1]) for k, v in out.items()}


def lidar_findings(rows: Sequence[dict[str, Any]]) -> list[str]:
    """What differs across the grid's LiDARs: a node that crashes with some of them only, and one that passes with
    one and fails with another, most likely reads the scan by fixed indices or takes a no-return reading for a
    distance: a sentence each naming the LiDARs (nothing when the grid has one LiDAR, or every LiDAR fares alike)."""
    rates = {name: passed / runs for name, (passed, runs) in per_lidar(rows).items() if runs}
    if len(rates) < 2:
        return []
    found = _crash_finding(rows)
    best = max(rates, key=lambda n: rates[n])
    worst = [n for n in rates if rates[n] < rates[best] - 0.34]
    if not worst or rates[best] < 0.5:
        return found
    failing = ", ".join(lidar_label(n) for n in sorted(worst, key=lambda n: rates[n]))
    return [*found, f"passes with {lidar_label(best)}, fails with {failing}: are the scan indices computed from "
            "angle_min and angle_increment (not fixed, not assuming 360 beams from 0 rad), and are NaN, inf and "
            "readings outside [range_min, range_max] filtered?"]


#: How the reason of a run whose node died begins: an exit with an error code before the verdict, or a crash.
CRASH_REASONS = ("the node exited with code", "the node crashed")


def _crash_finding(rows: Sequence[dict[str, Any]]) -> list[str]:
    """A node that crashes with some LiDARs and never with the others: the scan those publish differently (beam
    count, angle range, no-return readings) is what its code trips on. Nothing when no LiDAR or every one crashes."""
    counts: dict[str, list[int]] = {}  # LiDAR -> [crashed, judged]
    for row in rows:
        if row.get("outcome") == "bt_nav error":
            continue
        cell = counts.setdefault(row.get("lidar", ""), [0, 0])
        cell[0] += str(row.get("reason", "")).startswith(CRASH_REASONS)
        cell[1] += 1
    crashed = [n for n, (k, _) in counts.items() if k]
    clean = [n for n, (k, _) in counts.items() if not k]
    if not crashed or not clean:
        return []
    k, n = sum(counts[c][0] for c in crashed), sum(counts[c][1] for c in crashed)
    return [f"crashes with {', '.join(lidar_label(c) for c in crashed)} only ({k} of {n} runs), never with "
            f"{', '.join(lidar_label(c) for c in clean)}: the exception is in those runs' node.log; does the node "
            "index past the end of a scan with another beam count or angle range, or turn an inf or NaN reading "
            "into an int?"]


def cell_label(row: dict[str, Any]) -> str:
    """A grid cell's name, ``lab_object C rplidar``: world, maneuver and (when the grid varies it) LiDAR, and the
    cell's own node parameters (``lab_hallway B lds01 safety_distance=0.7``); a grid over three LiDARs has three cells
    per world and maneuver, and a report that left the LiDAR out would name them alike."""
    parts = (row["world"], row["maneuver"], row.get("lidar") or "", params_text(row.get("cell_params")))
    return " ".join(part for part in parts if part)


def maneuvers_text(rows: Sequence[dict[str, Any]]) -> str:
    """The maneuvers a grid graded, as a report's header says them (``maneuver C``, ``maneuvers A, C``; '' for a
    grid without one): the student's choice, not the ``-p maneuver:=X`` the grader appends to their command."""
    letters = sorted({str(r.get("maneuver")) for r in rows if r.get("maneuver") and r.get("maneuver") != "none"})
    return f"maneuver{'s' if len(letters) > 1 else ''} {', '.join(letters)}" if letters else ""


def run_label(row: dict[str, Any]) -> str:
    """A run's name, ``lab_object C rplidar seed 0``: how the CLI's lines, ``summary.md``, ``report.html`` and
    ``class.md`` name a run."""
    return f"{cell_label(row)} seed {row['seed']}"


def preview_said(row: dict[str, Any]) -> str:
    """How a preview's failed run went when graded again at 1x, whose verdict the row is
    (:mod:`bt_nav.grading.exe.realtime`), in a clause; "" for any other run."""
    preview = row.get("preview") or {}
    if not preview.get("reason"):
        return ""
    rtf = float(preview.get("rtf") or 0.0)
    where = f"at {rtf:.1f}x" if rtf else "as fast as it kept up"
    now = "passed" if row.get("passed") else "failed"
    return f"in the preview ({where}) it failed ({preview['reason']}); graded again at 1x real time it {now}"


def runs_label(rows: Sequence[dict[str, Any]]) -> str:
    """Runs of one cell named at once: ``lab_object C rplidar seed 0``, ``lab_object C rplidar seeds 0, 3``."""
    if len(rows) == 1:
        return run_label(rows[0])
    return f"{cell_label(rows[0])} seeds {', '.join(str(r['seed']) for r in rows)}"


def failure_groups(rows: Sequence[dict[str, Any]]) -> list[tuple[str, list[dict[str, Any]]]]:
    """The failed runs (bt_nav's own errors are none of the node's) by cell and reason, in the rows' order: each
    reason with the runs of one cell that failed so."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        if not row.get("passed") and row.get("outcome") != "bt_nav error":
            groups.setdefault((cell_label(row), str(row.get("reason", "?"))), []).append(row)
    return [(reason, runs) for (_, reason), runs in groups.items()]


def rate_table(summary: Sequence[dict[str, Any]]) -> tuple[list[str], list[tuple[str, str, dict[str, list[int]]]]]:
    """The pass rates of a summary of ``--exe`` cells (:func:`bt_nav.grading.report.summarize_exe`) as a table: its
    maneuvers (the columns), and a row per world and LiDAR (``""`` when the grid has the profile's only) with the
    passed and judged runs per maneuver. Why per LiDAR: a node failing with one LiDAR in three would read 2/3 on a
    row of the world, as if it failed by chance."""
    maneuvers = sorted({s["maneuver"] for s in summary})
    table: dict[tuple[str, str], dict[str, list[int]]] = {}
    for s in summary:
        world = " ".join(filter(None, (s["world"], s.get("params"))))  # a cell's own node parameters name its row
        cell = table.setdefault((world, s.get("lidar") or ""), {}).setdefault(s["maneuver"], [0, 0])
        cell[0] += s["passed"]
        cell[1] += s["runs"]
    return maneuvers, [(world, lidar, cells) for (world, lidar), cells in sorted(table.items())]


def format_lidars(rows: Sequence[dict[str, Any]]) -> list[str]:
    """A line per LiDAR of the grid (pass rate), then the findings across them; nothing for a grid of one."""
    rates = per_lidar(rows)
    if len(rates) < 2:
        return []
    lines = [f"  {lidar_label(name)}: {p}/{n} passed" for name, (p, n) in rates.items()]
    return ["per LiDAR:", *lines, *(f"finding: {f}" for f in lidar_findings(rows))]


def checkoff_jobs(jobs: Sequence[Job]) -> tuple[list[Job], list[tuple[str, str]]]:
    """The jobs whose arena can check their maneuver off (its ``checkoff_maneuvers``: a lone object in the open
    cannot squeeze a robot for B), and the (world, maneuver) pairs left out.

    Raises:
        ValueError: no arena among the worlds can check these maneuvers off.
    """
    from bt_nav_sim.world import load_world

    can = {world: load_world(world).checkoff_maneuvers for world in {job.world for job in jobs}}
    kept = [job for job in jobs if not can[job.world] or job.maneuver in can[job.world]]
    skipped = sorted({(job.world, job.maneuver) for job in jobs} - {(job.world, job.maneuver) for job in kept})
    if not kept:
        raise ValueError("no arena among the worlds can check these maneuvers off")
    return kept, skipped
