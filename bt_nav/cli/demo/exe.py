"""``bt-nav demo --exe 'CMD'``: a student's own robot node filmed for the hand-in, in place of bt_nav's executive.

One run of ``bt-nav grade --exe``'s machinery (:func:`bt_nav.grading.exe.run.run_exe_job`: the simulator, the
profile's judge, the node with ``use_sim_time`` and the profile's remaps, the recorder) with a terminal: the node's
log lines with the sim time each was logged at, the judge's service calls and replies and its report
(:class:`bt_nav.run.terminal.NodeTerminal`), then the verdict. The bag is recorded into the run directory
(``bag/``) and filmed (``--video``, default ``video.mp4`` there): the robot, its scan, the node's command and its
log lines, which is what the lab's hand-in asks for (the terminal output and the robot reacting).

In the lab the maneuver is the one the node's file declares (the template's ``# CHOICE: X``, read as ``bt-nav
grade`` reads it) unless ``--maneuver`` says another (a line says which wins), and the arena the one that checks it
off (``lab_object`` for A and C, ``lab_dead_end`` for B) unless ``--world``.

The run directory is ``<out>/<name>/<world>_<maneuver>_seed<seed>`` with grade --exe's files (``node.log``,
``verdict.json``, ``result.json``, ``bag/``). Exit code: 0 PASSED, 1 FAILED, 2 no verdict or a bad option.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

#: Sim seconds per wall second when ``--rtf 0``: the simulator does not wait for a foreign node (grade --exe's pace).
EXE_RTF = 5.0


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


def _settings(opts: argparse.Namespace) -> tuple[Any, Any, str]:
    """The run's :class:`~bt_nav.grading.grid.Job` and :class:`~bt_nav.grading.exe.run.ExeSettings`, and a note on
    its maneuver (:func:`exe_maneuver`; ValueError on a bad option)."""
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
                           record="on", videos="off", cwd=str(Path.cwd()))
    return Job(world, maneuver, opts.seed, profile=opts.profile), settings, note


def run_exe_demo(opts: argparse.Namespace) -> int:
    """The demo of ``--exe``; 0 PASSED, 1 FAILED, 2 no verdict (or a bad option)."""
    from bt_nav.cli.options import film
    from bt_nav.grading.exe.bag import BAG
    from bt_nav.grading.exe.run import run_exe_job
    from bt_nav.ros.simclock import SimClock
    from bt_nav.ros.supervise import StopRequest, use_domain_here
    from bt_nav.run.terminal import NodeTerminal

    try:
        job, settings, note = _settings(opts)
    except (ValueError, FileNotFoundError) as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    if note:
        print(f"bt-nav demo: {note}", flush=True)
    print(f"bt-nav demo: {settings.command!r} as the robot node, {opts.profile} judge, {job.world}, maneuver "
          f"{job.maneuver}, seed {job.seed}, {settings.rtf:g}x real time", flush=True)
    clock = SimClock()
    terminal = NodeTerminal(clock)
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
    print(f"bt-nav demo: {'PASSED' if row['passed'] else 'FAILED'}: {row['reason']}", flush=True)
    run_dir = Path(row["run_dir"])
    if row.get("bag"):
        video = opts.video or str(run_dir / "video.mp4")
        try:
            film(str(run_dir / BAG), video, 10.0)
        except Exception as exc:  # noqa: BLE001 - a film that cannot be made must not hide the verdict
            print(f"bt-nav demo: no video: {exc}", file=sys.stderr)
    else:
        print("bt-nav demo: no bag was recorded, so no video (see record.log)", file=sys.stderr)
    if row["outcome"] != "verdict":
        return 2
    return 0 if row["passed"] else 1
