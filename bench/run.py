"""``make bench`` / ``python -m bench.run``: measure what bt_nav exists for, side by side.

Benchmarks (``--only`` picks some, comma-separated):

``tick``     tree tick + scan processing vs the hand-written if/else baseline (:mod:`bench.tick_cost`)
``latency``  scan -> cmd_vel reaction latency over DDS with the real executive (:mod:`bench.latency`)
``sim``      LiDAR scans/s, lock-step mission wall time, ROS-path real-time factor (:mod:`bench.sim_throughput`)
``quality``  referee verdicts over worlds x maneuvers x seeds (:mod:`bench.quality`)
``memory``   peak RSS of the executive during a ROS-path mission (:mod:`bench.memory`)
``video``    bag a lock-step mission and film it: render time of a 55 s mission at 10 fps (:mod:`bench.video`)
``exe``      DDS grading throughput: missions/min of ``bt-nav grade --exe "bt-nav executive" --jobs 2``
             (:mod:`bench.exe_throughput`)
``testquick`` wall time of ``make test-quick``, the contributor's loop of tests without DDS (:mod:`bench.quick_tests`)
``gradespeed`` a lab grade at real time (issue 52's default) side by side with the paced default before it: a right
             node, a wall-clock node, a class of 10 (:mod:`bench.grade_speed`; 30+ min)

Writes ``<out>/latest.json`` (every result, every target and whether it is met, the machine) and
``<out>/latest.md`` (the same as tables). With ``--only``, the sections not run this time are
carried over from the previous ``latest.json`` in ``<out>``, each marked with the run it comes from.
Every run also appends one line to ``<out>/history.jsonl`` (when, which commit, the load, and the value
and verdict of every target it measured), and ``latest.md`` shows the last few runs side by side, so a
regression shows as a change between columns instead of needing an old report.
Missed targets do not fail the command (a benchmark is a measurement, not a test); a benchmark that
crashes does (exit 1), after the others have run and the files are written.

DDS: every ROS process started here talks on localhost only, in a domain of 201-214 claimed with a
lock file (:func:`bt_nav.ros.rosutil.claim_domain_id`): above ``bt-nav demo``/``sim-run`` (100-200) and
below the tests (215-232), so benchmarks, tests and demos can run side by side. ``--no-dds`` skips
everything that needs DDS (the latency, the ROS path of ``sim``, memory).
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .common import DOMAIN_RANGE, REPO, Target, load_average, machine, now_iso

BENCHMARKS = ("tick", "latency", "sim", "quality", "memory", "video", "exe", "testquick", "gradespeed")
#: The order they run in: the quiet single-process measurements first, the process pools last.
ORDER = ("tick", "sim", "video", "latency", "memory", "exe", "quality", "testquick", "gradespeed")
SCHEMA = 1
DEFAULT_OUT = REPO / "bench" / "results"
#: Runs of the history shown in latest.md.
HISTORY_SHOWN = 6


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """Command-line options."""
    parser = argparse.ArgumentParser(prog="python -m bench.run", description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="\n".join(__doc__.splitlines()[2:15]))
    parser.add_argument("--quick", action="store_true", help="a fast smoke run: few repetitions and seeds")
    parser.add_argument("--only", default=",".join(BENCHMARKS),
                        help=f"comma-separated subset of {','.join(BENCHMARKS)} (default: all)")
    parser.add_argument("--no-dds", action="store_true", help="skip every part that needs DDS")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="directory of latest.json / latest.md")
    parser.add_argument("--jobs", type=int, default=None, help="worker processes of the quality grid (default: cores)")
    parser.add_argument("--keep", type=Path, default=None,
                        help="gradespeed: keep every grade's directory and log here (default: a removed temporary one)")
    args = parser.parse_args(argv)
    chosen = [name.strip() for name in args.only.split(",") if name.strip()]
    unknown = [name for name in chosen if name not in BENCHMARKS]
    if unknown or not chosen:
        parser.error(f"--only: unknown benchmark(s) {', '.join(unknown) or '(none given)'}; "
                     f"choose from {', '.join(BENCHMARKS)}")
    args.chosen = [name for name in ORDER if name in chosen]
    return args


def _domain() -> int:
    """A fresh DDS domain for one activity (the claim lasts until this process exits)."""
    from bt_nav.ros.rosutil import claim_domain_id

    return claim_domain_id(*DOMAIN_RANGE)


def _run_ros_mission(seed: int, profile_to: Path | None = None) -> dict[str, Any]:
    from .ros_mission import run_mission

    domain = _domain()
    what = "profiled ROS-path mission" if profile_to else "ROS-path mission"
    print(f"  {what}, seed {seed}, ROS_DOMAIN_ID={domain} ...", flush=True)
    result = run_mission(domain, seed=seed, profile_to=profile_to)
    print(f"    {'PASSED' if result.get('passed') else 'FAILED'}, real-time factor {result.get('rtf')}, "
          f"{result.get('total_wall_s')} s wall", flush=True)
    return result


class Session:
    """Runs the chosen benchmarks and keeps what one benchmark hands to another (ROS missions, memory)."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.quick = bool(args.quick)
        self.ros_missions: list[dict[str, Any]] = []
        self.latency_result: dict[str, Any] | None = None
        self.run_ros: Callable[[int, Path | None], dict[str, Any]] | None = None if args.no_dds else self._ros

    def _ros(self, seed: int, profile_to: Path | None = None) -> dict[str, Any]:
        result = _run_ros_mission(seed, profile_to)
        if profile_to is None:  # a profiled executive is slower and bigger: not a measurement
            self.ros_missions.append(result)
        return result

    def tick(self) -> dict[str, Any]:
        """Benchmark 1."""
        from . import tick_cost

        return tick_cost.run(quick=self.quick)

    def sim(self) -> dict[str, Any]:
        """Benchmark 3."""
        from . import sim_throughput

        return sim_throughput.run(quick=self.quick, run_ros=self.run_ros)

    def memory(self) -> dict[str, Any]:
        """Benchmark 5 (reuses the sim benchmark's missions when it ran)."""
        from . import memory

        return memory.run(list(self.ros_missions), self.run_ros, latency=self.latency_result)

    def latency(self) -> dict[str, Any]:
        """Benchmark 2."""
        if self.args.no_dds:
            return {"skipped": "no DDS in this run (--no-dds)"}
        from . import latency

        domain = _domain()
        switches = 40 if self.quick else 400
        print(f"  {switches} switches, ROS_DOMAIN_ID={domain} (about {switches * 0.3 + 10:.0f} s) ...", flush=True)
        self.latency_result = latency.run(domain, switches=switches)
        return self.latency_result

    def video(self) -> dict[str, Any]:
        """Benchmark 6."""
        from . import video

        return video.run(quick=self.quick)

    def exe(self) -> dict[str, Any]:
        """Benchmark 7."""
        if self.args.no_dds:
            return {"skipped": "no DDS in this run (--no-dds)"}
        from . import exe_throughput

        return exe_throughput.run(quick=self.quick)

    def quality(self) -> dict[str, Any]:
        """Benchmark 4."""
        from . import quality

        return quality.run(quick=self.quick, jobs=self.args.jobs)

    def testquick(self) -> dict[str, Any]:
        """Benchmark 8: ``make test-quick``'s wall time."""
        from . import quick_tests

        return quick_tests.run(quick=self.quick)

    def gradespeed(self) -> dict[str, Any]:
        """Benchmark 9: issue 52's grades (real time by default), before and after, side by side."""
        if self.args.no_dds:
            return {"skipped": "no DDS in this run (--no-dds)"}
        from . import grade_speed

        return grade_speed.run(quick=self.quick, out=self.args.keep.absolute() if self.args.keep else None)


def targets_of(name: str, result: dict[str, Any]) -> list[Target]:
    """The targets of one benchmark's result (none for a skipped one)."""
    if "skipped" in result:
        return []
    if name == "tick":
        from .tick_cost import targets
    elif name == "latency":
        from .latency import targets
    elif name == "sim":
        from .sim_throughput import targets
    elif name == "quality":
        from .quality import targets
    elif name == "video":
        from .video import targets
    elif name == "exe":
        from .exe_throughput import targets
    elif name == "testquick":
        from .quick_tests import targets
    elif name == "gradespeed":
        from .grade_speed import targets
    else:
        return []
    return targets(result)


def _previous(path: Path) -> dict[str, Any]:
    """The benchmark sections of an earlier ``latest.json`` (empty when absent or of another schema)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if doc.get("schema") != SCHEMA:
        return {}
    return dict(doc.get("benchmarks") or {})


def main(argv: list[str] | None = None) -> int:
    """Run, merge, write; exit 1 only when a benchmark crashed."""
    args = parse_args(argv)
    session = Session(args)
    started, load_start, t_start = now_iso(), load_average(), time.monotonic()
    command = " ".join(["python -m bench.run", *(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))])
    out_dir: Path = args.out
    out_dir.mkdir(parents=True, exist_ok=True)
    json_path, md_path = out_dir / "latest.json", out_dir / "latest.md"
    sections = _previous(json_path) if set(args.chosen) != set(BENCHMARKS) else {}
    crashed = []
    print(f"bench: {', '.join(args.chosen)}{' (quick)' if args.quick else ''} -> {out_dir}", flush=True)
    for name in args.chosen:
        print(f"[{name}]", flush=True)
        t0 = time.monotonic()
        section: dict[str, Any] = {"run_started": started, "measured_at": now_iso(), "quick": args.quick}
        try:
            section["result"] = getattr(session, name)()
        except Exception as exc:  # one broken benchmark must not lose the others' numbers
            crashed.append(name)
            section["error"] = repr(exc)
            section["traceback"] = traceback.format_exc()
            print(section["traceback"], file=sys.stderr, flush=True)
        section["duration_s"] = round(time.monotonic() - t0, 1)
        sections[name] = section
        for target in ([] if "error" in section else targets_of(name, section["result"])):
            print(f"  {target.description}: {target.value} {target.unit} (target {target.goal}): "
                  f"{ {True: 'met', False: 'MISSED', None: 'n/a'}[target.met]}", flush=True)
        print(f"  ({section['duration_s']} s)", flush=True)

    targets = [t.to_dict() for name in BENCHMARKS if name in sections and "result" in sections[name]
               for t in targets_of(name, sections[name]["result"])]
    duration = time.monotonic() - t_start
    doc = {
        "schema": SCHEMA,
        "run": {"started": started, "duration_s": round(duration, 1), "mode": "quick" if args.quick else "full",
                "command": command, "only": args.chosen, "no_dds": args.no_dds,
                "load_start": load_start, "load_end": load_average()},
        "machine": machine(),
        "targets": targets,
        "benchmarks": {name: sections[name] for name in BENCHMARKS if name in sections},
    }
    fresh = [t for t in targets if t["benchmark"] in args.chosen]
    doc["history"] = append_history(out_dir / "history.jsonl", doc, fresh)[-HISTORY_SHOWN:]
    json_path.write_text(json.dumps(_clean(doc), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    from .report import render

    md_path.write_text(render(json.loads(json_path.read_text(encoding="utf-8"))), encoding="utf-8")
    met = sum(1 for t in targets if t["met"] is True)
    print(f"bench: {met}/{len(targets)} targets met; {duration:.0f} s; wrote {json_path} and {md_path}", flush=True)
    if crashed:
        print(f"bench: crashed: {', '.join(crashed)}", file=sys.stderr)
    return 1 if crashed else 0


def git_commit() -> str:
    """The checked-out commit (short), with ``+dirty`` when tracked files other than the benchmark results
    differ from it; ``?`` without git."""
    import subprocess

    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True,
                              timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":(exclude)bench/results"],  # the benchmark's own output is not the code
                               cwd=REPO, capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "?"
    return head + ("+dirty" if dirty else "")


def append_history(path: Path, doc: dict[str, Any], targets: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Append this run's line to ``path`` (JSON lines) and return every line, oldest first.

    One line per run, whatever it measured: when, the mode, the commit, the load, and for each target
    it measured its value, unit and verdict. Lines that cannot be read are skipped, not fatal: a
    history is a convenience, the measurement is ``latest.json``.
    """
    run = doc["run"]
    line = {"started": run["started"], "mode": run["mode"], "only": run["only"], "commit": git_commit(),
            "load_start": run["load_start"], "cores": doc["machine"].get("cores"),
            "targets": {t["id"]: {"value": t["value"], "unit": t["unit"], "met": t["met"], "goal": t["goal"],
                                  "description": t["description"]} for t in targets}}
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a", encoding="utf-8") as stream:
        stream.write(json.dumps(_clean(line), allow_nan=False) + "\n")
    lines = []
    for raw in path.read_text(encoding="utf-8").splitlines():
        try:
            lines.append(json.loads(raw))
        except ValueError:
            continue
    return lines


def _clean(value: Any) -> Any:
    """Strict JSON: NaN and infinities become null (a value that could not be measured), numpy scalars
    plain numbers, tuples lists."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, str | bytes):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


if __name__ == "__main__":
    raise SystemExit(main())
