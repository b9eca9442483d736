"""A periodic callback on the node's clock that fires on time under rclpy's ``EventsExecutor``, sim time included.

Why: on sim time the ``SingleThreadedExecutor`` costs a node most of its CPU (it rebuilds its wait set in Python
at every wake-up: ~0.15 ms a callback, and ``/clock``, odometry and scans wake a node hundreds of times a wall
second at 5-30x real time). Jazzy's ``EventsExecutor`` runs its loop in C++ and costs a third of that, but its
timers of a simulated clock fire late: it does not wake them when ``/clock`` jumps past their deadline, so a
simulator that waits for the node's command at that deadline stalls (see :func:`bt_nav.ros.runner.uses_sim_time`).

:class:`ClockTimers` makes rclpy timers where that matters: on wall time they *are* rclpy timers
(``node.create_timer``); on sim time one ``/clock`` subscription of their own calls each back from the sample that
reaches its deadline, by the rule rclpy's own timers follow (:class:`Deadlines`). A node whose periodic work all runs
on ClockTimers can spin the EventsExecutor on sim time (:func:`bt_nav.ros.runner.run_node` asks its wiring for
``events_ready``).

The time a callback runs at is :meth:`ClockTimers.now_s`: the ``/clock`` sample that fired it. The node's own
clock takes the same sample in rclpy's time source, but the two subscriptions' callbacks run in no fixed order,
so a callback that read ``node.get_clock()`` could see the sample before.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

NS = 1_000_000_000


class Deadlines:
    """When a periodic timer of a jumping clock is due: what rclpy's own timer does on sim time (measured against it,
    tests/ros/test_clock_timers.py).

    The first deadline is one period after the start. A sample at or past the deadline fires once, and the next
    deadline is the first point of the grid after that sample: a clock that jumped over several deadlines fires once,
    then keeps the grid. A clock that went backwards (a simulator restarted) restarts the grid one period after the
    sample. Pure: integer nanoseconds, no rclpy.
    """

    def __init__(self, period_ns: int, start_ns: int) -> None:
        if period_ns <= 0:
            raise ValueError(f"a timer's period must be positive, got {period_ns} ns")
        self.period = int(period_ns)
        self.next = int(start_ns) + self.period
        self.last = int(start_ns)

    def take(self, now_ns: int) -> bool:
        """True when a call is due at ``now_ns`` (and counts it)."""
        if now_ns < self.last:
            self.next = now_ns + self.period
        self.last = now_ns
        if now_ns < self.next:
            return False
        self.next += self.period
        if self.next <= now_ns:
            self.next += ((now_ns - self.next) // self.period + 1) * self.period
        return True


class ClockTimers:
    """Periodic callbacks on ``node``'s clock (see the module docstring): :meth:`every` makes one, ``cancel()`` on
    what it returns stops it. One ``/clock`` subscription serves all of a node's timers.

    ``sim``: the node runs on ``/clock`` (its ``use_sim_time``: :func:`bt_nav.ros.runner.uses_sim_time`); otherwise
    every timer is an rclpy timer of the node's clock.
    """

    def __init__(self, node: Any, sim: bool) -> None:
        self._node = node
        self._now_ns = int(node.get_clock().now().nanoseconds)
        self._timers: list[_SimTimer] = []
        self._subscription: Any = None
        if sim:
            from rclpy.qos import QoSProfile, ReliabilityPolicy
            from rosgraph_msgs.msg import Clock

            # What rclpy's time source subscribes with: the newest sample is all a clock needs.
            self._subscription = node.create_subscription(
                Clock, "/clock", self._on_clock, QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))

    @property
    def sim(self) -> bool:
        """Driven by ``/clock`` samples (not rclpy timers)."""
        return self._subscription is not None

    def every(self, period: float, callback: Callable[[], None]) -> Any:
        """``callback()`` every ``period`` s of the node's clock from now; returns the timer (``cancel()``)."""
        if self._subscription is None:
            return self._node.create_timer(period, callback)
        timer = _SimTimer(Deadlines(round(period * NS), self._now_ns), callback)
        self._timers.append(timer)
        return timer

    def now_s(self) -> float:
        """The node's time in seconds: on sim time the newest ``/clock`` sample taken here."""
        if self._subscription is None:
            return self._node.get_clock().now().nanoseconds * 1e-9
        return self._now_ns * 1e-9

    def _on_clock(self, msg: Any) -> None:
        now = int(msg.clock.sec) * NS + int(msg.clock.nanosec)
        self._now_ns = now
        for timer in tuple(self._timers):
            if not timer.cancelled and timer.deadlines.take(now):
                timer.callback()
        if any(timer.cancelled for timer in self._timers):
            self._timers = [timer for timer in self._timers if not timer.cancelled]

    def cancel(self) -> None:
        """Cancel every sim timer made here (rclpy timers are the node's to destroy)."""
        for timer in self._timers:
            timer.cancel()


class _SimTimer:
    """One periodic callback of :class:`ClockTimers` on sim time."""

    def __init__(self, deadlines: Deadlines, callback: Callable[[], None]) -> None:
        self.deadlines = deadlines
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        """No more calls (idempotent)."""
        self.cancelled = True
