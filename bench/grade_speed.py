"""Benchmark 9 (issue 52): a lab grade at today's default (real time, every cell at once) side by side with the
commit before issue 52 (its default: ``--rtf 0``, as fast as the node keeps up, "paced"), on each commit's own
default grid for maneuver C, the same node file; and what each side's verdicts were.

Why side by side: on a shared 2-core machine a wall time alone says little (the load moves it by tens of per cent);
the two commits measured in one sitting, each scenario's grades back to back (before, after, before, after, ...:
:data:`PAIRS` pairs), share the machine's drift (of the medians, over several pairs: :func:`paired`). The load
average before and after each grade is recorded next to it. Why the simulated seconds too: at 1x with every cell at
once a grade cannot end before its longest run's simulated time, so the share of the wall that is simulated time
says what is left to gain (start-up, shutdown, admission) and what is not (the mission itself).

The "before" side is :data:`BEFORE` (issue 52's session's starting commit), checked out in a ``git worktree`` of its
own (removed at the end, also on an error or Ctrl-C) and run by this venv's Python with ``PYTHONPATH=<worktree>:
<worktree>/sim`` in the worktree's directory: ``sys.path`` (``PYTHONPATH``) is searched before the venv's editable
finder of the checkout (appended to ``sys.meta_path``), so ``python -m bt_nav.cli`` imports the old code. Each side's
imports are checked before its first grade (:func:`check_imports`), and every Python process a grade starts is
sampled for its ``PYTHONPATH`` and directory (:class:`Sampler`). The "after" side is this checkout, run the same way.

Each grade is what a user runs, ``<venv python> -m bt_nav.cli grade ...`` in a subprocess, with its own ``--out``
and ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (no ``ROS_DOMAIN_ID``: bt-nav claims its own), with :data:`GRID`
and no ``--worlds``, ``--lidars``, ``--seeds`` or ``--rtf``: each side's own defaults. :data:`BEFORE` grades C on
lab_beside and lab_dead_end x 3 LiDARs x 2 seeds, 12 runs (its ``assignments.LAB.exe_grid``); the after side's
default grid may have gained cells (issue 52's arenas), so each side's runs are counted by its own code
(:func:`count_runs`), a grade is checked against its side's count, and verdicts are compared over the runs both
sides graded. The node is ``tests/fixtures/lab_student_node.py`` of this checkout for both sides (alike at both
commits). Scenarios:

``correct``    the right node (``--choice C``)
``wallclock``  a node timing its turns by the wall clock (``--choice C --timing wall``: open loop on
               ``time.monotonic``, right on a robot at 1x and nowhere faster)
``class``      ``--class`` of 10 hand-ins (:data:`CLASS`): 7 right C variants and 3 C mistakes

Targets (issue 52's "Done when", :func:`targets`): the right node's grade after <= :data:`CORRECT_WALL_S` wall (the
median of the pairs; the after / before ratio and the runs' simulated seconds are information); the class after no
slower than before, the wrong ones' run verdicts the same on both sides, every right one passing after; the
wall-clock node passing every run after.

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

#: Issue 52's session's starting commit: the grader before real time became the default (its default: --rtf 0).
BEFORE = "b6541ee"
NODE = REPO / "tests" / "fixtures" / "lab_student_node.py"
#: Each side's own default lab grid for maneuver C (no --worlds: the assignment's cells; LiDARs and seeds: defaults).
GRID = ("--profile", "lab", "--maneuvers", "C")
#: How many runs a side's default grid for a node has, by its own code (its grade's parser and jobs; stdout: the
#: count): the lab's default grid may change between commits (issue 52 added arenas), so each side is counted.
GRID_PROBE = ("import sys; from bt_nav.cli.grade import _parser; "
              "from bt_nav.grading.plan import build_jobs, grid_axes; "
              "a = _parser().parse_args(['--exe', 'node', *sys.argv[1:]]); w, s = grid_axes(a); "
              "print(len(build_jobs(a, w, s)))")
QUICK_LIDARS, QUICK_SEEDS = "lds01", 1
SCENARIOS = ("correct", "wallclock", "class")
NODES = {"correct": ("--choice", "C"), "wallclock": ("--choice", "C", "--timing", "wall")}
#: The class: name -> the fixture's flags. Every variant and mistake exists, alike, at both commits. A name's prefix
#: says which it is (:data:`RIGHT`, :data:`WRONG`): the targets read it.
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
RIGHT, WRONG = "right_", "wrong_"
QUICK_CLASS = ("right_plain", "right_clock_timed", "wrong_half_angle")
#: Wall seconds a grade may take before it is stopped (SIGINT) and counted as failed to measure.
LIMITS = {"correct": 1200.0, "wallclock": 3600.0, "class": 7200.0}
#: Issue 52: the right node's default grade (every cell at 1x, all at once) on 2 cores, wall seconds at most.
CORRECT_WALL_S = 60.0
#: Alternating pairs (before, after, before, after, ...) per scenario: the right node's grade is short and its wall
#: time on a shared machine moved by 56-70 s between two sittings of the same commit, so its figure is the median of
#: three pairs; the others take minutes each and are graded once per side.
PAIRS = {"correct": 3, "wallclock": 1, "class": 1}
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
    runs: int | None = None  # runs of its default grid for one node (:func:`count_runs`)

    def describe(self) -> dict[str, Any]:
        """JSON-able form."""
        return {"commit": self.commit, "root": str(self.root), "pythonpath": self.env.get("PYTHONPATH"),
                "imports": self.imports, "grid_runs": self.runs}


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


def count_runs(side: Side, quick: bool) -> int | None:
    """The runs of ``side``'s default grid for one node (:data:`GRID_PROBE` with :func:`grid`), by its code; None
    when the probe fails (its grade then checks nothing against it)."""
    out = subprocess.run([sys.executable, "-c", GRID_PROBE, *grid(quick)], cwd=side.root, env=side.env,
                         capture_output=True, text=True, timeout=120)
    try:
        return int(out.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return None


@contextmanager
def sides(work: Path, quick: bool = False) -> Iterator[tuple[Side, Side]]:
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
            side.runs = count_runs(side, quick)
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
    """The grid's options: :data:`GRID` alone (each side's default LiDARs and seeds are the measurement);
    ``quick``: one LiDAR and one seed."""
    return [*GRID, "--lidars", QUICK_LIDARS, "--seeds", str(QUICK_SEEDS)] if quick else list(GRID)


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
    """What happened to a run beyond its one attempt, read alike from both commits' rows: today's (issue 52)
    ``not_graded`` (not graded: bt_nav's fault or a machine too busy for 1x, twice), a note "run again" (a 1x run
    that fell behind, run once more) or ``preview`` (a preview's failure graded again at 1x); :data:`BEFORE`'s
    ``rerun.decision`` (load, wall clock, stands). None: one attempt, kept."""
    if row.get("not_graded"):
        return "not graded"
    if any(str(note).startswith("run again") for note in row.get("notes") or ()):
        return "run again"
    if isinstance(row.get("preview"), dict) and "reason" in row["preview"]:
        return "preview failed, 1x"
    if isinstance(row.get("rerun"), dict):
        return row["rerun"].get("decision")
    return None


def at_1x(row: dict[str, Any]) -> bool:
    """Whether a run went at 1x: set so (today's ``speed.set``), a re-run in ``<out>/realtime/`` (both commits), or
    a factor achieved near 1 (both commits' rows carry ``rtf``, what the run achieved)."""
    factor = row.get("rtf")
    return (row.get("speed") or {}).get("set") == 1.0 or "realtime" in Path(str(row.get("run_dir", ""))).parts or \
        (isinstance(factor, int | float) and 0 < factor <= 1.2)


def sim_seconds(row: dict[str, Any], out: Path) -> float | None:
    """The run's simulated seconds: its row's ``speed.sim_s`` (both commits), else its simulator's ``pace.json``
    ``t_end`` (``run_dir``, relative to the grade's ``out``); None when neither is there (a run stopped early)."""
    sim = (row.get("speed") or {}).get("sim_s")
    if isinstance(sim, int | float):
        return float(sim)
    if not row.get("run_dir"):
        return None
    try:
        pace = json.loads((out / str(row["run_dir"]) / "pace.json").read_text(encoding="utf-8"))
        return float(pace["t_end"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _rows_of(grid_dir: Path) -> list[dict[str, Any]]:
    grade = read_grade(grid_dir)
    if grade is None:
        raise ValueError(f"no grade.json in {grid_dir}")
    return list(grade["runs"])


def read_verdicts(out: Path, scenario: str, manifest: Path | None) -> dict[str, Any]:
    """A grade's runs and verdicts from its ``grade.json`` (a class: each student's, ``<out>/<name>/grade.json``):
    run key (``job``; a class: ``student/job``) -> passed, what happened beyond one attempt, the simulated seconds;
    and the grade's sums: its runs' simulated seconds (max, the floor of a grade of every cell at once at 1x; median)
    and, for a class, each student's verdict (every run passed)."""
    if scenario == "class" and manifest is not None:
        names = [line.split(":", 1)[0].strip() for line in manifest.read_text(encoding="utf-8").splitlines()
                 if line.strip()]
        grids = {name: (out / name, _rows_of(out / name)) for name in names}
    else:
        grids = {"": (out, _rows_of(out))}
    verdicts, factors, sims, at_1x_count = {}, [], [], 0
    for name, (where, rows) in grids.items():
        for row in rows:
            key = f"{name}/{row['job']}" if name else row["job"]
            sim = sim_seconds(row, where)
            verdicts[key] = {"passed": bool(row["passed"]), "decision": decision(row), "outcome": row.get("outcome"),
                             "wall_s": row.get("wall_time"), "rtf": row.get("rtf"), "sim_s": sim}
            at_1x_count += at_1x(row)
            sims += [sim] if sim is not None else []
            if isinstance(row.get("rtf"), int | float):
                factors.append(float(row["rtf"]))
    passed = sum(1 for v in verdicts.values() if v["passed"])
    result = {"runs": len(verdicts), "passed": passed, "failed": len(verdicts) - passed,
              "not_graded": sum(1 for v in verdicts.values() if v["decision"] == "not graded"),
              "decisions": _count(v["decision"] for v in verdicts.values() if v["decision"]),
              "runs_at_1x": at_1x_count, "rtf_median": round(median(factors), 2) if factors else None,
              "sim_s_max": round(max(sims), 1) if sims else None,
              "sim_s_median": round(median(sims), 1) if sims else None, "verdicts": verdicts}
    if scenario == "class":
        result["student_verdicts"] = {name: all(v["passed"] for k, v in verdicts.items() if k.startswith(f"{name}/"))
                                      for name in grids}
        result["students_passed"] = sum(result["student_verdicts"].values())
        result["students"] = len(grids)
    return result


def _count(values: Any) -> dict[str, int]:
    counts: dict[str, int] = {}
    for value in values:
        counts[value] = counts.get(value, 0) + 1
    return counts


def compare(before: dict[str, Any], after: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Of the runs whose key starts with ``prefix`` (a class's wrong ones): those both sides graded whose verdict
    (passed) differs; those only one side has, apart (each side grades its own default grid, which may have gained
    a cell); the runs whose re-run decision differs, apart (informative: a paced grade re-runs a wall-clock node at
    1x, today's default runs it at 1x from the start)."""
    one = {k: v for k, v in (before.get("verdicts") or {}).items() if k.startswith(prefix)}
    two = {k: v for k, v in (after.get("verdicts") or {}).items() if k.startswith(prefix)}
    both = sorted(set(one) & set(two))
    differ = [{"run": key, "before": one[key]["passed"], "after": two[key]["passed"]} for key in both
              if one[key]["passed"] != two[key]["passed"]]
    decided = [{"run": key, "before": one[key]["decision"], "after": two[key]["decision"]}
               for key in both if one[key]["decision"] != two[key]["decision"]]
    measured = bool(both) and "error" not in before and "error" not in after
    return {"identical": measured and not differ, "measured": measured, "differences": differ,
            "decisions_differ": decided, "only_before": sorted(set(one) - set(two)),
            "only_after": sorted(set(two) - set(one))}


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
        with sigterm_as_interrupt(), sides(work, quick) as (before, after):
            result["sides"] = {side.name: side.describe() for side in (before, after)}
            result["grid_runs"] = {side.name: side.runs for side in (before, after)}
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
                result["scenarios"][scenario] = paired(repeats, WRONG if scenario == "class" else "")
    finally:
        shutil.rmtree(work, ignore_errors=True)  # the manifest, and the grades unless --out keeps them
    return result


def paired(repeats: list[dict[str, dict[str, Any]]], prefix: str = "") -> dict[str, Any]:
    """A scenario's result from its alternating pairs: ``before`` and ``after``, each side's grade of median wall
    time (the table's rows); ``before_median_s``/``after_median_s``, the median wall over the pairs (only when every
    grade of the side ended by itself with a grade: one stopped or unread grade leaves it unmeasured);
    ``after_over_before``, their ratio; ``comparison``, every pair's verdicts compared (one differing run in any pair
    is a difference), and with ``prefix`` ``focus``, those of the runs whose key starts with it (a class's wrong
    ones); ``pairs``, each pair's walls; ``repeats``, every grade."""
    def middle(name: str) -> dict[str, Any]:
        timed = sorted((g for g in (r[name] for r in repeats) if g.get("wall_s")), key=lambda g: g["wall_s"])
        return timed[(len(timed) - 1) // 2] if timed else repeats[0][name]

    out: dict[str, Any] = {"before": middle("before"), "after": middle("after"),
                           "comparison": _merged([compare(r["before"], r["after"]) for r in repeats]),
                           "pairs": [{"before_s": r["before"].get("wall_s"), "after_s": r["after"].get("wall_s")}
                                     for r in repeats], "repeats": repeats}
    if prefix:
        out["focus"] = {"prefix": prefix, **_merged([compare(r["before"], r["after"], prefix) for r in repeats])}
    for name in ("before", "after"):
        walls = [g["wall_s"] for g in (r[name] for r in repeats) if g.get("wall_s") and "error" not in g]
        if walls and len(walls) == len(repeats):
            out[f"{name}_median_s"] = round(median(walls), 1)
    if out.get("before_median_s") and out.get("after_median_s"):
        out["after_over_before"] = round(out["after_median_s"] / out["before_median_s"], 3)
    return out


def _merged(compared: list[dict[str, Any]]) -> dict[str, Any]:
    """Several pairs' comparisons (:func:`compare`) as one: identical only if every pair's is."""
    return {"identical": all(c["identical"] for c in compared), "measured": all(c["measured"] for c in compared),
            "differences": [d for c in compared for d in c["differences"]],
            "decisions_differ": [d for c in compared for d in c["decisions_differ"]],
            "only_before": sorted({k for c in compared for k in c.get("only_before", ())}),
            "only_after": sorted({k for c in compared for k in c.get("only_after", ())})}


def _line(grade: dict[str, Any]) -> str:
    if "error" in grade and not grade.get("runs"):
        return f"ERROR: {grade['error'][:300]}"
    return (f"{grade['wall_s']} s wall, {grade.get('passed')}/{grade.get('runs')} passed, "
            f"{grade.get('wall_s_per_run')} s per run, sim s max {grade.get('sim_s_max')} median "
            f"{grade.get('sim_s_median')}, load {grade['load_before'][:1]} -> {grade['load_after'][:1]}")


def _graded(pair: dict[str, Any], name: str) -> dict[str, Any] | None:
    """The side's table grade of a scenario when it ended by itself with a grade (no ``error``), else None."""
    grade = pair.get(name) or {}
    return grade if grade.get("verdicts") and "error" not in grade else None


def right_passing(grade: dict[str, Any] | None) -> tuple[int, int] | None:
    """A class grade's right hand-ins (:data:`RIGHT`) that passed every run, and how many there are."""
    if grade is None:
        return None
    right = {k: v for k, v in (grade.get("student_verdicts") or {}).items() if k.startswith(RIGHT)}
    return sum(right.values()), len(right)


def wrong_differences(klass: dict[str, Any]) -> int | None:
    """How the class's wrong hand-ins' verdicts differ after vs before: their runs both sides graded whose verdict
    differs, plus the wrong hand-ins whose own verdict (every run passed) differs; None when not measured."""
    focus = klass.get("focus") or {}
    before, after = _graded(klass, "before"), _graded(klass, "after")
    if not focus.get("measured") or before is None or after is None:
        return None
    one, two = before.get("student_verdicts") or {}, after.get("student_verdicts") or {}
    return len(focus["differences"]) + sum(1 for name in one if name.startswith(WRONG) and one[name] != two.get(name))


def targets(result: dict[str, Any]) -> list[Target]:
    """Issue 52's "Done when": the right node's default grade (every cell at 1x, at once) <= :data:`CORRECT_WALL_S`
    wall (the median of the pairs); the class no slower than the paced default before, its wrong ones' verdicts
    the same, every right one passing; the wall-clock node (right on a robot at 1x) passing every run. Information,
    not targets (:func:`markdown`): the right node's after / before and its runs' simulated seconds."""
    scenarios = result.get("scenarios") or {}
    correct, klass, wall = (scenarios.get(name) or {} for name in ("correct", "class", "wallclock"))
    runs = (result.get("grid_runs") or {}).get("after")
    correct_s = correct.get("after_median_s")
    if runs is not None and any(r["after"].get("runs") != runs for r in correct.get("repeats") or []):
        correct_s = None  # a grade of other runs than the side's default grid is no measurement of it
    wrong_differ = wrong_differences(klass) if klass else None
    right = right_passing(_graded(klass, "after")) if klass else None
    graded_wall = _graded(wall, "after") if wall else None
    wall_failed = None if graded_wall is None else int(runs or graded_wall["runs"]) - int(graded_wall["passed"])
    pairs = len(correct.get("pairs") or [])
    return [
        Target("gradespeed_correct_s", "gradespeed", f"right C node's default grade after ({runs} runs at 1x, all at "
               f"once): wall s, median of {pairs} pairs", f"<= {CORRECT_WALL_S:g} s", correct_s, "s",
               at_most(correct_s, CORRECT_WALL_S)),
        Target("gradespeed_class_ratio", "gradespeed", f"class of {len(result.get('class') or CLASS)}: wall after / "
               f"before ({BEFORE}, paced default)", "<= 1x", klass.get("after_over_before"), "x",
               at_most(klass.get("after_over_before"), 1.0)),
        Target("gradespeed_class_wrong_verdicts", "gradespeed", "class's wrong hand-ins: verdicts differing after vs "
               "before (runs both graded, hand-ins)", "0", wrong_differ, "verdicts", at_most(wrong_differ, 0)),
        Target("gradespeed_class_right_passing", "gradespeed", "class's right hand-ins passing every run after",
               f"all {right[1] if right else '-'}", right[0] if right else None, "hand-ins",
               None if right is None else right[0] == right[1] > 0),
        Target("gradespeed_wallclock_failed", "gradespeed", f"wall-clock C node's default grade after: runs not "
               f"passed (of {runs})", "0", wall_failed, "runs", at_most(wall_failed, 0)),
    ]


def _row(scenario: str, name: str, g: dict[str, Any]) -> str:
    """One table row: a side's grade of a scenario."""
    decided = ", ".join(f"{k} {v}" for k, v in (g.get("decisions") or {}).items()) or "-"
    share = round(g["sim_s_max"] / g["wall_s"], 2) if g.get("sim_s_max") and g.get("wall_s") else None
    cells = [scenario, f"{name} `{g.get('commit', '?')}`", g.get("wall_s"), g.get("runs"), g.get("wall_s_per_run"),
             g.get("passed"), g.get("failed"), decided, g.get("runs_at_1x"),
             f"{g.get('sim_s_max', '-')} / {g.get('sim_s_median', '-')}", share, g.get("rtf_median"), g.get("cpu_s"),
             f"{(g.get('load_before') or ['?'])[0]} -> {(g.get('load_after') or ['?'])[0]}", g.get("returncode")]
    return "| " + " | ".join("-" if c is None else str(c) for c in cells) + " |"


def _verdicts_said(c: dict[str, Any]) -> str:
    """A comparison (:func:`compare`) in words."""
    if not c.get("measured"):
        return "not compared (a side has no grade)"
    if c["identical"]:
        return "identical"
    return "DIFFER: " + "; ".join(f"{d['run']} {d['before']} -> {d['after']}" for d in c["differences"][:10])


def _scenario_notes(scenario: str, pair: dict[str, Any]) -> list[str]:
    """What the table's rows do not say of one scenario: the medians, the simulated time, the verdicts."""
    walls = "; ".join(f"{p['before_s']} -> {p['after_s']} s" for p in pair.get("pairs") or [])
    ratio = pair.get("after_over_before")
    after = pair.get("after") or {}
    line = (f"- {scenario}: wall before {pair.get('before_median_s', '-')} s, after {pair.get('after_median_s', '-')}"
            f" s, after / before {ratio if ratio is not None else '-'}"
            + (f" (medians of {len(pair['pairs'])} alternating pairs: {walls})" if len(pair.get("pairs") or []) > 1
               else ""))
    if after.get("sim_s_max") and after.get("wall_s"):
        line += (f"; simulated: the after grade's longest run {after['sim_s_max']} sim s (median "
                 f"{after['sim_s_median']}), {100 * after['sim_s_max'] / after['wall_s']:.0f} % of its "
                 f"{after['wall_s']} s wall")
    line += f"; every run both graded: verdict {_verdicts_said(pair['comparison'])}"
    only = {k: len(pair["comparison"].get(f"only_{k}") or ()) for k in ("before", "after")}
    if any(only.values()):
        line += f" (runs only before: {only['before']}, only after: {only['after']})"
    if pair["comparison"]["decisions_differ"]:
        line += f"; beyond one attempt differs in {len(pair['comparison']['decisions_differ'])} runs"
    lines = [line]
    if "focus" in pair:
        right = right_passing(_graded(pair, "after"))
        failing = [k for k, v in (after.get("student_verdicts") or {}).items() if k.startswith(RIGHT) and not v]
        lines.append(f"  - the wrong hand-ins' run verdicts: {_verdicts_said(pair['focus'])}; right hand-ins passing "
                     f"after: {f'{right[0]}/{right[1]}' if right else '-'}"
                     + (f" (failing: {', '.join(failing)})" if failing else ""))
    return lines


def markdown(result: dict[str, Any]) -> list[str]:
    """The section's lines: a row per scenario and side, then per scenario the medians, the simulated time and the
    verdicts compared."""
    head = ["scenario", "side", "wall s", "runs", "wall s / run", "passed", "failed", "beyond one attempt",
            "runs at 1x", "sim s max / median", "max sim / wall", "median factor achieved", "CPU s",
            "load before -> after", "exit"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    notes = []
    for scenario, pair in (result.get("scenarios") or {}).items():
        for name in ("before", "after"):
            g = pair.get(name) or {}
            lines.append(_row(scenario, name, g))
            if "error" in g:
                notes.append(f"- {scenario} {name}: {g['error'][:400]}")
            odd = (g.get("processes") or {}).get("not_the_side")
            if odd:
                notes.append(f"- {scenario} {name}: Python processes not on the side's code: {'; '.join(odd[:5])}")
            per_node = (result.get("grid_runs") or {}).get(name)
            if g.get("runs") is not None and per_node and g["runs"] != per_node * int(g.get("students") or 1):
                notes.append(f"- {scenario} {name}: {g['runs']} runs, not its default grid's {per_node} a node")
        notes += _scenario_notes(scenario, pair)
    grid = " ".join(result.get("grid") or [])
    counted = ", ".join(f"{k} {v}" for k, v in (result.get("grid_runs") or {}).items())
    notes.append(f"- grid: `{grid}`, each side's defaults otherwise (runs a node: {counted or '-'}); node "
                 f"`{result.get('node')}`")
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
