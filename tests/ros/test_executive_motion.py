"""The executive over DDS: arming, disarming, scans, cmd_vel flavours and the ``~/tree`` topic.

Each test starts its own executive subprocess (``use_sim_time``) and drives it tick by tick from the
harness node (see conftest.py): simulated time only moves when the test moves it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest
from ros_harness import PERIOD, REPO, V_MAX, Harness
from std_msgs.msg import String

from bt_nav.mission.params import SPECS
from bt_nav.mission.snapshot import read_snapshot
from bt_nav.ros.rosutil import LATCHED
from bt_nav.testing import front_scan, laserscan_msg

FREE = laserscan_msg(front_scan())  # nothing within 3 m: full speed


def test_no_motion_before_arm_then_motion_after(executive: Callable[..., Harness]) -> None:
    h = executive("-p", "stats_period:=0.5")
    h.ticks(10, scan=FREE)
    before = len(h.samples)
    assert before >= 11 and all(s.is_zero for s in h.samples), h.samples

    response = h.arm(True)
    assert response.success and "armed" in response.message

    after = h.tick(scan=FREE)  # the first tick after the arming
    assert len(h.samples) == before + 1
    assert after.linear == pytest.approx(V_MAX) and after.angular == 0.0
    # Tick statistics every stats_period of the node clock, i.e. of simulated time here.
    h.wait(lambda: h.process.has_line(r"stats: tick ms min/mean/p99/max [\d./]+ over \d+; ticks \d+, overruns \d+"),
           "a stats line")


def test_disarm_stops_on_the_next_tick(executive: Callable[..., Harness]) -> None:
    h = executive()
    h.arm(True)
    moving = h.ticks(5, scan=FREE)
    assert all(s.linear > 0.0 for s in moving)

    response = h.arm(False)
    assert response.success and "stopped" in response.message
    assert h.tick(scan=FREE).is_zero  # the first tick after the disarm
    assert all(s.is_zero for s in h.ticks(5, scan=FREE))

    again = h.arm(True)
    assert again.success and "again" in again.message
    assert h.tick(scan=FREE).linear > 0.0  # re-armed: drives again


def test_stale_scan_stops_with_a_log_line(executive: Callable[..., Harness]) -> None:
    h = executive("-p", "scan_timeout:=0.5")
    h.arm(True)
    assert h.tick(scan=FREE).linear > 0.0

    # No scans from here on: moving while the scan is fresh, stopped once it is older than 0.5 s. The
    # last scan arrived at the previous tick's time or at this one's (it raced the clock): age +- 1 period.
    last_scan = h.sim_time
    samples = h.ticks(12)
    for sample in samples:
        youngest = sample.sim_time - last_scan
        if youngest + PERIOD < 0.5 - 1e-6:
            assert sample.linear > 0.0, (youngest, sample)
        elif youngest > 0.5 + 1e-6:
            assert sample.is_zero, (youngest, sample)
    assert samples[-1].is_zero
    h.wait(lambda: h.process.has_line(r"ProcessScan: stale scan.*stopping"), "the stale-scan log line")

    usable = len([line for line in h.process.lines if "scan usable again" in line])
    assert h.tick(scan=FREE).linear > 0.0  # a fresh scan: drives again
    h.wait(lambda: len([line for line in h.process.lines if "scan usable again" in line]) > usable,
           "the scan-usable log line")


def test_malformed_scan_stops_and_the_node_survives(executive: Callable[..., Harness]) -> None:
    h = executive()
    h.arm(True)
    assert h.tick(scan=FREE).linear > 0.0
    bad = laserscan_msg(front_scan(increment=0.0))  # angle_increment 0: every beam at one angle
    assert h.tick(scan=bad).is_zero
    h.wait(lambda: h.process.has_line(r"malformed scan"), "the malformed-scan log line")
    nan_ranges = laserscan_msg(front_scan())
    nan_ranges.range_min = math.nan
    assert h.tick(scan=nan_ranges).is_zero
    assert h.tick(scan=FREE).linear > 0.0
    assert h.process.alive


def test_obstacle_ahead_turns_and_odometry_is_accepted(executive: Callable[..., Harness]) -> None:
    h = executive()
    h.arm(True)
    h.publish_odom(0.3)
    close = h.tick(scan=laserscan_msg(front_scan(front=0.2)))  # inside close_distance: rotate in place
    assert close.linear == 0.0 and close.angular != 0.0
    far = h.tick(scan=laserscan_msg(front_scan(front=0.5)))  # far band: keep going, turn away
    assert 0.0 < far.linear <= V_MAX and far.angular != 0.0


def test_twist_stamped_with_the_turtlebot3_params_file(executive: Callable[..., Harness]) -> None:
    h = executive("--params-file", str(REPO / "config" / "turtlebot3.yaml"), stamped=True)
    h.arm(True)
    sample = h.tick(scan=FREE)
    assert sample.linear > 0.0
    assert sample.frame_id == "base_footprint"
    assert sample.stamp == pytest.approx(h.sim_time, abs=1e-6)  # stamped with the (simulated) node clock


def test_tree_topic_follows_the_tip(executive: Callable[..., Harness]) -> None:
    h = executive()
    h.wait(lambda: bool(h.trees), "the first ~/tree message (transient local)")
    assert h.trees[-1]["tip"] == "StopDisarmed"
    h.arm(True)
    count = len(h.trees)
    h.tick(scan=FREE)
    h.wait(lambda: len(h.trees) > count, "a ~/tree message after arming")
    assert h.trees[-1]["tip"] == "FullSpeed" and h.trees[-1]["format"] == "bt_nav.tree/1"
    count = len(h.trees)
    h.ticks(3, scan=FREE)  # nothing changes: no new snapshot
    h.tick(scan=laserscan_msg(front_scan(front=0.2)))
    h.wait(lambda: len(h.trees) > count, "a ~/tree message after the tip changed")
    assert len(h.trees) == count + 1 and h.trees[-1]["tip"] == "RotateInPlace"

    # Transient local, depth 1: a late joiner (bt-nav watch) gets the current tree at once, and only it.
    late: list[str] = []
    h.node.create_subscription(String, "/bt_nav_executive/tree", late.append, LATCHED)
    h.wait(lambda: bool(late), "the latched tree for a late subscriber")
    assert [read_snapshot(m.data) for m in late] == [h.trees[-1]]


def test_remapped_service_names(executive: Callable[..., Harness]) -> None:
    h = executive("-r", "arm:=/reactive_control/activate", "-r", "evaluate_mission:=/reactive_control/evaluate_mission",
                  "-p", "mission_duration:=5.0", arm_service="/reactive_control/activate")
    h.serve_evaluation("/reactive_control/evaluate_mission")
    assert h.arm(True).success
    armed_at = h.sim_time
    assert h.tick(scan=FREE).linear > 0.0
    h.tick(armed_at + 5.0 - float(SPECS["stop_margin"].default) + PERIOD)  # past the deadline: stop
    h.tick(scan=FREE)  # then call
    h.wait(lambda: len(h.calls) == 1, "the evaluation call on the remapped name")
    assert h.samples[-1].is_zero
    assert h.process.has_line(r"arm server /reactive_control/activate")
