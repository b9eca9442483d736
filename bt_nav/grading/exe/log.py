"""What a graded node's own output (``node.log``) says about how it ended, in words for its author.

Three readings, all of the text only (no rclpy):

- :func:`import_findings`: ``No module named X``: the node ran with a Python that lacks ROS 2 (or X).
- :func:`node_crash`: the exception that ended a node which exited with an error, as its author needs it: the
  ``Type: message`` line and where the node's own code raised it (``reactive_navigator.py:57 in scan_cb``), and
  whether it came while the node was still starting (importing, or inside an ``__init__``, outside rclpy's
  executor), where no speed of the simulation can have changed it.
- :func:`rclpy_shutdown_race`: the node's last traceback was raised inside rclpy's executor while it took a
  message, with no frame of the node's own code below the spin call. SIGINT landed while the executor was inside
  its C++ take: the KeyboardInterrupt that Python raises there (or the take on a context rclpy's own handler has
  just shut down) comes out of pybind11 as ``RuntimeError: Unable to convert call argument '0'`` (or an
  ``RCLError``), which ``rclpy.spin`` re-raises and no ``except KeyboardInterrupt`` catches. Seen with rclpy's
  signal handler (tests/fixtures/stamped_node.py: 1 in 6 runs under load) and without it (the lab fixture: 2 in
  42), as ``joint_state_publisher`` reports on Humble: the grader must not tell a node's author to fix rclpy's.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import PurePath

#: One frame line of a Python traceback: its file, line and function.
_FRAME = re.compile(r'^\s*File "([^"]+)", line (\d+), in (\S+)', re.MULTILINE)
#: Where rclpy's own files live (a wheel's site-packages or /opt/ros/<distro>/lib/python3.x/site-packages).
_RCLPY = re.compile(r"[/\\]rclpy[/\\]")
#: A Python installation's own tree (the standard library, its site- or dist-packages: numpy, rclpy, messages) ...
_INSTALLED = re.compile(r"[/\\]lib(?:64)?[/\\]python3[^/\\]*[/\\]|^/opt/ros/")
#: ... except a colcon workspace's install of the student's package (``ros2 run``):
#: ``ws/install/<pkg>/lib/python3.12/site-packages/<pkg>/node.py`` (``--merge-install``: no ``<pkg>/``).
_WORKSPACE = re.compile(r"[/\\]install[/\\](?:[^/\\]+[/\\])?lib(?:64)?[/\\]python3")
#: The functions a traceback that ended the process starts at: the script's top level (``python3 -m``: runpy's).
_TOP_LEVEL = ("<module>", "_run_module_as_main")
#: Exceptions only an import raises (a module missing, or one that does not compile).
_IMPORTING = ("ImportError", "ModuleNotFoundError", "SyntaxError", "IndentationError", "TabError")
#: Characters of an exception line quoted in a reason (a message can hold a whole array).
QUOTE_LIMIT = 200

#: One frame of a traceback: file, line, function.
Frame = tuple[str, int, str]


def import_findings(text: str) -> list[str]:
    """``No module named X`` in the node's output: its interpreter is not the one with ROS 2 (or X is missing)."""
    missing = sorted(set(re.findall(r"No module named '([\w.]+)'", text)))
    return [f"the node could not import {name} (ModuleNotFoundError): run it with a Python that has ROS 2 and "
            "its packages (the venv's python, or a sourced ROS install)" for name in missing]


def last_traceback(text: str) -> tuple[list[Frame], str] | None:
    """The frames ``(file, line, function)`` and the final ``Type: message`` line of the last traceback in ``text``."""
    start = text.rfind("Traceback (most recent call last):")
    if start < 0:
        return None
    block = text[start:]
    frames = [(path, int(line), function) for path, line, function in _FRAME.findall(block)]
    tail = [line for line in block.splitlines()[1:] if line and not line.startswith((" ", "\t"))]
    return frames, (tail[0] if tail else "")


def rclpy_shutdown_race(text: str) -> str | None:
    """The exception line when the last traceback is rclpy's executor failing on its own during shutdown.

    That is: the traceback enters rclpy at a spin call of the node's code, passes through ``rclpy/executors.py``,
    and no frame after that entry is outside rclpy (a callback of the node's that raised would be one).
    """
    found = last_traceback(text)
    if found is None:
        return None
    frames, exception = found
    inside = [bool(_RCLPY.search(path)) for path, _, _ in frames]
    if True not in inside or exception.startswith(("KeyboardInterrupt", "SystemExit")):
        return None
    entry = inside.index(True)
    if not all(inside[entry:]) or entry == 0:
        return None
    if not any(path.endswith("executors.py") for path, _, _ in frames[entry:]):
        return None
    if not frames[entry][2].startswith("spin"):
        return None
    return exception.split(" (#define")[0]  # pybind11's advice on its own build is no help to a student


#: The end of Python's report on a script that does not compile: no "Traceback" header, the file and line, the
#: source line and a caret, then ``SyntaxError: ...`` (or IndentationError, TabError) at the start of a line.
_COMPILE_ERROR = re.compile(r'^  File "([^"]+)", line (\d+)\n(?:[ \t].*\n)*?((?:SyntaxError|IndentationError|TabError)'
                            r'\b.*)$', re.MULTILINE)


def script_compile_error(text: str) -> Crash | None:
    """The node's own script did not compile (Python printed no traceback, only where and the error): a crash
    while starting, at that line."""
    matches = list(_COMPILE_ERROR.finditer(text))
    if not matches:
        return None
    path, line, exception = matches[-1].groups()
    quoted = exception if len(exception) <= QUOTE_LIMIT else exception[:QUOTE_LIMIT - 3] + "..."
    return Crash(quoted, f"{PurePath(path).name}:{line}", True)


@dataclass(frozen=True)
class Crash:
    """The exception that ended a node, in the words of its traceback."""

    exception: str  # the traceback's last line, ``Type: message`` (cut at QUOTE_LIMIT characters)
    where: str | None  # ``file.py:57 in scan_cb``: the innermost frame of the node's own code (None: none is)
    starting: bool  # raised while importing or inside an ``__init__``, outside rclpy's executor

    def quote(self) -> str:
        """``ValueError: min() arg is an empty sequence (reactive_navigator.py:57 in scan_cb; see node.log)``."""
        return f"{self.exception} ({self.where}; see node.log)" if self.where else f"{self.exception} (see node.log)"


def is_nodes_own(path: str) -> bool:
    """Whether a traceback's file is the node's code: not rclpy's, not in a Python installation (the standard
    library, site-packages: numpy, messages) unless in a colcon workspace's ``install/``, not Python's frozen
    modules (``<frozen runpy>``)."""
    if path.startswith("<") or _RCLPY.search(path):
        return False
    return not _INSTALLED.search(path) or bool(_WORKSPACE.search(path))


def node_crash(text: str) -> Crash | None:
    """The exception that ended the node whose output is ``text``, or None when its last traceback did not end it.

    Only a traceback that starts at the script's top level ended the process (Python prints an uncaught exception
    from there, after which nothing of the node runs): one a thread printed, or the node printed and survived,
    starts lower. A KeyboardInterrupt is a signal's, and rclpy's own shutdown race (:func:`rclpy_shutdown_race`)
    is not the node's: neither is quoted as its crash. ``starting``: no frame of rclpy's executor (no callback,
    no spin) and the exception an ImportError or raised inside an ``__init__`` of the node's code, i.e. before
    the node could see the simulation move: no speed of it can have changed the crash.
    """
    found = last_traceback(text)
    if found is None or not found[0] or not found[1]:
        return script_compile_error(text)
    frames, exception = found
    if frames[0][2] not in _TOP_LEVEL or exception.startswith("KeyboardInterrupt") or rclpy_shutdown_race(text):
        return None
    own = [(path, line, function) for path, line, function in frames if is_nodes_own(path)]
    where = f"{PurePath(own[-1][0]).name}:{own[-1][1]} in {own[-1][2]}" if own else None
    spinning = any(_RCLPY.search(path) and path.endswith("executors.py") for path, _, _ in frames)
    importing = exception.split(":")[0].rsplit(".", 1)[-1] in _IMPORTING
    starting = not spinning and (importing or any(function == "__init__" for _, _, function in own))
    quoted = exception if len(exception) <= QUOTE_LIMIT else exception[:QUOTE_LIMIT - 3] + "..."
    return Crash(quoted, where, starting)
