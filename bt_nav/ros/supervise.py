"""One home for running bt_nav processes: DDS isolation, stop signals and child supervision.

Every launcher (``bt-nav demo``, ``bt-nav sim-run``, the bench) and every node process shares three
concerns, and each has exactly one implementation here:

- **DDS isolation** (:func:`dds_env`, :func:`child_env`, :func:`choose_domain_id`,
  :func:`claim_domain_id`, :func:`domain_id_for`): discovery stays on this machine
  (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) and every run gets a ROS domain no concurrent run
  holds, unless the user chose one. Two runs in one domain see each other's ``/clock``,
  ``ground_truth_odom`` and services, and a referee summing two robots' poses reports distances no
  robot drove.
- **Stop signals** (:class:`StopRequest`): SIGINT, SIGTERM and SIGHUP set a flag instead of tearing the
  process down mid-callback, so a node can publish its last zero twist while its ROS context is
  still up. Installed explicitly, so a process started in the background by a non-interactive shell
  (which starts it with SIGINT *ignored*) still reacts to SIGINT.
- **Children that cannot outlive their launcher** (:class:`Launcher`): each child runs in its own
  session and process group (a terminal's Ctrl-C reaches only the launcher, which stops the children
  in order), asks the kernel for SIGTERM when the launcher dies (``PR_SET_PDEATHSIG``, set in the
  child between fork and exec) and also watches a pipe whose write end only the launcher holds
  (:func:`watch_parent_pipe`, started by the ``bt-nav`` dispatcher): when the launcher is gone,
  even by SIGKILL, the child receives SIGTERM, stops the robot and exits; a child that does not exit
  within :data:`ORPHAN_GRACE` seconds kills itself.

No rclpy at import: launch files and the dispatcher import this module cheaply. Only
:func:`publish_zero_twist` imports rclpy, when it is called.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from types import FrameType
from typing import IO, Any, Protocol

from bt_nav.mission.resources import written_whole
from bt_nav.ros.domain_guard import RUN_MARK_ENV, run_mark
from bt_nav.ros.forkserver import ForkedProcess, ForkServer, ForkServerError
from bt_nav.ros.parentdeath import die_with_parent, libc_prctl

# ---------------------------------------------------------------------------------------------- DDS env
#: Where launchers claim a domain when the user set none (override: ``BT_NAV_DOMAIN_RANGE=LOW-HIGH``).
LAUNCHER_DOMAINS = (100, 199)
DOMAIN_RANGE_ENV = "BT_NAV_DOMAIN_RANGE"

#: Lock files of the domains this process claimed; kept open so that the claims last until it exits.
_DOMAIN_CLAIMS: list[Any] = []


def domain_id_for(key: str | int, low: int = 100, high: int = 199) -> int:
    """A ROS domain in ``[low, high]`` derived from ``key`` (a pid, a worker name): stable per key."""
    import zlib

    if isinstance(key, int):
        return low + key % (high - low + 1)
    return low + zlib.crc32(key.encode()) % (high - low + 1)


class NoFreeDomainError(ValueError):
    """Every ROS domain of a range is claimed by another run on this machine (after waiting, if the claimer waited).

    A ValueError, as a malformed ``BT_NAV_DOMAIN_RANGE`` is (:func:`launcher_domains`): the launchers report either
    as why a run cannot start. Never a domain handed out unclaimed instead: it may be another run's, and two runs in
    one domain see each other's topics and services."""

    def __init__(self, low: int, high: int, waited: float = 0.0, range_name: str = "range") -> None:
        self.low, self.high, self.waited, self.range_name = low, high, waited, range_name
        waiting = f"; waited {waited:.1f} s" if waited > 0.0 else ""
        super().__init__(f"no free ROS_DOMAIN_ID in {range_name} {low}-{high} (each one is claimed by another run "
                         f"on this machine{waiting})")


#: Wall seconds between two looks at the lock files while a claim waits (a claim of another process's ending is
#: seen no later; one of this process's, at once: :func:`release_domain_id` wakes the waiters).
_CLAIM_POLL = 0.25
#: Woken (and counted) each time this process hands a domain back: a waiting claim takes it at once.
_HANDED_BACK = threading.Condition()
_handed_back = [0]


def claim_domain_id(low: int = 215, high: int = 232, *, start: int | None = None,
                    lock_dir: str | os.PathLike[str] | None = None, wait: float = 0.0,
                    stop: StopRequest | None = None, range_name: str = "range") -> int:
    """A ROS domain in ``[low, high]`` that no other process on this machine has claimed this way, now claimed.

    A claim is an exclusive ``flock`` on ``<lock_dir>/bt_nav_ros_domains/domain-<id>.lock`` held until
    this process ends (the kernel drops it even after a crash, so nothing needs cleaning up). The
    search starts at ``start`` (default: the pid) so concurrent claimers rarely contend. Processes that
    pick a domain another way (a fixed ``ROS_DOMAIN_ID``) are invisible here: give them a different
    range. 215-232 (the tests' default) lies above the Linux ephemeral ports (Fast DDS uses ports
    7400 + 250 * domain + ...; 102-214 overlap 32768-60999) and below 233, where the ports would pass
    65535.

    When every domain is claimed, the claim waits for one up to ``wait`` wall seconds, counted again from each
    domain this process hands back (:func:`release_domain_id`): a grid with more workers than domains goes on for
    as long as its own runs keep ending, while domains held by others for longer than ``wait`` end it. ``stop``
    ends the wait early.

    Raises:
        NoFreeDomainError: none came free (``range_name`` names the range in its words: ``BT_NAV_DOMAIN_RANGE``).
    """
    directory = _lock_dir(lock_dir)
    os.makedirs(directory, exist_ok=True)
    span = high - low + 1
    first = (os.getpid() if start is None else start) % span
    began = time.monotonic()
    deadline, seen = began + max(0.0, wait), _handed_back[0]
    while True:
        for offset in range(span):
            domain = low + (first + offset) % span
            if _lock_domain(directory, domain):
                return domain
        with _HANDED_BACK:
            now = time.monotonic()
            if _handed_back[0] != seen:  # one of ours came back since the last look: try again, wait on afresh
                deadline, seen = now + max(0.0, wait), _handed_back[0]
                continue
            if now >= deadline or (stop is not None and stop.requested):
                raise NoFreeDomainError(low, high, now - began if wait > 0.0 else 0.0, range_name)
            _HANDED_BACK.wait(min(_CLAIM_POLL, deadline - now))


def _lock_dir(lock_dir: str | os.PathLike[str] | None) -> str:
    """Where the domains' lock files are (``lock_dir``, default the temporary directory)."""
    return os.path.join(os.fspath(lock_dir) if lock_dir is not None else tempfile.gettempdir(), "bt_nav_ros_domains")


def _lock_domain(directory: str, domain: int) -> bool:
    """Claim ``domain`` (its lock file in ``directory``) for this process, unless another open file holds it."""
    import fcntl

    handle = open(os.path.join(directory, f"domain-{domain}.lock"), "a+")  # noqa: SIM115 - held open: the claim
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        return False
    _DOMAIN_CLAIMS.append(handle)
    return True


def release_domain_id(domain: int, lock_dir: str | os.PathLike[str] | None = None) -> bool:
    """Give up this process's claim on ``domain`` (from :func:`claim_domain_id`, in the same ``lock_dir``); False
    when it held none.

    A grid that runs many DDS missions in one process claims a domain per run and must hand it back when
    the run ends, or a long grid would run out of domains; a claim of this process waiting for one takes it now.
    """
    path = os.path.join(_lock_dir(lock_dir), f"domain-{int(domain)}.lock")
    for handle in list(_DOMAIN_CLAIMS):
        if handle.name == path:
            _DOMAIN_CLAIMS.remove(handle)
            handle.close()  # closing the file drops the flock
            with _HANDED_BACK:
                _handed_back[0] += 1
                _HANDED_BACK.notify_all()
            return True
    return False


def launcher_domains(env: Mapping[str, str] | None = None) -> tuple[int, int]:
    """The range launchers claim from: ``$BT_NAV_DOMAIN_RANGE`` (``LOW-HIGH``) or :data:`LAUNCHER_DOMAINS`.

    Raises:
        ValueError: a malformed range (the launcher says so instead of silently using another).
    """
    text = (os.environ if env is None else env).get(DOMAIN_RANGE_ENV, "").strip()
    if not text:
        return LAUNCHER_DOMAINS
    low, sep, high = text.partition("-")
    if not (sep and low.strip().isdigit() and high.strip().isdigit()) or not 0 <= int(low) <= int(high) <= 232:
        raise ValueError(f"{DOMAIN_RANGE_ENV}={text!r}: expected LOW-HIGH with 0 <= LOW <= HIGH <= 232")
    return int(low), int(high)


def choose_domain_id(requested: int | None = None) -> int:
    """The run's ROS domain: ``requested``, else ``$ROS_DOMAIN_ID`` (the user's choice is kept), else a
    domain of :func:`launcher_domains` claimed for this process, so concurrent runs never share one.

    Raises:
        NoFreeDomainError: every domain of the range is claimed (a ValueError, as a malformed range)."""
    if requested is not None:
        return int(requested)
    env = os.environ.get("ROS_DOMAIN_ID", "").strip()
    if env.isdigit():
        return int(env)
    low, high = launcher_domains()
    return claim_domain_id(low, high, start=random.randrange(high - low + 1), range_name=DOMAIN_RANGE_ENV)


def dds_env(domain_id: int, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """An environment whose DDS traffic stays on this machine, in ``domain_id``.

    ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` keeps discovery off the network (a lab full of
    robots on one Wi-Fi must not see our test nodes); the domain keeps concurrent runs apart.
    ``ROS_LOCALHOST_ONLY`` is the pre-Jazzy spelling and is dropped to avoid the deprecation warning.
    """
    env = dict(os.environ if base is None else base)
    env.pop("ROS_LOCALHOST_ONLY", None)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["ROS_DOMAIN_ID"] = str(int(domain_id))
    return env


#: The Fast DDS profile of every process bt_nav starts (unless the user set one): a participant announces itself every
#: 0.25 s instead of every 3 s (as the tests' nodes do, tests/ros/fastdds_tests.xml). Why: when one process misses
#: another's start-up announcements on a loaded machine, the two find each other only at the next periodic one, 3 s
#: later: 15 s of sim time at 5x for a graded run, and seen as 3 s of a `bt-nav demo`'s 7.7 s (its judge waiting for
#: /clock with the simulator already running). It changes nothing but how often a participant says it exists.
DISCOVERY_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"><profiles>
 <participant profile_name="bt_nav_discovery" is_default_profile="true"><rtps><builtin><discovery_config>
  <leaseAnnouncement><sec>0</sec><nanosec>250000000</nanosec></leaseAnnouncement>
  <leaseDuration><sec>5</sec></leaseDuration>
 </discovery_config></builtin></rtps></participant>
</profiles></dds>
"""
#: The environment variables naming a Fast DDS profile file (the older and the newer name).
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")


def discovery_profile() -> Path:
    """:data:`DISCOVERY_PROFILE` as a file (written once into the temporary directory, atomically)."""
    path = Path(tempfile.gettempdir()) / "bt_nav_discovery_fastdds.xml"
    if not path.is_file() or path.read_text(encoding="utf-8") != DISCOVERY_PROFILE:
        # A temporary file of this call's own: the runs of a grid start in threads of one process, and a name made
        # of the pid alone was shared by two of them (one moved it into place, the other's move then failed with
        # FileNotFoundError: a run lost to "bt_nav failed to run it" on a fresh machine).
        with written_whole(path) as stream:
            stream.write(DISCOVERY_PROFILE)
    return path


def child_env(domain_id: int, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """:func:`dds_env` for a launched node: also unbuffered, uncoloured output (it is piped),
    :data:`DISCOVERY_PROFILE` unless the user named a Fast DDS profile of their own, and the run's mark
    (:mod:`bt_nav.ros.domain_guard`: a participant on the domain without it is not the run's)."""
    env = dds_env(domain_id, base)
    env[RUN_MARK_ENV] = run_mark(domain_id)  # the run's own processes, told from others on its domain
    env["PYTHONUNBUFFERED"] = "1"
    env.setdefault("RCUTILS_COLORIZED_OUTPUT", "0")
    if not any(env.get(name) for name in PROFILE_VARIABLES):
        env.update({name: str(discovery_profile()) for name in PROFILE_VARIABLES})
    return env


def use_domain_here(domain_id: int) -> None:
    """Put this process itself (an in-process recorder or probe node) in ``domain_id``, localhost only."""
    os.environ.update(dds_env(domain_id))
    os.environ.pop("ROS_LOCALHOST_ONLY", None)


# ---------------------------------------------------------------------------------------------- signals
class StopRequest:
    """SIGINT/SIGTERM/SIGHUP set a flag; the process's own loop then stops the robot and exits.

    rclpy's handlers would shut the ROS context down first, so a node could not publish its final
    zero twist. With this, the first signal only sets :attr:`signum`; a second one while still
    running raises KeyboardInterrupt (for a loop that does not come back); once :attr:`closing` is
    set, further signals are ignored so they cannot cut the stop short. The one stop-signal handler:
    the launchers, the executive's runner and the simulator and referee nodes all use it.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

    def __init__(self) -> None:
        self.signum: int | None = None
        self.closing = False
        self._previous: dict[int, Any] = {}
        self._listeners: list[Callable[[int], None]] = []

    def __bool__(self) -> bool:
        return self.signum is not None

    @property
    def requested(self) -> bool:
        """A stop signal arrived."""
        return self.signum is not None

    @property
    def name(self) -> str:
        """The signal's name (``SIGTERM``), or "" before one arrived."""
        return signal.Signals(self.signum).name if self.signum is not None else ""

    def handle(self, signum: int, frame: FrameType | None) -> None:
        """The signal handler."""
        if self.closing:
            return
        if self.signum is not None:
            raise KeyboardInterrupt
        self.signum = signum
        for listener in self._listeners:
            listener(signum)

    def on_signal(self, listener: Callable[[int], None]) -> None:
        """Call ``listener(signum)`` from the handler on the first signal (keep it tiny: it runs in a handler)."""
        self._listeners.append(listener)

    def install(self, signals: Iterable[int] | None = None) -> StopRequest:
        """Install the handlers (main thread only; elsewhere a no-op). Explicit even for SIGINT: a
        background job of a non-interactive shell starts with SIGINT ignored, and Python then never
        installs its KeyboardInterrupt handler."""
        if threading.current_thread() is threading.main_thread():
            for signum in self.SIGNALS if signals is None else signals:
                self._previous[signum] = signal.signal(signum, self.handle)
        return self

    @property
    def installed(self) -> bool:
        """Whether :meth:`install` took effect (False off the main thread)."""
        return bool(self._previous)

    def restore(self) -> None:
        """Put the previous handlers back (``main`` may run inside another program, e.g. a test)."""
        for signum, previous in self._previous.items():
            signal.signal(signum, previous)
        self._previous.clear()


# ---------------------------------------------------------------------------------------------- children
#: Environment variable naming the read end of the launcher's watchdog pipe in a child.
WATCHDOG_ENV = "BT_NAV_WATCHDOG_FD"
#: Seconds an orphaned child may take to stop the robot before it kills itself.
ORPHAN_GRACE = 3.0


def child_preexec(parent_pid: int, death_signal: int = signal.SIGTERM) -> Callable[[], None]:
    """What a child runs between fork and exec: default SIGINT/SIGHUP (a background launcher's child
    would inherit SIGINT ignored), ``PR_SET_PDEATHSIG`` and a check that the launcher did not already
    die before that took effect.

    Note ``PR_SET_PDEATHSIG`` fires when the *thread* that started the child ends, so start children
    from the main thread; the watchdog pipe does not have that caveat.
    """
    prctl = libc_prctl()

    def preexec() -> None:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.signal(signal.SIGHUP, signal.SIG_DFL)
        if not die_with_parent(prctl, death_signal, parent_pid):  # the launcher died between fork and prctl
            os.kill(os.getpid(), death_signal)

    return preexec


def watch_parent_pipe(env: Mapping[str, str] | None = None, grace: float = ORPHAN_GRACE) -> bool:
    """In a child: when the launcher's watchdog pipe closes (it died), SIGTERM ourselves, and SIGKILL
    after ``grace`` s if the graceful stop hangs. Returns whether a pipe was being watched.

    The ``bt-nav`` dispatcher calls this first thing, so every launched node gets it.
    """
    source = os.environ if env is None else env
    text = source.get(WATCHDOG_ENV, "")
    os.environ.pop(WATCHDOG_ENV, None)  # grandchildren have their own launcher, if any
    if not text.isdigit():
        return False
    fd = int(text)
    try:
        os.set_inheritable(fd, False)
    except OSError:
        return False

    def watch() -> None:
        try:
            while os.read(fd, 64):
                pass
        except OSError:
            pass
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(grace)
        os.kill(os.getpid(), signal.SIGKILL)

    threading.Thread(target=watch, name="bt_nav-watchdog", daemon=True).start()
    return True


class Startable(Protocol):
    """What a launcher starts: a name and a command line (``bringup.NodeSpec`` is one)."""

    executable: str

    def command(self, python: str | None = None) -> list[str]: ...  # noqa: D102


class Child:
    """One started process: its spec, its Popen and the thread that forwards its output line by line."""

    def __init__(self, spec: Startable, popen: subprocess.Popen | ForkedProcess, thread: threading.Thread) -> None:
        self.spec = spec
        self.popen = popen
        self.thread = thread
        #: Set by :meth:`Launcher.shutdown` when the child was still running: the signal it ended after
        #: (SIGINT, SIGTERM or SIGKILL), and the wall seconds from the first signal to its end.
        self.stopped_by: signal.Signals | None = None
        self.stop_seconds = 0.0
        self.sigints = 0  # SIGINTs sent to its group by shutdown (the ``first`` child may get two)

    @property
    def name(self) -> str:
        """Short name used as output prefix (the executable: sim, executive, referee)."""
        return self.spec.executable

    @property
    def pid(self) -> int:
        """Its pid, which is also its process group id."""
        return self.popen.pid

    def poll(self) -> int | None:
        """Exit code, or None while running."""
        return self.popen.poll()

    def signal_group(self, signum: int) -> None:
        """Send ``signum`` to the child's whole process group (gone already: nothing to do)."""
        try:
            os.killpg(self.popen.pid, signum)
        except (ProcessLookupError, PermissionError):
            pass


LineSink = Callable[[str, str], None]  # (child name, line without newline)


class Launcher:
    """Starts processes that cannot outlive it, and stops them politely and in order.

    Children run in their own sessions, so a terminal Ctrl-C reaches only this process; :meth:`shutdown`
    stops them in reverse start order (the executive before the simulator that consumes its final
    zero twist), each with SIGINT, then SIGTERM, then SIGKILL to its process group. If the launcher
    itself dies, the kernel (``PR_SET_PDEATHSIG``) and the watchdog pipe stop the children.

    Args:
        env: the children's environment (see :func:`child_env`).
        sink: where output lines go (default: ``[name] line`` on stdout).
        stop: the process's :class:`StopRequest`; :meth:`wait_any` returns early once it is set.
        last_word: called at the end of :meth:`shutdown` when the ``driver`` child (the one that
            commands the robot) did not exit with 0, e.g. ``publish_zero_twist`` for it.
        forker: a :class:`bt_nav.ros.forkserver.ForkServer` that forks bt_nav's own commands (``python -m bt_nav.cli``)
            instead of starting an interpreter for each; None: every process is started.
    """

    def __init__(self, env: dict[str, str], sink: LineSink | None = None, *, stop: StopRequest | None = None,
                 last_word: Callable[[], object] | None = None, driver: str = "executive",
                 forker: ForkServer | None = None) -> None:
        self.env = env
        self.forker = forker
        self.sink = sink or self.print_line
        self.stop = stop
        self.last_word = last_word
        self.driver = driver
        self.children: list[Child] = []
        self._lock = threading.Lock()
        self._width = 9
        self._watch_read, self._watch_write = os.pipe()  # both close-on-exec; the read end is passed on

    def print_line(self, name: str, line: str) -> None:
        """Default sink: ``[name] line`` on stdout."""
        with self._lock:
            print(f"[{name:<{self._width}}] {line}", flush=True)

    def start(self, spec: Startable, sink: LineSink | None = None, cwd: str | None = None) -> Child:
        """Start one process (in ``cwd``, default this process's); its stdout and stderr go line by line to ``sink``
        (default: the launcher's)."""
        command = spec.command()
        popen = self._forked(command, cwd)
        if popen is None:
            env = dict(self.env)
            env[WATCHDOG_ENV] = str(self._watch_read)
            popen = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL, start_new_session=True, text=True, bufsize=1,
                                     errors="replace", pass_fds=(self._watch_read,), cwd=cwd,
                                     preexec_fn=child_preexec(os.getpid()))  # noqa: PLW1509 - see child_preexec
        out = sink or self.sink
        thread = threading.Thread(target=self._pump, args=(spec.executable, popen.stdout, out), daemon=True)
        thread.start()
        child = Child(spec, popen, thread)
        self.children.append(child)
        return child

    def _forked(self, command: list[str], cwd: str | None) -> ForkedProcess | None:
        """``python -m bt_nav.cli ...`` forked from :attr:`forker` (:mod:`bt_nav.ros.forkserver`), with the same
        environment, directory and watchdog pipe as a started one; None: start it the usual way (no fork server, not
        one of bt_nav's commands, or the server is gone)."""
        if self.forker is None or command[:3] != [sys.executable, "-m", "bt_nav.cli"]:
            return None
        try:
            return self.forker.spawn(command[3:], self.env, cwd or os.getcwd(), {WATCHDOG_ENV: self._watch_read})
        except ForkServerError:
            return None

    @staticmethod
    def _pump(name: str, stream: IO[str], sink: LineSink) -> None:
        for line in stream:
            sink(name, line.rstrip("\n"))

    def wait_any(self, timeout: float | None = None, poll: float = 0.05) -> Child | None:
        """Block until a child exits (returned), ``timeout`` wall seconds pass or a stop signal arrives (None)."""
        end = None if timeout is None else time.monotonic() + timeout
        while end is None or time.monotonic() < end:
            for child in self.children:
                if child.poll() is not None:
                    return child
            if self.stop is not None and self.stop.requested:
                return None
            time.sleep(poll)
        return None

    def shutdown(self, grace: float = 5.0, *, together: bool = False, first: Child | None = None,
                 after_first: Callable[[], None] | None = None) -> None:
        """Stop every child, last started first: SIGINT, ``grace`` s, SIGTERM, 2 s, SIGKILL (to its group).

        ``together``: every child at once, each step to every live group and then one wait for them all, for
        children whose order no longer matters (a grade's run after its verdict): the stop then takes the
        slowest child's time instead of the sum of all of theirs.

        ``first``: that child alone before the others, while they still run. A graded node is stopped as a
        robot's node is: its world goes on. Stopped together with the simulator, a node whose wait wakes only on
        messages or sim-time timers (one that turned rclpy's signal handler off to send a last zero twist, as
        many do) would sleep through its SIGINT once ``/clock`` stopped, and be blamed for ignoring it. It gets
        SIGINT twice (half of ``grace`` each), as a user presses Ctrl-C again: a node's first SIGINT can be lost
        inside rclpy (seen once in 42 graded runs of a node that takes it as KeyboardInterrupt: it ran on for 3 s),
        and the second one ends it; :attr:`Child.sigints` says how many it got.

        Which signal ended each running child is kept (:attr:`Child.stopped_by`): a graded node that ignores
        SIGINT cannot be stopped with Ctrl-C, and its grader says so. ``after_first`` is called once ``first`` has
        ended (or was killed), before the others get their signals.
        """
        if first is None and after_first is not None:
            self._after_first(after_first)
        live = [child for child in reversed(self.children) if child is not first]
        groups = [live] if together else [[child] for child in live]
        ladder = ((signal.SIGINT, grace), (signal.SIGTERM, 2.0), (signal.SIGKILL, 2.0))
        twice = ((signal.SIGINT, grace / 2.0), (signal.SIGINT, grace / 2.0), *ladder[1:])
        for group in [[first], *groups] if first is not None else groups:
            began = time.monotonic()
            for signum, wait in twice if group[0] is first else ladder:
                running = [child for child in group if child.poll() is None]
                if not running:
                    break
                for child in running:
                    child.signal_group(signum)
                    child.sigints += signum == signal.SIGINT
                end = time.monotonic() + wait
                for child in running:
                    try:
                        child.popen.wait(timeout=max(0.0, end - time.monotonic()))
                    except subprocess.TimeoutExpired:
                        continue
                    child.stopped_by, child.stop_seconds = signum, time.monotonic() - began
            for child in group:
                child.signal_group(signal.SIGKILL)  # anything the child left behind in its group
            if group[0] is first and after_first is not None:
                self._after_first(after_first)
        unclean = [c for c in self.children if c.name == self.driver and c.poll() != 0]
        if unclean and self.last_word is not None:
            self.last_word()  # the driver may not have sent its stop: say it for it
        for child in self.children:
            child.thread.join(timeout=2.0)
        for fd in (self._watch_read, self._watch_write):
            try:
                os.close(fd)
            except OSError:
                pass
        self._watch_read = self._watch_write = -1

    @staticmethod
    def _after_first(hook: Callable[[], None]) -> None:
        """``shutdown``'s hook, which must not keep the others from being stopped."""
        try:
            hook()
        except Exception as exc:  # noqa: BLE001 - whatever it raised, the children are stopped next
            print(f"bt-nav: while stopping: {exc!r}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------- the last word
def publish_zero_twist(domain_id: int, *, topic: str = "/cmd_vel", stamped: bool = False,
                       frame_id: str = "base_link", wait: float = 0.5) -> int:
    """Publish zero twists on ``topic`` for ``wait`` s from a short-lived node of this process; returns
    how many subscribers matched.

    A launcher's last word after an executive that did not stop cleanly (killed, crashed): a robot
    driver keeps its last command, so someone must say stop. Imports rclpy, in a private context.
    """
    import rclpy
    from geometry_msgs.msg import Twist, TwistStamped
    from rclpy.signals import SignalHandlerOptions

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(domain_id), signal_handler_options=SignalHandlerOptions.NO)
    try:
        node = rclpy.create_node("bt_nav_launcher_stop", context=context)
        kind = TwistStamped if stamped else Twist
        publisher = node.create_publisher(kind, topic, 10)
        end = time.monotonic() + wait
        while time.monotonic() < end:
            msg = kind()
            if stamped:
                msg.header.stamp = node.get_clock().now().to_msg()
                msg.header.frame_id = frame_id
            publisher.publish(msg)
            time.sleep(0.05)
        matched = publisher.get_subscription_count()
        node.destroy_node()
        return matched
    finally:
        rclpy.try_shutdown(context=context)


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity, as a container or ``taskset`` sets it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)
