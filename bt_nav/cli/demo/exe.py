"""``bt-nav demo --exe 'CMD'``: a student's own robot node filmed for the hand-in, in place of bt_nav's executive.

One run of ``bt-nav grade --exe``'s machinery (:func:`bt_nav.grading.exe.run.run_exe_job`: the simulator, the
profile's judge, the node with ``use_sim_time`` and the profile's remaps, the recorder) with a terminal: the node's
log lines with the sim time each was logged at, the judge's service calls and replies and its report
(:class:`bt_nav.run.terminal.NodeTerminal`), then the verdict. The bag is recorded into the run directory
(``bag/``) and filmed (``--video``, default ``video.mp4`` there): the robot, its scan, the node's command and the
terminal, which is what the lab's hand-in asks for (the terminal output and the robot reacting).

The terminal (and the film's console, :mod:`bt_nav.grading.handin_film`) begins with the command that ran and, in the
lab, the ``ros2 launch`` it stands in for (the package and the node's parameters from the launch file beside the
node, or ``--launch FILE``), then the node's lines and the judge's service calls in time order. One time base: every
line is stamped with the simulator's clock (``[sim 5.76 s]``), the judge's report lines are said on it too
(:func:`bt_nav.run.terminal.on_sim_clock`), and the film's caption counts on it.

In the lab the maneuver is the one the node's file declares (the template's ``# CHOICE: X``, read as ``bt-nav
grade`` reads it) unless ``--maneuver`` says another (a line says which wins), and the arena the one that checks it
off (``lab_object`` for A and C, ``lab_dead_end`` for B) unless ``--world``.

The run directory is ``<out>/<name>/<world>_<maneuver>_seed<seed>`` with grade --exe's files (``node.log``,
``verdict.json``, ``result.json``, ``bag/``). Exit code: 0 PASSED, 1 FAILED, 2 no verdict or a bad option.
"""

from __future__ import annotations

import argparse
import shlex
import sys
import time
from pathlib import Path
from typing import Any

#: Sim seconds per wall second when ``--rtf 0``: real time, the speed a grade judges at and the robot runs at. A
#: student's node filmed faster can misbehave in ways it never would on the robot (its turns timed late, its
#: callbacks queued); ``--rtf N`` films a faster preview on request.
EXE_RTF = 1.0
#: Sim seconds a terminal line waits for earlier ones that come over DDS (:class:`bt_nav.run.terminal.NodeTerminal`).
HOLD = 2.0


def exe_maneuver(opts: argparse.Namespace) -> tuple[str, str]:
    """The maneuver a node is filmed on, and a line to say when ``--maneuver`` overrides its file's: in the lab the
    ``# CHOICE: X`` the node's file declares, as ``bt-nav grade`` reads it, unless ``--maneuver`` is given
    (:func:`bt_nav.grading.plan.lab_maneuver`); the homework's as for bt_nav's executive. ValueError: a lab node
    without either, or an unknown maneuver."""
    from bt_nav.grading.plan import lab_maneuver
    from bt_nav.mission.params import normalise_maneuver
    from bt_nav.run.settings import profile_maneuver

    if opts.profile != "lab":
        return profile_maneuver(opts.profile, opts.maneuver), ""
    chosen, note = lab_maneuver(opts.exe, opts.maneuver, "--maneuver")
    return normalise_maneuver(chosen), note


def stand_in(opts: argparse.Namespace) -> Any:
    """The lab's ``ros2 launch`` this run stands in for (:class:`bt_nav.grading.handin_film.StandIn`): from
    ``--launch FILE``, else the launch file beside the node's file; None for the homework (it has no launch file).
    ValueError: a ``--launch`` file that does not exist."""
    from bt_nav.grading.exe.grid import node_file
    from bt_nav.grading.handin_film import launch_beside, launch_stand_in

    if opts.profile != "lab":
        if opts.launch:
            raise ValueError("--launch is the lab's (its launch file); the homework has none")
        return None
    node = node_file(opts.exe)
    node = node if node is not None and node.is_file() else None
    if opts.launch and not Path(opts.launch).is_file():
        raise ValueError(f"--launch {opts.launch}: no such file")
    return launch_stand_in(Path(opts.launch) if opts.launch else launch_beside(node), node)


def _settings(opts: argparse.Namespace, params: tuple[tuple[str, Any], ...] = ()) -> tuple[Any, Any, str]:
    """The run's :class:`~bt_nav.grading.grid.Job` and :class:`~bt_nav.grading.exe.run.ExeSettings` (``params``: the
    node's parameters, as its launch file gives them), and a note on its maneuver (:func:`exe_maneuver`; ValueError
    on a bad option)."""
    from bt_nav.grading.exe.grid import resolve_program
    from bt_nav.grading.exe.run import ExeSettings
    from bt_nav.grading.grid import Job
    from bt_nav.mission.maneuver_spec import letters_text
    from bt_nav.ros.bringup import CHECKOFF_WORLDS

    if opts.profile not in ("homework", "lab"):
        raise ValueError(f"--profile {opts.profile}: --exe runs the homework's referee or the lab's check-off judge")
    if opts.bag:
        raise ValueError("--exe records its bag into the run directory (bag/): leave out --bag")
    if opts.robots != 1:
        raise ValueError("--exe films one robot (--robots 1)")
    if opts.overrides:
        raise ValueError("--set is for bt_nav's executive; give your node its parameters in the --exe command")
    lab = opts.profile == "lab"
    maneuver, note = exe_maneuver(opts)
    if lab and maneuver not in CHECKOFF_WORLDS:
        raise ValueError(f"--profile lab checks off maneuver {letters_text()}, not {maneuver!r}")
    world = opts.world or (CHECKOFF_WORLDS[maneuver] if lab else "stage_4")
    name = opts.name or f"{time.strftime('%Y%m%d-%H%M%S')}_exe"
    settings = ExeSettings(resolve_program(opts.exe), opts.profile, Path(opts.out) / name,
                           limit=opts.timeout, rtf=opts.rtf or EXE_RTF, maneuvers=opts.maneuver is not None or lab,
                           record="on", videos="off", cwd=str(Path.cwd()), node_params=params)
    return Job(world, maneuver, opts.seed, profile=opts.profile), settings, note


def run_exe_demo(opts: argparse.Namespace) -> int:
    """The demo of ``--exe``; 0 PASSED, 1 FAILED, 2 no verdict (or a bad option)."""
    from bt_nav.grading.exe.bag import BAG
    from bt_nav.grading.exe.run import exe_ros_args, run_exe_job
    from bt_nav.grading.handin_film import terminal_head, write_transcript
    from bt_nav.ros.simclock import SimClock
    from bt_nav.ros.supervise import StopRequest, use_domain_here
    from bt_nav.run.terminal import NodeTerminal

    try:
        launched = stand_in(opts)
        job, settings, note = _settings(opts, launched.params if launched is not None else ())
    except (ValueError, FileNotFoundError) as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    if note:
        print(f"bt-nav demo: {note}", flush=True)
    print(f"bt-nav demo: {settings.command!r} as the robot node, {opts.profile} judge, {job.world}, maneuver "
          f"{job.maneuver}, seed {job.seed}, {settings.rtf:g}x real time; times on the simulator's clock "
          "([sim T s])", flush=True)
    argv = [*shlex.split(settings.command), *exe_ros_args(job.maneuver if settings.maneuvers else None,
                                                          settings.profile, settings.node_params)]
    head = terminal_head(argv, launched)
    for line in head:
        print(line, flush=True)
    terminal = NodeTerminal(SimClock(), hold=HOLD)
    recorder: list[Any] = []

    def on_start(domain: int, run_dir: Path) -> None:
        from bt_nav.run.recorder import Recorder

        print(f"bt-nav demo: run directory {run_dir}/, ROS_DOMAIN_ID={domain} (localhost only)", flush=True)
        use_domain_here(domain)  # the clock node of this process too
        recorder.append(Recorder(executive=False))  # a student's node: no tree to wait for
        terminal.clock = recorder[0].clock
        terminal.listen()  # the judge's calls, from its events

    stop = StopRequest().install()
    try:
        row = run_exe_job(job, settings, stop, sink=terminal.sink, on_start=on_start)
    finally:
        stop.restore()
        terminal.close()
        if recorder:
            recorder[0].close()
    run_dir = Path(row["run_dir"])
    write_transcript(run_dir, head, terminal.transcript())
    _print_report(row, terminal.report)
    print(f"bt-nav demo: {'PASSED' if row['passed'] else 'FAILED'}: {_on_sim_clock(row, row['reason'])}", flush=True)
    if row.get("bag"):
        _film(run_dir, run_dir / BAG, opts.video or str(run_dir / "video.mp4"))
    else:
        print("bt-nav demo: no bag was recorded, so no video (see record.log)", file=sys.stderr)
    if row["outcome"] != "verdict":
        return 2
    return 0 if row["passed"] else 1


def _on_sim_clock(row: dict[str, Any], text: str) -> str:
    """``text`` of the judge's (its times from its t0) said on the sim clock, when the verdict gives t0's reading."""
    from bt_nav.run.terminal import on_sim_clock

    t0 = (row.get("verdict") or {}).get("t0_sim")
    return text if t0 is None else on_sim_clock(text, float(t0))


def _print_report(row: dict[str, Any], kept: list[str]) -> None:
    """The judge's report lines, their times said on the sim clock (the verdict's ``t0_sim``); without a verdict the
    lines the judge printed, as it printed them (its times count from its t0)."""
    verdict = row.get("verdict") or {}
    lines = verdict.get("report_lines")
    if lines and verdict.get("t0_sim") is not None:
        print("the judge's report (times on the simulator's clock):", flush=True)
        for line in lines:
            print(_on_sim_clock(row, str(line)), flush=True)
    elif kept:
        print("the judge's report (t: seconds from its start, t0):", flush=True)
        for line in kept:
            print(line, flush=True)


def _film(run_dir: Path, bag: Path, video: str) -> None:
    """The hand-in film (:func:`bt_nav.grading.handin_film.film_handin`); a film that cannot be made is said, never
    hides the verdict."""
    from bt_nav.grading.handin_film import film_handin

    try:
        stats = film_handin(run_dir, bag, video, 10.0)
    except Exception as exc:  # noqa: BLE001 - a film that cannot be made must not hide the verdict
        print(f"bt-nav demo: no video: {exc}", file=sys.stderr)
        return
    print(f"video: {video} ({stats.frames} frames at {stats.fps:g} fps, rendered in {stats.seconds:.1f} s; its "
          "console, frame by frame, beside it as .console.json)", flush=True)
