"""Benchmark 9 (issue 43): a lab grade's wall time side by side with the commit before the speed work, on the same
grid, the same node file and each commit's own defaults, and whether every run's verdict stayed the same.

Why side by side: on a shared 2-core machine a wall time alone says little (the load moves it by tens of per cent);
the two commits measured in one sitting, each scenario's grades back to back (before, after, before, after, ...:
:data:`PAIRS` pairs), share the machine's drift, so their ratio is the measurement (of the medians, over several
pairs: :func:`paired`). The load average before and after each grade is
recorded next to it.

The "before" side is :data:`BEFORE` (the head when issue 43 was filed), checked out in a ``git worktree`` of its own
(removed at the end, also on an error or Ctrl-C) and run by this venv's Python with ``PYTHONPATH=<worktree>:
<worktree>/sim`` in the worktree's directory: ``sys.path`` (``PYTHONPATH``) is searched before the venv's editable
finder of the checkout (appended to ``sys.meta_path``), so ``python -m bt_nav.cli`` imports the old code. Each side's
imports are checked before its first grade (:func:`check_imports`), and every Python process a grade starts is
sampled for its ``PYTHONPATH`` and directory (:class:`Sampler`). The "after" side is this checkout, run the same way.

Each grade is what a user runs, ``<venv python> -m bt_nav.cli grade ...`` in a subprocess, with its own ``--out``
and ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (no ``ROS_DOMAIN_ID``: bt-nav claims its own), on the default lab
grid of :data:`BEFORE` for maneuver C (:data:`GRID`: 2 arenas x 3 LiDARs x 2 seeds, 12 runs), no ``--rtf``. The
node is ``tests/fixtures/lab_student_node.py`` of this checkout for both sides. Scenarios:

``correct``    the right node (``--choice C``)
``wallclock``  a node timing its turns by the wall clock (``--choice C --timing wall``: open loop on
               ``time.monotonic``, right on a robot at 1x and nowhere faster)
``class``      ``--class`` of 10 hand-ins (:data:`CLASS`): 7 right C variants and 3 C mistakes

Targets (issue 43's "Done when"): the right node's grade after <= 0.55 x before; the wall-clock node's grade after
<= one 1x run (the median wall of the after side's runs at 1x, else :data:`ONE_RUN_1X_FALLBACK`) + 30 s; every
run's verdict the same on both sides.

Standalone: ``python -m bench.grade_speed [--quick] [--only correct,wallclock,class] [--out DIR]`` prints the
table (``--out``: also ``grade_speed.json``/``.md`` and every grade's directory there, kept). ``--quick``: 1 seed, 1
LiDAR, a class of 3, for smoke tests only. The full benchmark takes 30 minutes or more on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav.grading.report import read_grade
from bt_nav.ros.supervise import child_preexec

from .common import REPO, Target, at_most, load_average, median

#: The head when issue 43 was filed: the grader before the speed work.
BEFORE = "6a6b504"
NODE = REPO / "tests" / "fixtures" / "lab_student_node.py"
#: The default lab grid of :data:`BEFORE` for maneuver C (its ``assignments.LAB.exe_grid``, ``plan.EXE_LIDARS``).
GRID = ("--profile", "lab", "--maneuvers", "C", "--worlds", "lab_object,lab_dead_end")
LIDARS, SEEDS = "lds01,lds02,rplidar", 2
QUICK_LIDARS, QUICK_SEEDS = "lds01", 1
SCENARIOS = ("correct", "wallclock", "class")
NODES = {"correct": ("--choice", "C"), "wallclock": ("--choice", "C", "--timing", "wall")}
#: The class: name -> the fixture's flags. Every variant and mistake exists, alike, at both commits.
CLASS: dict[str, tuple[str, ...]] = {
    "right_plain": ("--choice", "C"),
    "right_clock_timed": ("--variant", "c_clock_timed"),
    "right_stands_05": ("--variant", "c_stands_05"),
    "right_scan_only": ("--variant", "c_scan_only"),
    "right_timer_slow": ("--variant", "c_timer_slow"),
    "right_front15_sides75": ("--variant", "c_front15_sides75"),
    "right_brakes_at_safety": ("--variant", "c_brakes_at_safety"),
    "wrong_half_angle": ("--choice", "C", "--mistake", "half_angle"),
    "wrong_side": ("--choice", "C", "--mistake", "wrong_side"),
    "wrong_forward_while_turning": ("--choice", "C", "--mistake", "forward_while_turning"),
}
QUICK_CLASS = ("right_plain", "right_clock_timed", "wrong_half_angle")
#: Wall seconds a grade may take before it is stopped (SIGINT) and counted as failed to measure.
LIMITS = {"correct": 1200.0, "wallclock": 3600.0, "class": 7200.0}
#: Wall seconds of one lab run at 1x when the after side ran none at 1x (about 75 sim s, start-up and shutdown).
ONE_RUN_1X_FALLBACK = 80.0
CORRECT_RATIO = 0.55
#: Alternating pairs (before, after, before, after, ...) per scenario: the right node's grade is short and its wall
#: time on a shared machine moved by 56-70 s between two sittings of the same commit, so its ratio is that of the
#: medians of three pairs; the others take minutes each and are graded once per side.
PAIRS = {"correct": 3, "wallclock": 1, "class": 1}
WALLCLOCK_MARGIN = 30.0
#: Seconds a stopped grade gets to stop its runs before SIGTERM, then SIGKILL.
STOP_GRACE = 60.0


@dataclass
class Side:
    """One commit's code: where it is, the environment and directory its grades run in, what it imports."""

    name: str  # before, after
    root: Path
    commit: str
    env: dict[str, str] = field(default_factory=dict)
    imports: dict[str, Any] = field(default_factory=dict)

    def describe(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"commit": self.commit, "root": str(self.root), "pythonpath": self.env.get("PYTHONPATH"),
                "imports": self.imports}


def _git(*args: str) -> str:
    """``git -C REPO args``'s output (CalledProcessError on failure)."""
    return subprocess.run(["git", "-C", str(REPO), *args], capture_output=True, text=True, check=True,
                          timeout=300).stdout.strip()


def side_env(root: Path) -> dict[str, str]:
    """A grade's environment: this one, the code of ``root`` first on ``sys.path``, DDS on this machine only, and
    no fixed ``ROS_DOMAIN_ID`` (each grade claims its own)."""
    env = {key: value for key, value in os.environ.items() if key != "ROS_DOMAIN_ID"}
    env["PYTHONPATH"] = f"{root}{os.pathsep}{root / 'sim'}"
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return env


def check_imports(side: Side) -> dict[str, Any]:
    """Where ``bt_nav`` and ``bt_nav_sim`` come from in ``side``'s environment and directory (as ``python -m``
    there finds them); RuntimeError when either is not ``side.root``'s: the comparison would be of one code."""
    probe = ("import json, sys, bt_nav, bt_nav_sim, bt_nav.cli.grade as g; print(json.dumps({'bt_nav': "
             "bt_nav.__file__, 'bt_nav_sim': bt_nav_sim.__file__, 'grade': g.__file__, 'finders': "
             "[getattr(f, '__name__', type(f).__name__) for f in sys.meta_path]}))")
    out = subprocess.run([sys.executable, "-c", probe], cwd=side.root, env=side.env, capture_output=True, text=True,
                         timeout=120)
    if out.returncode != 0:
        raise RuntimeError(f"{side.name}: cannot import bt_nav there: {out.stderr[-1000:]}")
    found = json.loads(out.stdout.strip().splitlines()[-1])
    foreign = {k: v for k, v in found.items() if k != "finders" and not Path(v).is_relative_to(side.root)}
    if foreign:
        raise RuntimeError(f"{side.name} ({side.commit}) imports code outside {side.root}: {foreign}")
    return found


@contextmanager
def sides(work: Path) -> Iterator[tuple[Side, Side]]:
    """(before, after): :data:`BEFORE` in a detached worktree under ``work`` (removed on the way out, whatever
    ends the block), and this checkout."""
    tree = work / f"before-{BEFORE}"
    _git("worktree", "add", "--detach", str(tree), BEFORE)
    try:
        before = Side("before", tree, _git("rev-parse", "--short", f"{BEFORE}^{{commit}}"), side_env(tree))
        changed = _git("status", "--porcelain", "--untracked-files=no")
        after = Side("after", REPO, _git("rev-parse", "--short", "HEAD") + ("+modified" if changed else ""),
                     side_env(REPO))
        for side in (before, after):
            side.imports = check_imports(side)
        yield before, after
    finally:
        try:
            _git("worktree", "remove", "--force", str(tree))
        except (subprocess.SubprocessError, OSError):
            shutil.rmtree(tree, ignore_errors=True)
            _git("worktree", "prune")


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM raises KeyboardInterrupt here (as Ctrl-C does), so the worktree and the grades are cleaned up."""
    def interrupt(_signum: int, _frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


class Sampler:
    """The ``PYTHONPATH`` and directory of every Python process a grade starts (sampled each second; a process
    that lives less may be missed): the proof that the grade's simulators and judges ran the side's code too."""

    def __init__(self, root: int) -> None:
        self.root = root
        self.seen: dict[int, tuple[str, str, str]] = {}  # pid -> (what, PYTHONPATH, cwd)

    def sample(self) -> None:
        """Look at the descendants not seen yet."""
        import psutil

        try:
            children = psutil.Process(self.root).children(recursive=True)
        except psutil.Error:
            return
        for child in children:
            if child.pid in self.seen:
                continue
            try:
                cmd = child.cmdline()
                if not cmd or "python" not in Path(cmd[0]).name:
                    continue
                what = " ".join(cmd[1:4]) if cmd[1:2] == ["-m"] else Path(cmd[1]).name if len(cmd) > 1 else cmd[0]
                self.seen[child.pid] = (what, child.environ().get("PYTHONPATH", ""), child.cwd())
            except (psutil.Error, IndexError):
                continue

    def summary(self, side: Side) -> dict[str, Any]:
        """How many Python processes were seen, and those not run with ``side``'s ``PYTHONPATH`` and directory."""
        wanted = side.env["PYTHONPATH"]
        odd = sorted({f"{what} (PYTHONPATH={path!r}, cwd={cwd})" for what, path, cwd in self.seen.values()
                      if path != wanted or cwd != str(side.root)})
        kinds: dict[str, int] = {}
        for what, _, _ in self.seen.values():
            kinds[what] = kinds.get(what, 0) + 1
        return {"python_processes": len(self.seen), "by_command": kinds, "not_the_side": odd}


def grade_argv(scenario: str, out: Path, manifest: Path | None, quick: bool) -> list[str]:
    """The grade a user runs for ``scenario`` (the same on both sides), into ``out``."""
    what = ["--class", str(manifest)] if scenario == "class" else \
        ["--exe", " ".join([sys.executable, str(NODE), *NODES[scenario]])]
    return [sys.executable, "-m", "bt_nav.cli", "grade", *what, *grid(quick), "--out", str(out), "--progress", "off"]


def grid(quick: bool) -> list[str]:
    """The grid's options (:data:`GRID`, the LiDARs and seeds; ``quick``: one of each)."""
    return [*GRID, "--lidars", QUICK_LIDARS if quick else LIDARS, "--seeds", str(QUICK_SEEDS if quick else SEEDS)]


def write_manifest(path: Path, quick: bool) -> Path:
    """The class's manifest (``name: command`` lines, the format of both commits' ``--class``)."""
    names = QUICK_CLASS if quick else tuple(CLASS)
    path.write_text("".join(f"{name}: {' '.join([sys.executable, str(NODE), *CLASS[name]])}\n" for name in names),
                    encoding="utf-8")
    return path


def _wait(proc: subprocess.Popen[bytes], sampler: Sampler, limit: float) -> bool:
    """Wait for the grade, sampling its processes; stop it (SIGINT, then SIGTERM, SIGKILL) past ``limit`` or on
    Ctrl-C/SIGTERM here (re-raised). Whether it ended by itself."""
    started = time.monotonic()
    try:
        while proc.poll() is None:
            if time.monotonic() - started > limit:
                _stop(proc)
                return False
            sampler.sample()
            time.sleep(1.0)
    except KeyboardInterrupt:
        _stop(proc)
        raise
    return True


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Stop a grade as a user would (Ctrl-C: it stops its runs), harder if it does not end."""
    for sig, grace in ((signal.SIGINT, STOP_GRACE), (signal.SIGTERM, 30.0), (signal.SIGKILL, 30.0)):
        if proc.poll() is not None:
            return
        proc.send_signal(sig)
        try:
            proc.wait(grace)
        except subprocess.TimeoutExpired:
            continue


def run_grade(side: Side, scenario: str, out: Path, manifest: Path | None, quick: bool) -> dict[str, Any]:
    """One grade of ``scenario`` by ``side``'s code, timed, with its verdicts (:func:`read_verdicts`)."""
    argv = grade_argv(scenario, out, manifest, quick)
    log = out.with_name(out.name + ".log")
    load_before = load_average()
    cpu_before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.monotonic()
    with open(log, "wb") as stream:
        proc = subprocess.Popen(argv, cwd=side.root, env=side.env, stdout=stream, stderr=subprocess.STDOUT,
                                preexec_fn=child_preexec(os.getpid()))  # dies with this process
        sampler = Sampler(proc.pid)
        ended = _wait(proc, sampler, LIMITS[scenario])
    wall = time.monotonic() - started
    cpu_after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (cpu_after.ru_utime + cpu_after.ru_stime) - (cpu_before.ru_utime + cpu_before.ru_stime)
    result: dict[str, Any] = {
        "side": side.name, "commit": side.commit, "argv": argv, "out": str(out), "log": str(log),
        "returncode": proc.returncode, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
        "load_before": load_before, "load_after": load_average(), "processes": sampler.summary(side)}
    if not ended:
        result["error"] = f"stopped after {LIMITS[scenario]:g} s (the limit of a {scenario} grade)"
    elif proc.returncode not in (0, 1):  # 1: some run failed; anything else: no grade of this command
        result["error"] = f"the grade exited with code {proc.returncode}"
    try:
        result.update(read_verdicts(out, scenario, manifest))
    except (OSError, ValueError, KeyError) as exc:
        tail = log.read_text(encoding="utf-8", errors="replace")[-2000:]
        result["error"] = f"{result.get('error', 'no grade written')}: {exc}; the grade's output ended: {tail}"
    if result.get("runs"):
        result["wall_s_per_run"] = round(wall / result["runs"], 2)
    return result


def decision(row: dict[str, Any]) -> str | None:
    """What the re-runs decided for a run, read alike from both commits' rows: today's ``rerun.decision`` (load,
    wall clock, stands); :data:`BEFORE`'s ``realtime`` (the 1x run passed and replaced it: wall clock) or
    ``realtime_probe`` (its 1x probe failed: stands). None: not run again."""
    if isinstance(row.get("rerun"), dict):
        return row["rerun"].get("decision")
    if "realtime" in row:
        return "wall clock"
    if "realtime_probe" in row:
        return "stands"
    return None


def at_1x(row: dict[str, Any]) -> bool:
    """Whether a run went at 1x: a re-run in ``<out>/realtime/`` (both commits), or a factor achieved near 1
    (today's rows carry ``rtf``, what the run achieved)."""
    factor = row.get("rtf")
    return "realtime" in Path(str(row.get("run_dir", ""))).parts or \
        (isinstance(factor, int | float) and 0 < factor <= 1.2)


def _rows_of(grid_dir: Path) -> list[dict[str, Any]]:
    grade = read_grade(grid_dir)
    if grade is None:
        raise ValueError(f"no grade.json in {grid_dir}")
    return list(grade["runs"])


def read_verdicts(out: Path, scenario: str, manifest: Path | None) -> dict[str, Any]:
    """A grade's runs and verdicts from its ``grade.json`` (a class: each student's, ``<out>/<name>/grade.json``):
    run key (``job``; a class: ``student/job``) -> passed and the re-runs' decision."""
    if scenario == "class" and manifest is not None:
        names = [line.split(":", 1)[0].strip() for line in manifest.read_text(encoding="utf-8").splitlines()
                 if line.strip()]
        grids = {name: _rows_of(out / name) for name in names}
    else:
        grids = {"": _rows_of(out)}
    verdicts, walls_1x, factors = {}, [], []
    for name, rows in grids.items():
        for row in rows:
            key = f"{name}/{row['job']}" if name else row["job"]
            verdicts[key] = {"passed": bool(row["passed"]), "decision": decision(row), "outcome": row.get("outcome"),
                             "wall_s": row.get("wall_time"), "rtf": row.get("rtf")}
            if at_1x(row) and row.get("wall_time"):
                walls_1x.append(float(row["wall_time"]))
            if isinstance(row.get("rtf"), int | float):
                factors.append(float(row["rtf"]))
    passed = sum(1 for v in verdicts.values() if v["passed"])
    result = {"runs": len(verdicts), "passed": passed, "failed": len(verdicts) - passed,
              "decisions": _count(v["decision"] for v in verdicts.values() if v["decision"]),
              "runs_at_1x": len(walls_1x), "run_wall_1x_median_s": round(median(walls_1x), 1) if walls_1x else None,
              "rtf_median": round(median(factors), 2) if factors else None, "verdicts": verdicts}
    if scenario == "class":
        result["students_passed"] = sum(1 for name in grids if all(v["passed"] for k, v in verdicts.items()
                                                                   if k.startswith(f"{name}/")))
        result["students"] = len(grids)
    return result


def _count(values: Any) -> dict[str, int]:
    counts: dict[str, int] = {}
    for value in values:
        counts[value] = counts.get(value, 0) + 1
    return counts


def compare(before: dict[str, Any], after: dict[str, Any]) -> dict[str, Any]:
    """The runs whose verdict (passed) differs between the sides, or that only one side has; the runs whose re-run
    decision differs apart (informative: a wall-clock node is re-run at one commit and run at 1x at the other)."""
    one, two = before.get("verdicts") or {}, after.get("verdicts") or {}
    differ = []
    for key in sorted(set(one) | set(two)):
        a, b = one.get(key), two.get(key)
        if a is None or b is None or a["passed"] != b["passed"]:
            differ.append({"run": key, "before": None if a is None else a["passed"],
                           "after": None if b is None else b["passed"]})
    decided = [{"run": key, "before": one[key]["decision"], "after": two[key]["decision"]}
               for key in sorted(set(one) & set(two)) if one[key]["decision"] != two[key]["decision"]]
    measured = bool(one) and bool(two) and "error" not in before and "error" not in after
    return {"identical": measured and not differ, "measured": measured, "differences": differ,
            "decisions_differ": decided}


def run(quick: bool = False, only: Sequence[str] = SCENARIOS, out: Path | None = None) -> dict[str, Any]:
    """Every chosen scenario, before then after, back to back (see the module docstring); the result for
    ``bench.run`` (``latest.json``)."""
    if out is not None and (out / "grades").is_dir() and any((out / "grades").iterdir()):
        # a grade refuses an --out that holds one (exit 2), and its old grade.json would be read as this one's
        raise ValueError(f"{out / 'grades'} holds grades already: keep them elsewhere (a benchmark never mixes runs)")
    work = Path(tempfile.mkdtemp(prefix="bench-gradespeed-"))
    grades = (out or work) / "grades"
    grades.mkdir(parents=True, exist_ok=True)
    manifest = write_manifest(work / "class.yaml", quick)
    result: dict[str, Any] = {"quick": quick, "grid": grid(quick), "node": str(NODE), "scenarios": {},
                              "class": {n: list(CLASS[n]) for n in (QUICK_CLASS if quick else CLASS)}}
    try:
        with sigterm_as_interrupt(), sides(work) as (before, after):
            result["sides"] = {side.name: side.describe() for side in (before, after)}
            for scenario in [s for s in SCENARIOS if s in only]:
                repeats = []
                for index in range(1 if quick else PAIRS[scenario]):
                    one = {}
                    for side in (before, after):
                        print(f"  {scenario}: {side.name} ({side.commit}) ...", flush=True)
                        one[side.name] = run_grade(side, scenario, grades / f"{scenario}-{side.name}-{index + 1}",
                                                   manifest if scenario == "class" else None, quick)
                        print(f"    {_line(one[side.name])}", flush=True)
                    repeats.append(one)
                result["scenarios"][scenario] = paired(repeats)
    finally:
        shutil.rmtree(work, ignore_errors=True)  # the manifest, and the grades unless --out keeps them
    result["one_run_1x_s"], result["one_run_1x_from"] = one_run_1x(result)
    return result


def paired(repeats: list[dict[str, dict[str, Any]]]) -> dict[str, Any]:
    """A scenario's result from its alternating pairs: ``before`` and ``after``, each side's grade of median wall
    time (the table's rows); ``after_over_before``, the ratio of the sides' median wall times; ``comparison``, every
    pair's verdicts compared (one differing run in any pair is a difference); ``pairs``, each pair's walls and
    ratio; ``repeats``, every grade."""
    def middle(name: str) -> dict[str, Any]:
        timed = sorted((g for g in (r[name] for r in repeats) if g.get("wall_s")), key=lambda g: g["wall_s"])
        return timed[(len(timed) - 1) // 2] if timed else repeats[0][name]

    compared = [compare(r["before"], r["after"]) for r in repeats]
    comparison = {"identical": all(c["identical"] for c in compared), "measured": all(c["measured"] for c in compared),
                  "differences": [d for c in compared for d in c["differences"]],
                  "decisions_differ": [d for c in compared for d in c["decisions_differ"]]}
    out: dict[str, Any] = {"before": middle("before"), "after": middle("after"), "comparison": comparison,
                           "pairs": [{"before_s": r["before"].get("wall_s"), "after_s": r["after"].get("wall_s")}
                                     for r in repeats], "repeats": repeats}
    walls = {name: [g["wall_s"] for g in (r[name] for r in repeats) if g.get("wall_s")] for name in ("before", "after")}
    if walls["before"] and walls["after"] and all(len(w) == len(repeats) for w in walls.values()):
        out["after_over_before"] = round(median(walls["after"]) / median(walls["before"]), 3)
    return out


def _line(grade: dict[str, Any]) -> str:
    if "error" in grade and not grade.get("runs"):
        return f"ERROR: {grade['error'][:300]}"
    return (f"{grade['wall_s']} s wall, {grade.get('passed')}/{grade.get('runs')} passed, "
            f"{grade.get('wall_s_per_run')} s per run, load {grade['load_before'][:1]} -> {grade['load_after'][:1]}")


def one_run_1x(result: dict[str, Any]) -> tuple[float, str]:
    """One 1x run's wall seconds: the median of the after side's runs at 1x (the wall-clock grade's first), else
    :data:`ONE_RUN_1X_FALLBACK`; and where it comes from."""
    for scenario in ("wallclock", "class", "correct"):
        grade = (result["scenarios"].get(scenario) or {}).get("after") or {}
        if grade.get("run_wall_1x_median_s"):
            return grade["run_wall_1x_median_s"], f"median of the after side's {grade['runs_at_1x']} runs at 1x " \
                                                  f"({scenario})"
    return ONE_RUN_1X_FALLBACK, "none ran at 1x on the after side: the issue's estimate"


def targets(result: dict[str, Any]) -> list[Target]:
    """Issue 43's "Done when": the right node's grade <= 0.55 x before; the wall-clock node's <= one 1x run + 30 s;
    the same verdict for every run."""
    scenarios = result.get("scenarios") or {}
    correct, wall = scenarios.get("correct") or {}, scenarios.get("wallclock") or {}
    ratio = correct.get("after_over_before") if "error" not in correct.get("after", {}) else None
    runs = (correct.get("after") or {}).get("runs")
    limit = float(result.get("one_run_1x_s") or ONE_RUN_1X_FALLBACK) + WALLCLOCK_MARGIN
    wall_after = (wall.get("after") or {}).get("wall_s") if wall and "error" not in wall.get("after", {}) else None
    compared = [s["comparison"] for s in scenarios.values()]
    differing = None if not compared or not all(c["measured"] for c in compared) else \
        sum(len(c["differences"]) for c in compared)
    return [
        Target("gradespeed_correct_ratio", "gradespeed", f"right C node's lab grade ({runs} runs): wall time after / "
               f"before ({BEFORE})", f"<= {CORRECT_RATIO:g}x", ratio, "x", at_most(ratio, CORRECT_RATIO)),
        Target("gradespeed_wallclock_s", "gradespeed", "wall-clock C node's lab grade after: wall s (one 1x run "
               f"{result.get('one_run_1x_s')} s + {WALLCLOCK_MARGIN:g} s)", f"<= {limit:.0f} s", wall_after, "s",
               at_most(wall_after, limit)),
        Target("gradespeed_verdicts", "gradespeed", "runs whose verdict differs after vs before "
               f"({', '.join(scenarios)})", "0", differing, "runs", at_most(differing, 0)),
    ]


def markdown(result: dict[str, Any]) -> list[str]:
    """The section's lines: a row per scenario and side, the ratio, and the verdicts compared."""
    head = ["scenario", "side", "wall s", "runs", "wall s / run", "passed", "failed", "re-run decisions",
            "median factor achieved", "CPU s", "load before -> after", "exit"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    notes = []
    for scenario, pair in (result.get("scenarios") or {}).items():
        for name in ("before", "after"):
            g = pair.get(name) or {}
            decided = ", ".join(f"{k} {v}" for k, v in (g.get("decisions") or {}).items()) or "-"
            cells = [scenario, f"{name} `{g.get('commit', '?')}`", g.get("wall_s"), g.get("runs"),
                     g.get("wall_s_per_run"), g.get("passed"), g.get("failed"), decided, g.get("rtf_median"),
                     g.get("cpu_s"), f"{(g.get('load_before') or ['?'])[0]} -> {(g.get('load_after') or ['?'])[0]}",
                     g.get("returncode")]
            lines.append("| " + " | ".join("-" if c is None else str(c) for c in cells) + " |")
            if "error" in g:
                notes.append(f"- {scenario} {name}: {g['error'][:400]}")
            odd = (g.get("processes") or {}).get("not_the_side")
            if odd:
                notes.append(f"- {scenario} {name}: Python processes not on the side's code: {'; '.join(odd[:5])}")
        c = pair["comparison"]
        same = "identical" if c["identical"] else "not compared (a side has no grade)" if not c["measured"] else \
            "DIFFER: " + "; ".join(f"{d['run']} {d['before']} -> {d['after']}" for d in c["differences"][:10])
        ratio = pair.get("after_over_before")
        walls = "; ".join(f"{p['before_s']} -> {p['after_s']} s" for p in pair.get("pairs") or [])
        notes.append(f"- {scenario}: after / before {ratio if ratio is not None else '-'}"
                     + (f" (medians of {len(pair['pairs'])} alternating pairs: {walls})"
                        if len(pair.get("pairs") or []) > 1 else "") + f"; verdicts {same}"
                     + (f"; re-run decisions differ in {len(c['decisions_differ'])} runs" if c["decisions_differ"]
                        else ""))
    grid = " ".join(result.get("grid") or [])
    notes.append(f"- grid: `{grid}`; node `{result.get('node')}`; one 1x run: {result.get('one_run_1x_s')} s "
                 f"({result.get('one_run_1x_from')})")
    return [*lines, "", *notes]


def main(argv: list[str] | None = None) -> int:
    """``python -m bench.grade_speed``: run, print the table (and write it with ``--out``)."""
    parser = argparse.ArgumentParser(prog="python -m bench.grade_speed", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 seed, 1 LiDAR, a class of 3 (a smoke test)")
    parser.add_argument("--only", default=",".join(SCENARIOS), help=f"comma-separated of {','.join(SCENARIOS)}")
    parser.add_argument("--out", type=Path, default=None, help="keep every grade and write grade_speed.json/.md here")
    args = parser.parse_args(argv)
    only = [s.strip() for s in args.only.split(",") if s.strip()]
    if not only or any(s not in SCENARIOS for s in only):
        parser.error(f"--only: choose from {', '.join(SCENARIOS)}")
    try:
        result = run(args.quick, only, args.out.absolute() if args.out else None)
    except KeyboardInterrupt:
        print("bench.grade_speed: stopped (every grade stopped, the worktree removed)", file=sys.stderr)
        return 130
    table = [*markdown(result), "", *(f"- target {t.description}: {t.value} {t.unit} (goal {t.goal}): "
                                     f"{ {True: 'met', False: 'MISSED', None: 'n/a'}[t.met]}"
                                     for t in targets(result))]
    print("\n".join(table))
    if args.out:
        (args.out / "grade_speed.json").write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        (args.out / "grade_speed.md").write_text("\n".join(table) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
