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
ends when the socket closes (the grade ended, or died).
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
from contextlib import contextmanager
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
        self._ended = threading.Event()

    def poll(self) -> int | None:
        """Its exit code (negative: the signal that ended it), None while it runs."""
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        """Block until it ends; :class:`subprocess.TimeoutExpired` after ``timeout`` wall seconds."""
        if not self._ended.wait(timeout):
            raise subprocess.TimeoutExpired(self.args, timeout or 0.0)
        return int(self.returncode or 0)

    def ended(self, code: int) -> None:
        """The server reaped it with ``code`` (or is gone: then the code is a guess, SIGTERM's)."""
        if self.returncode is None:
            self.returncode = int(code)
            self._ended.set()


class ForkServer:
    """``python -m bt_nav.ros.forkserver``, started now; :meth:`spawn` forks a child of it once it is ready (it has
    imported ``preload``: about a second, which a grade spends starting its first nodes meanwhile, not waiting), or
    raises :class:`ForkServerError` when it never became ready; :meth:`close` ends it (its children get SIGTERM)."""

    def __init__(self, preload: Sequence[str] = PRELOAD, timeout: float = READY_TIMEOUT) -> None:
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        # one BLAS thread: the server must have none but its own when it forks (OpenBLAS starts its pool at import)
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "SPT_NOENV": "1"}
        try:
            self.proc = subprocess.Popen([sys.executable, "-m", __name__, str(theirs.fileno()), *preload],
                                         pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                                         stdout=subprocess.DEVNULL, start_new_session=True, env=env)
        finally:
            theirs.close()
        self.sock = mine
        self._lock = threading.Lock()  # one request at a time on the socket, and the tables below
        self._replies: dict[int, dict[str, Any]] = {}
        self._replied = threading.Condition(self._lock)
        self._children: dict[int, ForkedProcess] = {}
        self._early: dict[int, int] = {}  # pid -> code of a child reaped before spawn() registered it
        self._next_id = 0
        self.alive = False  # ready and not ended
        self.settled = False  # its hello came (ready or refusing), or never will
        self.refusal = ""  # why it is not ready, once settled so
        self._timeout = timeout
        threading.Thread(target=self._read, name="bt_nav-forkserver", daemon=True).start()

    @property
    def usable(self) -> bool:
        """Whether :meth:`spawn` may fork: ready, or not yet known (it waits for the hello)."""
        return self.alive or not self.settled

    def ready(self, timeout: float | None = None) -> bool:
        """Wait for the server's hello (at most ``timeout`` s; None: as long as it takes); whether it is ready."""
        with self._lock:
            self._replied.wait_for(lambda: self.settled, timeout)
            return self.alive

    def _hello(self) -> bool:
        """Read the server's first message (``timeout`` s at most); whether it said it is ready."""
        self.sock.settimeout(self._timeout)
        try:
            hello = json.loads(self.sock.recv(_PACKET) or b"{}")
        except (OSError, ValueError) as exc:
            hello = {"ready": False, "error": f"it did not start: {exc}"}
        ready = bool(hello.get("ready"))
        if ready:
            self.sock.settimeout(None)
        with self._lock:
            self.alive, self.settled = ready, True
            self.refusal = "" if ready else f"the fork server is not ready: {hello}"
            self._replied.notify_all()
        return ready

    def spawn(self, argv: Sequence[str], env: Mapping[str, str], cwd: str,
              fd_env: Mapping[str, int] | None = None, target: str = TARGET) -> ForkedProcess:
        """Fork a child that runs ``target(argv)`` with ``env`` in ``cwd``; ``fd_env``: descriptors it keeps, each
        named in its environment by its number there. Raises :class:`ForkServerError` (nothing was started)."""
        names = list(fd_env or {})
        if not self.ready():
            raise ForkServerError(self.refusal or "the fork server has ended")
        read, write = os.pipe()
        with self._lock:
            if not self.alive:
                os.close(read)
                os.close(write)
                raise ForkServerError("the fork server has ended")
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
            reply = self._replies.pop(ident, {"error": "the fork server has ended"})
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
            self.close()
            return
        try:
            while True:
                packet = self.sock.recv(_PACKET)
                if not packet:
                    break
                message = json.loads(packet)
                with self._lock:
                    if "exited" in message:
                        pid, code = int(message["exited"]), int(message["code"])
                        child = self._children.pop(pid, None)
                        if child is None:
                            self._early[pid] = code
                        else:
                            child.ended(code)
                    else:
                        self._replies[int(message["id"])] = message
                        self._replied.notify_all()
        except (OSError, ValueError):
            pass
        with self._lock:
            self.alive = False
            for child in self._children.values():
                child.ended(-signal.SIGTERM)
            self._children.clear()
            self._replied.notify_all()

    def close(self, timeout: float = 5.0) -> None:
        """End the server (its socket closes; children still running get SIGTERM from its end)."""
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self.sock.close()
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def wanted(env: Mapping[str, str] | None = None) -> bool:
    """Whether a grade forks its simulators (:data:`SWITCH_ENV`; on unless switched off)."""
    value = (os.environ if env is None else env).get(SWITCH_ENV, "on").strip().lower()
    return value not in ("off", "0", "no", "false")


_current: ForkServer | None = None
_current_lock = threading.Lock()


def current() -> ForkServer | None:
    """The fork server of the :func:`serving` block this process is in (None: start processes the usual way)."""
    return _current if _current is not None and _current.usable else None


@contextmanager
def serving(enabled: bool = True) -> Iterator[ForkServer | None]:
    """A fork server for the block (nested blocks share the outer one), starting while the block goes on; None when
    it cannot be started (and one that never becomes ready refuses its spawns): either only costs the imports it
    would have saved. ``enabled`` False: none."""
    global _current
    with _current_lock:
        outer = _current is not None
        if enabled and not outer:
            try:
                _current = ForkServer()
            except (ForkServerError, OSError):
                _current = None
        server = _current
    try:
        yield server if enabled else None
    finally:
        if enabled and not outer and server is not None:
            with _current_lock:
                _current = None
            server.close()


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
    """The server's life (see the module docstring): import, say ready, fork on request, reap, report."""
    sock = socket.socket(fileno=fd)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C is the grade's to handle; the socket's end is ours
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
    sock.send(json.dumps({"ready": ready, "threads": threads, "lttng": hooks is not None}).encode())
    if not ready:
        return 1
    wake_read, wake_write = os.pipe()
    os.set_blocking(wake_write, False)
    signal.set_wakeup_fd(wake_write)
    signal.signal(signal.SIGCHLD, lambda *_: None)  # a handler, so SIGCHLD reaches the wake-up pipe
    try:
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
    except (BrokenPipeError, ConnectionResetError):
        return 0


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
