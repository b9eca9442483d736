"""One mission over DDS from start to stop: the one layer every path that runs a ROS graph goes through.

``bt-nav grade --exe`` (:mod:`bt_nav.grading.exe.run`, and ``bt-nav demo --exe`` through it), ``bt-nav demo`` and
its lab check-off (:class:`bt_nav.run.rosmission.RosMission`), ``bt-nav sim-run``
(:func:`bt_nav.run.rosmission.run_graph`) and the ROS benchmark (:mod:`bench.ros_mission`) each start, watch and
stop their processes here, so "which domain, which files, which processes, is there a verdict yet" is written once:

- :class:`DomainLease`: the run's ROS domain (the user's, or one claimed for the run alone, handed back at the end;
  a run that finds its domain shared claims another while still holding the first; with every domain claimed, it
  waits for one or gets none, never another run's);
- :class:`MissionSession`: the children's environment in that domain, the run directory's log files (one
  ``<name>.log`` per process, :class:`bt_nav.run.rundir.LogFiles`), one :class:`bt_nav.ros.supervise.Launcher`, the
  one verdict wait (:meth:`MissionSession.wait`) and the stop of everything (:meth:`MissionSession.close`);
- :func:`read_verdict`: the one reader of a judge's verdict file.

Recorders in this process (the demo's) are :class:`~bt_nav.run.rosmission.RosMission`'s, on top of a session; a
recorder process (a graded run's bag) is one more child of the session's launcher.
"""

from __future__ import annotations

import json
import os
import random
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bt_nav.ros.supervise import (
    DOMAIN_RANGE_ENV,
    Child,
    Launcher,
    LineSink,
    Startable,
    StopRequest,
    child_env,
    claim_domain_id,
    launcher_domains,
    release_domain_id,
)
from bt_nav.run.rundir import LogFiles

if TYPE_CHECKING:
    from bt_nav.ros.forkserver import ForkServer

#: What :meth:`MissionSession.wait` returns first: the verdict is in, a watched process ended before it, a stop
#: request came, or the time ran out.
VERDICT, EXITED, STOPPED, TIMEOUT = "verdict", "exited", "stopped", "timeout"


class DomainLease:
    """The ROS domains one run holds (:mod:`bt_nav.ros.supervise` says why a run needs one of its own).

    Args:
        requested: the user's domain (``--domain-id``): kept as it is, never claimed nor released.
        start: where the search for a free domain starts (default: anywhere); a later claim of the same lease starts
            one further on, so a run that moves does not come back to the domain it left.
        user_env: take ``$ROS_DOMAIN_ID`` as the user's choice (the demo and ``sim-run`` do; a grid's runs never:
            one domain per run).
    """

    def __init__(self, requested: int | None = None, *, start: int | None = None, user_env: bool = True) -> None:
        self.requested = requested
        self.start = start
        self.user_env = user_env
        self.held: list[int] = []  # claimed by this lease, handed back by release()

    def claim(self, wait: float = 0.0, stop: StopRequest | None = None) -> int:
        """The run's domain: the user's (``requested``, else ``$ROS_DOMAIN_ID`` with ``user_env``), else one of
        :func:`bt_nav.ros.supervise.launcher_domains` no other run on this machine holds, claimed until
        :meth:`release` (every domain claimed before is still held, so no other run takes a shared one). With every
        one claimed, waits for one up to ``wait`` wall seconds (:func:`bt_nav.ros.supervise.claim_domain_id`; a
        ``stop`` ends the wait).

        Raises:
            NoFreeDomainError: none came free (a ValueError; its words name ``BT_NAV_DOMAIN_RANGE``): never a domain
                this lease did not claim.
        """
        if self.requested is not None:
            return int(self.requested)
        env = os.environ.get("ROS_DOMAIN_ID", "").strip()
        if self.user_env and env.isdigit():
            return int(env)
        low, high = launcher_domains()
        start = random.randrange(high - low + 1) if self.start is None else self.start
        domain = claim_domain_id(low, high, start=start + len(self.held), wait=wait, stop=stop,
                                 range_name=DOMAIN_RANGE_ENV)
        self.held.append(domain)
        return domain

    def release(self) -> None:
        """Hand back every domain this lease claimed (a long grid would otherwise run out of them)."""
        while self.held:
            release_domain_id(self.held.pop())

    def __enter__(self) -> DomainLease:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


class MissionSession:
    """The processes of one mission in one ROS domain: started, watched until the verdict, stopped.

    Args:
        domain: the run's domain (:meth:`DomainLease.claim`); the children get :func:`~bt_nav.ros.supervise.child_env`
            for it, plus ``env``.
        run_dir: the run's directory (:func:`bt_nav.run.rundir.make_run_dir`): with it and no ``logs``, one
            ``<name>.log`` per process there (:class:`~bt_nav.run.rundir.LogFiles`).
        logs: the run's log files when the caller made them (the demo's stamped :class:`~bt_nav.run.rundir.Logs`).
        sink: where lines go instead of ``logs`` (the lab's terminal, which writes them to ``logs`` itself);
            ``tee``: where every line also goes, after its log file (``bt-nav demo --exe``'s terminal).
        stop, last_word, driver, forker: as :class:`bt_nav.ros.supervise.Launcher`'s.
    """

    def __init__(self, domain: int, *, run_dir: Path | None = None, logs: LogFiles | None = None,
                 sink: LineSink | None = None, tee: LineSink | None = None, env: Mapping[str, str] | None = None,
                 stop: StopRequest | None = None, last_word: Callable[[], Any] | None = None,
                 driver: str = "executive", forker: ForkServer | None = None) -> None:
        self.domain = domain
        self.run_dir = run_dir
        self.logs = logs if logs is not None or run_dir is None else LogFiles(run_dir)
        self.env = {**child_env(domain), **(env or {})}
        self.stop = stop
        first = sink or (self.logs.sink if self.logs is not None else None)
        self.launcher = Launcher(self.env, sink=_both(first, tee), stop=stop, last_word=last_word, driver=driver,
                                 forker=forker)
        self.sink = self.launcher.sink

    @property
    def children(self) -> list[Child]:
        """The processes started so far, in start order."""
        return self.launcher.children

    def start(self, spec: Startable, sink: LineSink | None = None, cwd: str | None = None) -> Child:
        """Start one process (its lines to ``sink``, default the session's)."""
        return self.launcher.start(spec, sink=sink, cwd=cwd)

    def stopped(self) -> bool:
        """A stop request came (Ctrl-C, SIGTERM)."""
        return self.stop is not None and self.stop.requested

    def ended(self, watched: Callable[[Child], bool] | None = None) -> Child | None:
        """The first process (in start order) that has exited and is ``watched`` (default: any); None: none."""
        return next((c for c in self.children if c.poll() is not None and (watched is None or watched(c))), None)

    def wait(self, timeout: float | None, verdict: Callable[[], bool], *,
             watched: Callable[[Child], bool] | None = None, poll: Callable[[], None] | None = None,
             interval: float = 0.05) -> tuple[str, Child | None]:
        """The one verdict wait: until ``verdict()`` (``(VERDICT, None)``), a stop request (``(STOPPED, None)``), a
        ``watched`` process's end (``(EXITED, child)``; a verdict written just before a process ended still counts)
        or ``timeout`` wall seconds (``(TIMEOUT, None)``; None: no limit). ``poll`` runs every ``interval`` s.
        ``verdict`` may be any condition the run waits for the same way (the demo's recorders seeing the robot).

        A verdict already in wins over a stop request: it is the run's answer; the stop only ends the wait."""
        end = None if timeout is None else time.monotonic() + timeout
        while end is None or time.monotonic() < end:
            if verdict():
                return VERDICT, None
            if self.stopped():
                return STOPPED, None
            ended = self.ended(watched)
            if ended is not None:
                return (VERDICT, None) if verdict() else (EXITED, ended)
            if poll is not None:
                poll()
            time.sleep(interval)
        return TIMEOUT, None

    def close(self, grace: float = 5.0, **shutdown: Any) -> None:
        """Stop every process (:meth:`bt_nav.ros.supervise.Launcher.shutdown`'s ``grace`` and options), then close
        the log files."""
        try:
            self.launcher.shutdown(grace, **shutdown)
        finally:
            if self.logs is not None:
                self.logs.close()


def _both(first: LineSink | None, then: LineSink | None) -> LineSink | None:
    """A sink that gives each line to ``first``, then to ``then`` (either may be None)."""
    if first is None or then is None:
        return first or then

    def sink(name: str, line: str) -> None:
        first(name, line)
        then(name, line)

    return sink


def files_written(paths: list[Path]) -> Callable[[], bool]:
    """A :meth:`MissionSession.wait` verdict: every one of ``paths`` is a file (the judges write theirs whole)."""
    return lambda: all(path.is_file() for path in paths)


def read_verdict(path: Path) -> dict[str, Any] | None:
    """A judge's verdict file (its JSON object); None while there is none or it cannot be read."""
    try:
        verdict = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return verdict if isinstance(verdict, dict) else None
