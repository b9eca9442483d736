"""The simulator node over real DDS: clock, sensor metadata, motion, collisions, bad input, followers."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from simtools import Probe, Proc, stamp_of, wait_until, yaw_of

SPAWN = (-0.7, 0.0)  # stage_4's spawn, facing +x
# The inner wall at x = 0.204 (0.15 thick) has its face at x = 0.129: a robot (r = 0.12) spawned at
# x = -0.3 touches it after 0.309 m.
WALL_FACE = 0.204 - 0.075


@pytest.fixture
def sim(ros_context: Any) -> Iterator[Callable[..., tuple[Proc, Probe]]]:
    """Factory: start ``bt-nav sim <args>`` and a probe; both stopped at teardown."""
    started: list[tuple[Proc, Probe]] = []

    def start(*args: str, stamped: bool = False) -> tuple[Proc, Probe]:
        probe = Probe(ros_context, stamped=stamped)
        proc = Proc("sim", *args)
        started.append((proc, probe))
        wait_until(lambda: probe.now() > 0.0 and len(probe.truth) > 0, 20.0, "the simulator's first messages",
                   proc.output)
        return proc, probe

    yield start
    for proc, probe in started:
        proc.stop()
        probe.close()


@pytest.mark.parametrize("profile, range_max, period", [("lab", 3.5, 0.2), ("homework", 10.0, 0.1)])
def test_clock_scan_and_odometry(sim: Callable[..., tuple[Proc, Probe]], profile: str, range_max: float,
                                 period: float) -> None:
    proc, probe = sim("--profile", profile)
    probe.wait_sim_time(probe.now() + 1.5)
    with probe.lock:
        clock = list(probe.clock)
        scans = list(probe.scans)
        odom = list(probe.odom)
        truth = list(probe.truth)
    assert proc.alive(), proc.output()
    assert all(b > a for a, b in zip(clock, clock[1:], strict=False)), "/clock must only move forward"
    assert len(scans) >= 5
    scan = scans[-1]
    assert len(scan.ranges) == 360
    assert scan.angle_min == 0.0
    assert scan.angle_increment == pytest.approx(2 * math.pi / 360, rel=1e-6)
    assert scan.angle_max == pytest.approx(2 * math.pi * 359 / 360, rel=1e-6)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.12, range_max))
    assert scan.scan_time == pytest.approx(period)
    assert scan.header.frame_id == "base_scan"
    stamps = [stamp_of(s) for s in scans]
    assert [round(b - a, 6) for a, b in zip(stamps, stamps[1:], strict=False)] == [period] * (len(stamps) - 1)
    # stage_4 at the spawn: the wall at x = 0.129 is 0.829 m straight ahead (beam 0), nothing is beyond range.
    assert scan.ranges[0] == pytest.approx(WALL_FACE - SPAWN[0], abs=0.05)
    assert all(math.isfinite(r) and scan.range_min <= r <= range_max for r in scan.ranges[:10])

    assert odom[-1].header.frame_id == "odom" and odom[-1].child_frame_id == "base_footprint"
    assert truth[-1].header.frame_id == "world"
    assert (truth[-1].pose.pose.position.x, truth[-1].pose.pose.position.y) == pytest.approx(SPAWN)
    assert (odom[-1].pose.pose.position.x, odom[-1].pose.pose.position.y) == pytest.approx((0.0, 0.0))
    odom_stamps = [stamp_of(m) for m in odom]
    gaps = [b - a for a, b in zip(odom_stamps, odom_stamps[1:], strict=False)]
    assert max(gaps) <= 0.041 and sum(gaps) / len(gaps) == pytest.approx(1 / 30, rel=0.1)


def test_cmd_vel_moves_the_robot(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim("--ros-args", "-p", "noise:=false")
    start = probe.now()
    probe.command = (0.2, 0.4)
    probe.wait_sim_time(start + 2.0)
    probe.command = (0.0, 0.0)
    probe.wait_sim_time(probe.now() + 0.5)
    truth = probe.last_truth().pose.pose
    odom = probe.odom[-1].pose.pose
    assert proc.alive(), proc.output()
    moved = math.hypot(truth.position.x - SPAWN[0], truth.position.y - SPAWN[1])
    assert 0.3 < moved < 0.5, moved
    assert truth.position.y > 0.01 and yaw_of(truth) > 0.5  # turning left while driving
    # Without noise, odometry is exact: the pose relative to the start, in the odom frame.
    assert (odom.position.x, odom.position.y) == pytest.approx((truth.position.x - SPAWN[0], truth.position.y),
                                                                abs=1e-6)
    assert yaw_of(odom) == pytest.approx(yaw_of(truth), abs=1e-6)


def test_one_collision_event_per_contact(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim("--ros-args", "-p", "spawn_x:=-0.3", "-p", "noise:=false")
    probe.command = (0.22, 0.0)
    wait_until(lambda: len(probe.collisions) >= 1, 20.0, "a collision event", proc.output)
    probe.wait_sim_time(probe.now() + 2.0)  # keep pushing against the wall: still one event
    assert len(probe.collisions) == 1, probe.collisions
    event = probe.collisions[0]
    assert set(event) == {"t", "x", "y", "yaw"}
    assert event["x"] == pytest.approx(WALL_FACE - 0.12, abs=1e-3) and event["y"] == pytest.approx(0.0)
    assert probe.last_truth().pose.pose.position.x == pytest.approx(WALL_FACE - 0.12, abs=1e-3)  # no penetration
    probe.command = (-0.1, 0.0)  # back off, then drive in again: a second event
    probe.wait_sim_time(probe.now() + 1.0)
    probe.command = (0.22, 0.0)
    wait_until(lambda: len(probe.collisions) >= 2, 20.0, "a second collision event", proc.output)
    assert probe.collisions[1]["t"] > event["t"] + 1.0


def test_bad_commands_never_crash_it(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim()
    probe.command = (math.nan, math.inf)
    probe.wait_sim_time(probe.now() + 1.0)
    assert proc.alive(), proc.output()
    assert probe.last_truth().pose.pose.position.x == pytest.approx(SPAWN[0])  # a bad command is a stop
    probe.command = (0.2, 0.0)
    probe.wait_sim_time(probe.now() + 1.0)
    assert probe.last_truth().pose.pose.position.x > SPAWN[0] + 0.1
    assert any("non-finite cmd_vel" in line for line in proc.stderr)


def test_twist_stamped_commands(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim("--ros-args", "-p", "cmd_vel_stamped:=true", stamped=True)
    probe.command = (0.2, 0.0)
    probe.wait_sim_time(probe.now() + 1.0)
    assert probe.last_truth().pose.pose.position.x > SPAWN[0] + 0.1, proc.output()


def test_sim_time_waits_for_a_holding_follower(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim()
    held_at = probe.now()
    probe.sync(who="test", t=held_at, hold=True)
    wait_until(lambda: any("following test" in line for line in proc.stderr), 10.0, "the sim to follow", proc.output)
    import time

    time.sleep(0.2)  # a step the loop had begun before the hold may still land (its /clock in flight)
    frozen = probe.now()
    time.sleep(0.5)  # wall time passes, sim time must not
    assert probe.now() == frozen
    assert frozen - held_at < 1.0
    probe.sync(who="test", t=frozen, hold=False)  # released, but lagging: at most max_lag (0.1 s) ahead
    time.sleep(0.3)
    assert probe.now() <= frozen + 0.1 + 1e-6
    probe.sync(who="test", leave=True)
    probe.wait_sim_time(frozen + 1.0)


def test_a_thinned_clock_ticks_with_every_message_and_where_it_waits(sim: Callable[..., tuple[Proc, Probe]]) -> None:
    proc, probe = sim("--ros-args", "-p", "clock_rate_hz:=10.0")
    probe.wait_sim_time(probe.now() + 1.0)
    with probe.lock:
        clock = [round(c, 6) for c in probe.clock]
        stamps = [round(stamp_of(m), 6) for m in probe.odom[-20:] + probe.scans[-5:]]
    assert set(stamps) <= set(clock), "a message's stamp must be an instant /clock said"
    rate = (len(clock) - 1) / (clock[-1] - clock[0])
    # odometry's 30 Hz holds the 10 Hz floor and the scans' instants; the probe reads best effort and, on a busy
    # machine, misses one now and then (29.8 seen in CI): thinned means well under one per 10 ms physics step
    assert 27.0 <= rate <= 50.0, f"{rate:.1f} /clock samples per sim second (odometry's 30 Hz, the 10 Hz floor)"
    import time

    ahead = probe.now() + 0.3  # a follower that says its clock is there: sim time stops one max_lag later
    probe.sync(who="test", t=ahead, hold=False)
    wait_until(lambda: any("following test" in line for line in proc.stderr), 10.0, "the sim to follow", proc.output)
    time.sleep(0.6)
    assert probe.now() == pytest.approx(ahead + 0.05, abs=1e-6), "the instant it waits at must go out on /clock"
    probe.sync(who="test", leave=True)


def test_its_pace_stops_are_written_as_data_at_exit(sim: Callable[..., tuple[Proc, Probe]], tmp_path: Path) -> None:
    """``pace_path``: when sim time stopped waiting for a follower (silent, or holding too long) and when that
    follower spoke again, in sim time, as the log lines say them to people (a grade reads the file, never the log)."""
    pace = tmp_path / "pace.json"
    proc, probe = sim("--ros-args", "-p", f"pace_path:={pace}", "-p", "follower_timeout:=0.3", "-p",
                      "hold_timeout:=0.3")

    def said(words: str, count: int = 1) -> list[float]:
        wait_until(lambda: sum(words in line for line in proc.stderr) >= count, 20.0, words, proc.output)
        return [float(m) for line in proc.stderr if words in line for m in re.findall(r"\(t=([\d.]+) s\)", line)]

    probe.command = (0.0, 0.0)
    said("following cmd_vel")
    probe.command = None  # silent: dropped after 0.3 s wall
    [dropped] = said("cmd_vel silent or holding too long")
    probe.command = (0.0, 0.0)  # speaks again: waited for again
    resumed = said("following cmd_vel", 2)[1]
    probe.sync(who="test", t=probe.now(), hold=True)  # holds longer than hold_timeout: dropped too
    [held] = said("test silent or holding too long")
    assert not pace.exists()  # written on the way out
    assert proc.stop() == 0, proc.output()
    record = json.loads(pace.read_text(encoding="utf-8"))
    assert record["follower_timeout"] == 0.3 and record["hold_timeout"] == 0.3 and record["t_end"] >= held
    stops = record["stops"]
    assert [(s["who"], s["why"]) for s in stops] == [("cmd_vel", "silent"), ("test", "holding")], stops
    assert (stops[0]["t"], stops[0]["resumed"]) == pytest.approx((dropped, resumed), abs=0.006)
    assert stops[1]["t"] == pytest.approx(held, abs=0.006) and stops[1]["resumed"] is None
    assert dropped < resumed <= held


def test_refuses_an_unknown_profile() -> None:
    proc = Proc("sim", "--ros-args", "-p", "profile:=gazebo")
    assert proc.wait(20.0) == 2  # a refused configuration (bt_nav.ros.runner), as the executive's
    assert "unknown profile 'gazebo'" in proc.output()


def test_a_reliable_subscriber_gets_scans_and_odometry(sim: Callable[..., tuple[Proc, Probe]],
                                                        ros_context: Any) -> None:
    """The lab's template subscribes ``create_subscription(LaserScan, 'scan', cb, 10)`` (RELIABLE, depth 10):
    a best-effort writer offered it nothing (the probe's sensor-data reader still gets scans too)."""
    import threading

    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import LaserScan

    proc, probe = sim("--profile", "lab")
    node = rclpy.create_node("template_like", context=ros_context)
    got: dict[str, int] = {"scan": 0, "odom": 0}
    node.create_subscription(LaserScan, "scan", lambda m: got.__setitem__("scan", got["scan"] + 1), 10)
    node.create_subscription(Odometry, "odom", lambda m: got.__setitem__("odom", got["odom"] + 1), 10)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    try:
        wait_until(lambda: got["scan"] >= 5 and got["odom"] >= 5, 20.0, "scans and odometry on reliable readers",
                   proc.output)
        before = len(probe.scans)
        wait_until(lambda: len(probe.scans) > before, 10.0, "scans on the best-effort probe too", proc.output)
    finally:
        executor.shutdown()
        node.destroy_node()


def _spun_node(ros_context: Any, name: str) -> tuple[Any, Any]:
    """A plain rclpy node in the test's context with its own executor spinning in a thread (node, executor)."""
    import threading

    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node = rclpy.create_node(name, context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    return node, executor


def test_a_default_subscription_gets_ground_truth(sim: Callable[..., tuple[Proc, Probe]], ros_context: Any) -> None:
    """The homework's own evaluator subscribes ``/ground_truth_odom`` with the default QoS (reliable, depth 10)."""
    from nav_msgs.msg import Odometry

    proc, _ = sim()
    node, executor = _spun_node(ros_context, "evaluator_like")
    got: list[Any] = []
    node.create_subscription(Odometry, "/ground_truth_odom", got.append, 10)
    try:
        wait_until(lambda: len(got) >= 5, 20.0, "ground truth on a default subscription", proc.output)
        assert got[-1].header.frame_id == "world"
    finally:
        executor.shutdown()
        node.destroy_node()


@pytest.mark.parametrize("follow", [False, True])
def test_cmd_vel_reader_reliability(sim: Callable[..., tuple[Proc, Probe]], ros_context: Any, follow: bool) -> None:
    """Without ``follow`` (``bt-nav grade --exe``) the reader is best effort, so a node publishing commands with
    sensor-data QoS drives the robot; with ``follow`` (bt_nav's executive, reliable) it stays reliable."""
    from geometry_msgs.msg import Twist
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    proc, probe = sim("--ros-args", "-p", f"follow:={str(follow).lower()}", "-p", "noise:=false")
    def readers() -> list[Any]:
        return [r for r in probe.node.get_subscriptions_info_by_topic("/cmd_vel") if r.node_name == "bt_nav_sim"]

    wait_until(lambda: len(readers()) == 1, 20.0, "the simulator's cmd_vel reader on the graph", proc.output)
    [reader] = readers()
    expected = ReliabilityPolicy.RELIABLE if follow else ReliabilityPolicy.BEST_EFFORT
    assert reader.qos_profile.reliability == expected
    assert any("cmd_vel read " + expected.name.lower() in line for line in proc.stderr), proc.output()
    if follow:
        return
    node, executor = _spun_node(ros_context, "best_effort_driver")
    pub = node.create_publisher(Twist, "cmd_vel", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    command = Twist()
    command.linear.x = 0.2
    node.create_timer(0.05, lambda: pub.publish(command))
    try:
        wait_until(lambda: probe.last_truth().pose.pose.position.x > SPAWN[0] + 0.1, 20.0,
                   "the robot to move on best-effort commands", proc.output)
    finally:
        executor.shutdown()
        node.destroy_node()


def test_refuses_an_unknown_cmd_vel_reliability() -> None:
    proc = Proc("sim", "--ros-args", "-p", "cmd_vel_reliability:=sometimes")
    assert proc.wait(20.0) == 2
    assert "cmd_vel_reliability must be auto, reliable or best_effort" in proc.output()


def _sim_rate(probe: Probe, wall: float) -> float:
    """Sim seconds per wall second over ``wall`` s, as the probe's /clock shows them."""
    import time

    began, first = time.monotonic(), probe.now()
    time.sleep(wall)
    return (probe.now() - first) / (time.monotonic() - began)


def test_sim_time_runs_at_1x_until_its_hosted_judge_starts(sim: Callable[..., tuple[Proc, Probe]],
                                                           tmp_path: Path) -> None:
    """Before its t0 a hosted judge judges nothing: sim time runs at ``unjudged_rtf`` (1x, as a robot's world while
    its node starts), not at ``idle_rtf`` (10x); from t0 on, with nobody to follow, at ``idle_rtf``."""
    from std_srvs.srv import SetBool

    judge = ["--ros-args", "-p", "use_sim_time:=false", "-p", "activate_service:=/paced/activate", "-p",
             f"json:={tmp_path / 'verdict.json'}", "-p", "audit:=false", "-p", "timeout:=60.0"]
    proc, probe = sim("--rtf", "0", "--judge", "referee", "--judge-args", json.dumps(judge))
    before = _sim_rate(probe, 1.0)
    assert 0.5 <= before <= 1.5, f"{before:.2f}x before t0\n{proc.output()}"
    probe.node.create_service(SetBool, "/paced/activate", lambda _request, response: response)
    wait_until(lambda: any("t0 = sim" in line for line in proc.stderr), 20.0, "the judge's t0", proc.output)
    judged = _sim_rate(probe, 1.0)
    assert judged >= 3.0, f"{judged:.2f}x after t0 (idle_rtf 10x)\n{proc.output()}"
