"""Where a grading grid runs: local worker processes, or a Dask distributed cluster.

Each grid cell is a :class:`Job`: one deterministic lock-step mission. Both executors yield
``(job, summary)`` pairs as missions finish, so ``bt-nav grade`` can show progress and save partial
results; which executor ran a job never changes its summary (only ``wall_time``).

Dask (``--scheduler tcp://HOST:PORT``): the grid is submitted to an existing scheduler, whose workers
run :func:`run_job`. A worker that dies mid-grid loses only its running tasks, which the scheduler
reruns elsewhere; results are collected per job key, so every job is counted exactly once. py_trees'
blackboard is process-global, so missions in one worker process are serialised by a lock: start workers
with ``--nthreads 1`` and as many ``--nworkers`` as cores to use them all.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from typing import Any

#: One mission at a time per process: the py_trees blackboard is shared by every tree in a process.
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

    @property
    def key(self) -> str:
        """A stable name of the job (results files and Dask keys use it)."""
        jitter = "exact" if not self.jitter else f"{self.jitter[0]:g}m{self.jitter[1]:g}deg"
        return f"{self.world}|{self.maneuver}|{self.seed}|{self.profile}|{self.kinematics or '-'}|{jitter}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return asdict(self)


def run_job(job: Job) -> dict[str, Any]:
    """One mission's summary; a mission that raises is reported as a failed run, never lost."""
    from bt_nav.cli.lockstep import run_mission

    with _MISSION_LOCK:
        try:
            summary = run_mission(job.world, job.maneuver, job.seed, job.overrides, job.profile, jitter=job.jitter,
                                  kinematics=job.kinematics).summary()
        except Exception as exc:  # one broken mission must not sink the whole grade
            summary = {"world": job.world, "maneuver": job.maneuver, "seed": job.seed, "profile": job.profile,
                       "kinematics": job.kinematics, "passed": False, "error": repr(exc), "travelled": 0.0,
                       "efficiency": 0.0, "collisions": 0, "failed_checks": ["error"], "wall_time": 0.0}
    summary["job"] = job.key
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
    with Client(**kwargs, timeout="30s") as client:
        futures = [client.submit(run_job, job, key=f"bt-nav-grade-{job.key}", pure=False, retries=retries)
                   for job in jobs]
        by_key = {future.key: job for future, job in zip(futures, jobs, strict=True)}
        for future in dask_completed(futures):  # each future once, whichever worker finished it
            yield by_key[future.key], future.result()
