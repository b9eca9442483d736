"""bt_nav.ros.stencil: a message's bytes with a few numbers written in place read back as the message whose fields were
set one by one, whatever the numbers; what it cannot write it refuses."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan

from bt_nav.ros.nodes.simulator import ODOM_FIELDS, _pose
from bt_nav.ros.stencil import Stencil

FINITE = st.floats(allow_nan=False, allow_infinity=False, width=64)


def _odometry(frame: str) -> Odometry:
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = frame, "base_footprint"
    msg.pose.covariance = [0.0 if i not in (0, 7, 35) else 1e-3 for i in range(36)]
    return msg


@given(sec=st.integers(-2**31, 2**31 - 1), nanosec=st.integers(0, 999_999_999), x=FINITE, y=FINITE,
       yaw=st.floats(-10.0, 10.0), v=FINITE, w=FINITE)
def test_an_odometry_stencil_reads_back_as_the_message_set_field_by_field(sec, nanosec, x, y, yaw, v, w) -> None:
    stencil = Stencil(_odometry("odom"), ODOM_FIELDS)
    expected = _odometry("odom")
    expected.header.stamp.sec, expected.header.stamp.nanosec = sec, nanosec
    p = expected.pose.pose
    p.position.x, p.position.y = x, y
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)
    expected.twist.twist.linear.x, expected.twist.twist.angular.z = v, w
    assert deserialize_message(stencil.fill(sec, nanosec, *_pose(x, y, yaw), v, w), Odometry) == expected


def test_a_stencil_leaves_its_message_alone_and_keeps_what_it_does_not_write() -> None:
    msg = _odometry("world")
    msg.pose.pose.position.z = 0.25
    before = deserialize_message(serialize_message(msg), Odometry)
    stencil = Stencil(msg, ODOM_FIELDS)
    assert msg == before  # no marker left behind
    out = deserialize_message(stencil.fill(7, 8, 1.0, 2.0, 0.0, 1.0, 0.5, 0.5), Odometry)
    assert out.header.frame_id == "world" and out.child_frame_id == "base_footprint"
    assert out.pose.pose.position.z == 0.25 and list(out.pose.covariance) == list(msg.pose.covariance)
    assert stencil.example == msg


def test_a_clock_stencil() -> None:
    stencil = Stencil(Clock(), ("clock.sec", "clock.nanosec"))
    assert deserialize_message(stencil.fill(12, 345_000_000), Clock).clock.nanosec == 345_000_000
    assert deserialize_message(stencil.fill(13, 0), Clock).clock.sec == 13


@pytest.mark.parametrize(("fields", "match"), [(("header.frame_id",), "is a string"),
                                               (("ranges",), "is a sequence<float>"),
                                               (("header.stamp.secs",), "has no field 'secs'")])
def test_what_a_stencil_cannot_write_is_refused(fields, match) -> None:
    with pytest.raises(ValueError, match=match):
        Stencil(LaserScan(), fields)
