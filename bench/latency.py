"""Benchmark 2: reaction latency over DDS, from a scan that changes the decision to the command that shows it.

Set-up: the real executive runs as a subprocess (``bt-nav executive``, wall time, default 20 Hz tick,
maneuver none, a one-hour mission so the deadline never interferes) in a DDS domain of its own; a
probe node in this process plays the LiDAR and listens to ``cmd_vel``. Once armed, the probe
alternates between a *clear* scan (everything at 3 m: full speed, 0.22 m/s straight) and a *blocked*
one (an obstacle 0.2 m ahead: stop and rotate in place), switching after a random 0.25-0.35 s so
the switches fall at every phase of the executive's tick timer. Between switches the same content is
re-sent at 10 Hz (the homework LiDAR's rate) so the scan never goes stale.

Every scan's ``header.stamp`` is the wall-clock (``CLOCK_REALTIME``) instant it was published: the
marker of the event. Latency of a switch = DDS reception time, in this process, of the first
``cmd_vel`` whose content reflects the new scan (linear 0.22 and angular 0 after *clear*; linear 0
and angular != 0 after *blocked*) minus that marker. rmw's message info splits it:

- ``to published``: the reflecting command's ``source_timestamp`` (when the executive published it)
  minus the marker: scan transport, the wait for the next tick, the tick itself;
- ``return``: its reception minus its ``source_timestamp``: the command's transport.

A command published after the marker that still shows the old decision is a *late pickup* (the scan
arrived just after that tick started). A switch with no reflecting command before the next switch
is a *miss*. Theory: the wait for the next tick is uniform in [0, 50 ms], so p99 is about 49.5 ms
plus transport and tick; the target is one tick period + 3 ms, with no misses.
"""

from __future__ import annotations

import bisect
import os
import random
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

from bt_nav.ros.bringup import EXECUTIVE_NAME, NodeSpec
from bt_nav.ros.rosutil import ThreadedNode, dds_env
from bt_nav.run.session import MissionSession
from bt_nav.testing import front_scan, laserscan_msg, wait_until

from .common import Target, at_most, percentiles
from .ros_mission import EXECUTIVE_STATS, executive_stats, proc_status

TICK_HZ = 20.0
TARGET_SLACK_MS = 3.0
V_MAX = 0.22
CLEAR_RANGE, BLOCKED_RANGE = 3.0, 0.2
PHASE_S = (0.25, 0.35)
RESEND_S = 0.1
STARTUP_TIMEOUT = 30.0


def reflects(kind: str, linear: float, angular: float) -> bool:
    """Does a command show the decision a ``kind`` scan calls for?"""
    if kind == "clear":
        return abs(linear - V_MAX) < 1e-6 and angular == 0.0
    return linear == 0.0 and angular != 0.0


class Probe:
    """The measuring node: publishes scans, records every ``cmd_vel`` with rmw's timestamps, calls ``arm``.

    Its executor spins in a thread of its own, so receptions are handled while the main thread
    sleeps between publications; the latency itself uses the DDS reception timestamp, which does not
    depend on when the callback runs.
    """

    def __init__(self, domain: int) -> None:
        from geometry_msgs.msg import Twist
        from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
        from sensor_msgs.msg import LaserScan
        from std_srvs.srv import SetBool

        os.environ.update(dds_env(domain))
        self.ros = ThreadedNode("bt_nav_bench_latency")
        self.node = self.ros.node
        self.scan_pub = self.node.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        # (callback ns, received ns, source ns, linear, angular)
        self.commands: list[tuple[int, int, int, float, float]] = []
        self.cmd_sub = self.node.create_subscription(
            Twist, "cmd_vel", self._on_cmd, QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.arm_client = self.node.create_client(SetBool, "arm")
        self._set_bool = SetBool
        self.ros.start()

    def _on_cmd(self, msg: Any, info: Any) -> None:
        self.commands.append((time.time_ns(), int(info.get("received_timestamp") or 0),
                              int(info.get("source_timestamp") or 0), float(msg.linear.x), float(msg.angular.z)))

    def publish(self, msg: Any) -> int:
        """Stamp ``msg`` with the wall clock now and publish it; returns the stamp (ns)."""
        stamp = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        self.scan_pub.publish(msg)
        return stamp

    def matched(self) -> bool:
        """Both topics matched and the arm service is up."""
        return (self.scan_pub.get_subscription_count() > 0 and self.cmd_sub.get_publisher_count() > 0
                and self.arm_client.service_is_ready())

    def arm(self, timeout: float = 5.0) -> tuple[bool, str]:
        """Call ``arm`` with true; (success, message)."""
        future = self.arm_client.call_async(self._set_bool.Request(data=True))
        end = time.monotonic() + timeout
        while not future.done() and time.monotonic() < end:
            time.sleep(0.01)
        if not future.done():
            return False, "no answer"
        result = future.result()
        return bool(result.success), str(result.message)

    def close(self) -> None:
        """Stop spinning, destroy the node, shut the context down."""
        self.ros.close()


def analyse(events: list[tuple[int, str]], commands: list[tuple[int, int, int, float, float]],
            end_ns: int) -> dict[str, Any]:
    """Latencies of the switches (see the module docstring); times in ns in, milliseconds out."""
    total, published, returned, callback = [], [], [], []
    late_pickups = misses = 0
    commands = sorted(commands, key=lambda c: c[1])
    received = [c[1] for c in commands]
    for index, (stamp, kind) in enumerate(events):
        until = events[index + 1][0] if index + 1 < len(events) else end_ns
        stale = 0
        hit = None
        for cb_ns, recv_ns, src_ns, linear, angular in commands[bisect.bisect_right(received, stamp):]:
            if recv_ns > until:
                break
            if reflects(kind, linear, angular):
                hit = (cb_ns, recv_ns, src_ns)
                break
            if src_ns > stamp:
                stale += 1
        if hit is None:
            misses += 1
            continue
        late_pickups += stale > 0
        cb_ns, recv_ns, src_ns = hit
        total.append(recv_ns - stamp)
        published.append(src_ns - stamp)
        returned.append(recv_ns - src_ns)
        callback.append(cb_ns - stamp)
    sources = sorted(c[2] for c in commands if c[1] <= end_ns)  # not the stops published at shutdown
    gaps = [b - a for a, b in zip(sources, sources[1:], strict=False) if b > a]
    return {
        "switches": len(events), "measured": len(total), "misses": misses, "late_pickups": late_pickups,
        "latency_ms": percentiles(total, 1e-6, 3),
        "to_published_ms": percentiles(published, 1e-6, 3),
        "return_transport_ms": percentiles(returned, 1e-6, 3),
        "to_callback_ms": percentiles(callback, 1e-6, 3),
        "tick_interval_ms": percentiles(gaps, 1e-6, 3),
        "commands": len(commands),
    }


def run(domain: int, switches: int = 400, seed: int = 1) -> dict[str, Any]:
    """Start the executive, arm it, alternate clear / blocked ``switches`` times; the latencies."""
    rnd = random.Random(seed)
    clear, blocked = (laserscan_msg(front_scan(front, CLEAR_RANGE)) for front in (CLEAR_RANGE, BLOCKED_RANGE))
    stats_dir = Path(tempfile.mkdtemp(prefix="bt_nav_bench_latency_"))  # the executive's exit statistics
    spec = NodeSpec("executive", EXECUTIVE_NAME,
                    {"use_sim_time": False, "maneuver": "none", "mission_duration": 3600.0,
                     "tick_rate_hz": TICK_HZ, "stats_path": str(stats_dir / EXECUTIVE_STATS)})
    probe = Probe(domain)
    session = MissionSession(domain, sink=lambda _name, _line: None)  # the executive, in the domain
    events: list[tuple[int, str]] = []
    memory: dict[str, int] = {}
    started = time.monotonic()
    try:
        child = session.start(spec)
        wait_until(probe.matched, STARTUP_TIMEOUT, "the executive's endpoints", interval=0.02)
        wait_until(lambda: len(probe.commands) > 0, STARTUP_TIMEOUT, "the executive's first command",
                   step=lambda: probe.publish(clear), interval=0.02)
        ok, message = False, ""
        end = time.monotonic() + STARTUP_TIMEOUT
        while not ok and time.monotonic() < end:
            probe.publish(clear)
            ok, message = probe.arm()
            time.sleep(0.1)
        if not ok:
            raise RuntimeError(f"arming refused: {message}")
        wait_until(lambda: reflects("clear", *probe.commands[-1][3:]), 10.0, "full speed after arming",
                   step=lambda: probe.publish(clear), interval=0.02)
        time.sleep(0.2)
        kind = "clear"
        for _ in range(switches):
            kind = "blocked" if kind == "clear" else "clear"
            msg = blocked if kind == "blocked" else clear
            phase_end = time.monotonic() + rnd.uniform(*PHASE_S)
            events.append((probe.publish(msg), kind))
            next_send = time.monotonic() + RESEND_S
            while True:
                now = time.monotonic()
                if now >= phase_end:
                    break
                if now >= next_send:
                    probe.publish(msg)
                    next_send += RESEND_S
                time.sleep(max(0.0, min(phase_end, next_send) - time.monotonic()))
            if child.poll() is not None:
                raise RuntimeError(f"the executive exited with {child.poll()}")
        time.sleep(0.2)
        end_ns = time.time_ns()
        memory = proc_status(child.popen.pid)
    finally:
        session.close()
        probe.close()
    out = analyse(events, list(probe.commands), end_ns)
    stats = executive_stats(stats_dir / EXECUTIVE_STATS)
    shutil.rmtree(stats_dir, ignore_errors=True)
    out.update({"tick_hz": TICK_HZ, "period_ms": 1e3 / TICK_HZ, "domain": domain,
                "target_p99_ms": 1e3 / TICK_HZ + TARGET_SLACK_MS,
                "executive_tick_stats": stats.get("tick_stats"), "executive_memory": memory,
                "wall_s": round(time.monotonic() - started, 1)})
    return out


def targets(result: dict[str, Any]) -> list[Target]:
    """p99 within a tick period plus 3 ms, and no switch left without a reaction."""
    p99 = result["latency_ms"]["p99"]
    limit = result["target_p99_ms"]
    met = at_most(p99, limit)
    if met is not None and result["misses"]:
        met = False
    return [Target("latency_p99", "latency", "scan -> cmd_vel reaction latency p99 over DDS (20 Hz tick; no misses)",
                   f"<= {limit:g} ms", p99, "ms", met)]
