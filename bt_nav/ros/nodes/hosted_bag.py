"""A run's bag written by the simulator's own process: ``bt-nav sim --record BAG`` (a ``bt-nav grade --exe`` run).

Why in the simulator: a recorder of its own process started a Python interpreter and a DDS participant per graded
run, subscribed to what the simulator had just published, and followed ``/clock`` to stamp it; that was about a fifth
of a run's CPU on two cores, taken from the node being graded, and its bag began whenever it had found the topics.
Hosted, every message the simulator publishes goes into the bag as it is published (:attr:`SimulatorNode.taps`),
stamped with the exact sim time of its step, from the first one on. What the simulator does not publish comes over DDS
as before: the robot's commands at the sim time they arrived (the instant the physics took them), and the graph's log
lines. The bag holds what a ``bt-nav record`` of the run held (:data:`bt_nav.grading.exe.bag.RUN_TOPICS`): the same
topics, types and offered QoS, ``/rosout`` lines as mission events on ``/bt_nav/events`` at the sim time of their log
call, ``/bt_nav/mission`` naming the world, and :data:`bt_nav.media.bag.FIRST_MESSAGES` beside it.

Threads: the loop thread taps the simulator's messages, the executor thread the commands and log lines; one lock keeps
the writer whole. The bag is closed once the loop has stopped (:attr:`SimulatorNode.closers`), after the graded node
was stopped (its last zero twists are in it); a message arriving after that is dropped.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import serialize_message

from bt_nav.media.bag import (
    CLOCK,
    CMD,
    COLLISIONS,
    EVENTS,
    ODOM,
    ROSOUT,
    SCAN,
    TOPICS,
    TREE,
    TRUTH,
    WALKERS,
    MissionBag,
    write_first_messages,
)
from bt_nav.ros.graphtap import OWN_NODES, event_text
from bt_nav.ros.simclock import SimClock

#: What ``bt-nav sim --record`` records unless told (``--record-topics``): all it publishes but ``/clock``, the
#: commands, the log lines, bt_nav's executive's tree. A graded run records less
#: (:data:`bt_nav.grading.exe.bag.RUN_TOPICS`).
RECORD_TOPICS = (SCAN, ODOM, TRUTH, CMD, COLLISIONS, WALKERS, ROSOUT, TREE)


def msgtype_of(msg: Any) -> str:
    """``pkg/msg/Name`` of an rclpy message object (what a bag's connection names)."""
    cls = type(msg)
    return f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}"


class HostedRecorder:
    """The bag ``path`` of the simulator ``sim`` (a :class:`bt_nav.ros.nodes.simulator.SimulatorNode` whose loop has
    not started), recording ``topics`` (absolute names; ``/rosout`` as events); ``mission``: the run's facts for
    ``/bt_nav/mission``.

    Raises:
        bt_nav.media.bag.BagError: the bag cannot be written (the directory exists, no room).
    """

    def __init__(self, sim: Any, path: str | Path, topics: Iterable[str], mission: dict[str, Any]) -> None:
        self.sim = sim
        self.wanted = set(topics)
        self.bag = MissionBag(path, flush_every=1.0)
        self.lock = threading.Lock()
        self.clock = SimClock()  # wall -> sim, for the log lines' stamps (a log call's wall time)
        self.first_clock: tuple[int, int] | None = None  # (wall ns, sim ns) of the first /clock
        self.first: dict[str, float] = {}
        with self.lock:
            self.bag.mission(0.0, {**mission, "source": "dds"})
        sim.taps.append(self._tap)
        sim.closers.append(self.close)
        if ROSOUT in self.wanted:
            self._rosout_sub()
        if TREE in self.wanted:  # bt_nav's own executive publishes its tree (latched)
            from std_msgs.msg import String

            sim.create_subscription(String, TREE, lambda data: self._write(TREE, None, self._now(), bytes(data)),
                                    QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL), raw=True)

    def _now(self) -> int:
        return int(self.sim.core.t_ns)

    def _tap(self, topic: str, msg: Any, t_ns: int, data: bytes | None = None) -> None:
        """One message the simulator published or took (see :attr:`SimulatorNode.taps`; ``data``: its bytes, when the
        simulator serialized it)."""
        if topic == CLOCK:
            wall = time.time_ns()
            self.clock.add(wall, t_ns)
            if self.first_clock is None:
                self.first_clock = (wall, t_ns)
            return
        if topic in self.wanted:
            self._write(topic, msgtype_of(msg), t_ns, serialize_message(msg) if data is None else data)

    def _rosout_sub(self) -> None:
        """The graph's log lines (the robot node's, the hosted judge's, the simulator's) as mission events."""
        from rcl_interfaces.msg import Log
        from std_msgs.msg import String

        def on_log(msg: Any) -> None:
            if msg.level >= 20 and not msg.name.startswith(OWN_NODES):
                wall = msg.stamp.sec * 1_000_000_000 + msg.stamp.nanosec  # the log call's wall time
                when = self.clock.sim_at(wall) if wall else None
                if when is None and self.first_clock is not None and wall < self.first_clock[0]:
                    when = self.first_clock[1]  # logged before the first /clock (the start-up lines): not now
                data = serialize_message(String(data=event_text(msg.name, msg.level, msg.msg)))
                self._write(EVENTS, "std_msgs/msg/String", self._now() if when is None else int(when), data)

        # transient local, as Jazzy's /rosout publishers offer it: the node's start-up lines come as history
        self.sim.create_subscription(Log, ROSOUT, on_log,
                                     QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL))

    def _write(self, topic: str, msgtype: str | None, t_ns: int, data: bytes) -> None:
        """Into the bag (any thread); the topic's first message noted in :data:`FIRST_MESSAGES`."""
        with self.lock:
            if self.bag.closed:
                return
            first = topic not in self.bag.counts
            self.bag.write_raw(topic, t_ns, data, msgtype or TOPICS[topic].msgtype)
            if first:
                self._note_first(topic, t_ns * 1e-9)

    def _note_first(self, topic: str, t: float) -> None:
        """Rewrite :data:`FIRST_MESSAGES` with ``topic`` (a file that cannot be written is skipped: the bag matters
        more than its note)."""
        self.first[topic] = round(t, 6)
        write_first_messages(self.bag.path, self.first)

    def close(self) -> None:
        """Close the bag (idempotent; the messages still arriving are dropped)."""
        with self.lock:
            if not self.bag.closed:
                self.bag.close()

