"""Running an ``--exe`` grid: every :class:`bt_nav.run.grid.Job` through :func:`bt_nav.run.exegrade.run_exe_job`,
``workers`` at a time in threads of this process (each thread only supervises its run's children)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from typing import Any

from bt_nav.ros.supervise import StopRequest
from bt_nav.run.exegrade import ExeSettings, run_exe_job
from bt_nav.run.grid import Job


def run_exe_grid(jobs: Sequence[Job], settings: ExeSettings, workers: int = 2, stop: StopRequest | None = None,
                 on_row: Callable[[dict[str, Any]], None] | None = None) -> list[dict[str, Any]]:
    """Every job, ``workers`` at a time; the rows in the jobs' order (a stop request: the finished ones)."""
    rows: dict[str, dict[str, Any]] = {}
    with ThreadPoolExecutor(max_workers=max(1, workers), thread_name_prefix="exe-run") as pool:
        pending: set[Future] = {pool.submit(run_exe_job, job, settings, stop) for job in jobs}
        while pending:
            done, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in done:
                if not future.cancelled():
                    row = future.result()
                    rows[row["job"]] = row
                    if on_row is not None:
                        on_row(row)
            if stop is not None and stop.requested:
                for future in pending:
                    future.cancel()
    return [rows[job.key] for job in jobs if job.key in rows]
