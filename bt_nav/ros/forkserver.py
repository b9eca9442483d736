"""bt_nav's own processes forked from one that has imported them already: a grade's simulators.

Why: a graded run's simulator process spent about half a CPU second importing numpy, rclpy, the simulator, its judge
and ``rosbags`` (and building the bag's message types) before its first step, on a grade that is CPU-bound (measured:
2.7 CPU s a run, 0.5 s of it before t0; twelve runs at once on two cores). A :class:`ForkServer` does that work once
per grade; each run's simulator is a fork of it.

Isolation is still a process per run: the fork shares only imported modules (copy on write). Nothing is initialised
before the fork (no rclpy context, no DDS participant, no thread: the server checks it has one thread and refuses
otherwise, and the launcher then starts processes as before). Each child takes the environment, directory and
arguments of the request, so a run's ``ROS_DOMAIN_ID`` and run mark are its own, and runs
``bt_nav.cli.main(argv)`` as ``python -m bt_nav.cli`` would. It is in a session of its own (its pid is its process
group, as :class:`subprocess.Popen` with ``start_new_session``), it gets SIGTERM when the server dies
(``PR_SET_PDEATHSIG``), and it keeps the launcher's watchdog pipe (:func:`bt_nav.ros.supervise.watch_parent_pipe`).
The graded node is never started here: it starts fresh, as a student runs it.

Protocol (one ``SOCK_SEQPACKET`` socket pair, one JSON message per packet): the server says ``{"ready": bool,
"threads": n}`` once; a request ``{"id", "argv", "env", "cwd", "fd_env": [names], "target"}`` comes with its file
descriptors (the child's stdout and stderr first, then one per ``fd_env`` name, whose number the child's environment
gets under that name); the server answers ``{"id", "pid"}`` or ``{"id", "error"}``, and ``{"exited": pid, "code"}``
when it has reaped a child (``code`` as :attr:`subprocess.Popen.returncode`: negative for a signal). The server
ends when the socket closes (the grade ended, or died), quietly: a client gone is no error. Its own failure is one
message, ``{"ended": "one line", "traceback": text}`` (before its hello: the hello says ``"error"``), never a traceback
on the grade's terminal (its stderr is not the terminal's).

Either end may go at any time, and the other end takes it in its stride (issue 52): a client that closes the server
before its hello kills it (it has forked nothing yet); a spawn waits for the hello :data:`HELLO_WAIT` s at most and
then gives the server up (its commands start the usual way); the socket is closed once, by :meth:`ForkServer.close`,
after the reader thread that uses it has ended; and :func:`serving` ends a server when the last block using it ends,
not the first one (a grade's probe re-runs beside its grid share the grid's server: the grid's end killed their
simulators with SIGTERM, ``PR_SET_PDEATHSIG``).
"""

from __future__ import annotations

import ctypes
import importlib
import io
import json
import os
import random
import select
import signal
import socket
import subprocess
import sys
import threading
import traceback
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from typing import IO, Any

from bt_nav.ros.parentdeath import die_with_parent, libc_prctl

#: What the server imports before its first fork: the simulator's process with its hosted judges and recorder.
PRELOAD = ("bt_nav.cli", "bt_nav.ros.nodes.simulator", "bt_nav.ros.nodes.hosting", "bt_nav.ros.nodes.checkoff",
           "bt_nav.ros.nodes.referee", "bt_nav.ros.nodes.hosted_bag", "bt_nav.media.bag", "bt_nav.ros.bringup",
           "bt_nav.mission.profiles")
#: What those import only once they run, imported too when present (a child listed what it imported after the fork:
#: 0.12 CPU s a run): the bag writer and what it writes with, numpy's random generators, and the loader of rclpy's
#: type supports (which imports the whole IDL parser on its first use).
WARM_MODULES = ("rosbags.rosbag2", "ruamel.yaml", "numpy.random", "importlib.metadata",
                "rosidl_generator_py.import_type_support_impl")
#: The ROS interfaces whose C type support a simulator's process loads (``module:Name``): its topics, its judges'
#: services and those every node serves (parameters, type descriptions).
WARM_TYPES = ("rosgraph_msgs.msg:Clock", "sensor_msgs.msg:LaserScan", "nav_msgs.msg:Odometry",
              "geometry_msgs.msg:Twist", "geometry_msgs.msg:TwistStamped", "std_msgs.msg:String",
              "rcl_interfaces.msg:Log", "std_srvs.srv:SetBool", "std_srvs.srv:Trigger",
              "rcl_interfaces.srv:DescribeParameters", "rcl_interfaces.srv:GetParameters",
              "rcl_interfaces.srv:GetParameterTypes", "rcl_interfaces.srv:ListParameters",
              "rcl_interfaces.srv:SetParameters", "rcl_interfaces.srv:SetParametersAtomically",
              "type_description_interfaces.srv:GetTypeDescription")
#: What a child runs unless told: ``bt-nav``'s dispatcher (``module:function``, called with the argument list).
TARGET = "bt_nav.cli:main"
#: ``BT_NAV_FORKSERVER=off`` (or 0, no, false): a grade starts every simulator as a process of its own, as before.
SWITCH_ENV = "BT_NAV_FORKSERVER"
#: Wall seconds the server may take to import :data:`PRELOAD` and say it is ready.
READY_TIMEOUT = 60.0
#: Wall seconds a spawn waits for the server's hello before the server is given up (killed: it has forked nothing) and
#: the command started the usual way: a server stuck in its imports must not hold a run's simulator back for
#: :data:`READY_TIMEOUT` (two CPU hogs on two cores: its imports take ~3 s; a fresh interpreter needs as long).
HELLO_WAIT = 20.0
#: The most file descriptors one request passes (stdout, stderr and the ``fd_env`` ones).
MAX_FDS = 8
_PACKET = 1 << 20


class ForkServerError(RuntimeError):
    """The fork server could not start, refused, or is gone: start the process the usual way."""


class ForkedProcess:
    """A child of the fork server, answering as much of :class:`subprocess.Popen` as a launcher uses: ``pid``,
    ``stdout`` (its output, text, line by line), :meth:`poll`, :meth:`wait` and ``returncode``."""

    def __init__(self, pid: int, stdout: IO[str], args: Sequence[str]) -> None:
        self.pid = pid
        self.stdout = stdout
        self.args = list(args)
        self.returncode: int | None = None
        #: Why its end is a guess (the fork server is gone, and with it the child's exit code), else "".
        self.lost = ""
        self._ended = threading.Event()

    def poll(self) -> int | None:
        """Its exit code (negative: the signal that ended it), None while it runs."""
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Block until it ends; :class:`subprocess.TimeoutExpired` after ``timeout`` wall seconds."""
        if not self._ended.wait(timeout):
            raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
        return int(self.returncode or 0)

    def ended(self, code: int, lost: str = "") -> None:
        """The server reaped it with ``code``; or is gone (``lost`` says how): then the code is a guess, SIGTERM's,
        which its death sent the child (``PR_SET_PDEATHSIG``)."""
        if self.returncode is None:
            self.lost = lost
            self.returncode = int(code)
            self._ended.set()


class ForkServer:
    """``python -m bt_nav.ros.forkserver``, started now; :meth:`spawn` forks a child of it once it is ready (it has
    imported ``preload``: about a second, which a grade spends starting its first nodes meanwhile, not waiting), or
    raises :class:`ForkServerError` when it never became ready; :meth:`close` ends it (its children get SIGTERM).

    Its stderr is not the grade's: what it has to say comes over the socket (:attr:`refusal`, :attr:`last_words`,
    :attr:`traceback`), so no traceback of the server's reaches a grade's terminal."""

    def __init__(self, preload: Sequence[str] = PRELOAD, timeout: float = READY_TIMEOUT) -> None:
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        # one BLAS thread: the server must have none but its own when it forks (OpenBLAS starts its pool at import)
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "SPT_NOENV": "1"}
        try:
            self.proc = subprocess.Popen([sys.executable, "-m", __name__, str(theirs.fileno()), *preload],
                                         pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                         start_new_session=True, env=env)
        except BaseException:
            mine.close()
            raise
        finally:
            theirs.close()
        self.sock = mine  # used by the reader thread and spawn(); shut down and closed by close() alone
        self._lock = threading.Lock()  # one request at a time on the socket, and the tables below
        self._replies: dict[int, dict[str, Any]] = {}
        self._replied = threading.Condition(self._lock)
        self._children: dict[int, ForkedProcess] = {}
        self._early: dict[int, int] = {}  # pid -> code of a child reaped before spawn() registered it
        self._next_id = 0
        self._closed = False
        self.alive = False  # ready and not ended
        self.settled = False  # its hello came (ready or refusing), or never will
        self.refusal = ""  # why it is not ready, once settled so
        self.last_words = ""  # why it ended, when it ended by itself (its one line, or its exit code)
        self.traceback = ""  # its own traceback, when it failed with one
        self._timeout = timeout
        self._reader = threading.Thread(target=self._read, name="bt_nav-forkserver", daemon=True)
        self._reader.start()

    @property
    def usable(self) -> bool:
        """Whether :meth:`spawn` may fork: ready, or not yet known (it waits for the hello)."""
        return self.alive or not self.settled

    def ready(self, timeout: float | None = None) -> bool:
        """Wait for the server's hello (at most ``timeout`` s; None: as long as it takes); whether it is ready."""
        with self._lock:
            self._replied.wait_for(lambda: self.settled, timeout)
            return self.alive

    def _settle(self, ready: bool, refusal: str = "") -> bool:
        """Take the hello's answer (or a refusal in its place) unless one was taken already (a spawn gave the server
        up, or it was closed, first); whether this one was taken."""
        with self._lock:
            if self.settled:
                return False
            self.alive, self.settled, self.refusal = ready, True, "" if ready else refusal
            self._replied.notify_all()
            return True

    def _hello(self) -> bool:
        """Read the server's first message (``timeout`` s at most); whether it said it is ready (and is still
        wanted: a server closed or given up meanwhile is not)."""
        try:
            self.sock.settimeout(self._timeout)
            packet = self.sock.recv(_PACKET)
            hello = json.loads(packet) if packet else {"ready": False, "error": "it ended before its hello"}
        except TimeoutError:
            hello = {"ready": False, "error": f"no hello within {self._timeout:g} s"}
        except (OSError, ValueError) as exc:
            hello = {"ready": False, "error": f"its hello could not be read: {exc}"}
        ready = bool(hello.get("ready"))
        if ready:
            self.sock.settimeout(None)
        if not ready:
            self.traceback = str(hello.get("traceback") or "")
        said = hello.get("error") or f"{hello.get('threads')} threads, LTTng's fork protocol " \
                                     f"{'loaded' if hello.get('lttng') else 'absent'}"
        return self._settle(ready, f"the fork server is not ready: {said}") and ready

    def give_up(self, why: str) -> None:
        """Stop waiting for a server that has not said hello: it is refused from now on, and ended (it has forked
        nothing: spawns fork only after its hello)."""
        if self._settle(False, f"the fork server was given up: {why}"):
            self._end_process()

    def spawn(self, argv: Sequence[str], env: Mapping[str, str], cwd: str,
              fd_env: Mapping[str, int] | None = None, target: str = TARGET,
              hello_wait: float | None = None) -> ForkedProcess:
        """Fork a child that runs ``target(argv)`` with ``env`` in ``cwd``; ``fd_env``: descriptors it keeps, each
        named in its environment by its number there. Waits for the server's hello ``hello_wait`` s at most (default
        :data:`HELLO_WAIT`), then gives it up. Raises :class:`ForkServerError` (nothing was started)."""
        names = list(fd_env or {})
        wait = HELLO_WAIT if hello_wait is None else hello_wait
        if not self.settled and not self.ready(wait):
            self.give_up(f"no hello after {wait:g} s")
        if not self.ready(0.0):
            raise ForkServerError(self.refusal or "the fork server has ended")
        read, write = os.pipe()
        with self._lock:
            if not self.alive:
                os.close(read)
                os.close(write)
                raise ForkServerError(self.last_words or "the fork server has ended")
            self._next_id += 1
            ident = self._next_id
            request = {"id": ident, "argv": list(argv), "env": dict(env), "cwd": cwd, "fd_env": names,
                       "target": target}
            try:
                socket.send_fds(self.sock, [json.dumps(request).encode()], [write, *(int(fd_env[n]) for n in names)])
            except OSError as exc:
                os.close(read)
                raise ForkServerError(f"the fork server did not take the request: {exc}") from None
            finally:
                os.close(write)
            while ident not in self._replies and self.alive:
                self._replied.wait(1.0)
            reply = self._replies.pop(ident, {"error": self.last_words or "the fork server has ended"})
            if "pid" not in reply:
                os.close(read)
                raise ForkServerError(str(reply.get("error")))
            child = ForkedProcess(int(reply["pid"]), os.fdopen(read, "r", buffering=1, errors="replace"), argv)
            self._children[child.pid] = child
            if child.pid in self._early:
                child.ended(self._early.pop(child.pid))
        return child

    def _read(self) -> None:
        """The server's hello, then its answers and its children's ends (a thread of its own); at its end every child
        still listed is taken as ended (the server's death sent it SIGTERM). A server that is not ready is ended."""
        if not self._hello():
            self._end_process()
            return
        try:
            while True:
                packet = self.sock.recv(_PACKET)
                if not packet:
                    break
                self._take(json.loads(packet))
        except (OSError, ValueError) as exc:  # closed under it, or a message cut short: the server is lost either way
            self.last_words = self.last_words or f"its socket failed: {exc}"
        self._lost()

    def _take(self, message: dict[str, Any]) -> None:
        """One message of the ready server: a child reaped, an answer to a request, or its last words."""
        with self._lock:
            if "exited" in message:
                pid, code = int(message["exited"]), int(message["code"])
                child = self._children.pop(pid, None)
                if child is None:
                    self._early[pid] = code
                else:
                    child.ended(code)
            elif "ended" in message:
                self.last_words, self.traceback = str(message["ended"]), str(message.get("traceback") or "")
            else:
                self._replies[int(message["id"])] = message
                self._replied.notify_all()

    def _lost(self) -> None:
        """The connection ended: the server is no more, and every child it had is taken as ended by SIGTERM."""
        with self._lock:
            self.alive = False
            if not self._closed and not self.last_words:
                code = self.proc.poll()
                self.last_words = "the fork server ended" + (f" with code {code}" if code is not None else "")
            lost = "closed by its grade" if self._closed else self.last_words
            for child in self._children.values():
                child.ended(-signal.SIGTERM, f"the fork server it was forked from is gone ({lost})")
            self._children.clear()
            self._replied.notify_all()

    def _end_process(self, timeout: float = 5.0, kill: bool = True) -> None:
        """End the server's process: at once with ``kill`` (one that never said it was ready has forked nothing),
        else it goes at its socket's end, and is killed after ``timeout`` s."""
        if kill:
            with suppress(OSError):
                self.proc.kill()
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()

    def close(self, timeout: float = 5.0) -> None:
        """End the server (its socket closes; children still running get SIGTERM from its end). Once: a second call
        does nothing. The socket is closed here alone, after its reader thread has let go of it."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            ready, self.alive = self.alive, False
            if not self.settled:  # importing still: it would only write its hello into a void
                self.settled, self.refusal = True, "the fork server was closed before its hello"
            self._replied.notify_all()
        if not ready:
            self._end_process(timeout)  # it has forked nothing
        with suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)  # wakes the reader thread's recv
        if self._reader is not threading.current_thread():
            self._reader.join(timeout)
        self._end_process(timeout, kill=False)
        self.sock.close()


def wanted(env: Mapping[str, str] | None = None) -> bool:
    """Whether a grade forks its simulators (:data:`SWITCH_ENV`; on unless switched off)."""
    value = (os.environ if env is None else env).get(SWITCH_ENV, "on").strip().lower()
    return value not in ("off", "0", "no", "false")


_current: ForkServer | None = None
_users = 0  # the serving() blocks open now, in any thread
_current_lock = threading.Lock()


def current() -> ForkServer | None:
    """The fork server of the :func:`serving` block this process is in (None: start processes the usual way)."""
    server = _current
    return server if server is not None and server.usable else None


@contextmanager
def serving(enabled: bool = True) -> Iterator[ForkServer | None]:
    """A fork server for the block, starting while the block goes on; None when it cannot be started (and one that
    never becomes ready refuses its spawns): either only costs the imports it would have saved. ``enabled`` False:
    none.

    Blocks open at once share one server, nested or in other threads (a grid's runs and the probe re-runs of its
    first failure beside them), and it ends with the last of them, whichever that is: ended with the first, it took
    the others' simulators with it (``PR_SET_PDEATHSIG``: SIGTERM 0.4 s into their runs)."""
    global _current, _users
    if not enabled:
        yield None
        return
    with _current_lock:
        if _current is None:
            try:
                _current = ForkServer()
            except (ForkServerError, OSError):
                _current = None
        _users += 1
        server = _current
    try:
        yield server
    finally:
        with _current_lock:
            _users -= 1
            last = _current if _users == 0 else None
            if last is not None:
                _current = None
        if last is not None:
            last.close()


# ------------------------------------------------------------------------------------------------ the server side
def _threads() -> int:
    """How many threads this process has (the OS's count: a library's threads are not Python's)."""
    return len(os.listdir("/proc/self/task")) if os.path.isdir("/proc/self/task") else threading.active_count()


#: The threads LTTng-UST starts when it is loaded (its listeners for the global and the per-user session daemon).
LTTNG_THREADS = 2


def lttng_fork_hooks() -> tuple[Any, Any, Any] | None:
    """LTTng-UST's own fork protocol (what its ``liblttng-ust-fork.so`` wraps ``fork`` with: before, after in the
    parent, after in the child), when this process has it loaded; None otherwise.

    Why: rclpy's libraries load LTTng-UST (ROS 2 tracing), whose constructor starts :data:`LTTNG_THREADS` listener
    threads. A fork must not happen while one of them holds the tracer's locks, and the child must restart them;
    these three calls take the locks across the fork (with signals blocked) and reset the child's tracer.
    """
    try:
        with open("/proc/self/maps", encoding="utf-8") as maps:
            paths = {line.split()[-1] for line in maps if "/liblttng-ust" in line and "tracepoint" not in line}
    except OSError:
        return None
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for prefix in ("ust_", "lttng_ust_"):  # the 2.12 and the 2.13 names
            hooks = tuple(getattr(lib, f"{prefix}{name}", None) for name in ("before_fork", "after_fork_parent",
                                                                               "after_fork_child"))
            if all(hook is not None for hook in hooks):
                return hooks  # type: ignore[return-value]
    return None


def _warm(modules: Sequence[str], types: Sequence[str]) -> None:
    """Import ``modules`` and load the type supports of ``types`` where they exist (a missing one is the child's to
    import, or to fail on, as without the server)."""
    from rclpy.type_support import check_for_type_support

    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            pass
    for spec in types:
        module, _, name = spec.partition(":")
        try:
            check_for_type_support(getattr(importlib.import_module(module), name))
        except (ImportError, AttributeError):
            pass


def serve(fd: int, preload: Sequence[str]) -> int:
    """The server's life (see the module docstring): import, say ready, fork on request, reap, report. A client gone
    (the grade ended, died, or closed it before its hello) ends it quietly with 0; its own failure is said to the
    client in one message (:func:`_last_words`), its exit code 1."""
    sock = socket.socket(fileno=fd)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the grade's to handle; the socket's end is ours
    said = False  # the hello was sent: a failure after it is the server's "ended", not its hello's "error"
    try:
        hooks, ready, hello = _start(preload)
        sock.send(json.dumps(hello).encode())
        said = True
        return _loop(sock, hooks) if ready else 1
    except (BrokenPipeError, ConnectionResetError):
        return 0
    except Exception as exc:  # noqa: BLE001 - the server's own failure, told to its client instead of a terminal
        _last_words(sock, exc, said)
        return 1


def _start(preload: Sequence[str]) -> tuple[tuple[Any, Any, Any] | None, bool, dict[str, Any]]:
    """Import what the children share; LTTng's fork hooks, whether the server may fork, and its hello."""
    try:  # before the first fork; with SPT_NOENV (set by ForkServer): the environment block stays as it is
        importlib.import_module("setproctitle").getproctitle()  # its first call finds the command line's room
    except ImportError:
        pass
    importlib.import_module("rclpy")  # its libraries, and the threads they start
    hooks = lttng_fork_hooks()
    loaded = _threads()
    for name in preload:
        importlib.import_module(name)
    if "bt_nav.media.bag" in sys.modules:
        sys.modules["bt_nav.media.bag"].typestore()  # the bag's message types, built once for every child
    _warm(WARM_MODULES, WARM_TYPES)
    threads = _threads()
    # forkable: one thread of ours, plus LTTng's listeners only when their fork protocol is there to take them along
    ready = threads == loaded and loaded - 1 in ((0, LTTNG_THREADS) if hooks is not None else (0,))
    return hooks, ready, {"ready": ready, "threads": threads, "lttng": hooks is not None}


def _loop(sock: socket.socket, hooks: tuple[Any, Any, Any] | None) -> int:
    """Fork on request and report the children's ends until the client's socket closes (0)."""
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # a handler, so SIGCHLD reaches the wake-up pipe
    while True:
        readable, _, _ = select.select([sock, wake_read], [], [])
        if wake_read in readable:
            os.read(wake_read, 512)
        _reap(sock)
        if sock in readable:
            packet, fds, _, _ = socket.recv_fds(sock, _PACKET, MAX_FDS)
            if not packet:
                return 0
            _fork(sock, json.loads(packet), fds, (wake_read, wake_write), hooks)


def _last_words(sock: socket.socket, exc: BaseException, said: bool) -> None:
    """Tell the client why the server fails (one line, and the traceback for a log): before its hello as the hello's
    ``error``, after it as ``ended``. A client gone too hears nothing."""
    line = f"{type(exc).__name__}: {exc}".splitlines()[0][:300]
    text = traceback.format_exc()
    message = {"ended": line, "traceback": text} if said else {"ready": False, "error": line, "traceback": text}
    with suppress(OSError):
        sock.send(json.dumps(message).encode())


def _reap(sock: socket.socket) -> None:
    """Every ended child's exit code to the client."""
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        sock.send(json.dumps({"exited": pid, "code": os.waitstatus_to_exitcode(status)}).encode())


def _forked(hooks: tuple[Any, Any, Any] | None) -> int:
    """``os.fork()``, inside LTTng-UST's fork protocol when it is loaded (:func:`lttng_fork_hooks`)."""
    if hooks is None:
        return os.fork()
    before, after_parent, after_child = hooks
    saved = ctypes.create_string_buffer(256)  # a sigset_t (128 bytes with glibc), the signal mask across the fork
    before(saved)
    try:
        pid = os.fork()
    except OSError:
        after_parent(saved)
        raise
    (after_child if pid == 0 else after_parent)(saved)
    return pid


def _fork(sock: socket.socket, request: dict[str, Any], fds: list[int], wake: tuple[int, int],
          hooks: tuple[Any, Any, Any] | None) -> None:
    """Fork the child of ``request`` and say its pid (or why not)."""
    try:
        pid = _forked(hooks)
    except OSError as exc:
        for fd in fds:
            os.close(fd)
        sock.send(json.dumps({"id": request["id"], "error": f"fork failed: {exc}"}).encode())
        return
    if pid == 0:
        os._exit(_run_child(request, fds, (sock.fileno(), *wake)))
    for fd in fds:
        os.close(fd)
    sock.send(json.dumps({"id": request["id"], "pid": pid}).encode())


def _run_child(request: dict[str, Any], fds: list[int], server_fds: Sequence[int]) -> int:
    """The child's life and its exit code, ending as an interpreter's would: ``SystemExit``'s code, a traceback and 1
    for an error, and a ``KeyboardInterrupt`` nobody caught ends it by SIGINT."""
    code, interrupted = 1, False
    try:
        code = _child(request, fds, server_fds)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except KeyboardInterrupt:
        traceback.print_exc()
        interrupted = True
    except BaseException:  # noqa: BLE001 - the child's last words, as an interpreter would print them
        traceback.print_exc()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    if interrupted:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    return code


def _retitle(command: Sequence[str]) -> None:
    """Show the child in ``ps`` (``/proc/<pid>/cmdline``) as the command it runs, as far as the server's own command
    line's room allows (``SPT_NOENV``: its environment block is left alone, and still reads as the server's); without
    ``setproctitle`` it keeps the server's command line. The module must be imported before the environment is
    replaced (it finds the command line from the environment block): :func:`serve` does that."""
    module = sys.modules.get("setproctitle")  # imported by the server, where it finds the command line's room
    if module is not None:
        module.setproctitle(" ".join(command))
        _keep_invocation_name(command[0])


#: glibc's ``program_invocation_name`` and ``program_invocation_short_name`` of a retitled child, holding the bytes
#: they point to.
_INVOCATION: list[ctypes.c_char_p] = []


def _keep_invocation_name(executable: str) -> None:
    """Point glibc's ``program_invocation_name`` (and its short form) at ``executable`` again.

    Why: they point into the command line's memory, which ``setproctitle`` overwrites with one string; rcutils names a
    process's log file in ``~/.ros/log`` after it (``<name>_<pid>_<ms>.log``), so a retitled child wrote its log to a
    file named after the tail of its title, and refused to start once that name passed 255 bytes. A fresh interpreter's
    is its executable's path, and so is this one's.
    """
    try:
        libc = ctypes.CDLL(None)
        full = ctypes.c_char_p.in_dll(libc, "program_invocation_name")
        short = ctypes.c_char_p.in_dll(libc, "program_invocation_short_name")
    except (OSError, ValueError):  # not glibc: nothing points there
        return
    name = os.fsencode(executable)
    full.value, short.value = name, os.path.basename(name)
    _INVOCATION[:] = [full, short]  # each holds its bytes: the pointers stay valid for the process's life


def _standard_streams(unbuffered: bool) -> None:
    """``sys.stdout`` and ``sys.stderr`` on the new descriptors 1 and 2, buffered as a fresh interpreter's would be
    with this environment (``PYTHONUNBUFFERED``: written through; else stdout block-buffered, stderr by line)."""
    for fd, name in ((1, "stdout"), (2, "stderr")):
        old = getattr(sys, name)
        raw = io.FileIO(fd, "w", closefd=False)
        binary = raw if unbuffered else io.BufferedWriter(raw)
        stream = io.TextIOWrapper(binary, encoding=getattr(old, "encoding", None) or "utf-8",
                                  errors="backslashreplace" if name == "stderr" else getattr(old, "errors", "strict"),
                                  write_through=unbuffered, line_buffering=not unbuffered and name == "stderr")
        setattr(sys, name, stream)
        setattr(sys, f"__{name}__", stream)


def _child(request: dict[str, Any], fds: list[int], server_fds: Sequence[int]) -> int:
    """In the forked child: become a process of its own run, then run the target; its exit code."""
    server = os.getppid()
    signal.set_wakeup_fd(-1)
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)  # as a fresh interpreter has it
    for fd in server_fds:
        os.close(fd)
    os.setsid()
    if not die_with_parent(libc_prctl(), signal.SIGTERM, server):  # the server died between the fork and the prctl
        return 1
    output, *kept = fds
    null = os.open(os.devnull, os.O_RDONLY)
    for target, source in ((0, null), (1, output), (2, output)):
        os.dup2(source, target)
    os.close(null)
    os.close(output)
    env = dict(request["env"])
    env.update({name: str(fd) for name, fd in zip(request["fd_env"], kept, strict=True)})
    os.environ.clear()
    os.environ.update(env)
    _standard_streams(bool(env.get("PYTHONUNBUFFERED")))
    os.chdir(request["cwd"])
    random.seed()  # the server's state would be every child's
    sys.argv = ["bt-nav", *request["argv"]]
    _retitle([sys.executable, "-m", "bt_nav.cli", *request["argv"]])
    module, _, function = str(request["target"]).partition(":")
    return int(getattr(importlib.import_module(module), function)(list(request["argv"])) or 0)


if __name__ == "__main__":
    sys.exit(serve(int(sys.argv[1]), sys.argv[2:]))
