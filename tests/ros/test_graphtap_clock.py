"""The graph tap before the first ``/clock``: what comes first waits for the clock instead of being stamped 0.

Over real DDS, in this process: a publisher sends commands (no stamp of their own) before anything publishes
``/clock``; then the clock starts at 40 s of sim time. The tap must hand the early commands on once the clock is
there, timed against it (40 s), not at 0 s, which a recorder joined to the node before the simulator (10 sim s at
20x on a loaded CI machine, seen) used to write. A graph that never gets a ``/clock`` still gets its messages,
stamped 0, after :data:`bt_nav.ros.graphtap.EARLY_WAIT` wall seconds: a live view must not stay blank.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from bt_nav.testing import wait_until

CLOCK_S = 40.0


@pytest.fixture
def tap_and_talker(ros_context: Any) -> Any:
    """A tap on /tap_test_cmd (in a node of its own) and a talker node; both spun in a thread."""
    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.executors import MultiThreadedExecutor
    from rosgraph_msgs.msg import Clock

    from bt_nav.ros.graphtap import GraphTap

    got: list[tuple[str, int]] = []
    tap_node = rclpy.create_node("tap_under_test", context=ros_context)
    tap = GraphTap(tap_node, ["/tap_test_cmd"], lambda topic, _type, t_ns, _data, _qos: got.append((topic, t_ns)))
    talker = rclpy.create_node("tap_talker", context=ros_context)
    cmd = talker.create_publisher(Twist, "/tap_test_cmd", 10)
    clock = talker.create_publisher(Clock, "/clock", 10)
    executor = MultiThreadedExecutor(context=ros_context)
    executor.add_node(tap_node)
    executor.add_node(talker)
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.02)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    wait_until(lambda: "/tap_test_cmd" in tap.subscribed, 10.0, "the tap subscribed to the commands")

    def send_clock(t: float) -> None:
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = int(t), int((t % 1.0) * 1e9)
        clock.publish(msg)

    try:
        yield tap, got, lambda: cmd.publish(Twist()), send_clock
    finally:
        stop.set()
        thread.join(timeout=2.0)
        for node in (tap_node, talker):
            executor.remove_node(node)
            node.destroy_node()


def test_commands_before_the_first_clock_are_timed_by_it(tap_and_talker: Any) -> None:
    tap, got, send_cmd, send_clock = tap_and_talker
    time.sleep(0.5)  # the talker's publisher matched
    for _ in range(5):
        send_cmd()
        time.sleep(0.05)
    time.sleep(0.3)
    assert got == [], "handed on before any /clock: they would be stamped 0"
    deadline = time.monotonic() + 10.0
    while not got and time.monotonic() < deadline:
        send_clock(CLOCK_S)
        time.sleep(0.05)
    wait_until(lambda: len(got) >= 5, 5.0, "the held commands handed on")
    assert all(t_ns >= int(CLOCK_S * 1e9) for _, t_ns in got), [t for _, t in got]
    send_cmd()
    wait_until(lambda: len(got) >= 6, 5.0, "a command after the clock, at once")


def test_a_graph_without_a_clock_still_gets_its_messages(tap_and_talker: Any) -> None:
    from bt_nav.ros.graphtap import EARLY_WAIT

    tap, got, send_cmd, _ = tap_and_talker
    time.sleep(0.5)
    started = time.monotonic()
    while len(got) < 3 and time.monotonic() - started < EARLY_WAIT + 5.0:
        send_cmd()
        time.sleep(0.1)
    assert len(got) >= 3, "messages held for ever on a graph without /clock"
    assert time.monotonic() - started >= EARLY_WAIT * 0.9, "handed on before the wait for a clock ended"
    assert all(t_ns == 0 for _, t_ns in got), "no clock: stamped 0, as before"
