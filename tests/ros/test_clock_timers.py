""":class:`bt_nav.ros.clocktimer.ClockTimers` on rclpy's EventsExecutor against rclpy's own timer on the
SingleThreadedExecutor: two nodes on sim time, one ``/clock`` publisher over real DDS, the same samples; the callbacks
must come at the same sample times (and on wall time a ClockTimers timer is an rclpy timer)."""

from __future__ import annotations

import time
from typing import Any

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

from bt_nav.ros.clocktimer import NS, ClockTimers

SAMPLES_MS = [10, 30, 50, 51, 120, 370, 400, 410, 2000, 2050, 2100, 2149, 2151, 2250, 500, 520, 550, 551, 600]


def _sim_node(name: str, context: Any) -> Any:
    return rclpy.create_node(name, context=context, parameter_overrides=[Parameter("use_sim_time", value=True)])


def _spin_until(executors: list[Any], done: Any, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for executor in executors:
            executor.spin_once(timeout_sec=0.005)
        if done():
            return True
    return False


def test_clock_timers_fire_at_the_samples_rclpys_own_timer_fires_at(ros_context: Any) -> None:
    from rclpy.experimental import EventsExecutor

    ours, theirs, source = (_sim_node("clock_timers_ours", ros_context), _sim_node("clock_timers_rclpy", ros_context),
                            rclpy.create_node("clock_timers_source", context=ros_context))
    fired_ours: list[int] = []
    fired_theirs: list[int] = []
    timers = ClockTimers(ours, sim=True)
    assert timers.sim
    timers.every(0.05, lambda: fired_ours.append(round(timers.now_s() * 1000)))
    theirs.create_timer(0.05, lambda: fired_theirs.append(round(theirs.get_clock().now().nanoseconds / 1e6)))
    events, single = EventsExecutor(context=ros_context), SingleThreadedExecutor(context=ros_context)
    events.add_node(ours)
    single.add_node(theirs)
    clock = source.create_publisher(Clock, "/clock", QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE))
    try:
        # Ours, ours' time source and theirs' time source: three readers matched.
        assert _spin_until([events, single], lambda: clock.get_subscription_count() >= 3)
        for ms in SAMPLES_MS:
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = divmod(ms * 1_000_000, NS)
            clock.publish(msg)
            assert _spin_until([events, single], lambda ms=ms: round(timers.now_s() * 1000) == ms
                               and round(theirs.get_clock().now().nanoseconds / 1e6) == ms), f"sample {ms} ms lost"
            for _ in range(5):  # rclpy's timer is ready after its clock's jump: let it fire
                single.spin_once(timeout_sec=0.01)
        assert fired_ours == fired_theirs, f"{fired_ours} vs rclpy {fired_theirs}"
        assert fired_ours[:3] == [50, 120, 370] and 2000 in fired_ours, fired_ours
    finally:
        events.shutdown()
        single.shutdown()
        for node in (ours, theirs, source):
            node.destroy_node()


def test_on_wall_time_clock_timers_are_rclpy_timers(ros_context: Any) -> None:
    node = rclpy.create_node("clock_timers_wall", context=ros_context)
    try:
        timers = ClockTimers(node, sim=False)
        timer = timers.every(0.01, lambda: None)
        assert not timers.sim and isinstance(timer, rclpy.timer.Timer)
        assert timers.now_s() == pytest.approx(time.time(), abs=1.0)
    finally:
        node.destroy_node()
