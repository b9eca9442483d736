"""Running an ``--exe`` grid: every :class:`bt_nav.grading.grid.Job` through
:func:`bt_nav.grading.exe.run.run_exe_job`, here or on a Dask cluster, resumable, with the checks that refuse
a grid before any run starts.

Where runs go (:data:`Workers`, :func:`run_pool`, the one place that starts runs for a grid, a class and their
re-runs alike): ``workers`` threads of this process (each thread only supervises its run's three process
groups: no py_trees in-process, so threads are enough), or a :class:`Cluster`: one Dask task per run on the
cluster's workers, through one connection per grade, made before any run (an unreachable scheduler refuses the
grade; it never falls back to this machine). A worker claims the domains of its runs itself (per machine,
:mod:`bt_nav.ros.supervise`: two workers on one machine never share one), and writes each run's directory under
the grid's ``out``, which must therefore be a path every worker sees (a shared filesystem) and is made absolute
before the tasks leave. A worker that dies loses its running runs, which the scheduler reruns elsewhere (in a run
directory ``NAME-2``); rows are collected per task, so each run is counted once. A worker thread per run:
``dask worker --nthreads N`` runs N at a time.

Stops: this process's :class:`~bt_nav.ros.supervise.StopRequest` stops local runs directly; on a cluster it
sets a Dask :class:`distributed.Event` of the grade that every running task polls (:class:`ClusterStop`), and
tasks not yet started return without starting anything. A stopped run's row has outcome ``stopped``.

Resume: the grid's directory holds ``grid.json`` (what every run shares) and each run's ``result.json``;
:func:`prepare_out` refuses a directory that already holds a grade unless resuming, refuses to resume a
grade of another command or other settings, and returns the finished runs (those with a verdict or a real
failure; not those stopped or lost), which are kept instead of run again.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import signal
import sys
import time
import zlib
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import asdict
from pathlib import Path
from typing import Any

from bt_nav.grading.admission import Admission, describe
from bt_nav.grading.exe.pace import REAL_TIME, check_speed, rtf_cap, with_speed
from bt_nav.grading.exe.run import ERROR, ExeSettings, run_exe_job
from bt_nav.grading.grid import Job, progress_bar
from bt_nav.mission.maneuver_spec import choice_pattern
from bt_nav.ros import forkserver
from bt_nav.ros.supervise import StopRequest

#: The grid's own file in its directory: the settings every run shares, and the jobs.
GRID_FILE = "grid.json"
#: The outcome of a run cut short by a stop: no result; left out of the report, run again by a resume.
STOPPED = "stopped"
#: The settings a resumed grade must share with the grade it continues.
SHARED = ("command", "cwd", "profile", "limit", "rtf", "maneuvers", "jitter", "node_params", "rtf_max")
#: What a grade written before a setting existed had instead (the setting's default then).
SHARED_BEFORE = {"rtf_max": 0.0}
#: Wall seconds a stopped cluster grid waits for its running tasks to report their stopped runs.
CLUSTER_STOP_WAIT = 30.0

Row = dict[str, Any]


def finished(row: Row) -> bool:
    """Whether a row is a result of the node (a verdict or a real failure of the node), not a run cut short or
    one bt_nav failed to run: what a resume keeps."""
    return row.get("outcome") not in (STOPPED, ERROR)


# ---------------------------------------------------------------------------------------------- up-front checks
def resolve_program(command: str) -> str:
    """``command`` with its program as the absolute path that will run.

    A bare name is looked up on ``PATH``, then next to this Python (``.venv/bin/bt-nav grade --exe
    "bt-nav executive"`` works without an activated venv); a path is taken relative to the current directory.

    Raises:
        ValueError: an empty or badly quoted command, or a program that is not there or not executable: the
            grid is refused before any run, instead of every run failing alike.
    """
    try:
        argv = shlex.split(command)
    except ValueError as exc:
        raise ValueError(f"--exe {command!r}: {exc}") from None
    if not argv:
        raise ValueError("--exe: an empty command")
    program = argv[0]
    if "/" in program:
        path = Path(program).expanduser().absolute()
        if not path.is_file():
            raise ValueError(f"--exe: program {program!r} not found")
        if not os.access(path, os.X_OK):
            raise ValueError(f"--exe: program {program!r} is not executable")
        found = str(path)
    else:
        here = Path(sys.executable).parent
        found = shutil.which(program) or shutil.which(program, path=str(here)) or ""
        if not found:
            raise ValueError(f"--exe: program {program!r} not found on PATH nor in {here}")
        found = str(Path(found).absolute())
    _check_interpreter(found)
    return shlex.join([found, *argv[1:]])


def _check_interpreter(program: str) -> None:
    """A ``python...`` program must import rclpy: a system Python without ROS 2 fails every run alike (the node
    exits at once with ``No module named 'rclpy'``), so the grid is refused before it starts, naming the fix."""
    import subprocess

    if not Path(program).name.startswith("python"):
        return
    try:
        subprocess.run([program, "-c", "import rclpy"], check=True, capture_output=True, timeout=60)
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired, OSError):
        ours = Path(sys.executable)
        raise ValueError(f"--exe: {program} cannot import rclpy (no ROS 2 for that Python): run the node with "
                         f"{ours.parent / 'python'} (this venv's, which has it), or source a ROS 2 install "
                         "first") from None


def exe_settings(args: Any, maneuvers: bool, command: str | None = None) -> ExeSettings:
    """A grid's :class:`ExeSettings` from ``bt-nav grade``'s options: the program resolved (``command``: resolved
    already, a class's student), the command run in this directory, ``--out`` absolute for a cluster (its workers
    may start elsewhere; both must be on a filesystem they share)."""
    from bt_nav.mission.params import parse_assignments
    from bt_nav.run.settings import DEFAULT_JITTER

    if args.resume and not args.out:
        raise ValueError("--resume with --exe needs --out DIR (the grade to continue)")
    out = Path(args.out or f"runs/grade-exe-{time.strftime('%Y%m%d-%H%M%S')}")
    node_params = tuple(parse_assignments(args.node_param).items())
    return ExeSettings(command or resolve_program(args.exe), args.profile, out.absolute() if args.scheduler else out,
                       args.timeout, args.rtf, maneuvers, None if args.no_jitter else DEFAULT_JITTER, args.record,
                       args.videos, os.getcwd(), node_params, args.realtime_check == "on",
                       rtf_cap(args.rtf, args.rtf_max), strict_findings=strict_option(args))


def strict_option(args: Any) -> str:
    """``--strict-findings`` checked before any run (an unknown kind is refused): the check-off's finding kinds that
    fail instead (:mod:`bt_nav.judge.findings`; the lab's judge parameter ``strict_findings``)."""
    from bt_nav.judge.findings import strict_kinds

    text = str(getattr(args, "strict_findings", "") or "")
    strict_kinds(text)
    return text


def check_node_options(args: Any) -> None:
    """Refuse the ``bt-nav grade`` options a grade cannot honour with ``--class``, ``--exe`` or ``--scheduler``
    (an option is refused, never silently ignored), and a speed no run can keep
    (:func:`bt_nav.grading.exe.pace.check_speed`; ``--rtf-max`` without them). ``args.jobs`` is None unless
    ``--jobs`` was given.

    Raises:
        ValueError: naming the option and what to do instead.
    """
    mode = "--class" if args.klass is not None else "--exe" if args.exe is not None else None
    if mode:
        check_speed(args.rtf, args.rtf_max)
    elif args.rtf_max is not None:
        raise ValueError("--rtf-max caps the speed of --exe and --class runs; lock-step runs as fast as it can")
    if args.scheduler and args.jobs is not None:
        raise ValueError("--jobs counts the runs at once on this machine; with --scheduler the cluster's workers run "
                         "them (each dask worker's --nthreads sets how many at once there): leave --jobs out")
    if mode and args.overrides:
        raise ValueError(f"--set sets the parameters of bt_nav's own tree in lock-step; {mode} grades a node of its "
                         "own: give it parameters with --node-param NAME=VALUE")
    if mode and args.kinematics:
        raise ValueError(f"--kinematics sets the lock-step robot; {mode} runs the profile's simulated robot "
                         "(--sim-param sets the simulator)")
    if mode == "--class" and args.json:
        raise ValueError("--json is one grid's results file; a class writes class.json (and each student's "
                         "grade.json) in --out")
    if mode == "--class" and args.progress == "on":
        raise ValueError("--class prints a line per run, no progress bar: leave --progress out")


def _grid_doc(settings: ExeSettings, jobs: Sequence[Job]) -> dict[str, Any]:
    shared = {name: getattr(settings, name) for name in SHARED}
    shared["jitter"] = list(settings.jitter) if settings.jitter else None
    shared["node_params"] = [list(pair) for pair in settings.node_params]
    return {**shared, "jobs": [job.key for job in jobs]}


#: Python options that take the next word as their value (``python3 -X dev node.py``: the file is node.py).
_VALUED_OPTIONS = ("-W", "-X")


def choice_line() -> re.Pattern[str]:
    """The lab template's declaration of the student's maneuver (``# CHOICE: B``), any letter of the maneuver spec."""
    return re.compile(rf"^\s*#\s*CHOICE\s*:\s*({choice_pattern()})\b", re.MULTILINE)


def node_file(command: str) -> Path | None:
    """The Python file ``command`` runs, as written (relative to where it runs): a ``python...`` program's script
    (its first argument that is not an option; none with ``-m`` or ``-c``), else the first word ending in ``.py``
    (``./node.py``). None when it runs no file of its own (``ros2 run pkg node``) or cannot be split."""
    try:
        words = shlex.split(command)
    except ValueError:
        return None
    if words and Path(words[0]).name.startswith("python"):
        skip = False
        for word in words[1:]:
            if skip:
                skip = False
            elif word in ("-m", "-c"):
                return None
            elif word in _VALUED_OPTIONS:
                skip = True
            elif not word.startswith("-"):
                return Path(word)
        return None
    return next((Path(word) for word in words if word.endswith(".py")), None)


def declared_choice(command: str) -> str | None:
    """The lab choice (a maneuver letter) a ``# CHOICE: X`` comment declares in the Python file ``command`` runs
    (:func:`node_file`; the lab's template asks for it), else None."""
    path = node_file(command)
    if path is None or not path.is_file():
        return None
    try:
        found = choice_line().search(path.read_text(errors="replace"))
    except OSError:
        return None
    return found.group(1) if found else None


def prepare_out(settings: ExeSettings, jobs: Sequence[Job], resume: bool) -> dict[str, Row]:
    """Check the grid's directory, write its ``grid.json``; the finished runs to keep (job key -> row).

    Raises:
        ValueError: ``out`` holds something already and ``resume`` is off (a grade is never mixed with
            another); or, resuming, ``out`` holds no grade, or one of another command or other settings.
    """
    out, grid_file = settings.out, settings.out / GRID_FILE
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out} is a file, not a directory")
    held = out.is_dir() and any(out.iterdir())
    done: dict[str, Row] = {}
    if held and not resume:
        what = "a grade" if grid_file.exists() else "files"
        raise ValueError(f"--out {out} holds {what} already: add --resume to continue it, or choose a new "
                         "directory (grades are never mixed)")
    if held:
        try:
            before = json.loads(grid_file.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise ValueError(f"--resume: {out} holds no grade to continue ({GRID_FILE}: {exc})") from None
        now = _grid_doc(settings, jobs)
        had = {name: before.get(name, SHARED_BEFORE.get(name)) for name in SHARED}
        differ = [f"{name} {had[name]!r} there, {now[name]!r} now" for name in SHARED if had[name] != now[name]]
        if differ:
            raise ValueError(f"--resume: the grade in {out} differs: " + "; ".join(differ))
        done = finished_runs(out, jobs)
    out.mkdir(parents=True, exist_ok=True)
    tmp = grid_file.with_name(GRID_FILE + ".tmp")
    tmp.write_text(json.dumps(_grid_doc(settings, jobs), indent=1) + "\n", encoding="utf-8")
    tmp.replace(grid_file)
    return done


def finished_runs(out: Path, jobs: Sequence[Job]) -> dict[str, Row]:
    """The finished runs (:func:`finished`) in ``out``'s run directories that are jobs of this grid, by job key
    (the newest ``result.json`` when a job has several)."""
    wanted = {job.key for job in jobs}
    found: dict[str, tuple[float, Row]] = {}
    for path in out.glob("*/result.json"):
        try:
            row = json.loads(path.read_text(encoding="utf-8"))
            stamp = path.stat().st_mtime
        except (OSError, json.JSONDecodeError):
            continue  # a run killed mid-write: run it again
        key = row.get("job") if isinstance(row, dict) else None
        if key in wanted and finished(row) and stamp >= found.get(key, (-1.0, {}))[0]:
            found[key] = (stamp, with_parameters(row))
    return {key: row for key, (_, row) in found.items()}


# ---------------------------------------------------------------------------------------------- parameters
def with_parameters(row: Row) -> Row:
    """``row`` with ``parameters``: the node's parameters as ``ros2 param list`` shows them (the judge's audit asked
    the node, and read their values back), and for each one the run passed (``-p NAME:=VALUE``: ``--node-param`` and
    the cell's own) whether it was applied: the value read back equals the one passed. The check-off's step
    "ros2 param list to ensure the parameters are applied to your node", as a grade can take it."""
    listed = (row.get("verdict") or {}).get("parameters")
    if listed is None:
        return row
    applied = {}
    for name, value in (row.get("node_params") or {}).items():
        read = [node["values"][name] for node in listed if name in node.get("values", {})]
        declared = any(name in node.get("names", ()) for node in listed)
        applied[name] = {"given": value, "read": read[0] if read else None, "declared": declared,
                         "applied": any(_same_value(r, value) for r in read)}
    row["parameters"] = {"nodes": listed, "given": applied}
    return row


def _same_value(read: Any, given: Any) -> bool:
    """Whether a value read back is the one given (numbers by value: 0.7 given, 0.7 read as a double)."""
    if isinstance(read, bool) or isinstance(given, bool):
        return read is given
    if isinstance(read, int | float) and isinstance(given, int | float):
        return abs(float(read) - float(given)) <= 1e-9 * max(1.0, abs(float(given)))
    return str(read) == str(given)


def parameters_lines(row: Row) -> list[str]:
    """The run's parameters in words: the nodes' lists (``ros2 param list``) and each passed one, applied or not."""
    info = row.get("parameters")
    if not info:
        return []
    lines = [f"ros2 param list {node['node']}: {', '.join(node['names']) or '(none)'}" for node in info["nodes"]]
    for name, p in info["given"].items():
        if p["applied"]:
            lines.append(f"{name}: passed {p['given']}, read back {p['read']} (applied)")
        elif not p["declared"]:
            lines.append(f"{name}: passed {p['given']}, but the node does not declare it (not applied)")
        else:
            lines.append(f"{name}: passed {p['given']}, read back {p['read']} (NOT applied)")
    return lines


# ---------------------------------------------------------------------------------------------- running
def error_row(job: Job, error: str, traceback_file: str = "", attempts: int = 1) -> Row:
    """The row of a run that raised inside bt_nav (not the node's fault): not graded (``not_graded``, as every run
    left without a verdict by bt_nav's own fault: an autograder error, never a 0), not failed either (its outcome is
    :data:`ERROR`, counted apart), never lost, rerun on resume. ``error``: one line; the traceback is in
    ``traceback_file`` (the grid's ``bt_nav_errors/``), never on the terminal."""
    tried = f"tried {attempts} times, " if attempts > 1 else ""
    said = f"not graded: bt_nav error (not the node's): {error} ({tried}traceback in bt_nav_errors/): --resume runs " \
           "it again"
    return {"passed": False, "outcome": ERROR, "reason": f"bt_nav error (not the node's): {error}", "verdict": None,
            "not_graded": said, "job": job.key, "world": job.world, "maneuver": job.maneuver, "lidar": job.lidar,
            "seed": job.seed, "profile": job.profile, "run_dir": "", "wall_time": 0.0, "traceback": traceback_file}


#: How often a run that raised inside bt_nav is tried in all (a passing fault, e.g. a file raced for, goes away; one
#: that raises twice is a bug, which a third try would only repeat).
ATTEMPTS = 2
#: How many times a run is run again after an attempt that ended without a verdict for a cause of bt_nav's own
#: (:data:`bt_nav.grading.exe.run.OWN_FAULT`: its fork server gone, its simulator killed by a sibling's signal):
#: those pass, and the cell is graded on the next attempt; after the last, it is not graded.
RERUNS = 2


def run_unless_stopped(job: Job, settings: ExeSettings, stop: StopRequest | None,
                       on_verdict: Callable[[], None] | None = None) -> Row | None:
    """:func:`run_exe_job`, or None without starting anything when the grid is stopping already (here and on a
    cluster alike; ``on_verdict``: :func:`run_exe_job`'s).

    bt_nav's own failures never decide a grade (issue 52). A run that raises inside bt_nav keeps its traceback in
    the grid's ``bt_nav_errors/`` (never on the terminal) and is tried again (:data:`ATTEMPTS` in all); an attempt
    that ends without a verdict for a cause of bt_nav's own (:data:`~bt_nav.grading.exe.run.OWN_FAULT`) is set aside
    and run again, up to :data:`RERUNS` times. Each such attempt is one note of the row's (one line on the terminal);
    a run left without a verdict after them is not graded (:func:`error_row`,
    :func:`~bt_nav.grading.exe.run.own_fault_not_graded`), never failed."""
    from bt_nav.grading.exe.run import OWN_FAULT, own_fault_not_graded, set_aside_own_fault, with_notes

    notes: list[str] = []
    error, where, raised = "", "", 0
    for attempt in range(1, RERUNS + 2):
        if stop is not None and stop.requested:
            return None
        try:
            row = with_parameters(_with_speed(run_exe_job(job, settings, stop, on_verdict=on_verdict), settings))
        except Exception as exc:  # one broken run must not sink the grid
            error, where, raised = _one_line(exc), str(_keep_traceback(job, settings, attempt)), raised + 1
            if raised >= ATTEMPTS:
                return error_row(job, error, where, attempt)
            notes.append(f"bt_nav error (not the node's): {error} (traceback in {where}): the run started again")
            continue
        if not row.get(OWN_FAULT) or row.get("outcome") == STOPPED:
            return with_notes(row, notes)
        if attempt > RERUNS:
            return own_fault_not_graded(with_notes(row, notes), attempt)
        notes.append(set_aside_own_fault(row))
    return error_row(job, error, where, RERUNS + 1)  # not reached: the last attempt returns


def _one_line(exc: BaseException) -> str:
    """An exception in one line for a row's reason (its traceback goes to a file)."""
    text = " ".join(repr(exc).split())
    return text if len(text) <= 300 else text[:297] + "..."


def _with_speed(row: Row, settings: ExeSettings) -> Row:
    """``row`` with the speed its run achieved (:func:`bt_nav.grading.exe.pace.with_speed`), also in its
    ``result.json`` (a resumed grade reads it there)."""
    with_speed(row, settings.rtf)
    result = Path(row.get("run_dir") or "") / "result.json"
    if row.get("run_dir") and result.is_file():
        result.write_text(json.dumps(row, indent=1) + "\n", encoding="utf-8")
    return row


def _keep_traceback(job: Job, settings: ExeSettings, attempt: int) -> Path:
    """The exception being handled, with its traceback, in ``<out>/bt_nav_errors/`` (one file per attempt)."""
    import traceback

    folder = Path(settings.out) / "bt_nav_errors"
    folder.mkdir(parents=True, exist_ok=True)
    lidar = f"_{job.lidar}" if job.lidar else ""
    path = folder / f"{job.world}_{job.maneuver}{lidar}_seed{job.seed}_attempt{attempt}.txt"
    path.write_text(f"job {job.key}\n{traceback.format_exc()}", encoding="utf-8")
    return path


def run_pool(tasks: Sequence[tuple[Job, ExeSettings]], workers: Workers,
             stop: StopRequest | None, admission: Admission | None = None) -> Iterator[tuple[int, Row | None]]:
    """Every (job, its grid's settings), ``workers`` at a time in threads (``--jobs auto``: as many as
    :class:`~bt_nav.grading.admission.Admission` lets start, or ``admission`` when given; one grid's, or a whole
    class's), or each a task on a :class:`Cluster` given as ``workers``; yields (the task's index, its row) as each
    ends, None for a run that never started. A stop cancels the runs not started."""
    if not tasks:  # nothing to run: no fork server to start
        return
    if isinstance(workers, Cluster):
        yield from workers.run(tasks, stop)
        return
    admission = admission or Admission.for_jobs(workers, real_time=all(s.rtf == REAL_TIME for _, s in tasks))
    # With an admission a run's place is free at its verdict, while its thread still stops its processes.
    threads = 2 * admission.limit if admission is not None else max(1, workers)
    with forkserver.serving(forkserver.wanted()), \
            ThreadPoolExecutor(max_workers=threads, thread_name_prefix="exe-run") as pool:
        index: dict[Future, int] = {pool.submit(_admitted, admission, job, settings, stop): i
                                    for i, (job, settings) in enumerate(tasks)}
        pending = set(index)
        while pending:
            done, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in done:
                yield index[future], None if future.cancelled() else future.result()
            if stop is not None and stop.requested:
                for future in pending:
                    future.cancel()


def _admitted(admission: Admission | None, job: Job, settings: ExeSettings, stop: StopRequest | None) -> Row | None:
    """One cell graded (:func:`bt_nav.grading.exe.realtime.graded_run`: a preview's failure again at 1x, a 1x run
    that fell behind once more), each attempt once ``admission`` lets it start (``--jobs auto``); None if stopped
    first. A place is given back at the attempt's verdict (a retry after that runs on its old place's account)."""
    from bt_nav.grading.exe.realtime import graded_run

    return graded_run(lambda own: _attempt(admission, job, own, stop), settings,
                      admission.fell_behind if admission is not None else None)


def _attempt(admission: Admission | None, job: Job, settings: ExeSettings, stop: StopRequest | None) -> Row | None:
    """:func:`run_unless_stopped` once ``admission`` lets the run start; None if stopped first."""
    if admission is None:
        return run_unless_stopped(job, settings, stop)
    if not admission.enter(stop):
        return None
    held = [True]

    def release() -> None:
        if held[0]:
            held[0] = False
            admission.leave()

    try:
        return run_unless_stopped(job, settings, stop, on_verdict=release)
    finally:
        release()


class ClusterStop(StopRequest):
    """A stop request read on a Dask worker from the grade's :class:`distributed.Event` (at most once per
    ``poll`` s: each read is a round trip to the scheduler). Installs no signal handler."""

    def __init__(self, event: str, poll: float = 1.0) -> None:
        super().__init__()
        self.event = event
        self.poll = poll
        self._checked = float("-inf")

    @property
    def requested(self) -> bool:  # noqa: D102 - StopRequest's
        if self.signum is None and time.monotonic() - self._checked >= self.poll:
            self._checked = time.monotonic()
            try:
                from distributed import Event

                if Event(self.event).is_set():
                    self.signum = int(signal.SIGTERM)
            except Exception:  # the scheduler unreachable: keep running, the run has its own limit
                pass
        return self.signum is not None

    @property
    def name(self) -> str:  # noqa: D102 - StopRequest's
        return "the stop of bt-nav grade" if self.signum is not None else ""


def run_cluster_task(job: Job, settings: ExeSettings, event: str) -> Row | None:
    """What a Dask worker runs for one job: the cell graded (:func:`_admitted`) with the grade's
    :class:`ClusterStop`."""
    return _admitted(None, job, settings, ClusterStop(event))


def grid_token(settings: ExeSettings) -> str:
    """A short name of the grid (its directory and command): two grids on one cluster, or a grid and its re-runs
    (another directory), never share a task key."""
    return f"{zlib.crc32(json.dumps(asdict(settings), default=str, sort_keys=True).encode()):08x}"


#: Wall seconds a grade waits to reach its Dask scheduler before it refuses to start.
CONNECT_TIMEOUT = 20.0


class Cluster:
    """Where a grade's runs go instead of this machine's threads: the Dask cluster of a scheduler, one connection
    for the whole grade (a grid or a class, their runs and re-runs alike). Pass it where a count of local runs
    goes (:func:`run_pool`'s ``workers``): every run becomes a task (:func:`run_cluster_task`). Open it with
    :meth:`connect`, before any run, so that an unreachable scheduler refuses the grade instead of grading here."""

    def __init__(self, scheduler: str, client: Any, retries: int = 3) -> None:
        from distributed import Event

        self.scheduler, self.client, self.retries = scheduler, client, retries
        self.event = Event(f"bt-nav-exe-stop-{os.getpid()}-{time.time_ns():x}", client=client)
        self.event.clear()

    @classmethod
    def connect(cls, scheduler: str, timeout: float | None = None) -> Cluster:
        """The cluster of ``scheduler`` (``tcp://HOST:PORT`` or a scheduler file ``.json``), connected, waiting up to
        ``timeout`` s (default :data:`CONNECT_TIMEOUT`).

        Raises:
            ValueError: the scheduler file is not there, or the scheduler does not answer within ``timeout`` s:
                the grade is refused (it never falls back to this machine unasked).
        """
        from distributed import Client

        by_file = scheduler.endswith(".json")
        if by_file and not Path(scheduler).is_file():  # Client would wait for it forever
            raise ValueError(f"--scheduler {scheduler}: no such scheduler file (dask scheduler --scheduler-file "
                             "writes it)")
        try:
            client = Client(**({"scheduler_file": scheduler} if by_file else {"address": scheduler}),
                            timeout=f"{timeout or CONNECT_TIMEOUT:g}s", set_as_default=False)
        except (OSError, ValueError, TypeError) as exc:
            raise ValueError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc}); start it with "
                             "'dask scheduler', or leave --scheduler out to grade on this machine") from None
        return cls(scheduler, client)

    def __enter__(self) -> Cluster:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Let go of the scheduler (the cluster keeps running)."""
        self.client.close()

    def describe(self) -> str:
        """For a grade's first line: where its runs go."""
        return f"on {self.scheduler}"

    def run(self, tasks: Sequence[tuple[Job, ExeSettings]],
            stop: StopRequest | None) -> Iterator[tuple[int, Row | None]]:
        """Every (job, its grid's settings) as a task; yields (the task's index, its row) as each ends, each task
        once whichever worker ran it (a task lost with its worker the scheduler runs again elsewhere, in a run
        directory ``NAME-2``; retried ``retries`` times), None for a run that never started. A stop sets the
        grade's event, which every running task polls, and waits up to :data:`CLUSTER_STOP_WAIT` s for their
        stopped rows; what is left then is cancelled."""
        futures = {self.client.submit(run_cluster_task, job, settings, self.event.name, pure=False,
                                      key=f"bt-nav-exe-{grid_token(settings)}-{job.key}",
                                      retries=self.retries): i for i, (job, settings) in enumerate(tasks)}
        pending, deadline = set(futures), None
        while pending:
            ended = [future for future in pending if future.done()]
            for future in ended:
                pending.discard(future)
                yield futures[future], self._row(future, tasks[futures[future]][0])
            if stop is not None and stop.requested and deadline is None:
                self.event.set()
                deadline = time.monotonic() + CLUSTER_STOP_WAIT
            if deadline is not None and time.monotonic() > deadline:
                self.client.cancel(list(pending))
                for future in pending:
                    yield futures[future], None
                return
            if not ended:
                time.sleep(0.2)

    @staticmethod
    def _row(future: Any, job: Job) -> Row | None:
        """An ended task's row: its result; None when cancelled; an :func:`error_row` when its workers kept dying
        (KilledWorker) or it could not be unpickled there."""
        if future.status == "finished":
            return future.result()
        if future.status == "cancelled":
            return None
        return error_row(job, repr(future.exception()))


#: Where a grade's runs go: a count of runs at once on this machine (``--jobs``), or a :class:`Cluster`.
Workers = int | Cluster


def connect_workers(jobs: int, scheduler: str | None) -> Workers:
    """``--jobs`` here, or with ``--scheduler`` its :class:`Cluster`, connected (ValueError: unreachable)."""
    return Cluster.connect(scheduler) if scheduler else jobs


def close_workers(workers: Workers) -> None:
    """Let go of a :class:`Cluster` (nothing to do for local runs)."""
    if isinstance(workers, Cluster):
        workers.close()


def describe_workers(workers: Workers, real_time: bool = False) -> str:
    """Where a grade's runs go, for its first line: ``on tcp://...``, ``2 at a time`` or (1x) ``up to 16 at once``."""
    return workers.describe() if isinstance(workers, Cluster) else describe(workers, real_time)


def run_exe_grid(jobs: Sequence[Job], settings: ExeSettings, workers: Workers = 2, stop: StopRequest | None = None,
                 on_row: Callable[[Row], None] | None = None, *, scheduler: str | None = None,
                 done: dict[str, Row] | None = None, progress: bool = False) -> list[Row]:
    """Every job not in ``done`` (job key -> row), here (``workers`` threads) or on a :class:`Cluster` (``workers``,
    or one connected to ``scheduler`` for this grid alone); ``on_row`` sees each new row as its run ends. Returns
    the rows in the jobs' order: those of ``done``, then what ran (on a stop: stopped runs too, and nothing for the
    runs never started)."""
    if scheduler:
        with Cluster.connect(scheduler) as cluster:
            return run_exe_grid(jobs, settings, cluster, stop, on_row, done=done, progress=progress)
    rows = dict(done or {})
    todo = [job for job in jobs if job.key not in rows]
    passed = sum(1 for row in rows.values() if row["passed"])
    with progress_bar(len(jobs), len(jobs) - len(todo), progress, "run") as bar:
        for _, row in run_pool([(job, settings) for job in todo], workers, stop):
            if row is None:
                continue
            rows[row["job"]] = row
            if on_row is not None:
                on_row(row)
            if row.get("outcome") != STOPPED:
                passed += bool(row["passed"])
                bar.set_postfix_str(f"{passed} passed", refresh=False)
                bar.update(1)
    return [rows[job.key] for job in jobs if job.key in rows]
