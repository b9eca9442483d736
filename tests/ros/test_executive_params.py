"""The executive's parameters over the rcl_interfaces services (what ``ros2 param`` uses).

One executive serves the whole module: these tests only read parameters or try to change them, and
each change that succeeds is put back.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import DescribeParameters, ListParameters
from rclpy.parameter import Parameter
from ros_harness import REPO, STARTUP_TIMEOUT, ExecutiveProcess, Harness

from bt_nav.mission import params as P
from bt_nav.testing import wait_until


@pytest.fixture(scope="module")
def h(ros_context: Any) -> Iterator[Harness]:
    """A harness connected to one executive for the module."""
    process = ExecutiveProcess(["--ros-args", "-p", "use_sim_time:=true"])
    harness = Harness(ros_context, name="bt_nav_test_params")
    try:
        harness.connect(process)
        yield harness
    finally:
        harness.close()
        process.stop()


def test_every_parameter_is_listed(h: Harness) -> None:
    client = h.parameter_client(ListParameters, "list_parameters")
    names = set(h.call(client, ListParameters.Request()).result.names)
    missing = {spec.name for spec in P.PARAMS} - names
    assert not missing, f"not declared: {sorted(missing)}"
    assert "use_sim_time" in names


def test_descriptors_carry_description_unit_range_and_read_only(h: Harness) -> None:
    client = h.parameter_client(DescribeParameters, "describe_parameters")
    names = [spec.name for spec in P.PARAMS]
    descriptors = h.call(client, DescribeParameters.Request(names=names)).descriptors
    assert len(descriptors) == len(names)
    for spec, descriptor in zip(P.PARAMS, descriptors, strict=True):
        assert descriptor.name == spec.name
        assert spec.description in descriptor.description
        if spec.unit:
            assert f"[{spec.unit}]" in descriptor.description
        assert descriptor.read_only == (not spec.live), spec.name
        if descriptor.type == ParameterType.PARAMETER_DOUBLE and spec.minimum is not None:
            (fp_range,) = descriptor.floating_point_range
            assert (fp_range.from_value, fp_range.to_value) == (spec.minimum, spec.maximum)
        if descriptor.type == ParameterType.PARAMETER_INTEGER and spec.minimum is not None:
            (int_range,) = descriptor.integer_range
            assert (int_range.from_value, int_range.to_value) == (spec.minimum, spec.maximum)


@pytest.mark.parametrize(("parameter", "reason"), [
    (Parameter("safety_distance", value=-0.4), "out of range"),
    (Parameter("safety_distance", value=math.nan), "out of range"),
    (Parameter("scan_timeout", value=math.inf), "out of range"),
    (Parameter("maneuver", value="zigzag"), "read-only"),
    (Parameter("maneuver", value="B"), "read-only"),
    (Parameter("close_distance", value=0.7), "must be smaller than far_distance"),
    (Parameter("far_distance", value=0.2), "must be smaller than far_distance"),
    (Parameter("slow_linear_speed", value=0.3), "must not exceed max_linear_speed"),
    (Parameter("evaluation_retries", value=2.5), "Wrong parameter type"),
    (Parameter("tick_rate_hz", value=50.0), "read-only"),
], ids=["negative-distance", "nan", "inf", "unknown-maneuver", "maneuver-while-running", "close-at-far",
        "far-below-close", "slow-above-max", "wrong-type", "tick-rate"])
def test_invalid_runtime_change_is_refused_with_a_reason(h: Harness, parameter: Parameter, reason: str) -> None:
    before = h.get_parameters(parameter.name)
    (result,) = h.set_parameters(parameter)
    assert not result.successful
    assert reason in result.reason
    assert h.get_parameters(parameter.name) == before


def test_valid_runtime_change_is_applied_and_logged(h: Harness) -> None:
    (result,) = h.set_parameters(Parameter("safety_distance", value=0.4))
    assert result.successful, result.reason
    assert h.get_parameters("safety_distance") == {"safety_distance": 0.4}
    h.wait(lambda: h.process.has_line(r"parameters changed: safety_distance=0\.4"), "the change's log line")
    (result,) = h.set_parameters(Parameter("safety_distance", value=0.5))
    assert result.successful


def test_atomic_change_is_judged_as_a_whole(h: Harness) -> None:
    # One at a time, close_distance 0.8 is refused (far is 0.7); together with far 1.0 it is fine.
    (alone,) = h.set_parameters(Parameter("close_distance", value=0.8))
    assert not alone.successful
    (together,) = h.set_parameters(Parameter("far_distance", value=1.0), Parameter("close_distance", value=0.8),
                                   atomically=True)
    assert together.successful, together.reason
    assert h.get_parameters("close_distance", "far_distance") == {"close_distance": 0.8, "far_distance": 1.0}
    (back,) = h.set_parameters(Parameter("close_distance", value=0.3), Parameter("far_distance", value=0.7),
                               atomically=True)
    assert back.successful, back.reason


@pytest.mark.parametrize(("profile", "says"), [("homework.yaml", r"maneuver C Smart Pivot"),
                                               ("turtlebot3.yaml", r"cmd_vel /robot1/cmd_vel as TwistStamped"),
                                               ("lab.yaml", r"arm server /robot1/toggle_navigation")])
def test_the_params_files_apply_inside_a_namespace(ros_context: Any, profile: str, says: str) -> None:
    """The config files key their section ``/**/bt_nav_executive``: a plain ``bt_nav_executive:`` would
    not match the node under ``/robot1`` and the executive would run on the defaults (maneuver none). The
    lab's file names its service itself: no remap, and it follows the namespace."""
    config = REPO / "config" / profile
    process = ExecutiveProcess(["--ros-args", "-r", "__ns:=/robot1", "--params-file", str(config)])
    try:
        wait_until(lambda: process.has_line(r"bt_nav_executive up:"), STARTUP_TIMEOUT, "the executive to start",
                   details=process.tail)
        assert process.has_line(r"\[robot1\.bt_nav_executive\]: bt_nav_executive up: .*" + says), process.tail()
    finally:
        process.stop()
