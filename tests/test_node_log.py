"""Reading a graded node's log: rclpy's shutdown race is told apart from the node's own crash on the way out."""

from __future__ import annotations

from bt_nav.grading.node_log import import_findings, last_traceback, rclpy_shutdown_race

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
    assert frames[0] == (NODE, "<module>") and frames[-1][1] == "_take_subscription" and line.startswith("Runtime")


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
