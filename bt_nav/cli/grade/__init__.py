"""Batch grading: lock-step missions over worlds x maneuvers x seeds, in local processes or on a Dask cluster.

Every mission is deterministic per (world, maneuver, seed, profile, kinematics), so a grade is
reproducible, two grades can be compared run by run, and where a mission ran (:mod:`bt_nav.grading.grid`)
does not change its result. ``--json`` is rewritten as missions finish, so ``--resume`` can continue an
interrupted grid from it without running any mission twice.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bt_nav_sim.lidar import LIDARS
from bt_nav_sim.physics import KINEMATICS

from bt_nav.cli.grade.formats import add_format_options, check_format_options
from bt_nav.cli.options import add_mission_options, jobs_arg
from bt_nav.grading.grid import Job, format_lidars, run_grid, summarize
from bt_nav.grading.grid import overall as overall
from bt_nav.grading.plan import EXE_LIDARS, build_jobs, grid_axes
from bt_nav.mission.params import LAB_MANEUVERS, MANEUVERS, parse_assignments
from bt_nav.run.settings import effective_parameters, tree_settings


def format_overall(total: dict[str, Any]) -> str:
    """One line with the headline figures (the lab's: maneuvers in their rule and the largest angle miss)."""
    head = (f"{total['passed']}/{total['runs']} passed ({100 * total['pass_rate']:.1f} %), "
            f"{total['collisions']} collisions in {total['runs_with_collisions']} runs")
    if "turns" in total:
        return (f"{head}, {total['turns_ok']}/{total['turns']} maneuvers within their rule, largest miss of an "
                f"announced angle {total['angle_error_max']:.1f} deg, {total['recoveries']} brake recoveries; "
                f"worst cell {total['worst_cell']}")
    return (f"{head}, efficiency median {total['efficiency_median']:.3f} worst {total['efficiency_worst']:.3f}; "
            f"worst cell {total['worst_cell']}")


def _failed(s: dict[str, Any]) -> str:
    return ", ".join(f"{name} x{n}" for name, n in s["failed_checks"].items()) or "-"


def format_table(summary: Sequence[dict[str, Any]]) -> str:
    """The summary as a fixed-width text table (the lab's check-off columns for a lab grid); with several LiDARs
    the world column names the LiDAR too."""
    if any(s.get("lidar") for s in summary):
        summary = [{**s, "world": f"{s['world']} {s.get('lidar') or 'profile'}"} for s in summary]
    if summary and "turns" in summary[0]:
        head = (f"{'world':<15} {'man':<4} {'pass':>7} {'coll':>5} {'turns':>6} {'in rule':>7} {'miss max':>8} "
                f"{'brakes':>6} {'wall/run':>8}  failed checks")
        rows = [f"{s['world']:<15} {s['maneuver']:<4} {s['passed']:>3}/{s['runs']:<3} {s['collisions']:>5} "
                f"{s['turns']:>6} {s['turns_ok']:>7} {s['angle_error_max']:>7.1f}° {s['recoveries']:>6} "
                f"{s['wall_time_mean']:>7.3f}s  {_failed(s)}" for s in summary]
    else:
        head = (f"{'world':<11} {'man':<4} {'pass':>7} {'coll':>5} {'trav med':>8} {'trav min':>8} "
                f"{'eff med':>7} {'eff min':>7} {'wall/run':>8}  failed checks")
        rows = [f"{s['world']:<11} {s['maneuver']:<4} {s['passed']:>3}/{s['runs']:<3} {s['collisions']:>5} "
                f"{s['travelled_median']:>8.2f} {s['travelled_min']:>8.2f} {s['efficiency_median']:>7.3f} "
                f"{s['efficiency_worst']:>7.3f} {s['wall_time_mean']:>7.3f}s  {_failed(s)}" for s in summary]
    return "\n".join([head, "-" * len(head), *rows])


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="bt-nav grade", description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", default=None, help="comma-separated world names, or 'all' (the bundled "
                        "worlds of the profile: the homework's, or with --profile lab the lab's check-off arenas); "
                        "default stage_4, or all for lab")
    parser.add_argument("--maneuvers", default=None, help=f"comma-separated: {', '.join(MANEUVERS)} (default "
                        f"{','.join(MANEUVERS)}; lab: {','.join(LAB_MANEUVERS)}, each in the arenas that can check it "
                        "off)")
    parser.add_argument("--seeds", type=int, default=None, help="seeds 0..N-1 (default 20; --exe: 2)")
    parser.add_argument("--lidars", default=None, metavar="NAME,...",
                        help="a grid axis of real LiDARs (" + ", ".join(("profile", *LIDARS)) + "; profile: the "
                        "profile's own); default profile, --exe: " + ",".join(EXE_LIDARS) + " (a node reading the "
                        "scan by fixed indices passes one and fails another)")
    parser.add_argument("--first-seed", type=int, default=0, help="the first seed (default 0)")
    parser.add_argument("--jobs", type=jobs_arg, default=None, metavar="N|auto",
                        help="runs at once on this machine (without --scheduler); auto (default): for --exe at 1x "
                        "the whole grid at once, up to ten per usable core and 400 MiB a run, then one more at a time "
                        "while the cores stay idle; in a preview up to three per core; N: exactly N at a time")
    parser.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                        help="run on this Dask scheduler (an address or a scheduler file .json)")
    add_mission_options(parser, grid=True)
    parser.add_argument("--kinematics", default="", choices=("", *KINEMATICS),
                        help="ideal or burger (per-wheel limits); default: the profile's")
    parser.add_argument("--no-jitter", action="store_true", help="start exactly at each world's spawn")
    parser.add_argument("--json", default=None, help="write every run and the summary here (updated as runs finish)")
    parser.add_argument("--resume", action="store_true", help="keep the finished runs of --json's file (--exe: of "
                        "--out's run directories), run the rest")
    parser.add_argument("--exe", default=None, metavar="'CMD ...'",
                        help="grade this command's node over DDS instead of bt_nav's tree in lock-step (appended: "
                        "--ros-args -p use_sim_time:=true, the profile's remaps -r arm:=<its arm service> (homework: "
                        "also -r evaluate_mission:=/reactive_control/evaluate_mission), and -p maneuver:=X with "
                        "--maneuvers or --profile lab)")
    parser.add_argument("--class", dest="klass", default=None, metavar="MANIFEST.yaml",
                        help="grade a class over DDS: every student of the manifest (YAML 'name: command') on the "
                        "same grid, one grid each in --out/<name>, one class page (class.html); --resume continues")
    parser.add_argument("--node-param", action="append", default=[], metavar="NAME=VALUE",
                        help="--exe: a parameter for the node, as a TA's launch file sets it (repeatable), e.g. "
                        "safety_distance=0.6 (the lab's judge then triggers at it too)")
    parser.add_argument("--strict-findings", default="", metavar="KIND[,KIND]|all",
                        help="--exe, --class, lab: the check-off's findings (what the sheet only implies) that fail "
                        "instead, for a course that teaches them: back_to_back, moved_on, side, search_chain, or all "
                        "(default: none, each is a finding and the run passes)")
    parser.add_argument("--launch", default=None, metavar="FILE",
                        help="--exe: the student's launch file (or hand-in folder), given the lab sheet's launch "
                        "checks as --class gives each hand-in (see bt-nav check-launch); grade.json and feedback.md "
                        "carry them")
    parser.add_argument("--timeout", type=float, default=150.0, help="--exe: wall seconds per run (default 150)")
    parser.add_argument("--rtf", type=float, default=1.0, help="--exe: sim seconds per wall second; 1 (default): "
                        "real time, as on the robot: the grade; 0 (as fast as the node keeps up) or above 1: a PREVIEW "
                        "for iterating (failed cells graded again at 1x; no score written)")
    parser.add_argument("--rtf-max", type=float, default=None, metavar="N", help="--exe, --rtf 0: at most N sim "
                        "seconds per wall second in the preview (default and 0: no cap)")
    parser.add_argument("--realtime-check", choices=("on", "off"), default="on",
                        help="--exe, a preview (--rtf other than 1): grade each failed cell again at 1x before it is "
                        "shown (default on); off: show the preview's failures as they are (still a preview)")
    parser.add_argument("--out", default=None, help="--exe: the grid's directory, new or empty unless --resume "
                        "(default runs/grade-exe-<time>); with --scheduler on a filesystem every worker shares")
    parser.add_argument("--record", choices=("on", "failures", "off"), default="on", help="--exe: each run's bag, "
                        "for report.html's pictures (failures: keep the failed runs' bags only; off: no pictures)")
    parser.add_argument("--videos", choices=("failures", "all", "off"), default="failures",
                        help="--exe: the runs report.html shows as videos (default failures)")
    parser.add_argument("--progress", choices=("auto", "on", "off"), default="auto",
                        help="progress bar on stderr (auto: when stderr is a terminal)")
    add_format_options(parser)
    return parser


def _load_done(path: Path, jobs: Sequence[Job]) -> dict[str, dict[str, Any]]:
    """The finished runs of an earlier (possibly interrupted) grid that belong to this grid."""
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot resume from {path}: {exc}") from None
    wanted = {job.key for job in jobs}
    return {row["job"]: row for row in data.get("runs", []) if row.get("job") in wanted and "error" not in row}


def _save(path: Path, settings: dict[str, Any], rows: Sequence[dict[str, Any]], complete: bool) -> None:
    """Write the results file atomically (a kill mid-write leaves the previous version)."""
    summary = summarize(rows) if rows else []
    doc = {"settings": settings, "complete": complete, "overall": overall(rows, summary) if rows else {},
           "summary": summary, "runs": list(rows)}
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1))
    tmp.replace(path)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav grade``: prints the table; exit 0 only if every mission passed."""
    parser = _parser()
    args = parser.parse_args(argv)
    lab = args.profile == "lab"
    try:
        check_format_options(args)  # a bad weights file refuses the grade before any run
        if args.launch is not None and args.exe is None:
            raise ValueError("--launch goes with --exe (with --class, each hand-in's own launch file is checked)")
        from bt_nav.grading.exe.grid import check_node_options

        check_node_options(args)  # --class, --exe, --scheduler: what they cannot honour is refused
    except ValueError as exc:
        parser.error(str(exc))
    args.jobs = jobs_arg("auto") if args.jobs is None else args.jobs  # the default, unless --scheduler
    if args.klass is not None:
        from bt_nav.cli.grade.exe import grade_class

        return grade_class(args, parser)
    try:
        worlds, seeds = grid_axes(args)
        jobs = build_jobs(args, worlds, seeds)
        overrides = parse_assignments(args.overrides) or None
        sim_params = parse_assignments(args.sim_param) or None
        maneuvers = list(dict.fromkeys(job.maneuver for job in jobs))
        if args.exe is not None and args.profile not in ("homework", "lab"):
            raise ValueError("--exe grades with --profile homework or lab")
        lockstep_resume = args.resume and args.exe is None
        if lockstep_resume and not args.json:
            raise ValueError("--resume needs --json FILE (the file to continue)")
        path = Path(args.json) if args.json else None
        done = _load_done(path, jobs) if lockstep_resume and path is not None and path.exists() else {}
    except ValueError as exc:
        parser.error(str(exc))
    if args.exe is not None:
        from bt_nav.cli.grade.exe import grade_exe

        return grade_exe(args, jobs, lab or args.maneuvers is not None, parser)
    settings = {"profile": args.profile, "kinematics": args.kinematics, "seeds": seeds, "worlds": worlds,
                "sim_params": sim_params or {},
                "maneuvers": maneuvers, "overrides": overrides or {}, "jitter": not args.no_jitter,
                "parameters": effective_parameters(tree_settings(args.profile, "none", seeds[0] if seeds else 0,
                                                                 overrides)),
                "parameters_note": "every mission's; maneuver and random_seed vary per run (maneuver, seed)"}
    by_key = {job.key: job for job in jobs}

    def save_partial(results: dict[str, dict[str, Any]]) -> None:
        if path is not None:
            _save(path, settings, [results[k] for k in by_key if k in results], complete=False)

    progress = args.progress == "on" or (args.progress == "auto" and sys.stderr.isatty())
    if done:
        print(f"resuming: {len(done)} of {len(jobs)} missions already in {path}", file=sys.stderr)
    started = time.perf_counter()
    try:
        rows = run_grid(jobs, args.jobs, args.scheduler, done, progress, save_partial)
    except ValueError as exc:  # an unreachable scheduler: refused, never a traceback
        print(f"bt-nav grade: error: {exc}", file=sys.stderr)
        return 2
    elapsed = time.perf_counter() - started
    summary = summarize(rows)
    print(format_table(summary))
    for r in [r for r in rows if "error" in r][:5]:
        print(f"error in {r['world']} {r['maneuver']} seed {r['seed']}: {r['error']}", file=sys.stderr)
    total = overall(rows, summary)
    print(format_overall(total))
    for line in format_lidars(rows):
        print(line)
    where = f"on {args.scheduler}" if args.scheduler else f"with {args.jobs} local processes"
    print(f"{len(rows)} missions ({args.profile} profile, {args.kinematics or 'profile'} kinematics) in "
          f"{elapsed:.1f} s wall {where}")
    if path is not None:
        _save(path, settings, rows, complete=True)
    return 0 if total["passed"] == total["runs"] else 1

