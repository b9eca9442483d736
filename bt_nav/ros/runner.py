"""Run one node as a process: ROS arguments, SIGINT/SIGTERM, the spin loop and a shutdown that stops the robot.

The executive's, the simulator's, the referee's and the check-off judge's ``main`` are this plus the node's
own wiring. The order matters for safety: a signal only ends the spin loop, the wiring's ``close()`` then
publishes its stops while the ROS context is still up, and only after that is the context shut down
(rclpy's own signal handlers would shut it down first, so they are off).

A node that ends by itself (the simulator after ``duration``, a judge after its verdict) offers
:class:`Finishing`: ``poll()`` runs after every spin and ends the loop when it returns True, and its
``exit_code`` (read after ``close()``) is the process's exit status. Wiring with more nodes of the process
(``extra_nodes``: the judge hosted by the simulator) gets them spun by the same executor and destroyed with it.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Callable, Sequence
from contextlib import suppress
from typing import Any, Protocol

import rclpy
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args

from bt_nav.ros.rosutil import ConfigError, make_executor
from bt_nav.ros.supervise import StopRequest

EXIT_OK, EXIT_ERROR, EXIT_CONFIG = 0, 1, 2
#: Longest wait inside the executor before the loop looks at the shutdown flag again.
SPIN_TIMEOUT = 0.05


class Closable(Protocol):
    """What a node's wiring offers the runner: a ``close()`` that stops the robot and never raises."""

    def close(self) -> None: ...  # noqa: D102


class Finishing(Closable, Protocol):
    """Wiring that ends by itself: ``poll()`` after every spin (True: done), then ``exit_code``."""

    exit_code: int

    def poll(self) -> bool: ...  # noqa: D102


def param_args(values: dict[str, Any]) -> list[str]:
    """``--ros-args -p name:=value ... --`` for options of a node's own command line that are shorthands for
    its parameters (None: not given, skipped)."""
    from bt_nav.ros.bringup import param_arg

    items = [a for name, value in values.items() if value is not None for a in ("-p", param_arg(name, value))]
    return ["--ros-args", *items, "--"] if items else []


def init_ros(name: str, argv: list[str] | None, parse_args: Callable[[list[str]], argparse.Namespace], *,
             ros_defaults: Sequence[str] = (),
             ros_args_of: Callable[[argparse.Namespace], list[str]] | None = None) -> argparse.Namespace | int:
    """``rclpy.init`` with the process's arguments; our own options, or the exit status to return now.

    ``ros_defaults`` (e.g. ``-p use_sim_time:=true``) go before the user's ROS arguments, so the user's win;
    ``ros_args_of(options)`` (shorthand options as ``-p``, see :func:`param_args`) go after them.
    """
    args = [name, *(sys.argv[1:] if argv is None else argv)]
    try:
        own = remove_ros_args(args=args)[1:]  # rcl parses (and refuses) --ros-args here, params files included
    except Exception as exc:
        print(f"{name}: refusing to start: bad ROS arguments: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_CONFIG
    try:
        options = parse_args(own)
    except SystemExit as exc:  # --help, or an unknown option
        return int(exc.code or 0) if not isinstance(exc.code, str) else EXIT_CONFIG
    defaults = ["--ros-args", *ros_defaults, "--"] if ros_defaults else []
    args = [args[0], *defaults, *args[1:], *(ros_args_of(options) if ros_args_of is not None else [])]
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:
        print(f"{name}: refusing to start: bad ROS arguments: {exc}".replace("\n", " "), file=sys.stderr)
        return EXIT_CONFIG
    return options


def uses_sim_time(node: Node) -> bool:
    """Does ``node`` run on ``/clock``? Such a node spins the ``SingleThreadedExecutor``: Jazzy's
    ``EventsExecutor`` lets a sim-time timer stall for up to a second when ``/clock`` stops at the timer's
    deadline, which is exactly where the simulator waits for its followers (measured: a 20 Hz timer behind a
    follower-paced clock ran at 1.6x real time with 12 one-second stalls in 20 sim s, against 250x)."""
    return bool(node.has_parameter("use_sim_time") and node.get_parameter("use_sim_time").value)


def spin_until_stopped(node: Node, executor: Executor, shutdown: StopRequest,
                       poll: Callable[[], bool] | None = None) -> None:
    """Spin until a signal, an external shutdown or ``poll()`` says done; then say which (signals, shutdown)."""
    while not shutdown.requested and rclpy.ok():
        executor.spin_once(timeout_sec=SPIN_TIMEOUT)
        if poll is not None and poll():
            return
    if shutdown.requested:
        name = signal.Signals(shutdown.signum).name if shutdown.signum is not None else "signal"
        node.get_logger().info(f"{name} received: stopping the robot and shutting down")
    else:
        node.get_logger().info("ROS shut down from outside: stopping the robot")


def run_node(name: str, argv: list[str] | None, parse_args: Callable[[list[str]], argparse.Namespace],
             build: Callable[[Node, argparse.Namespace], Closable],
             prepare: Callable[[Node], Callable[[], None]] | None = None, *,
             make_node: Callable[[str], Node] | None = None, ros_defaults: Sequence[str] = (),
             ros_args_of: Callable[[argparse.Namespace], list[str]] | None = None) -> int:
    """Run node ``name`` until SIGINT/SIGTERM, an external shutdown or (:class:`Finishing` wiring) its end;
    the process's exit status.

    ``make_node(name)`` creates the node (default a plain ``Node``; the simulator and the judges are
    ``Node`` subclasses); ``prepare`` runs first on the new node and returns its undo (the executive routes
    py_trees' logging); ``build`` wires the node and may raise :class:`ConfigError` (or ValueError, or
    FileNotFoundError for a file a parameter names) to refuse. ``ros_defaults``, ``ros_args_of``: as
    :func:`init_ros`'s.

    Returns:
        0 after a clean shutdown (signals included), 2 when the configuration is refused, 1 after an
        unexpected error (the robot is stopped in every case that still has a ROS context); Finishing
        wiring's ``exit_code`` otherwise.
    """
    options = init_ros(name, argv, parse_args, ros_defaults=ros_defaults, ros_args_of=ros_args_of)
    if isinstance(options, int):
        return options
    shutdown = StopRequest()
    shutdown.install()
    node: Node | None = None
    wiring: Closable | None = None
    executor: Executor | None = None
    undo: Callable[[], None] | None = None
    code = EXIT_OK
    try:
        try:
            node = make_node(name) if make_node is not None else Node(name)
            undo = prepare(node) if prepare is not None else None
            wiring = build(node, options)
            extra = tuple(getattr(wiring, "extra_nodes", ()))
            # A callback that takes MessageInfo (a hosted judge's audit, reading each command's sequence number) fails
            # under Jazzy's EventsExecutor.
            info = any(getattr(other, "needs_message_info", True) for other in extra)
            executor = make_executor(events=False if uses_sim_time(node) or info else None)
        except (ConfigError, ValueError, FileNotFoundError) as exc:
            message = f"refusing to start: {exc}".replace("\n", " ")
            if node is not None:
                node.get_logger().fatal(message)
            else:
                print(f"{name}: {message}", file=sys.stderr)
            return EXIT_CONFIG
        executor.add_node(node)
        for other in extra:
            executor.add_node(other)
        spin_until_stopped(node, executor, shutdown, getattr(wiring, "poll", None))
    except (KeyboardInterrupt, ExternalShutdownException):
        if node is not None:
            node.get_logger().warning("interrupted: stopping the robot and shutting down")
    except Exception as exc:
        code = EXIT_ERROR
        if node is not None:
            node.get_logger().fatal(f"unexpected error, shutting down: {exc!r}")
        else:
            print(f"{name}: unexpected error: {exc!r}", file=sys.stderr)
    finally:
        shutdown.closing = True
        _tear_down(wiring, executor, node, undo)
        shutdown.restore()
    if code == EXIT_OK and wiring is not None and hasattr(wiring, "exit_code"):
        code = int(wiring.exit_code)  # read after close(): a judge stopped before its verdict says so there
    return code


def _tear_down(wiring: Closable | None, executor: Executor | None, node: Node | None,
               undo: Callable[[], None] | None) -> None:
    """Close the wiring (the stop goes out), then the executor, the node and the context; never raises."""
    if wiring is not None:
        wiring.close()
    if executor is not None:
        with suppress(Exception):
            executor.shutdown(timeout_sec=0.5)
    for other in (*getattr(wiring, "extra_nodes", ()), node):
        if other is not None:
            with suppress(Exception):
                other.destroy_node()
    if undo is not None:
        undo()
    rclpy.try_shutdown()
