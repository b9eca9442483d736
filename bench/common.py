"""Helpers every benchmark module shares: percentile summaries, targets, the machine, profiles.

Timings on a shared machine are noisy, so every timing is reported as a distribution (p50 and p99
over many repetitions, never one run) and every comparison as a ratio measured in the same run; the
machine's load average is recorded next to the numbers so a reader can tell a loaded run from a
quiet one.
"""

from __future__ import annotations

import cProfile
import datetime as dt
import os
import platform
import pstats
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.ros.supervise import usable_cores

REPO = Path(__file__).resolve().parents[1]
#: Domains of the benchmarks' DDS traffic: above demo/sim-run (100-200), below the tests (215-232).
DOMAIN_RANGE = (201, 214)


def percentiles(values: Iterable[float], scale: float = 1.0, digits: int = 4) -> dict[str, float | int]:
    """p50, p90, p99, min, max and mean of ``values`` times ``scale`` (NaN for an empty sample).

    ``scale`` converts units (1e3 for seconds to milliseconds) so callers never round twice.
    """
    arr = np.asarray(list(values), dtype=np.float64) * scale
    if arr.size == 0:
        nan = float("nan")
        return {"n": 0, "p50": nan, "p90": nan, "p99": nan, "min": nan, "max": nan, "mean": nan}
    p50, p90, p99 = np.percentile(arr, [50, 90, 99])
    return {"n": int(arr.size), "p50": round(float(p50), digits), "p90": round(float(p90), digits),
            "p99": round(float(p99), digits), "min": round(float(arr.min()), digits),
            "max": round(float(arr.max()), digits), "mean": round(float(arr.mean()), digits)}


def median(values: Sequence[float]) -> float:
    """The median (NaN when empty), as a plain float for JSON."""
    return float(np.median(values)) if len(values) else float("nan")


@dataclass
class Target:
    """One goal a benchmark is held to, and whether this run met it.

    ``met`` is None when the value could not be measured (skipped or failed), so a missing number
    can never pass for a met target.
    """

    id: str
    benchmark: str
    description: str
    goal: str  # human-readable, e.g. "<= 0.25 ms"
    value: float | None
    unit: str
    met: bool | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        return asdict(self)


def at_most(value: float | None, limit: float) -> bool | None:
    """``value <= limit``; None when there is no value (NaN counts as none)."""
    if value is None or value != value:
        return None
    return bool(value <= limit)


def at_least(value: float | None, limit: float) -> bool | None:
    """``value >= limit``; None when there is no value (NaN counts as none)."""
    if value is None or value != value:
        return None
    return bool(value >= limit)


def homework_overrides() -> dict[str, Any]:
    """The parameters of ``config/homework.yaml`` but the maneuver (the benchmarks choose it).

    The lock-step benchmarks run what ``bt-nav demo`` runs (the executive with that file), not the
    bare defaults, so their missions and the ROS-path ones are the same missions.
    """
    from bt_nav.run.settings import profile_parameters

    return profile_parameters("homework")


# ---------------------------------------------------------------------------------------------- the machine
def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo (``platform.processor()`` is often empty on Linux)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as stream:
            for line in stream:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def load_average() -> list[float]:
    """1, 5 and 15 minute load averages (empty when unknown): the context for every timing."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return []


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "?"


def machine() -> dict[str, Any]:
    """What the numbers were measured on: CPU, cores, OS, Python and the libraries that matter."""
    usable = usable_cores()
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "cores_usable": usable,
        "os": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
        "python_impl": sys.implementation.name,
        "numpy": np.__version__,
        "py_trees": _version("py_trees"),
        "rclpy": _version("rclpy"),
        "hostname": platform.node(),
    }


def now_iso() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat()


# ---------------------------------------------------------------------------------------------- profiles
def _area(filename: str, function: str, areas: Sequence[tuple[str, str]]) -> str:
    """The first area whose marker occurs in the file name (or, for built-ins, the function text)."""
    text = filename if filename != "~" else function
    for marker, name in areas:
        if marker in text:
            return name
    return "builtins and stdlib (called from the areas above)"


def _label(key: tuple[str, int, str]) -> str:
    """``module.py:line(function)`` with the path shortened to what identifies it."""
    filename, line, function = key
    if filename == "~":
        return function
    path = Path(filename)
    parts = path.parts
    for anchor in ("site-packages", "bt_nav", "sim", "bench"):
        if anchor in parts:
            index = len(parts) - 1 - parts[::-1].index(anchor)
            tail = parts[index + 1:] if anchor == "site-packages" else parts[index:]
            return f"{'/'.join(tail)}:{line}({function})"
    return f"{path.name}:{line}({function})"


def profile_call(fn: Callable[[], Any], *, top: int = 8, areas: Sequence[tuple[str, str]] = (),
                 cumulative_of: Sequence[str] = ()) -> dict[str, Any]:
    """Run ``fn`` under cProfile and summarise it (see :func:`summarize_profile`)."""
    profiler = cProfile.Profile()
    profiler.enable()
    fn()
    profiler.disable()
    return summarize_profile(pstats.Stats(profiler), top=top, areas=areas, cumulative_of=cumulative_of)


def summarize_profile(stats: pstats.Stats, *, top: int = 8, areas: Sequence[tuple[str, str]] = (),
                      cumulative_of: Sequence[str] = (), idle: Sequence[str] = ()) -> dict[str, Any]:
    """The functions with the most own time, the time per area, and the inclusive time of chosen functions.

    cProfile inflates call-heavy code (py_trees' small methods) more than numpy kernels, so the
    shares are a guide to where the time goes, not a second measurement of it.

    Args:
        stats: a profile (from this process, or a ``-o`` file of ``python -m cProfile``).
        top: how many functions to list.
        areas: ``(marker, name)`` pairs; a function belongs to the first area whose marker is in its
            file name (built-ins: in their description), else to "builtins and stdlib".
        cumulative_of: ``file:function`` names (file name suffix match) whose inclusive time is
            reported, e.g. ``"lidar.py:cast"``.
        idle: markers of functions that only wait (cProfile times the wall clock, so a blocking wait
            shows up as time); their own time is reported as ``idle_s`` and left out of the shares.
    """
    everything: dict[tuple[str, int, str], tuple[int, int, float, float, dict]] = stats.stats  # type: ignore[attr-defined]
    raw = {k: v for k, v in everything.items() if not any(marker in _label(k) for marker in idle)}
    idle_s = sum(v[2] for k, v in everything.items() if k not in raw)
    total = sum(entry[2] for entry in raw.values()) or 1e-12
    ranked = sorted(raw.items(), key=lambda kv: kv[1][2], reverse=True)
    functions = [{"function": _label(key), "calls": entry[1], "own_s": round(entry[2], 4),
                  "own_share": round(entry[2] / total, 3), "cum_s": round(entry[3], 4)}
                 for key, entry in ranked[:top]]
    by_area: dict[str, float] = {}
    for key, entry in raw.items():
        name = _area(key[0], key[2], areas)
        by_area[name] = by_area.get(name, 0.0) + entry[2]
    shares = {name: round(seconds / total, 3) for name, seconds in sorted(by_area.items(), key=lambda kv: -kv[1])}
    inclusive: dict[str, float] = {}
    for wanted in cumulative_of:
        file_part, _, func = wanted.partition(":")
        best = 0.0
        for (filename, _line, function), entry in raw.items():
            if function == func and filename.endswith(file_part):
                best = max(best, entry[3])
        inclusive[wanted] = round(best, 4)
    return {"total_s": round(total, 4), "idle_s": round(idle_s, 4), "top_own_time": functions, "area_share": shares,
            "inclusive_s": inclusive, "inclusive_share": {k: round(v / total, 3) for k, v in inclusive.items()}}
