"""Lab day rehearsed (docs/lab.md): ``bt-nav rehearse`` runs a SIMULATED TurtleBot3 (real rclpy publishers of /odom,
/scan and /cmd_vel over real DDS, localhost, a domain of its own) and ``bt-nav checkoff --robot`` beside it; and the
live judge that hears nothing says which topics are missing and why that may be, and keeps listening."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest
from simtools import Proc

from bt_nav.ros.nodes.robotcheck import NOTHING_HEARD_AFTER, HearingWatch
from bt_nav.run.session import DomainLease


@pytest.fixture
def own_domain(monkeypatch: pytest.MonkeyPatch) -> Iterator[int]:
    """A domain no other run on this machine holds (BT_NAV_DOMAIN_RANGE), as this test's ROS_DOMAIN_ID."""
    with DomainLease(user_env=False) as lease:
        domain = lease.claim(wait=60.0)
        monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
        yield domain


def test_the_rehearsal_judges_a_simulated_robot_over_dds_within_90_s(own_domain: int) -> None:
    began = time.monotonic()
    proc = Proc("rehearse", "--maneuver", "A", "--domain-id", str(own_domain))
    try:
        code = proc.wait(85.0)
    finally:
        proc.stop()
    out = proc.stdout
    assert code == 0, proc.output()
    assert time.monotonic() - began < 90.0
    assert out[0].startswith("bt-nav rehearse: a SIMULATED TurtleBot3 (not a robot) publishing /odom, /scan, "
                             f"/cmd_vel on ROS_DOMAIN_ID={own_domain} (localhost only)"), out
    assert any(f"on ROS_DOMAIN_ID {own_domain}, discovery range LOCALHOST" in line for line in out), out
    heard = next(line for line in out if line.startswith("note: heard live"))
    counts = dict(part.rsplit(" ", 1) for part in heard.rsplit("): ", 1)[1].split(", "))
    assert int(counts["/odom"]) > 250 and int(counts["/scan"]) > 40 and int(counts["/cmd_vel"]) > 70, heard
    assert any(line.startswith("maneuvers (1 seen: 1 judged, 1 passed, 0 failed") for line in out), out
    turn = next(line for line in out if line.startswith("maneuver 1 (A at t="))
    assert "deg right, rule 80-190 deg either side" in turn and turn.endswith("): PASSED")
    assert out[-1] == "overall: PASSED", proc.output()
    assert not any("nothing heard" in line for line in out)


def test_nothing_heard_names_the_missing_topics_and_the_causes_and_keeps_listening(own_domain: int) -> None:
    began = time.monotonic()
    proc = Proc("checkoff", "--robot", "--maneuver", "C", "--duration", "8")
    try:
        code = proc.wait(60.0)
    finally:
        proc.stop()
    said = [line for line in proc.stdout if "nothing heard on" in line]
    assert len(said) == 1, proc.output()
    assert said[0].startswith("bt-nav checkoff: nothing heard on /odom, /scan, /cmd_vel in 5 s "
                              f"(ROS_DOMAIN_ID {own_domain}, discovery range LOCALHOST, RMW rmw_"), said
    for cause in ("another ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "RMW_IMPLEMENTATION", "still listening"):
        assert cause in said[0], cause
    assert time.monotonic() - began >= 8.0  # it listened the whole --duration, not ending at the warning
    assert code == 2 and proc.stderr, proc.output()
    assert proc.stderr[-1].startswith("bt-nav checkoff: the live robot: nothing heard on /odom, /scan, /cmd_vel in 8 s")
    assert "holds no readable message" not in proc.output()


def test_the_hearing_watch_speaks_once_at_5_s_and_once_more_when_the_topics_come() -> None:
    names = {"odom": "/odom", "scan": "/scan", "cmd": "/cmd_vel"}
    watch = HearingWatch(names, began=100.0)
    assert watch.check({}, 100.0 + NOTHING_HEARD_AFTER - 0.1) is None
    first = watch.check({"/odom": [1]}, 100.0 + NOTHING_HEARD_AFTER)
    assert first is not None and first.startswith("nothing heard on /scan, /cmd_vel in 5 s") and "still" in first
    assert watch.check({"/odom": [1]}, 107.0) is None
    assert watch.check({"/odom": [1], "/scan": [1], "/cmd_vel": [1]}, 109.0) == \
        "now hearing /odom, /scan, /cmd_vel (9 s into listening)"
    assert watch.check({"/odom": [1], "/scan": [1], "/cmd_vel": [1]}, 110.0) is None
    heard = HearingWatch(names, began=0.0)
    assert heard.check({"/odom": [1], "/scan": [1], "/cmd_vel": [1]}, 6.0) is None
