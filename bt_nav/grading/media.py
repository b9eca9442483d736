"""The pictures and videos of an ``--exe`` grid's report, drawn from the runs' bags after the grid.

Why after the grid and not at each run's end: drawing is CPU work (a trajectory picture about a second, a video of
a 60 s mission ten or more), and during the grid the cores belong to the runs, whose simulators keep their real-time
factor only while they get their share. Here they take every core (:func:`render_runs`, one process per core):

- each run's **trajectory picture** ``trajectory.png`` in its run directory (:func:`bt_nav.media.plot.plot_run`): the
  world, the path from the bag's ground truth, start and end, and the judge's verdict with its collisions;
- a **video** ``video.mp4`` (:func:`bt_nav.media.video.write_video`) of every failed run (``videos``: ``failures``,
  ``all`` or ``off``);
- the grid's figures next to ``report.html``: the **travelled distance** of every judged run as a histogram with
  the homework's requirement marked (``distance.png``), and for the lab the **check-off turns** judged and within
  their rule per run (``turns.png``).

A run whose files are there already (a report made again, a resumed grid) is not drawn again. With ``record`` set
to ``failures`` the bags of the passed runs are deleted once their pictures exist.

One exception to "after the grid": a :class:`Drawer` draws the pictures of the runs already ended while the others
run, in one worker at the lowest CPU priority (``nice`` 19: it gets what the runs leave idle, the runs keep their
share), so the report waits only for the last runs' pictures and the videos (measured: the report after an 8-run
grid went from ~1.6 s to ~0.6 s).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import queue
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from bt_nav.grading.exe.bag import BAG

PICTURE = "trajectory.png"
VIDEO = "video.mp4"
DISTANCE = "distance.png"
TURNS = "turns.png"
#: Frames per second of the failed runs' videos (``bt-nav video``'s default).
FPS = 10.0
#: The homework check whose ``required`` value is the distance marked on the histogram.
TRAVELLED_CHECK = "minimum travelled distance"
#: What :func:`render_run` is given for one run: its row, whether to film it, whether to keep its bag.
Task = tuple[dict[str, Any], bool, bool]


def wants_video(row: dict[str, Any], videos: str) -> bool:
    """Whether the report films this run: ``all``, or ``failures`` and it did not pass."""
    return videos == "all" or (videos == "failures" and not row.get("passed"))


def run_title(row: dict[str, Any]) -> str:
    """``stage_4, maneuver none, seed 3`` (``..., LiDAR rplidar, seed 3`` when the grid varies it): what a picture of
    the run is titled with."""
    lidar = f"LiDAR {row['lidar']}, " if row.get("lidar") else ""
    return f"{row['world']}, maneuver {row['maneuver']}, {lidar}seed {row['seed']}"


def _results(row: dict[str, Any], record: Any) -> dict[str, Any]:
    """What the picture prints: the judge's verdict, else the bag's own figures (a run without a verdict failed)."""
    if row.get("verdict"):
        return row["verdict"]
    dist = record.truth.distance()
    return {"passed": False, "travelled": float(dist[-1]) if dist.size else 0.0,
            "collisions": len(record.collisions),
            "collision_events": [c for c in record.collisions if "x" in c and "y" in c]}


def _world(row: dict[str, Any], record: Any) -> Any:
    """The run's world: the bag's ``/bt_nav/mission``, else the row's name and seed, else an empty one around the
    path (a world file that moved since the run still gets its picture)."""
    from bt_nav_sim.world import World, load_world

    from bt_nav.media.video import world_of

    world = world_of(record)
    if world is not None:
        return world
    try:
        return load_world(str(row["world"]), seed=int(row["seed"]))
    except (OSError, ValueError, KeyError):
        tr = record.truth
        bounds = (float(tr.x.min()) - 1, float(tr.y.min()) - 1, float(tr.x.max()) + 1,
                  float(tr.y.max()) + 1) if len(tr) else (-5.0, -5.0, 5.0, 5.0)
        return World(name=str(row["world"]), segments=np.zeros((0, 4)), circles=np.zeros((0, 3)),
                     spawn=(0.0, 0.0, 0.0), bounds=bounds)


def _path(record: Any) -> Any:
    """The bag's ground truth as a picture's path: coloured by branch when a bt_nav executive's tree is in the bag,
    else one black line (a foreign node has no branches; the picture's "Stopped" grey would say it never moved)."""
    from bt_nav.media.video import trajectory

    path = trajectory(record)
    if not record.trees:
        path.branch = np.full(len(path), "path", dtype=object)
    return path


def _from_t0(record: Any, row: dict[str, Any]) -> Any:
    """The record a video is made of: its time zero at the judge's t0 (``t0_sim`` of the verdict), so the film
    skips the simulator's idle seconds before the judge started and its clock reads what the judge's report lines
    say (activation at 5 s, ...). Without a verdict, from the bag's first message."""
    t0 = (row.get("verdict") or {}).get("t0_sim")
    if not isinstance(t0, int | float) or not record.start <= t0 < record.end:
        return record
    return dataclasses.replace(record, clock_start=float(t0))


def _draw(row: dict[str, Any], record: Any, run_dir: Path, film: bool) -> dict[str, Any]:
    """The picture of a readable bag, and its video when ``film`` and it holds ground truth (what it cost)."""
    from bt_nav.media.plot import plot_run, start_circle
    from bt_nav.media.video import write_video

    started = time.perf_counter()
    world = _world(row, record)
    moved = len(record.truth) > 0
    title = run_title(row) + ("" if moved else " (no ground truth in its bag)")
    plot_run(world, _path(record), _results(row, record), run_dir / PICTURE, title=title,
             min_distance=start_circle(row.get("profile")))
    out: dict[str, Any] = {"picture_s": round(time.perf_counter() - started, 2),
                           "note": "" if moved else "no ground truth in the bag: the world only, no video"}
    if film and moved:
        stats = write_video(_from_t0(record, row), run_dir / VIDEO, FPS, world)
        out.update({"frames": stats.frames, "video_s": round(stats.seconds, 2)})
    return out


def _no_record(path: Path) -> Any:
    """An empty record (no message at all): what a run's picture draws when its bag was never written."""
    from bt_nav.media.bagread import MissionRecord, Poses, Scans

    none = Poses.from_rows([])
    return MissionRecord(path, {}, none, none, Scans(np.zeros(0), np.zeros(0), np.zeros((0, 0), np.float32)),
                         np.zeros((0, 3)))


def _drawn(run_dir: Path, film: bool) -> bool:
    """Whether a run's files are there already (a report made again, a resumed grid): then it is not drawn again."""
    return (run_dir / PICTURE).is_file() and ((run_dir / VIDEO).is_file() or not film)


def render_run(row: dict[str, Any], film: bool, keep_bag: bool) -> dict[str, Any]:
    """One run's picture (and video when ``film``) from its bag; what exists afterwards and what it cost.

    Runs in a worker process. A run without a bag gets neither, a run whose bag holds no ground truth (a node that
    crashed at start) a picture of the world only; the ``note`` says so.
    """
    run_dir = Path(row["run_dir"])
    picture, video, bag = run_dir / PICTURE, run_dir / VIDEO, run_dir / BAG
    out: dict[str, Any] = {"job": row["job"], "note": ""}
    if _drawn(run_dir, film):
        out["note"] = "drawn before"
    elif not bag.is_dir() and "bag_bytes" in row and row.get("world"):
        # recorded, but the node ended before the simulator's process wrote a bag: the world alone, as for an empty bag
        out.update(_draw(row, _no_record(bag), run_dir, False))
        out["note"] = "no bag: the node ended before the simulator recorded; the world only, no video"
    elif not bag.is_dir():
        out["note"] = "no bag" if "bag_bytes" in row else "no bag (recording off)"
    else:
        from bt_nav.media.bag import SCAN, BagError
        from bt_nav.media.bagread import read_bag

        try:  # a picture alone draws no scan: not decoding them halves its time
            out.update(_draw(row, read_bag(bag, skip=() if film else (SCAN,)), run_dir, film))
        except BagError as exc:
            out["note"] = f"bag unreadable: {exc}"
    if not keep_bag and picture.is_file() and bag.is_dir():
        shutil.rmtree(bag, ignore_errors=True)
    out["picture"] = PICTURE if picture.is_file() else None
    out["video"] = VIDEO if video.is_file() else None
    return out


def _task(row: dict[str, Any], videos: str, record: str) -> Task:
    """What :func:`render_run` is given for ``row``: the row, whether to film it, whether to keep its bag."""
    return row, wants_video(row, videos), record == "on" or (record == "failures" and not row.get("passed"))


def render_runs(rows: Sequence[dict[str, Any]], videos: str, record: str, workers: int | None = None,
                drawn: dict[str, dict[str, Any]] | None = None) -> dict[str, dict[str, Any]]:
    """:func:`render_run` for every row, those with something to draw in ``workers`` processes (default: one per
    core); by job key. ``drawn``: what a :class:`Drawer` drew already (by job key), taken as it is."""
    drawn = drawn or {}
    rows_left = [row for row in rows if row["job"] not in drawn or not _drawn(Path(row["run_dir"]), False)]
    tasks = [_task(row, videos, record) for row in rows_left]
    drawing = [(Path(row["run_dir"]) / BAG).is_dir() and not _drawn(Path(row["run_dir"]), film)
               for row, film, _ in tasks]
    todo = [task for task, draw in zip(tasks, drawing, strict=True) if draw]
    workers = max(1, min(workers or os.cpu_count() or 1, len(todo)))
    done = {task[0]["job"]: render_run(*task) for task, draw in zip(tasks, drawing, strict=True) if not draw}
    if workers == 1:
        done.update({row["job"]: render_run(row, film, keep) for row, film, keep in todo})
    else:
        done.update(_in_processes(balanced(todo, workers)))
    return {row["job"]: done.get(row["job"]) or drawn[row["job"]] for row in rows}


#: Relative cost of drawing a run: a picture, a picture and a video (about ten times as long).
PICTURE_COST, VIDEO_COST = 1, 10


def balanced(tasks: list[Task], workers: int) -> list[list[Task]]:
    """``tasks`` in ``workers`` chunks of about equal cost (the videos first, each to the least loaded chunk), so two
    failed runs are not filmed one after the other while another process only draws pictures."""
    chunks: list[list[Task]] = [[] for _ in range(workers)]
    load = [0] * workers
    for task in sorted(tasks, key=lambda t: -(PICTURE_COST + VIDEO_COST * t[1])):
        k = load.index(min(load))
        chunks[k].append(task)
        load[k] += PICTURE_COST + VIDEO_COST * task[1]
    return [chunk for chunk in chunks if chunk]


def _in_processes(chunks: list[list[Task]]) -> dict[str, dict[str, Any]]:
    """Each chunk of :func:`render_run` tasks in a ``python -m bt_nav.grading.media TASKS.json`` process of its own,
    all at once; what each drew comes back on its stdout (a few hundred bytes a run).

    Why processes of our own and not multiprocessing: a process pool leaves its resource tracker running in the
    grid's process until that exits (a child the grid did not mean to keep), and forking a process with threads
    (the launchers' pumps, a Dask client's) may copy a lock in mid-use.
    """
    with tempfile.TemporaryDirectory(prefix="bt_nav_media_") as tmp:
        procs = []
        for k, chunk in enumerate(chunks):
            tasks, errors = Path(tmp) / f"tasks{k}.json", Path(tmp) / f"errors{k}.txt"
            tasks.write_text(json.dumps(chunk), encoding="utf-8")
            with open(errors, "w", encoding="utf-8") as err:
                procs.append((subprocess.Popen([sys.executable, "-m", "bt_nav.grading.media", str(tasks)],
                                               stdout=subprocess.PIPE, stderr=err, stdin=subprocess.DEVNULL,
                                               text=True), chunk, errors))
        done: dict[str, dict[str, Any]] = {}
        for proc, chunk, errors in procs:
            out, _ = proc.communicate()
            try:
                done.update({media["job"]: media for media in json.loads(out)})
            except (json.JSONDecodeError, TypeError, KeyError):
                why = (errors.read_text(encoding="utf-8").strip().splitlines() or [f"exit {proc.returncode}"])[-1]
                done.update({row["job"]: {"job": row["job"], "note": f"drawing failed: {why}", "picture": None,
                                          "video": None} for row, _, _ in chunk})
    return done


#: Wall seconds :meth:`Drawer.finish` waits for the worker's next answer before it draws the rest at normal priority.
DRAWER_STALL = 5.0


class Drawer:
    """The pictures of a grid's ended runs, drawn while the others run (see the module docstring): :meth:`submit`
    each row as its run ends, :meth:`finish` after the grid (what was drawn, by job key, for :func:`render_runs`).

    The worker (``python -m bt_nav.grading.media --serve``, started at the first row, so not among the grid's first
    start-ups) reads one task per line on stdin and answers one line each; it ends when its stdin closes, so it never
    outlives the grid. A row to be filmed is left to the report (a video is ten pictures' work).

    Nothing here waits on the worker while the grid runs: a worker at ``nice`` 19 on a busy machine (another grade,
    a build) may read nothing for minutes, so the tasks go through a queue that a thread of their own writes to its
    pipe, and a thread of their own reads the answers. At :meth:`finish` the worker gets as long as it keeps
    answering; one that is starved is stopped and the report draws the rest at the grade's own priority."""

    def __init__(self, videos: str, record: str, stall: float = DRAWER_STALL) -> None:
        self.videos, self.record, self.stall = videos, record, stall
        self.proc: subprocess.Popen[str] | None = None
        self.sent = 0
        self._tasks: queue.Queue[str | None] = queue.Queue()
        self._answers: list[str] = []
        self._last_answer = time.monotonic()
        self._threads: list[threading.Thread] = []

    def submit(self, row: dict[str, Any]) -> None:
        """Draw ``row``'s picture now, unless it has no bag or is to be filmed; returns at once."""
        task = _task(row, self.videos, self.record)
        if task[1] or not (Path(row["run_dir"]) / BAG).is_dir():
            return
        if self.proc is None:
            self._start()
        self._tasks.put(json.dumps(task))
        self.sent += 1

    def _start(self) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "bt_nav.grading.media", "--serve"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True)
        self._threads = [threading.Thread(target=self._write, name="drawer-write", daemon=True),
                         threading.Thread(target=self._read, name="drawer-read", daemon=True)]
        for thread in self._threads:
            thread.start()

    def _write(self) -> None:
        """The queued tasks to the worker's stdin, in order; None closes it (the worker then ends)."""
        assert self.proc is not None and self.proc.stdin is not None
        stdin = self.proc.stdin
        with contextlib.suppress(OSError, ValueError):  # the worker died or was stopped: the report draws the rest
            while (line := self._tasks.get()) is not None:
                stdin.write(line + "\n")
                stdin.flush()
        with contextlib.suppress(OSError, ValueError):
            stdin.close()

    def _read(self) -> None:
        """The worker's answers, one line each, as they come."""
        assert self.proc is not None and self.proc.stdout is not None
        with contextlib.suppress(OSError, ValueError):
            for line in self.proc.stdout:
                self._answers.append(line)
                self._last_answer = time.monotonic()

    def _patience(self) -> float:
        """Seconds to wait for the next answer: ``stall``, three times that for the grid's figures (one answer for
        several pictures of the whole grid)."""
        return self.stall * (3.0 if len(self._answers) >= self.sent else 1.0)

    def finish(self, timeout: float = 60.0, wait: bool = True,
               figures: tuple[Sequence[dict[str, Any]], Path] | None = None) -> dict[str, dict[str, Any]]:
        """Wait for the worker to draw what it was sent (``wait`` False, a stopped grid: stop it now); what it drew,
        by job key (the report draws the rest). ``figures``: the grid's rows and directory, whose :func:`grid_figures`
        the worker draws last (its libraries are loaded), their names under the key ``figures``. The wait ends after
        ``timeout`` s, or when no answer came for ``stall`` s: the worker is then stopped."""
        if self.proc is None:
            return {}
        if wait and figures is not None:
            self._tasks.put(json.dumps({"figures": list(figures[0]), "out": str(figures[1])}))
        self._tasks.put(None)
        end = time.monotonic() + timeout
        self._last_answer = max(self._last_answer, time.monotonic())
        while wait and self.proc.poll() is None and time.monotonic() < min(end, self._last_answer + self._patience()):
            time.sleep(0.05)
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for thread in self._threads:
            thread.join(timeout=2.0)
        with contextlib.suppress(OSError, ValueError):
            if self.proc.stdout is not None:
                self.proc.stdout.close()
        done: dict[str, dict[str, Any]] = {}
        for line in list(self._answers):
            with contextlib.suppress(ValueError, KeyError, TypeError, AttributeError):
                media = json.loads(line)
                done[media.get("job", "figures")] = media
        return done


def _serve() -> None:
    """The :class:`Drawer`'s worker: one :func:`render_run` task per stdin line, one JSON answer per stdout line; at
    the lowest CPU priority (set here: ``preexec_fn`` is not safe in the grid's threaded process)."""
    os.nice(19)
    from bt_nav.media.bagread import read_bag  # noqa: F401 - imported once, before the first task
    from bt_nav.media.plot import plot_run  # noqa: F401

    answer = sys.stdout
    for line in sys.stdin:
        task = json.loads(line)
        with contextlib.redirect_stdout(sys.stderr):
            if isinstance(task, dict):
                media: dict[str, Any] = {"job": "figures", "names": grid_figures(task["figures"], Path(task["out"]))}
            else:
                media = render_run(task[0], bool(task[1]), bool(task[2]))
        answer.write(json.dumps(media) + "\n")
        answer.flush()


def main() -> None:
    """``python -m bt_nav.grading.media TASKS.json``: the :func:`render_run` tasks of the file (a JSON list of
    ``[row, film, keep_bag]``), what each drew on stdout (a JSON list); ``--serve``: a :class:`Drawer`'s worker."""
    if sys.argv[1] == "--serve":
        _serve()
        return
    tasks = json.loads(Path(sys.argv[1]).read_text(encoding="utf-8"))
    with contextlib.redirect_stdout(sys.stderr):  # stdout carries the answer only, whatever a library prints
        done = [render_run(row, bool(film), bool(keep)) for row, film, keep in tasks]
    json.dump(done, sys.stdout)


def travelled_requirement(rows: Sequence[dict[str, Any]]) -> float | None:
    """The distance the judge requires (its ``minimum travelled distance`` check), None when it checks none."""
    for row in rows:
        for check in (row.get("verdict") or {}).get("checks", ()):
            if check.get("name") == TRAVELLED_CHECK and isinstance(check.get("required"), int | float):
                return float(check["required"])
    return None


def distance_histogram(rows: Sequence[dict[str, Any]], path: Path) -> Path | None:
    """The travelled distance of every judged run (passed green, failed red, stacked), the requirement dashed;
    None when no run has a verdict."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    from bt_nav.media.plot import save_figure

    judged = [r for r in rows if r.get("verdict") and "travelled" in r["verdict"]]
    if not judged:
        return None
    passed = [float(r["verdict"]["travelled"]) for r in judged if r.get("passed")]
    failed = [float(r["verdict"]["travelled"]) for r in judged if not r.get("passed")]
    fig, ax = plt.subplots(figsize=(7.0, 3.6), dpi=100)
    try:
        required = travelled_requirement(judged)
        span = [*passed, *failed, *([required] if required is not None else [])]
        lo, hi = min(span), max(span)
        bins = np.linspace(lo - 0.25, hi + 0.25, min(30, max(6, len(judged))) + 1)  # the requirement inside
        ax.hist([passed, failed], bins=bins, stacked=True, color=["#2ca02c", "#d62728"],
                label=[f"passed ({len(passed)})", f"failed ({len(failed)})"])
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        if required is not None:
            ax.axvline(required, color="black", ls="--", lw=1.2, label=f"required {required:g} m")
        ax.set_xlabel("travelled distance [m] (ground truth, as judged)")
        ax.set_ylabel("runs")
        unjudged = len(rows) - len(judged)
        ax.set_title(f"travelled distance of {len(judged)} judged runs"
                     + (f" ({unjudged} without a verdict not shown)" if unjudged else ""), fontsize=10)
        ax.legend(fontsize=8)
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def turns_figure(rows: Sequence[dict[str, Any]], path: Path) -> Path | None:
    """The lab's check-off: per run, the maneuvers judged (light) and those within their rule (dark); None when
    no verdict lists maneuvers (the homework's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    from bt_nav.media.plot import save_figure

    judged = [r for r in rows if r.get("verdict") and "maneuvers" in r["verdict"]]
    if not judged:
        return None
    from bt_nav.grading.grid import cell_label

    names = [f"{cell_label(r)} s{r['seed']}" for r in judged]  # the LiDAR too: one run per LiDAR otherwise alike
    total = [len(r["verdict"]["maneuvers"]) for r in judged]
    ok = [sum(1 for m in r["verdict"]["maneuvers"] if m.get("passed")) for r in judged]
    fig, ax = plt.subplots(figsize=(max(5.0, 0.3 * len(judged) + 2.0), 3.6), dpi=100)
    try:
        ax.bar(range(len(judged)), total, color="#c6dbef", label=f"judged ({sum(total)})")
        ax.bar(range(len(judged)), ok, color="#2171b5", label=f"within their rule ({sum(ok)})")
        ax.set_xticks(range(len(judged)), names, rotation=90, fontsize=7)
        ax.set_ylim(0, max([*total, 1]) * 1.35)  # room for the legend above the bars
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel("maneuvers")
        ax.set_title("check-off turns per run", fontsize=10)
        ax.legend(fontsize=8, loc="upper right", ncols=2)
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def grid_figures(rows: Sequence[dict[str, Any]], out: Path) -> list[str]:
    """The grid's figures in ``out`` (file names, relative to it): the distance histogram, the lab's turns."""
    made = [distance_histogram(rows, out / DISTANCE), turns_figure(rows, out / TURNS)]
    return [p.name for p in made if p is not None]


if __name__ == "__main__":
    main()
