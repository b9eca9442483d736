"""``bt-nav grade --exe 'CMD ...'``: the options of a DDS grade checked before any run, the runs (here or on a
Dask cluster, :mod:`bt_nav.grading.exe.grid`), a line per run under a progress bar, the report.

Why the checks come first: a grid of a command that cannot start, or one that would write into another
grade's directory, fails every run alike or mixes two grades; both are refused with exit 2 instead.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tqdm import tqdm

from bt_nav.cli.grade.formats import write_class_formats, write_exe_formats
from bt_nav.grading.grid import Job, format_lidars, preview_said, run_label


def _show(row: dict[str, Any]) -> None:
    """One line per run as it ends (above the progress bar, when there is one)."""
    label = "STOPPED" if row["outcome"] == "stopped" else "PASSED" if row["passed"] else "FAILED"
    label = "NOT GRADED" if row.get("not_graded") else label  # not the node's doing: its domain, a busy machine
    label += " (preview)" if str((row.get("preview") or {}).get("said")).endswith("in the preview") else ""
    factor = f", {row['rtf']:.1f}x" if row.get("rtf") else ""  # what the run achieved (bt_nav.grading.exe.pace)
    tqdm.write(f"  {run_label(row)}: {label} ({row['reason']}; "
               f"{row['wall_time']:.1f} s wall{factor}) {row['run_dir']}", file=sys.stdout)
    if preview_said(row):  # a preview's failure graded at 1x: this is the 1x run's verdict
        tqdm.write(f"    {preview_said(row)}", file=sys.stdout)
    for note in row.get("notes", []):  # not the node's: a domain it had to leave, a lost SIGINT
        tqdm.write(f"    note: {note}", file=sys.stdout)
    sys.stdout.flush()


def grade_exe(args: argparse.Namespace, jobs: Sequence[Job], maneuvers: bool, parser: argparse.ArgumentParser) -> int:
    """``bt-nav grade --exe``: every run over DDS (:mod:`bt_nav.grading.exe.run`); exit 0 only if every run passed,
    2 for options refused before any run, 128 + the signal after SIGINT/SIGTERM (every process of the runs
    stopped; the report holds the runs that ended, ``--resume`` runs the others)."""
    from bt_nav.grading.exe.grid import (
        STOPPED,
        close_workers,
        connect_workers,
        describe_workers,
        exe_settings,
        prepare_out,
        run_exe_grid,
    )
    from bt_nav.grading.exe.pace import preview, speed_words
    from bt_nav.grading.launch import attach_launch, exe_launch
    from bt_nav.grading.media import Drawer
    from bt_nav.grading.report import format_exe_table, summarize_exe, write_exe_report
    from bt_nav.ros.supervise import StopRequest

    try:
        settings = exe_settings(args, maneuvers)
        launch = exe_launch(args.launch, settings.command)  # --launch FILE: its checks, shown before any run
        workers = connect_workers(args.jobs, args.scheduler)  # a cluster out of reach refuses the grade
        done = prepare_out(settings, jobs, args.resume)
    except ValueError as exc:
        parser.error(str(exc))
    where = describe_workers(workers, real_time=not preview(settings.rtf))
    print(f"bt-nav grade: {len(jobs)} runs of {settings.command!r} ({args.profile} profile, {where}, "
          f"{speed_words(settings.rtf, settings.rtf_max)}, {args.timeout:g} s wall each) in {settings.out}/",
          flush=True)
    if args.resume:
        print(f"resuming: {len(done)} of {len(jobs)} runs already in {settings.out}", file=sys.stderr, flush=True)
    progress = args.progress == "on" or (args.progress == "auto" and sys.stderr.isatty())
    stop = StopRequest().install()
    started = time.perf_counter()
    drawer = Drawer(settings.videos, settings.record)  # the ended runs' pictures while the others run

    def ended_run(row: dict[str, Any]) -> None:
        _show(row)
        if row["outcome"] != STOPPED:
            drawer.submit(row)

    rows: list[dict[str, Any]] = []
    try:
        rows = run_exe_grid(jobs, settings, workers, stop, ended_run, done=done, progress=progress)
    finally:
        close_workers(workers)
        stop.closing = True
        stop.restore()
        ended = [row for row in rows if row["outcome"] != STOPPED]
        drawn = drawer.finish(wait=not stop.requested, figures=(ended, settings.out) if ended else None)
    print(format_exe_table(summarize_exe(ended)))
    json_path, md_path = write_exe_report(ended, settings, drawn=drawn)
    from bt_nav.grading.feedback import write_grid_feedback

    attach_launch(settings.out, launch)  # grade.json carries the launch checks as a class's hand-in does
    write_grid_feedback(settings.out)
    if args.json:  # the grid's JSON results there too: --json means the same with and without --exe
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json_path.read_text(encoding="utf-8"), encoding="utf-8")
    print("".join(f"wrote {path}\n" for path in write_exe_formats(args, settings.out)), end="")  # --gradescope, --junit
    for line in format_lidars(ended):
        print(line)
    return _verdict(args, ended, len(jobs), settings, time.perf_counter() - started, stop, (json_path, md_path))


def _verdict(args: argparse.Namespace, ended: Sequence[dict[str, Any]], planned: int, settings: Any,
             wall: float, stop: Any, written: tuple[Path, Path]) -> int:
    """The grid's last lines and exit code: 0 every run passed; 1 a run failed; 3 no run failed but some hit a
    bt_nav error (not the node's: ``--resume`` reruns them); 128 + the signal after a stop."""
    from bt_nav.grading.exe.grid import ERROR
    from bt_nav.grading.launch import launch_passed

    errors = [r for r in ended if r["outcome"] == ERROR]
    judged = [r for r in ended if r["outcome"] != ERROR]
    passed = sum(1 for r in judged if r["passed"])
    extra = f", {len(errors)} without a verdict apart (not the node's: not graded, or a bt_nav error's traceback in " \
            f"{settings.out / 'bt_nav_errors'})" if errors else ""
    print(f"{passed}/{len(judged)} passed{extra} in {wall:.1f} s wall; wrote {written[0]}, {written[1]}, "
          f"{settings.out / 'report.html'}, {settings.out / 'feedback.md'}" + (f", {args.json}" if args.json else ""))
    if len(ended) < planned or errors:
        print(f"bt-nav grade: {planned - len(judged)} of {planned} runs without a verdict (not in the pass rate): "
              f"bt-nav grade ... --out {settings.out} --resume runs them", file=sys.stderr)
    if stop.requested:
        print(f"bt-nav grade: {stop.name}: stopped every run", file=sys.stderr)
        return 128 + int(stop.signum or 2)
    if passed < len(judged) or not (judged or errors) or not launch_passed(settings.out):  # --launch: a check failed
        return 1
    return 3 if errors or len(judged) < planned else 0


def _runs(count: int) -> str:
    return f"{count} run{'' if count == 1 else 's'}"


def _show_handins(handins: dict[str, Any]) -> None:
    """Each hand-in's node file and launch-file lines, before any run."""
    for name, handin in handins.items():
        if handin.node is not None:
            print(f"  {name}: node {handin.node}", flush=True)
        for line in [*handin.launch.lines(), *(f"note: {n}" for n in handin.launch.notes)]:
            print(f"  {name}: {line}", flush=True)


def _class_verdicts(out: Path, handins: dict[str, Any]) -> bool:
    """Every student's ``feedback.md``; for a folder of hand-ins a verdict line per student (runs and launch file
    together). Whether every student passed."""
    from bt_nav.grading.classroom import CLASS_FILE
    from bt_nav.grading.feedback import write_feedback
    from bt_nav.grading.handins import load_class

    if not (out / CLASS_FILE).is_file():
        return False
    results = load_class(out)
    for result in results:
        write_feedback(result)
        if handins:
            print(f"  {result.name}: hand-in {result.verdict}"
                  + (f" ({'; '.join(result.reasons)})" if result.reasons else ""), flush=True)
    print(f"wrote {len(results)} feedback.md: {out}/<student>/feedback.md", flush=True)
    return all(r.passed for r in results)


def grade_class(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """``bt-nav grade --class MANIFEST|DIR``: every student's grid (:func:`bt_nav.grading.classroom.run_class`), each
    written as ``--exe`` writes one, then the class page and each student's ``feedback.md``. Exit codes as for one
    grid, over the whole class (a hand-in whose launch file fails a check fails too)."""
    import copy

    from bt_nav.grading.classroom import admit, run_class, write_class_page
    from bt_nav.grading.exe.grid import close_workers, connect_workers, exe_settings, resolve_program
    from bt_nav.grading.feedback import drop_stale_feedback
    from bt_nav.grading.handins import read_class
    from bt_nav.grading.plan import build_jobs, grid_axes
    from bt_nav.ros.supervise import StopRequest

    if args.exe is not None:
        parser.error("--class grades the manifest's commands: leave --exe out")
    try:
        students, failed, handins = read_class(Path(args.klass))
        out = Path(args.out or f"runs/grade-class-{time.strftime('%Y%m%d-%H%M%S')}").absolute()
        worlds, seeds = grid_axes(args)
        # A bad entry fails its student; options that do not fit refuse the class, every plan before the first run.
        commands, refused = admit([s for s in students if s.name not in failed],
                                  args.profile == "lab" and not args.maneuvers, resolve_program)
        refused = {s.name: failed.get(s.name) or refused[s.name] for s in students
                   if s.name in failed or s.name in refused}
        plans, left_out = {}, set()
        for student in (s for s in students if s.name in commands):
            own = copy.copy(args)
            own.exe, own.out, own.json = student.command, str(out / student.name), None
            jobs = build_jobs(own, worlds, seeds, left_out)
            plans[student.name] = (exe_settings(own, own.profile == "lab" or own.maneuvers is not None,
                                                commands[student.name]), jobs)
        workers = connect_workers(args.jobs, args.scheduler)  # runs and re-runs there; out of reach: refused
    except ValueError as exc:
        parser.error(str(exc))
    if left_out:
        print("not checked off there: " + ", ".join(sorted(left_out)), file=sys.stderr)
    where = f" on {args.scheduler}" if args.scheduler else ""
    print(f"bt-nav grade: a class of {len(students)} in {out}/{where}: " + ", ".join(
        f"{s.name} (not run)" if s.name in refused else f"{s.name} ({_runs(len(plans[s.name][1]))})"
        for s in students), flush=True)
    for name, reason in refused.items():
        print(f"  {name}: FAILED (not run: {reason})", flush=True)
    _show_handins(handins)
    drop_stale_feedback(out, list(plans))
    stop = StopRequest().install()
    started = time.perf_counter()
    try:
        done = run_class([s for s in students if s.name in plans], lambda s: plans[s.name], workers, stop,
                         lambda name, row: _show({**row, "world": f"{name}: {row['world']}"}), args.resume,
                         lambda line: print(f"  {line}", flush=True))
    except ValueError as exc:  # a student's directory holds another grade
        parser.error(str(exc))
    finally:
        close_workers(workers)
        stop.closing = True
        stop.restore()
    from bt_nav.grading.handins import add_verdicts

    records = {name: h.record() for name, h in handins.items()}
    paths = write_class_page(out, students, f"Class grade ({args.profile} profile)", refused,
                             (lambda rows: add_verdicts(rows, records)) if records else None)
    paths = [*paths, *write_class_formats(args, out)]  # --gradescope, --junit
    wall = time.perf_counter() - started
    print(f"class of {len(students)} in {wall:.1f} s wall; wrote " + ", ".join(map(str, paths)))
    handed_in = _class_verdicts(out, handins)
    if stop.requested:
        return 128 + int(stop.signum or 2)
    rows = [row for student_rows in done.values() for row in student_rows]
    return 0 if len(done) == len(students) and rows and all(r["passed"] for r in rows) and handed_in else 1
