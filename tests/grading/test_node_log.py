"""Reading a graded node's log: rclpy's shutdown race is told apart from the node's own crash on the way out, and a
node that exited with an error is told the exception that ended it, where its code raised it, and whether it came
while the node was starting."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bt_nav.grading.exe.log import (
    Crash,
    import_findings,
    is_nodes_own,
    last_traceback,
    node_crash,
    rclpy_shutdown_race,
)

SITE = "/venv/lib/python3.11/site-packages/rclpy"
NODE = "/home/student/ws/src/pkg/pkg/node.py"

#: The traceback a correct node (tests/fixtures/stamped_node.py) printed when SIGINT met the executor's take.
RACE = f"""[INFO] [reactive_control]: armed
Traceback (most recent call last):
  File "{NODE}", line 56, in <module>
    main()
  File "{NODE}", line 47, in main
    rclpy.spin(node)
  File "{SITE}/__init__.py", line 247, in spin
    executor.spin_once()
  File "{SITE}/executors.py", line 839, in spin_once
    self._spin_once_impl(timeout_sec)
  File "{SITE}/executors.py", line 834, in _spin_once_impl
    raise handler.exception()
  File "{SITE}/task.py", line 269, in __call__
    self._handler.send(None)
  File "{SITE}/executors.py", line 396, in _take_subscription
    msg_info = sub.handle.take_message(sub.msg_type, sub.raw)
               ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^
RuntimeError: Unable to convert call argument '0' to Python object
"""

#: A callback of the node's raised: its frame is below rclpy's.
CALLBACK = f"""Traceback (most recent call last):
  File "{NODE}", line 47, in main
    rclpy.spin(node)
  File "{SITE}/__init__.py", line 247, in spin
    executor.spin_once()
  File "{SITE}/executors.py", line 834, in _spin_once_impl
    raise handler.exception()
  File "{SITE}/executors.py", line 532, in handler
    await call_coroutine()
  File "{NODE}", line 30, in on_scan
    self.publish(0.0)
  File "{SITE}/publisher.py", line 70, in publish
    self.__publisher.publish(msg)
rclpy._rclpy_pybind11.RCLError: failed to publish: publisher's context is invalid
"""

#: The node published after shutting down, in its own finally: rclpy raised, but from the node's call.
FINALLY = f"""Traceback (most recent call last):
  File "{NODE}", line 52, in main
    node.stop()
  File "{NODE}", line 33, in stop
    self.pub.publish(Twist())
  File "{SITE}/publisher.py", line 70, in publish
    self.__publisher.publish(msg)
rclpy._rclpy_pybind11.RCLError: failed to publish: publisher's context is invalid
"""


def test_the_executor_failing_its_take_is_rclpys_race() -> None:
    assert rclpy_shutdown_race(RACE) == "RuntimeError: Unable to convert call argument '0' to Python object"
    frames, line = last_traceback(RACE) or ([], "")
    assert frames[0] == (NODE, 56, "<module>") and frames[-1][2] == "_take_subscription" and line.startswith("Runtime")


def test_the_nodes_own_crashes_are_not() -> None:
    assert rclpy_shutdown_race(CALLBACK) is None  # its callback raised
    assert rclpy_shutdown_race(FINALLY) is None  # it published after shutdown
    assert rclpy_shutdown_race(RACE.replace("RuntimeError: Unable", "KeyboardInterrupt: Unable")) is None
    assert rclpy_shutdown_race("no traceback at all\n") is None
    # the last traceback counts: a race followed by the node's own crash is the node's
    assert rclpy_shutdown_race(RACE + "\nDuring handling ...\n" + FINALLY) is None


def test_a_missing_module() -> None:
    [found] = import_findings("ModuleNotFoundError: No module named 'rclpy'\n")
    assert found.startswith("the node could not import rclpy (ModuleNotFoundError)")
    assert import_findings("all fine") == []


VENV = "/work/main/.venv/lib/python3.11/site-packages"
STDLIB = "/root/.pyenv/versions/3.11.7/lib/python3.11"

#: ``bt-nav grade --profile lab --exe "python3 reactive_navigator.py" --lidars rplidar``: a lab node that reads
#: its rear-left at pi + 0.1 .. pi + 0.3 rad with angles taken 0..2pi, past the end of the RPLIDAR's scan
#: (-pi..pi), raised in its scan callback under ``rclpy.spin`` (the whole node.log).
SCAN_CALLBACK = f"""Traceback (most recent call last):
  File "/tmp/i35/reactive_navigator.py", line 47, in <module>
    main()
  File "/tmp/i35/reactive_navigator.py", line 41, in main
    rclpy.spin(node)
  File "{VENV}/rclpy/__init__.py", line 247, in spin
    executor.spin_once()
  File "{VENV}/rclpy/executors.py", line 839, in spin_once
    self._spin_once_impl(timeout_sec)
  File "{VENV}/rclpy/executors.py", line 834, in _spin_once_impl
    raise handler.exception()
  File "{VENV}/rclpy/task.py", line 269, in __call__
    self._handler.send(None)
  File "{VENV}/rclpy/executors.py", line 518, in handler
    await call_coroutine()
  File "{VENV}/rclpy/executors.py", line 406, in _execute
    await await_or_execute(sub.callback, *msg_tuple)
  File "{VENV}/rclpy/executors.py", line 111, in await_or_execute
    return callback(*args)
           ^^^^^^^^^^^^^^^
  File "/tmp/i35/reactive_navigator.py", line 30, in scan_cb
    behind = min(msg.ranges[first:last])
             ^^^^^^^^^^^^^^^^^^^^^^^^^^^
ValueError: min() arg is an empty sequence
"""

#: The same grade of a node that reads its parameter without declaring it: rclpy raised inside its ``__init__``.
INIT = f"""Traceback (most recent call last):
  File "/tmp/i35/init_crash.py", line 20, in <module>
    main()
  File "/tmp/i35/init_crash.py", line 16, in main
    rclpy.spin(ReactiveNavigator())
               ^^^^^^^^^^^^^^^^^^^
  File "/tmp/i35/init_crash.py", line 10, in __init__
    self.safety = self.get_parameter("safety_distance").value
                  ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^
  File "{VENV}/rclpy/node.py", line 690, in get_parameter
    raise ParameterNotDeclaredException(name)
rclpy.exceptions.ParameterNotDeclaredException: Invalid access to undeclared parameter(s): safety_distance
"""

#: A node run by a Python without ROS 2.
IMPORT = """Traceback (most recent call last):
  File "/tmp/i35/gen/node.py", line 2, in <module>
    import rclpy
ModuleNotFoundError: No module named 'rclpy'
"""

#: The standard library raised, from the node's function (python3.11, the node's code at top level).
STDLIB_RAISED = f"""Traceback (most recent call last):
  File "/tmp/i35/gen/stat2.py", line 8, in <module>
    mean_front([])
  File "/tmp/i35/gen/stat2.py", line 5, in mean_front
    return statistics.mean(r for r in ranges if r < 3.5)
           ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^
  File "{STDLIB}/statistics.py", line 432, in mean
    raise StatisticsError('mean requires at least one data point')
statistics.StatisticsError: mean requires at least one data point
"""

#: What a thread's uncaught exception prints: the thread ends, the process does not (it exited 0 here).
THREAD = f"""Exception in thread Thread-1 (worker):
Traceback (most recent call last):
  File "{STDLIB}/threading.py", line 1045, in _bootstrap_inner
    self.run()
  File "{STDLIB}/threading.py", line 982, in run
    self._target(*self._args, **self._kwargs)
  File "/tmp/i35/gen/stat.py", line 10, in worker
    mean_front([])
  File "/tmp/i35/gen/stat.py", line 6, in mean_front
    return statistics.mean(r for r in ranges if r < 3.5)
           ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^
  File "{STDLIB}/statistics.py", line 432, in mean
    raise StatisticsError('mean requires at least one data point')
statistics.StatisticsError: mean requires at least one data point
"""

#: The lab fixture stopped by SIGINT inside rclpy's wait (a real node.log): a signal's, not a crash.
SIGINT_IN_SPIN = f"""Traceback (most recent call last):
  File "/tmp/n35/drifter.py", line 26, in <module>
    main()
  File "/tmp/n35/drifter.py", line 22, in main
    rclpy.spin(Drifter())
  File "{VENV}/rclpy/__init__.py", line 247, in spin
    executor.spin_once()
  File "{VENV}/rclpy/executors.py", line 839, in spin_once
    self._spin_once_impl(timeout_sec)
  File "{VENV}/rclpy/executors.py", line 823, in _spin_once_impl
    handler, entity, node = self.wait_for_ready_callbacks(
                            ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^
  File "{VENV}/rclpy/executors.py", line 793, in wait_for_ready_callbacks
    return next(self._cb_iter)
           ^^^^^^^^^^^^^^^^^^^
  File "{VENV}/rclpy/executors.py", line 697, in _wait_for_ready_callbacks
    wait_set.wait(timeout_nsec)
KeyboardInterrupt
"""


def test_a_callback_crash_quotes_the_exception_and_the_nodes_line() -> None:
    crash = node_crash("[INFO] [reactive_navigator]: started\n" + SCAN_CALLBACK)
    assert crash == Crash("ValueError: min() arg is an empty sequence", "reactive_navigator.py:30 in scan_cb", False)
    assert crash.quote() == ("ValueError: min() arg is an empty sequence (reactive_navigator.py:30 in scan_cb; "
                             "see node.log)")


def test_a_crash_while_starting_is_told_so() -> None:
    """Raised in an ``__init__`` (rclpy's frame below it does not count as the node's) or at an import: before the
    node could spin, so no speed of the simulation changed it."""
    assert node_crash(INIT) == Crash("rclpy.exceptions.ParameterNotDeclaredException: Invalid access to undeclared "
                                     "parameter(s): safety_distance", "init_crash.py:10 in __init__", True)
    assert node_crash(IMPORT) == Crash("ModuleNotFoundError: No module named 'rclpy'", "node.py:2 in <module>", True)
    assert node_crash(STDLIB_RAISED) == Crash("statistics.StatisticsError: mean requires at least one data point",
                                              "stat2.py:5 in mean_front", False)


def test_what_did_not_end_the_node_is_not_its_crash() -> None:
    """A signal's KeyboardInterrupt (in rclpy's wait, or while importing), rclpy's own shutdown race, and a
    traceback that did not end the process (a thread's) are not quoted as the node's crash."""
    assert node_crash(SIGINT_IN_SPIN) is None
    assert node_crash(INIT.replace("rclpy.exceptions.ParameterNotDeclaredException: Invalid access to undeclared "
                                   "parameter(s): safety_distance", "KeyboardInterrupt")) is None
    assert node_crash(RACE) is None
    assert node_crash(THREAD) is None and last_traceback(THREAD) is not None
    assert node_crash("no traceback\n") is None


def test_the_nodes_own_files() -> None:
    """rclpy, the standard library, site- and dist-packages and frozen modules are not the node's; a colcon
    workspace's install of its package (``ros2 run``) is."""
    assert is_nodes_own("/tmp/i35/reactive_navigator.py")
    assert is_nodes_own("/home/s/ws/install/lab1/lib/python3.12/site-packages/lab1/reactive_navigator.py")
    assert is_nodes_own("/home/s/ws/install/lib/python3.12/site-packages/lab1/reactive_navigator.py")
    for path in (f"{VENV}/rclpy/executors.py", f"{STDLIB}/statistics.py", "<frozen runpy>",
                 "/usr/lib/python3/dist-packages/numpy/core/fromnumeric.py",
                 "/opt/ros/jazzy/lib/python3.12/site-packages/sensor_msgs/msg/_laser_scan.py",
                 "/home/s/ws/install/rclpy/lib/python3.12/site-packages/rclpy/node.py"):
        assert not is_nodes_own(path), path


def test_a_long_message_is_cut() -> None:
    crash = node_crash(IMPORT.replace("No module named 'rclpy'", "x" * 500))
    assert crash is not None and len(crash.exception) == 200 and crash.exception.endswith("...")


def test_the_reason_of_a_node_that_exited_with_an_error() -> None:
    """The grade's reason for a run whose node exited first (bt_nav.grading.exe.run): its crash quoted, else only
    its exit code; an exit code other than Python's 1 for an uncaught exception is named too."""
    from bt_nav.grading.exe.run import _exit_reason

    assert _exit_reason(1, 12.34, node_crash(SCAN_CALLBACK)) == (
        "the node crashed after 12.3 s wall: ValueError: min() arg is an empty sequence (reactive_navigator.py:30 in "
        "scan_cb; see node.log)")
    assert _exit_reason(3, 2.0, node_crash(IMPORT)).startswith("the node crashed after 2.0 s wall (exit code 3): ")
    assert _exit_reason(-11, 3.0, node_crash(THREAD)) == ("the node exited with code -11 after 3.0 s wall, before "
                                                         "the verdict (see node.log)")


@pytest.mark.parametrize("source, error", [
    ("import rclpy\ndef scan_cb(msg:\n    pass\n", "SyntaxError: "),
    ("import rclpy\nif True:\nprint('x')\n", "IndentationError: expected an indented block"),
])
def test_a_script_that_does_not_compile_is_quoted_at_its_line(tmp_path: Path, source: str, error: str) -> None:
    """Python reports a script that does not compile without a "Traceback" header: the crash is still quoted,
    at the script's line, as one that came while starting."""
    script = tmp_path / "reactive_navigator.py"
    script.write_text(source)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True)
    crash = node_crash("[INFO] [launcher]: starting\n" + out.stderr)
    assert crash is not None and crash.exception.startswith(error), out.stderr
    assert crash.where == "reactive_navigator.py:2" or crash.where == "reactive_navigator.py:3"
    assert crash.starting
