"""What a graded node's own output (``node.log``) says about how it ended, in words for its author.

Two readings, both of the text only (no rclpy):

- :func:`import_findings`: ``No module named X``: the node ran with a Python that lacks ROS 2 (or X).
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

#: One frame line of a Python traceback: its file and function.
_FRAME = re.compile(r'^\s*File "([^"]+)", line \d+, in (\S+)', re.MULTILINE)
#: Where rclpy's own files live (a wheel's site-packages or /opt/ros/<distro>/lib/python3.x/site-packages).
_RCLPY = re.compile(r"[/\\]rclpy[/\\]")


def import_findings(text: str) -> list[str]:
    """``No module named X`` in the node's output: its interpreter is not the one with ROS 2 (or X is missing)."""
    missing = sorted(set(re.findall(r"No module named '([\w.]+)'", text)))
    return [f"the node could not import {name} (ModuleNotFoundError): run it with a Python that has ROS 2 and "
            "its packages (the venv's python, or a sourced ROS install)" for name in missing]


def last_traceback(text: str) -> tuple[list[tuple[str, str]], str] | None:
    """The frames ``(file, function)`` and the final ``Type: message`` line of the last traceback in ``text``."""
    start = text.rfind("Traceback (most recent call last):")
    if start < 0:
        return None
    block = text[start:]
    frames = _FRAME.findall(block)
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
    inside = [bool(_RCLPY.search(path)) for path, _ in frames]
    if True not in inside or exception.startswith(("KeyboardInterrupt", "SystemExit")):
        return None
    entry = inside.index(True)
    if not all(inside[entry:]) or entry == 0:
        return None
    if not any(path.endswith("executors.py") for path, _ in frames[entry:]):
        return None
    if not frames[entry][1].startswith("spin"):
        return None
    return exception.split(" (#define")[0]  # pybind11's advice on its own build is no help to a student
