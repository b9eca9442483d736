"""Fixtures for tests that run real rclpy nodes over real DDS (all marked ``ros`` automatically).

Importing :mod:`ros_harness` sets this process's DDS environment (localhost only, a domain of its own
in 215-232 claimed with a lock file) before anything calls ``rclpy.init``; the executives started by
the fixtures inherit it. See ros_harness.py for how the tests drive simulated time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.signals import SignalHandlerOptions
from ros_harness import STARTUP_TIMEOUT, ExecutiveProcess, Harness

from bt_nav.testing import front_scan, laserscan_msg

PRIME = laserscan_msg(front_scan())  # a free scan, sent until the executive says it has one


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark every test below tests/ros with ``ros`` (``-m 'not ros'`` skips DDS tests)."""
    here = Path(__file__).parent
    for item in items:
        if here in item.path.parents:
            item.add_marker(pytest.mark.ros)


# ---------------------------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="session")
def ros_context() -> Iterator[Any]:
    """One rclpy context for the test process (its own, so other tests' ``rclpy.init`` is not disturbed)."""
    context = rclpy.Context()
    rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
    yield context
    rclpy.try_shutdown(context=context)


@pytest.fixture
def start_executive() -> Iterator[Callable[..., ExecutiveProcess]]:
    """Factory: start an executive subprocess with ``--ros-args -p use_sim_time:=true <args>``; stopped at teardown."""
    started: list[ExecutiveProcess] = []

    def start(*ros_args: str, sim_time: bool = True, command: list[str] | None = None,
              env: dict[str, str] | None = None, extra: tuple[str, ...] = ()) -> ExecutiveProcess:
        args = [*extra, "--ros-args", *(["-p", "use_sim_time:=true"] if sim_time else []), *ros_args]
        process = ExecutiveProcess(args, command=command, env=env)
        started.append(process)
        return process

    yield start
    for process in started:
        process.stop()


@pytest.fixture
def make_harness(ros_context: Any) -> Iterator[Callable[..., Harness]]:
    """Factory: a harness node; at teardown it checks every command it saw was sane, then goes away."""
    made: list[Harness] = []

    def make(**kwargs: Any) -> Harness:
        harness = Harness(ros_context, **kwargs)
        made.append(harness)
        return harness

    yield make
    for harness in made:
        harness.close()
    for harness in made:
        harness.assert_sane()


@pytest.fixture
def executive(start_executive: Callable[..., ExecutiveProcess], make_harness: Callable[..., Harness]
              ) -> Callable[..., Harness]:
    """Factory: start an executive and a harness connected to it: disarmed, commands and scans flowing."""

    def start(*ros_args: str, stamped: bool = False, arm_service: str = "/arm") -> Harness:
        harness = make_harness(stamped=stamped, arm_service=arm_service)
        process = start_executive(*ros_args)
        harness.connect(process)
        # Matching is seen from the harness's side only; these prove the executive's side too.
        harness.first_contact()  # its /clock reader and cmd_vel writer
        harness.wait(lambda: harness.tick(scan=PRIME).is_zero and process.has_line("scan usable again"),
                     "the executive to receive scans", STARTUP_TIMEOUT)
        return harness

    return start
