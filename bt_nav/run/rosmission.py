"""A mission over real DDS, for one robot or several: start the graph, a recorder per robot, the referees
(or the lab's check-off judge: every judge of :data:`bt_nav.ros.bringup.JUDGES`) once every robot is seen,
wait for every verdict, collect. One robot's judge is hosted by the simulator's process
(:mod:`bt_nav.ros.nodes.hosting`: fed by its loop, measured 37-38x -> 56x real time for the simulator, executive
and referee alone); it starts with the graph, and its t0 waits for this process's recorder to subscribe ground truth
(``truth_readers``), so the recording still holds the whole schedule; its verdict is its JSON file.

``bt-nav demo`` and the ROS benchmark (:mod:`bench.ros_mission`) both run a mission through
:class:`RosMission`, so "start the graph, wait for the recorder, start the referee, wait for the verdict"
is written once; ``bt-nav sim-run`` starts a graph without recorders and watches it until a node ends
(:func:`run_graph`); ``bt-nav grade --exe`` runs a foreign node in a run of its own
(:mod:`bt_nav.grading.exe.run`). All of them start, watch and stop their processes through one
:class:`bt_nav.run.session.MissionSession` (domain, log files, launcher, the verdict wait) and read a verdict with
its :func:`~bt_nav.run.session.read_verdict`. One robot is the
graph of :func:`bt_nav.ros.bringup.nodes` (the homework's root topics);
several are :func:`bt_nav.ros.bringup.robot_nodes` (one simulator, per robot an executive and a referee
in the robot's namespace). The referees start last, once every recorder sees its robot's ground truth and
commands, so each recording covers the whole schedule.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bt_nav.ros.bringup import JUDGES, NodeSpec, cmd_vel_stamped, host_judge, nodes, robot_nodes
from bt_nav.ros.supervise import Child, LineSink, StopRequest, publish_zero_twist, use_domain_here
from bt_nav.run.recorder import Recorder, Recording, rec_ready
from bt_nav.run.rundir import LOG_FORMAT, Logs
from bt_nav.run.session import EXITED, STOPPED, VERDICT, MissionSession, files_written, read_verdict

#: Extra wall time allowed beyond the referees' own timeout before the run gives up itself.
GRACE = 15.0
#: Wall seconds a hosted judge's report may take to be read from the simulator's output after its verdict file.
REPORT_WAIT = 1.0
#: Wall time to wait for the recorders to see ground truth and commands before starting the referees anyway.
STARTUP = 30.0


def mission_graph(names: list[str], results: dict[str, str], profile: str = "eval", **options: Any) -> list[NodeSpec]:
    """The judged graph of ``profile`` (``eval``: the homework and its referee; ``checkoff``: the lab and its
    judge) for ``names`` (one robot: root topics, its judge's verdict to ``results[name]``; several:
    namespaced), with :func:`bt_nav.ros.bringup.nodes`' ``options``."""
    if len(names) == 1:
        # t0 once our recorder reads ground truth; no sequence numbers for the audit, so the simulator hosting the
        # judge spins the EventsExecutor (measured 38-42x -> 44-48x real time; a flood is not bt_nav's executive's)
        options["referee"] = {"truth_readers": 1, "audit_message_info": False, **(options.get("referee") or {})}
        return host_judge(nodes(profile, results_json=results[names[0]], **options))
    return robot_nodes(profile, names, results_json=results, **options)


class RosMission:
    """The processes and recorders of one mission over DDS (see the module docstring).

    Args:
        specs: the graph (:func:`mission_graph`); its referees are the nodes whose executable is a judge
            (``referee`` or ``checkoff``).
        names: the robots' names; with one robot its recorder listens at the root topics.
        session: the run's processes (:class:`bt_nav.run.session.MissionSession`: its domain, its sink, its stop
            request); a node in a robot's namespace is named ``<robot>_<node>`` in the session's sink, its report
            lines prefixed ``<robot>: ``.
        verdicts: the judges' JSON files (:func:`mission_graph`'s ``results`` values): a graph whose judge is hosted
            by the simulator (no judge process) has its verdicts when they are all written.
    """

    def __init__(self, specs: list[NodeSpec], names: list[str], session: MissionSession, *,
                 verdicts: list[str] | None = None) -> None:
        self.specs = specs
        self.hosted = not any(spec.executable in JUDGES for spec in specs)
        self.verdicts = [Path(v) for v in verdicts or ()]
        if self.hosted and not self.verdicts:
            raise ValueError("a graph whose judge the simulator hosts needs its verdict files")
        self._printed: set[str] = set()
        self._lock = threading.Lock()
        self._written_at: float | None = None
        self.names = names
        self.recorders = {name: Recorder(name if len(names) > 1 else "") for name in names}
        self.session = session
        self.launcher = session.launcher
        self.stop = session.stop
        self.referees: list[Child] = []

    def _start(self, spec: NodeSpec) -> Child:
        """Start one node; in a robot's namespace its log name and report lines carry the robot's name."""
        robot, parent = spec.namespace, self.launcher.sink

        def sink(name: str, line: str) -> None:
            is_log = line.startswith(("[", "@"))  # "@<ns> [INFO] ...": a log line stamped (rundir.LOG_FORMAT)
            if self.hosted and not is_log:
                with self._lock:
                    self._printed.add(line)  # the hosted judge's report lines (see _judged)
            if not robot:
                parent(name, line)
            else:
                parent(f"{robot}_{name}", line if is_log else f"{robot}: {line}")

        return self.launcher.start(spec, sink=sink)

    def _stopped(self) -> bool:
        return self.session.stopped()

    def start_graph(self) -> None:
        """Every node but the referees."""
        for spec in self.specs:
            if spec.executable not in JUDGES:
                self._start(spec)

    def wait_ready(self, timeout: float = STARTUP) -> bool:
        """Wait until every recorder sees its robot (False: timed out, a node exited, or a stop request)."""
        seen = self.session.wait(timeout, lambda: all(rec_ready(r) for r in self.recorders.values()),
                                 watched=self._watched, interval=0.02)
        return seen[0] == VERDICT

    def start_referees(self) -> list[Child]:
        """The referees (their clocks start once they see their robot)."""
        self.referees = [self._start(spec) for spec in self.specs if spec.executable in JUDGES]
        return self.referees

    def exited(self) -> Child | None:
        """A node other than a referee that has exited (None: all running)."""
        return self.session.ended(self._watched)

    def _watched(self, child: Child) -> bool:
        """Whose end, before the verdict, ends the run: every node but a referee (whose end is its verdict)."""
        return child not in self.referees

    def wait_verdicts(self, timeout: float, poll: Callable[[], None] | None = None) -> tuple[str, Child | None]:
        """Wait until every referee has exited (hosted: every verdict file is written): ``("verdict", None)``;
        or ``("exited", child)`` when another node exited first, ``("timeout", None)``, ``("stopped", None)``
        (:meth:`bt_nav.run.session.MissionSession.wait`). ``poll`` runs every 50 ms."""
        return self.session.wait(timeout, self._judged, watched=self._watched, poll=poll)

    def _judged(self) -> bool:
        """Every referee has exited; hosted: every verdict file is written and its report read from the simulator's
        output (it is printed just before the file is written, but read by another thread of this process: a line
        of ours printed after the verdict must come after the report), or ``REPORT_WAIT`` s have passed."""
        if not self.hosted:
            return all(r.poll() is not None for r in self.referees)
        if not files_written(self.verdicts)():
            return False
        now = time.monotonic()
        self._written_at = self._written_at or now
        with self._lock:
            read = all(_last_report_line(path) in self._printed for path in self.verdicts)
        return read or now - self._written_at > REPORT_WAIT

    def supervise(self, timeout: float, run_dir: Path) -> int:
        """Start the nodes, the referees once every robot is seen, wait for every verdict (``timeout`` wall s);
        the exit code: the referees' (:meth:`referee_code`), 2 without a verdict, 128 + signal when stopped.
        Why a node ended the run early goes to stderr, naming its log in ``run_dir``."""
        self.start_graph()
        self.wait_ready(STARTUP)
        if self._stopped():
            return self._stop_code()
        self.start_referees()
        outcome, child = self.wait_verdicts(timeout)
        if outcome == VERDICT:
            return self.referee_code()
        if outcome == STOPPED:
            return self._stop_code()
        if outcome == EXITED and child is not None:
            where = f"{child.spec.namespace}_{child.name}" if child.spec.namespace else child.name
            print(f"bt-nav demo: {where} exited with {child.poll()} before the verdict; see "
                  f"{run_dir / (where + '.log')}", file=sys.stderr)
        else:
            print(f"bt-nav demo: no verdict within {timeout:g} s wall; stopping", file=sys.stderr)
        return 2

    def _stop_code(self) -> int:
        stop = self.stop
        print(f"bt-nav demo: {(stop.name if stop else '') or 'SIGINT'}: stopping every node", file=sys.stderr)
        return 128 + int((stop.signum if stop else 2) or 2)

    def referee_code(self) -> int:
        """0 when every referee passed its robot, else the worst exit code (1 FAILED, 2 no verdict)."""
        if self.hosted:
            return max((_verdict_code(path) for path in self.verdicts), default=2)
        return max((int(r.poll() or 0) for r in self.referees), default=2)

    def close(self) -> dict[str, Recording]:
        """Stop every node (and close the session's log files), then the recorders; each robot's recording."""
        try:
            self.session.close()
        finally:
            recordings = {name: rec.close() for name, rec in self.recorders.items()}
        return recordings


def demo_mission(specs: list[NodeSpec], names: list[str], verdicts: list[str], domain: int, logs: Logs, *,
                 sink: LineSink | None = None) -> RosMission:
    """The mission of ``bt-nav demo`` (and of its lab check-off) in ``domain``: this process joins the domain (its
    recorders), the nodes log with the wall time of each line (:data:`~bt_nav.run.rundir.LOG_FORMAT`, which ``logs``
    maps to sim time by the first robot's recorder), a stop request is installed (the caller restores
    ``mission.stop``), and each robot whose executive did not end cleanly is left with a zero twist. ``sink``: where
    the lines go instead of ``logs`` (the lab's terminal)."""
    use_domain_here(domain)
    stamped = cmd_vel_stamped(specs)
    topics = [f"/{n}/cmd_vel" for n in names] if len(names) > 1 else ["/cmd_vel"]
    session = MissionSession(domain, run_dir=logs.directory, logs=logs, sink=sink,
                             env={"RCUTILS_CONSOLE_OUTPUT_FORMAT": LOG_FORMAT}, stop=StopRequest().install(),
                             last_word=lambda: [publish_zero_twist(domain, topic=t, stamped=stamped) for t in topics])
    mission = RosMission(specs, names, session, verdicts=verdicts)
    logs.sim_time = mission.recorders[names[0]].sim_time
    logs.clock = mission.recorders[names[0]].clock
    return mission


def run_graph(specs: list[NodeSpec], domain: int, stop: StopRequest,
              on_early_exit: Callable[[Child], None] | None = None) -> int:
    """Start ``specs`` in ``domain`` and watch them until one ends or ``stop`` is requested (``bt-nav sim-run``);
    then stop every node, the executive's robot left with a zero twist. The exit code: the judge's when it ended
    (or the first node's to end, without a judge), that of a node that ended before the judge (1 for 0, after
    ``on_early_exit`` is told of it). The caller installs and restores ``stop`` and says what a stop means."""
    stamped = cmd_vel_stamped(specs)
    session = MissionSession(domain, stop=stop, last_word=lambda: publish_zero_twist(domain, stamped=stamped))
    code = 0
    try:
        for spec in specs:
            session.start(spec)
        judge = next((c for c in session.children if c.spec.executable in JUDGES), None)
        outcome, ended = session.wait(None, lambda: judge is not None and judge.poll() is not None)
        if outcome == VERDICT and judge is not None:
            code = judge.poll() or 0
        elif outcome == EXITED and ended is not None:
            if judge is not None:
                if on_early_exit is not None:
                    on_early_exit(ended)
                code = ended.poll() or 1
            else:
                code = ended.poll() or 0
    except KeyboardInterrupt:
        stop.signum = stop.signum or 2
    finally:
        stop.closing = True
        session.close()
    return code


def _last_report_line(path: Path) -> str | None:
    """The last line of a verdict file's report (None: none, or unreadable)."""
    lines = (read_verdict(path) or {}).get("report_lines") or []
    return lines[-1] if lines else None


def _verdict_code(path: Path) -> int:
    """A hosted judge's exit code, as its verdict file gives it (``exit_code``): 0 PASSED, 1 FAILED, 2 none."""
    code = (read_verdict(path) or {}).get("exit_code")
    return code if isinstance(code, int) and not isinstance(code, bool) else 2
