"""Grading any robot node over DDS (``bt-nav grade --exe 'CMD ...'``): the simulator and the profile's judge
around a command that is not bt_nav's, once per world x maneuver x seed, each run isolated.

Per run (:func:`run_exe_job`): a ROS domain claimed for the run alone (a :class:`bt_nav.run.session.DomainLease`,
handed back at its end), a run directory of its own, and two process groups started by one
:class:`bt_nav.run.session.MissionSession` (the one layer ``bt-nav demo``, ``sim-run`` and the bench run theirs on):

- the simulator node, hosting the judge (:mod:`bt_nav.ros.nodes.hosting`: fed by its loop, no ``/clock`` or ground
  truth to read over DDS, no process of its own), at 1x by default (:mod:`bt_nav.grading.exe.pace`): the robot's
  world does not wait for the node, and the simulator measures whether it kept real time while judged. A preview
  (``rtf`` 0 or above 1) is *paced to the node* (``follow``, :data:`FOLLOW_NODE`): sim time never runs more than
  0.05 s (or the node's own command period) ahead of its latest command, except to publish the next scan the node
  answers, and a node silent for ``follower_timeout`` wall seconds is not waited for until it publishes again.
  ``cmd_vel`` is read best effort, which hears reliable and best-effort writers alike;
- the user's command, with :func:`exe_ros_args` appended (``--ros-args -p use_sim_time:=true``, the
  profile's remaps of bt_nav's own names ``arm`` and ``evaluate_mission`` onto the assignment's, plus
  ``-p maneuver:="X"`` when the grid has maneuvers): a foreign node serves the homework's
  ``/reactive_control/activate`` and calls ``/reactive_control/evaluate_mission`` under those names itself, or
  serves the lab's ``toggle_navigation``;
- the judge it hosts (homework: the referee; lab: the check-off judge) without ``wait_for_cmd_vel`` (a node may stay
  silent until armed), without ``sync`` (the hosted judge needs no heartbeat), with ``robot_clock_wait`` (t0 once the
  node's /clock subscription has settled), with ``start_wait`` (a node that never offers its arm service gets a
  failed verdict naming it after :data:`START_WAIT` wall seconds, not a timeout) and its graph audit
  (:mod:`bt_nav.ros.nodes.audit`: no ``scan`` subscription, a QoS or type that cannot match, NaN commands, a
  flood ...);
- unless ``record`` is off, the run's bag in ``bag/`` of the run directory, written by the simulator's process as it
  publishes (:mod:`bt_nav.grading.exe.bag`); the report draws each run's picture and films the failed runs from it.

The run ends when the judge's JSON (the verdict) appears, when the node exits first with an error (the
reason quotes the exception that ended it and where the node's code raised it, else names its exit code; a node
that ends by itself with 0 still gets its verdict), at the wall-time limit, or on a stop request; then every group
gets SIGINT, SIGTERM, SIGKILL. The row's ``findings`` are the audit's plus how the node ended (it ignored SIGINT,
it ended before the verdict), each also appended to its ``reason``. The output of each process (stdout and
stderr, merged in order) is ``<name>.log`` in the run directory, the row ``result.json``. Grids:
:mod:`bt_nav.grading.exe.grid`; reports: :mod:`bt_nav.grading.report`.
"""

from __future__ import annotations

import errno
import json
import re
import shlex
import signal
import time
from collections.abc import Callable
from contextlib import suppress
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from bt_nav_sim.pacing import PACE_FILE

from bt_nav.grading.exe.bag import bag_row, record_args
from bt_nav.grading.exe.log import Crash, import_findings, last_traceback, node_crash, rclpy_shutdown_race
from bt_nav.grading.exe.pace import REAL_TIME, SIM_NICE, sim_pace
from bt_nav.grading.grid import Job
from bt_nav.judge.referee_core import failure_reason
from bt_nav.mission.assignments import ASSIGNMENTS, assignment_of
from bt_nav.ros import forkserver
from bt_nav.ros.bringup import NodeSpec, host_judge, nodes, param_arg
from bt_nav.ros.supervise import DOMAIN_RANGE_ENV, Child, NoFreeDomainError, StopRequest, launcher_domains
from bt_nav.run.rundir import make_run_dir
from bt_nav.run.session import EXITED, STOPPED, VERDICT, DomainLease, MissionSession, files_written, read_verdict
from bt_nav.run.settings import DEFAULT_JITTER

#: Seconds a stopped process group gets for SIGINT before SIGTERM (then 2 s before SIGKILL); the node gets two SIGINTs
#: in it, half each. Four runs on two cores, bt_nav's own executive took up to 1.6 s from its first SIGINT to its exit
#: (0.5 s of it waiting for its last zero twist to be acknowledged): with 3 s, 27 of 48 runs were stopped by the second.
STOP_GRACE = 5.0
#: Wall seconds the judge waits for the node's /clock subscription before t0 (then it starts anyway).
ROBOT_CLOCK_WAIT = 20.0
#: Wall seconds the judge's own timeout leaves before the run's limit, so it can still write a provisional report.
JUDGE_MARGIN = 5.0
#: Wall seconds the judge waits for the node's arm service before a failed verdict (a Python node on a loaded
#: machine starts within a few; at most a third of the judge's time).
START_WAIT = 20.0


@dataclass(frozen=True)
class ExeSettings:
    """What every run of an ``--exe`` grid shares."""

    command: str  # the user's command line (shell words; no shell runs it)
    profile: str  # homework (the referee) or lab (the check-off judge)
    out: Path  # the grid's directory; one run directory per run below it
    limit: float = 150.0  # wall seconds per run
    rtf: float = 1.0  # sim seconds per wall second: 1 the verdict; 0 (as fast as the node keeps up) or > 1 a preview
    maneuvers: bool = False  # append -p maneuver:=X
    jitter: tuple[float, float] | None = DEFAULT_JITTER
    record: str = "on"  # on, failures or off: each run's bag (bt_nav.grading.exe.bag.RECORD_MODES)
    videos: str = "failures"  # failures, all or off: which runs the report films from their bags
    cwd: str | None = None  # where the command runs (a cluster's worker starts elsewhere); None: this process's
    # Parameters given to the node as a TA's launch file would (-p NAME:=VALUE); safety_distance is the judge's too
    node_params: tuple[tuple[str, Any], ...] = ()
    # A preview's failure is graded again at 1x before it is shown (bt_nav.grading.exe.realtime); off: shown as the
    # preview's (tests that need no verdict of 1x, a student's quick look)
    realtime_check: bool = True
    rtf_max: float = 0.0  # in a preview at rtf 0, the most sim seconds per wall second (0: no cap)
    strict_findings: str = ""  # the check-off's finding kinds that fail instead (bt_nav.judge.findings; "": none)


@dataclass(frozen=True)
class ExeSpec:
    """The user's command as a :class:`bt_nav.ros.supervise.Startable` (named ``node``)."""

    argv: tuple[str, ...]
    executable: str = "node"

    def command(self, python: str | None = None) -> list[str]:
        """The command as given, then its ROS arguments."""
        return list(self.argv)


def profile_remaps(profile: str) -> tuple[tuple[str, str], ...]:
    """The remaps a profile appends: its assignment's service names, from the root
    (:meth:`bt_nav.mission.assignments.Assignment.remaps`), for a node written against bt_nav's own (``arm``,
    ``evaluate_mission``); a remap of a name the node does not use changes nothing. None for a profile that is
    not an assignment's own (``turtlebot3``)."""
    assignment = ASSIGNMENTS.get(profile)
    return assignment.remaps(absolute=True) if assignment is not None else ()


def exe_ros_args(maneuver: str | None, profile: str = "homework",
                 node_params: tuple[tuple[str, Any], ...] = ()) -> list[str]:
    """What is appended to the user's command: sim time, the profile's remaps, the maneuver when the grid
    has maneuvers, and the ``--node-param`` parameters."""
    args = ["--ros-args", "-p", "use_sim_time:=true"]
    for name, target in profile_remaps(profile):
        args += ["-r", f"{name}:={target}"]
    if maneuver is not None:
        args += ["-p", param_arg("maneuver", maneuver)]
    for name, value in node_params:
        args += ["-p", param_arg(name, value)]
    return args


#: The simulator's pacing for a graded node (see the module docstring): its ``cmd_vel`` is followed (at most
#: ``max_lag`` sim s past its latest command or its own command period, and in any case until the next scan it
#: answers is out: :class:`bt_nav_sim.pacing.Followers`), a silence of ``follower_timeout`` wall seconds ends the wait.
FOLLOW_NODE: dict[str, Any] = {"follow": True, "cmd_vel_reliability": "best_effort", "follower_timeout": 1.0,
                               "max_lag": 0.05, "lead_margin": 0.05, "scan_floor": True}


def exe_graph(job: Job, settings: ExeSettings, results_json: Path) -> NodeSpec:
    """The simulator of ``job`` hosting its judge (the profile's graph without bt_nav's executive)."""
    assignment = assignment_of(settings.profile)
    lab = assignment.judge.executable == "checkoff"
    # its pace stops and how it kept real time, as data beside the verdict (bt_nav.grading.exe.pace reads them)
    sim: dict[str, Any] = {**FOLLOW_NODE, "cmd_vel_stamped": False, "pace_path": str(results_json.with_name(PACE_FILE)),
                           **sim_pace(settings.rtf, settings.rtf_max)}  # at rtf 0 no cap but --rtf-max
    if settings.jitter:
        sim.update({"spawn_jitter_m": float(settings.jitter[0]), "spawn_jitter_deg": float(settings.jitter[1])})
    sim.update(dict(job.sim_params))  # --sim-param and the grid's LiDAR, as lock-step gets them
    timeout = max(1.0, settings.limit - JUDGE_MARGIN)
    judge = {"wait_for_cmd_vel": False, "sync": False, "cmd_vel_stamped": False, "timeout": timeout,
             "start_wait": round(min(START_WAIT, timeout / 3.0), 1), "audit": True, "domain_guard": True,
             "robot_clock_wait": ROBOT_CLOCK_WAIT}
    if lab and job.lidar:  # the check-off reads "from the LiDAR": the robot's, from its mount
        judge["lidar"] = job.lidar
    if lab and settings.strict_findings:  # what the sheet only implies fails where the course teaches it
        judge["strict_findings"] = settings.strict_findings
    # the trigger the node was given (as a TA's launch file gives it) is the one it is judged by
    judge.update(assignment.judge.given(dict(job.params_over(settings.node_params)), assignment.judge.launch_shared))
    specs = nodes(assignment.graph, world=job.world, maneuver=job.maneuver if lab else None,
                  seed=job.seed, rtf=settings.rtf, results_json=str(results_json), sim=sim, referee=judge)
    sim_spec = host_judge([spec for spec in specs if spec.executable != "executive"])[0]
    if settings.rtf == REAL_TIME:  # the robot's world keeps real time beside a busy machine (pace.py)
        sim_spec = replace(sim_spec, arguments=[*sim_spec.arguments, "--nice", str(SIM_NICE)])
    return sim_spec


def _wait(session: MissionSession, sim: Child, node: Child, limit: float, started: float,
          results_json: Path) -> tuple[str, str, Crash | None]:
    """Wait for the judge's verdict file (``("verdict", "", None)``), or why there is none: ``(outcome, reason
    line, the node's crash)`` (:meth:`bt_nav.run.session.MissionSession.wait`, until ``started + limit``).

    A node that exits with 0 ended by itself (some call ``rclpy.shutdown()`` after their mission): the judge
    still judges what the robot did; any other exit code is a crash and ends the run now (:func:`_exit_reason`).
    """
    def watched(child: Child) -> bool:
        return child is sim or (child is node and node.poll() != 0)

    left = max(0.0, started + limit - time.monotonic())
    outcome, ended = session.wait(left, files_written([results_json]), watched=watched)
    if outcome == VERDICT:
        return "verdict", "", None
    if outcome == STOPPED:
        stop = session.stop
        return "stopped", f"stopped by {(stop.name if stop else '') or 'a stop request'}", None
    if outcome == EXITED and ended is node:
        code, wall = node.poll(), time.monotonic() - started
        node.thread.join(LOG_DRAIN)  # the traceback's last lines may still be in the pipe
        log = results_json.parent / f"{node.name}.log"
        crash = node_crash(log.read_text(errors="replace")) if log.is_file() else None
        return "node exited", _exit_reason(int(code or 0), wall, crash), crash
    if outcome == EXITED:
        wall = time.monotonic() - started
        return SIM_LOST, f"no verdict: {_sim_cause(sim, results_json.parent / f'{sim.name}.log', wall)}", None
    return "timeout", f"no verdict within {limit:g} s wall", None


#: The outcome of an attempt whose simulator ended before its verdict: bt_nav's own process, so never the node's
#: failure (:data:`OWN_FAULT`); the run is run again (:func:`bt_nav.grading.exe.grid.run_unless_stopped`).
SIM_LOST = "sim exited"
#: A row's key for an attempt that ended without a verdict for a cause of bt_nav's own (its one-line cause): the
#: fork server gone, the simulator killed by a signal the run did not send (a sibling's stop), or crashed.
OWN_FAULT = "bt_nav_fault"


#: The simulator's line when a signal stops it (:mod:`bt_nav.ros.runner`).
_SIGNAL_SAID = re.compile(r"\]: (SIG[A-Z]+) received: stopping")


def _sim_cause(sim: Child, log: Path, wall: float) -> str:
    """Why the simulator ended before its verdict (``wall`` s into the run), in one line. The run signals its
    processes only after the wait, so a signal that ended it came from outside the run: never the node's doing (a
    node cannot reach the simulator's process group), and not the simulator's own result either."""
    code = sim.poll()
    lost = getattr(sim.popen, "lost", "")
    if lost:
        return f"the simulator was lost: {lost} (see {log.name})"
    if code is not None and code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"the simulator was killed by {name} from outside the run after {wall:.1f} s wall " \
               f"(not the run's stop, not the node's; see {log.name})"
    sim.thread.join(LOG_DRAIN)  # its traceback's last lines may still be in the pipe
    text = log.read_text(errors="replace") if log.is_file() else ""
    caught = _SIGNAL_SAID.search(text)  # the simulator catches SIGINT and SIGTERM, stops and exits with 0
    if caught:
        return f"the simulator was stopped by {caught.group(1)} from outside the run after {wall:.1f} s wall " \
               f"(not the run's stop, not the node's; see {log.name})"
    found = last_traceback(text)
    said = f": {found[1][:200]}" if found and found[1] else ""
    return f"the simulator exited with code {code} without a verdict{said} (see {log.name})"


#: Wall seconds a crashed node's output is waited for (its pipe closes at once unless a child of its holds it).
LOG_DRAIN = 2.0


def _exit_reason(code: int, wall: float, crash: Crash | None) -> str:
    """Why a node that exited with ``code`` after ``wall`` seconds has no verdict: the exception that ended it and
    where its code raised it, from its traceback (:func:`bt_nav.grading.exe.log.node_crash`); without one (no
    traceback, or one that is not a crash of the node's), only the exit code."""
    if crash is None:
        return f"the node exited with code {code} after {wall:.1f} s wall, before the verdict (see node.log)"
    status = "" if code == 1 else f" (exit code {code})"  # 1: what Python exits with on an uncaught exception
    return f"the node crashed after {wall:.1f} s wall{status}: {crash.quote()}"


#: The outcome of a run without a verdict of the node's: bt_nav failed to run it (it raised), or it was not graded
#: (another program on every domain it could take). A failed row in the report, counted apart (never the node's
#: failure), run again by a resume.
ERROR = "bt_nav error"
#: The outcome of an attempt that found its domain shared; how many times a run moves to another domain.
SHARED_DOMAIN, DOMAIN_MOVES = "shared domain", 3


def _verdict_row(outcome: str, reason: str, sim: Child, results_json: Path) -> dict[str, Any]:
    """``passed``, ``reason`` and the judge's JSON (when it wrote one) of a finished run."""
    verdict = read_verdict(results_json)
    if outcome == "verdict":
        if verdict is None:
            reason = f"the judge's verdict could not be read (see {results_json.name} and {sim.name}.log)"
        elif verdict.get("foreign"):
            outcome, reason = SHARED_DOMAIN, f"no verdict: {verdict['foreign']}"
        elif verdict.get("not_started"):
            reason = "; ".join(filter(None, [f"not judged: {verdict['not_started']}", verdict.get("unjudged")]))
        elif verdict.get("timed_out"):
            reason = "the judge timed out: " + "; ".join(c["name"] for c in verdict.get("checks", [])
                                                        if not c.get("passed")) + " not met"
        else:
            reason = "passed" if verdict.get("passed") else failure_reason(verdict.get("checks", []))
    passed = outcome == "verdict" and verdict is not None and bool(verdict.get("passed"))
    # an attempt on a shared domain says nothing of the node (the audit saw the other program's endpoints too)
    findings = list(verdict.get("findings") or []) if verdict is not None and outcome != SHARED_DOMAIN else []
    return _with_findings({"passed": passed, "outcome": outcome, "reason": reason, "verdict": verdict}, findings)


def _with_findings(row: dict[str, Any], findings: list[str]) -> dict[str, Any]:
    """``row`` with ``findings`` added to its list and appended to its reason (what the judge's checks miss)."""
    row["findings"] = [*row.get("findings", []), *findings]
    if findings:
        row["reason"] = "; ".join([row["reason"], *findings])
    return row


#: Exit codes of a node that ended as asked by SIGINT: caught (0), or Python's own re-raised signal (-2, 130).
SIGINT_EXITS = (0, -int(signal.SIGINT), 128 + int(signal.SIGINT))


def _ending_findings(node: Child | None, log: Path | None = None) -> tuple[list[str], list[str]]:
    """How the node ended, when the judge cannot see it: by itself before the run was over, not on SIGINT, or
    crashing on the way out; and an import its interpreter could not make (``log``: its output). Second, the
    notes: what is not the node's to fix (rclpy's own shutdown race, :mod:`.log`; a first SIGINT lost)."""
    text = log.read_text(errors="replace") if log is not None and log.is_file() else ""
    found = import_findings(text)
    if node is None:
        return found, []
    code, notes = node.poll(), []
    if node.stopped_by == signal.SIGINT and node.sigints > 1:
        notes.append(f"the node stopped at the second SIGINT ({node.stop_seconds:.1f} s): its first was lost, as "
                     "one can be inside rclpy's executor; not held against it")
    if node.stopped_by is None and code == 0:
        found.append("the node ended by itself (exit code 0) before the run was over (see node.log)")
    elif node.stopped_by is not None and node.stopped_by != signal.SIGINT:
        found.append(f"the node ignored SIGINT (stopped by {node.stopped_by.name} after {node.stop_seconds:.1f} s)")
    elif node.stopped_by == signal.SIGINT and code not in SIGINT_EXITS:
        race = rclpy_shutdown_race(text)
        if race is None:
            found.append(f"the node crashed while shutting down (exit code {code} after SIGINT, see node.log): "
                         "catch KeyboardInterrupt/ExternalShutdownException and call rclpy.try_shutdown()")
        else:
            notes.append(f"the node exited with code {code} after SIGINT from inside rclpy's executor ({race}): "
                         "rclpy's own, not the node's code; not held against it")
    return found, notes


def run_exe_job(job: Job, settings: ExeSettings, stop: StopRequest | None = None,
                sink: Callable[[str, str], None] | None = None,
                on_start: Callable[[int, Path], None] | None = None,
                on_verdict: Callable[[], None] | None = None) -> dict[str, Any]:
    """One run of the grid (see the module docstring); its row, also written to ``result.json``.

    ``sink`` also gets every line of every process (after its log file: ``bt-nav demo --exe`` shows them);
    ``on_start`` is called with the run's domain and directory before any process starts (the demo's clock node);
    ``on_verdict`` once the run's outcome is known, before its processes are stopped (the grid's next run may start
    while this one shuts down: stopping is waiting, not work).

    A program that is neither the node nor one of its children on the run's domain (:mod:`bt_nav.ros.domain_guard`)
    ends the attempt without a verdict; the run starts again on a free domain (the shared one held until the job
    ends, so no attempt picks it again), up to :data:`DOMAIN_MOVES` times, and its row's ``notes`` say which. With
    no free domain left (``BT_NAV_DOMAIN_RANGE`` of one domain, every other one claimed) the run is not graded
    (:func:`not_graded_row`): never the node's failure, never re-run at 1x, run again by ``--resume``.

    A run that finds every domain claimed before it starts (more ``--jobs`` than domains, other grades) waits for
    one (:func:`domain_wait`); none coming free, it is not graded either (:func:`no_domain_row`).
    """
    moves: list[str] = []
    tried: list[int] = []
    # the domains claimed, held until the job ends: the last the run's, the others found shared
    with DomainLease(start=hash(job.key), user_env=False) as lease:
        try:
            domain = lease.claim(domain_wait(settings), stop)
        except NoFreeDomainError as exc:
            return no_domain_row(job, settings, exc, stop)
        while True:
            tried.append(domain)
            row = _attempt(job, settings, domain, stop, sink, on_start, on_verdict)
            if row["outcome"] != SHARED_DOMAIN:
                break
            following = None
            if len(moves) < DOMAIN_MOVES:
                with suppress(NoFreeDomainError):  # none free now: not graded, never another run's domain
                    following = lease.claim()
            if following is None:
                row = not_graded_row(row, tried, len(moves) >= DOMAIN_MOVES)
                break
            aside = _set_aside(Path(row["run_dir"]))
            moves.append(f"{row['reason']}: the run started again on ROS_DOMAIN_ID {following} (that attempt on "
                         f"{domain}: {aside})")
            domain = following
    if moves:
        row["notes"] = [*moves, *row.get("notes", [])]
        (Path(row["run_dir"]) / "result.json").write_text(json.dumps(row, indent=1) + "\n", encoding="utf-8")
    return row


#: The errors of a command that cannot start (its program not there, not executable, not a program): the node's
#: verdict. Any other (EAGAIN, ENOMEM: a busy machine) is bt_nav's, and the run is run again.
COMMAND_ERRORS = (errno.ENOENT, errno.EACCES, errno.ENOEXEC, errno.ENOTDIR, errno.EISDIR, errno.ELOOP,
                  errno.ENAMETOOLONG, errno.EPERM)


#: Wall seconds a run waits for a free domain beyond its own limit: another run's shutdown (its processes get
#: :data:`STOP_GRACE` and 2 s each, the node first) and its bag's closing.
DOMAIN_WAIT_MARGIN = 30.0


def domain_wait(settings: ExeSettings) -> float:
    """How long a run waits for a free domain: a run's limit and :data:`DOMAIN_WAIT_MARGIN`, counted again from
    each domain this process's runs hand back (:func:`bt_nav.ros.supervise.claim_domain_id`), so a grid with more
    ``--jobs`` than domains grades them all as its runs end, and domains held elsewhere for longer end the wait."""
    return settings.limit + DOMAIN_WAIT_MARGIN


def no_domain_row(job: Job, settings: ExeSettings, exc: NoFreeDomainError, stop: StopRequest | None) -> dict[str, Any]:
    """The row of a run that never started for want of a domain: not graded (:data:`ERROR`, as
    :func:`not_graded_row`: counted apart, never the node's failure, run again by ``--resume``), or stopped when a
    stop ended its wait. No run directory (nothing ran)."""
    row = {"passed": False, "verdict": None, "findings": [], "job": job.key, "world": job.world,
           "maneuver": job.maneuver, "lidar": job.lidar, "seed": job.seed, "profile": settings.profile,
           "run_dir": "", "wall_time": round(exc.waited, 2), "domains": []}
    if stop is not None and stop.requested:
        return {**row, "outcome": "stopped", "reason": f"stopped by {stop.name or 'a stop request'} while waiting "
                                                       "for a free ROS domain"}
    said = f"not graded: {exc}: not the node's failure, --resume runs it again"
    return {**row, "outcome": ERROR, "reason": said, "not_graded": said}


def not_graded_row(row: dict[str, Any], tried: list[int], moved_enough: bool) -> dict[str, Any]:
    """The row of a run that found another program on every domain it could take (``tried``, in order): not
    graded. Its outcome is :data:`ERROR`, counted apart from the node's verdicts
    everywhere a bt_nav error is (the pass rate, the exit code, ``--resume`` runs it again); ``not_graded`` says
    why, for the reports (an autograder error, never a score)."""
    domains = ", ".join(str(d) for d in tried)
    if moved_enough:
        why = f"the run moved {len(tried) - 1} times and found another program each time (ROS_DOMAIN_ID {domains})"
    else:
        low, high = launcher_domains()
        why = (f"no other domain was free to move to (tried ROS_DOMAIN_ID {domains}; {DOMAIN_RANGE_ENV} "
               f"{low}-{high})")
    said = f"not graded: {row['reason'].removeprefix('no verdict: ')}; {why}: not the node's failure, --resume " \
           "runs it again"
    graded = {**row, "passed": False, "outcome": ERROR, "reason": said, "not_graded": said, "domains": list(tried)}
    (Path(row["run_dir"]) / "result.json").write_text(json.dumps(graded, indent=1) + "\n", encoding="utf-8")
    return graded


def _set_aside(run_dir: Path, kind: str = "shared-domain") -> Path:
    """Move an abandoned attempt's directory out of the run's name (kept: its logs show the other program, or what
    ended it)."""
    aside = make_run_dir(run_dir.parent, f"{run_dir.name}.{kind}")
    aside.rmdir()
    run_dir.rename(aside)
    return aside


def set_aside_own_fault(row: dict[str, Any]) -> str:
    """An attempt without a verdict for a cause of bt_nav's own (:data:`OWN_FAULT`), to be run again: its directory
    set aside (its ``result.json`` then says :data:`ERROR`, so ``--resume`` never keeps it as the run's result);
    the one-line note its run's row gets."""
    said = f"no verdict: {row[OWN_FAULT]}: bt_nav's, not the node's"
    if not row.get("run_dir"):
        return f"{said}: the run started again"
    aside = _set_aside(Path(row["run_dir"]), "bt_nav-fault")
    (aside / "result.json").write_text(json.dumps({**row, "passed": False, "outcome": ERROR, "run_dir": str(aside)},
                                                  indent=1) + "\n", encoding="utf-8")
    return f"{said}: the run started again (that attempt: {aside})"


def own_fault_not_graded(row: dict[str, Any], attempts: int) -> dict[str, Any]:
    """The row of a run whose every attempt (``attempts``) ended without a verdict for a cause of bt_nav's own: not
    graded (:data:`ERROR`, ``not_graded``: an autograder error, never a 0; ``--resume`` runs it again), its reason
    one line naming the last cause."""
    said = f"not graded: no verdict in {attempts} attempts, each ended by bt_nav's own fault (last: " \
           f"{row[OWN_FAULT]}): not the node's failure, --resume runs it again"
    return with_notes({**row, "passed": False, "outcome": ERROR, "reason": said, "not_graded": said}, [])


def with_notes(row: dict[str, Any], notes: list[str]) -> dict[str, Any]:
    """``row`` with ``notes`` before its own (what happened to the run that is not the node's), written again to its
    ``result.json``."""
    if notes:
        row["notes"] = [*notes, *row.get("notes", [])]
    result = Path(row.get("run_dir") or "") / "result.json"
    if row.get("run_dir") and result.parent.is_dir():
        result.write_text(json.dumps(row, indent=1) + "\n", encoding="utf-8")
    return row


def _attempt(job: Job, settings: ExeSettings, domain: int, stop: StopRequest | None,
             sink: Callable[[str, str], None] | None, on_start: Callable[[int, Path], None] | None,
             on_verdict: Callable[[], None] | None) -> dict[str, Any]:
    """One attempt of a run on ``domain``: its processes, its verdict, its row."""
    lidar = f"_{job.lidar}" if job.lidar else ""
    run_dir = make_run_dir(settings.out, f"{job.world}_{job.maneuver}{lidar}_seed{job.seed}")
    results_json = run_dir / "verdict.json"
    # the simulator forked from the grid's fork server when there is one (bt_nav.ros.forkserver); the node is started
    session = MissionSession(domain, run_dir=run_dir, tee=sink, stop=stop, driver="node", forker=forkserver.current())
    argv = (*shlex.split(settings.command), *exe_ros_args(job.maneuver if settings.maneuvers else None,
                                                          settings.profile, job.params_over(settings.node_params)))
    started = time.monotonic()
    node = None
    try:
        if on_start is not None:
            on_start(domain, run_dir)
        sim_spec = exe_graph(job, settings, results_json)
        if settings.record != "off":  # written by the simulator's process (bt_nav.grading.exe.bag says why)
            sim_spec.arguments += record_args(run_dir)
        try:
            node = session.start(ExeSpec(argv), cwd=settings.cwd)
        except OSError as exc:  # not found, not executable: a verdict, not a crash of the grid
            if exc.errno not in COMMAND_ERRORS:
                raise  # EAGAIN, ENOMEM: the machine's, not the command's; the run is run again
            row = {"passed": False, "outcome": "node exited", "reason": f"the command did not start: {exc}",
                   "verdict": None}
        else:
            sim = session.start(sim_spec)
            # the limit counts from the simulator's start (a fork server's hello may have held it back)
            limit = settings.limit + time.monotonic() - started
            outcome, reason, crash = _wait(session, sim, node, limit, started, results_json)
            row = _verdict_row(outcome, reason, sim, results_json)
            if crash is not None:  # the row's crash, for the reports
                row["crash"] = asdict(crash)
        if on_verdict is not None:
            on_verdict()
    finally:
        # the verdict is in (or never will be): the node first, while its world runs on and records (the bag holds
        # what the node sends on its way out); then the rest at once
        session.close(STOP_GRACE, together=True, first=node)
    if row["outcome"] == SIM_LOST:  # bt_nav's, not the node's: run again (grid.run_unless_stopped)
        row[OWN_FAULT] = row["reason"].removeprefix("no verdict: ")
    if row["outcome"] not in ("stopped", SHARED_DOMAIN, SIM_LOST):  # how its node ended is not the node's to answer
        findings, notes = _ending_findings(node, run_dir / "node.log")
        _with_findings(row, findings)
        if notes:
            row["notes"] = notes
    row.update({"job": job.key, "world": job.world, "maneuver": job.maneuver, "lidar": job.lidar, "seed": job.seed,
                "cell_params": dict(job.node_params), "node_params": dict(job.params_over(settings.node_params)),
                "profile": settings.profile, "command": list(argv), "domain": domain, "run_dir": str(run_dir),
                "wall_time": round(time.monotonic() - started, 2)})
    row.update(bag_row(run_dir, settings.record != "off", (row.get("verdict") or {}).get("t0_sim")))
    (run_dir / "result.json").write_text(json.dumps(row, indent=1) + "\n", encoding="utf-8")
    return row
