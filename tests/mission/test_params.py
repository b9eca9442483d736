"""The parameter table's one gate, its coercion and the one NAME=VALUE syntax of every command."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bt_nav.mission import params as P
from bt_nav.testing import TickHarness

NUMERIC = [spec for spec in P.PARAMS if isinstance(spec.default, int | float) and not isinstance(spec.default, bool)]
VALUES = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10_000), st.booleans(),
                   st.sampled_from(["", "x", "A", "randomizer", "1"]))


@settings(max_examples=120, deadline=None)
@given(spec=st.sampled_from([s for s in P.PARAMS if s.live]), value=VALUES)
def test_a_live_change_is_refused_exactly_when_start_up_would_refuse_it(spec: P.ParamSpec, value: Any) -> None:
    """MissionCore.set_param and params.resolve judge a value the same way (cross rules included)."""
    try:
        P.resolve({spec.name: value})
        start_up = None
    except ValueError as exc:
        start_up = str(exc)
    core = TickHarness("none").core
    live = core.set_param(spec.name, value)
    assert (live is None) == (start_up is None), (spec.name, value, live, start_up)
    if live is None:
        assert core.params[spec.name] == P.coerce(spec, value)


def test_read_only_parameters_refuse_a_change_only_while_running() -> None:
    assert P.check_changes(P.defaults(), {"tick_rate_hz": 50.0}, running=False)[1] is None
    assert "cannot change" in P.check_changes(P.defaults(), {"tick_rate_hz": 50.0})[1]
    assert P.check_changes(P.defaults(), {"tick_rate_hz": 20})[1] is None, "the same value is no change"
    values, reason = P.check_changes(P.resolve({"maneuver": "A"}), {"maneuver": "randomizer"})
    assert reason is None and values["maneuver"] == "A", "another spelling of the running maneuver is no change"


def test_a_batch_is_judged_as_a_whole() -> None:
    assert "smaller than far_distance" in P.check_changes(P.defaults(), {"close_distance": 0.9})[1]
    values, reason = P.check_changes(P.defaults(), {"far_distance": 1.2, "close_distance": 0.9})
    assert reason is None and (values["close_distance"], values["far_distance"]) == (0.9, 1.2)


@pytest.mark.parametrize(("default", "value", "expected"), [
    (0.5, 1, 1.0), (0.5, True, True), (3, 4, 4), (0.5, "1", "1"), (P.SPECS["safety_distance"], 2, 2.0),
])
def test_coerce_turns_an_int_into_a_float_only_for_a_float_parameter(default: Any, value: Any, expected: Any) -> None:
    out = P.coerce(default, value)
    assert out == expected and type(out) is type(expected)


def test_parse_assignments_reads_yaml_scalars_as_ros_does() -> None:
    parsed = P.parse_assignments(["a=1", "b=0.5", "c=x", "d=true", "e=1e-3", "f=", " g = -2E5 ", "m=A", "n=.nan"])
    assert parsed == {"a": 1, "b": 0.5, "c": "x", "d": True, "e": 0.001, "f": "", "g": -200000.0, "m": "A",
                      "n": parsed["n"]}
    assert math.isnan(parsed["n"]) and isinstance(parsed["e"], float) and isinstance(parsed["a"], int)


@pytest.mark.parametrize("item", ["novalue", "=1", "x=[1,", "x={a: 1"])
def test_parse_assignments_refuses_what_it_cannot_read(item: str) -> None:
    with pytest.raises(ValueError):
        P.parse_assignments([item])


def test_numeric_defaults_pass_their_own_checks() -> None:
    for spec in NUMERIC:
        assert spec.check(spec.default) is None, spec.name
    assert P.cross_check(P.defaults()) is None


def test_the_executive_names_its_params_files() -> None:
    from bt_nav.mission.profiles import params_files_note

    assert params_files_note(["x", "--ros-args", "--params-file", "/a/config/homework.yaml"]).endswith(
        "(profile homework)")
    note = params_files_note(["--params-file", "h/homework.yaml", "--params-file", "t/turtlebot3.yaml"])
    assert note == "params files h/homework.yaml, t/turtlebot3.yaml (profile turtlebot3)"
    assert params_files_note(["--params-file", "mine.yaml"]) == "params files mine.yaml"
    assert params_files_note([]).startswith("no params file: the package defaults")
