"""The one table of bt_nav's parameters.

Every consumer reads this table instead of repeating names and defaults: the ROS executive declares
its parameters (with descriptors and ranges) from it, the lock-step runner builds its configuration
from it, the launch files and the pip bringup take their defaults from it, and the docs' parameter
reference is generated from it. Tree leaves read the values from blackboard keys of the same names,
which is how a live parameter update reaches the tree on the next tick.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from bt_nav.mission.maneuver_spec import MANEUVER_SPECS, NONE, LiveLetters, LiveMap
from bt_nav.mission.maneuver_spec import aliases as maneuver_aliases
from bt_nav.mission.maneuver_spec import titles as maneuver_titles

Value = bool | int | float | str

#: The lab's evasive maneuvers, and with "none" every value of the ``maneuver`` parameter, with their spellings
#: and titles: live views of :data:`bt_nav.mission.maneuver_spec.MANEUVER_SPECS`, the one home of the maneuvers (the
#: worlds' ``checkoff_maneuvers``, the check-off judge, the grids and the benchmarks read them from here).
LAB_MANEUVERS: Sequence[str] = LiveLetters()
MANEUVERS: Sequence[str] = LiveLetters(prefix=(NONE,))
MANEUVER_ALIASES: Mapping[str, str] = LiveMap(maneuver_aliases)
MANEUVER_TITLES: Mapping[str, str] = LiveMap(maneuver_titles)


def normalise_maneuver(value: str) -> str:
    """Map a user's maneuver spelling (a letter in any case, a title such as ``Randomizer``...) to none or a letter.

    Raises:
        ValueError: for an unknown name, listing the accepted ones.
    """
    key = str(value).strip().lower().replace("-", "_").replace(" ", "_")
    try:
        return maneuver_aliases()[key]
    except KeyError:
        accepted = ", ".join(sorted(maneuver_aliases()))
        raise ValueError(f"unknown maneuver {value!r}; accepted: {accepted}") from None


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: its default, what it means and the values it accepts.

    ``live`` parameters may change while the executive runs (the next tick uses them); the others
    shape the tree or the node's wiring and are read-only after start-up.
    """

    name: str
    default: Value
    description: str
    unit: str = ""
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[str, ...] | None = None
    live: bool = True
    in_tree: bool = True  # written to the blackboard for the tree's leaves

    def check(self, value: Any) -> str | None:
        """Return why ``value`` is not acceptable, or None when it is."""
        expected = type(self.default)
        if expected is bool:
            if not isinstance(value, bool):
                return f"{self.name} must be a bool, got {value!r}"
            return None
        if expected is str:
            if not isinstance(value, str):
                return f"{self.name} must be a string, got {value!r}"
            if self.name == "maneuver":
                try:
                    normalise_maneuver(value)
                except ValueError as exc:
                    return f"{self.name}: {exc}"
            elif self.choices is not None and value not in self.choices:
                return f"{self.name} must be one of {', '.join(self.choices)}, got {value!r}"
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"{self.name} must be a number, got {value!r}"
        if expected is int and not isinstance(value, int):
            return f"{self.name} must be an integer, got {value!r}"
        if not math.isfinite(value):
            return f"{self.name} must be finite, got {value!r}"
        if self.minimum is not None and value < self.minimum:
            return f"{self.name} must be >= {self.minimum}{self.unit_suffix}, got {value}"
        if self.maximum is not None and value > self.maximum:
            return f"{self.name} must be <= {self.maximum}{self.unit_suffix}, got {value}"
        return None

    @property
    def unit_suffix(self) -> str:
        """`` m`` style suffix for messages."""
        return f" {self.unit}" if self.unit else ""


def _trigger_distance_text(name: str) -> str:
    """``Trigger distance of maneuvers A (front) and B (left and right).``: the maneuvers whose sheet distance is
    the parameter ``name``, from the maneuver spec."""
    users = [f"{m.letter} ({m.trigger.words})" for m in MANEUVER_SPECS.values() if m.trigger.distance == name]
    listed = users[0] if len(users) == 1 else f"{', '.join(users[:-1])} and {users[-1]}"
    return f"Trigger distance of maneuver{'s' if len(users) > 1 else ''} {listed}."


PARAMS: tuple[ParamSpec, ...] = (
    # --- the mission -------------------------------------------------------------------------------
    ParamSpec("maneuver", "none", "Evasive rotation maneuver: none, "
              + ", ".join(f"{m.letter} ({m.title})" for m in MANEUVER_SPECS.values()) + "; the names are accepted too.",
              live=False,
              choices=MANEUVERS),
    ParamSpec("mode", "homework", "What the robot does when armed and no maneuver runs: homework (reactive "
              "close / far / none driving at speed) or lab (creep straight ahead at creep_speed, brake before "
              "contact; the lab's maneuvers do the avoiding).", choices=("homework", "lab")),
    ParamSpec("mission_duration", 50.0, "Time from the first arming until the robot must have stopped "
              "and asked for evaluation; 0: no deadline and no evaluation call (the lab runs until disarmed).",
              "s", 0.0, 3600.0),
    ParamSpec("stop_margin", 0.25, "The stop and the evaluation call happen this long before "
              "mission_duration runs out, so the referee sees them inside the limit.", "s", 0.0, 10.0),
    ParamSpec("evaluation_timeout", 2.0, "How long one evaluation call may take before it is abandoned.",
              "s", 0.05, 60.0),
    ParamSpec("evaluation_retries", 5, "Further attempts after a failed, refused or timed-out "
              "evaluation call.", "", 0, 100),
    ParamSpec("evaluation_retry_delay", 0.5, "Pause between evaluation attempts.", "s", 0.0, 10.0),
    # --- perception --------------------------------------------------------------------------------
    ParamSpec("safety_distance", 0.5, _trigger_distance_text("safety_distance"), "m", 0.05, 10.0),
    ParamSpec("pivot_distance", 0.3, _trigger_distance_text("pivot_distance"), "m", 0.05, 10.0),
    ParamSpec("trigger_hysteresis", 0.1, "A maneuver fires on the rising edge of its condition; a clearing "
              "re-arms it only once its reading has risen above the trigger distance plus this (see the "
              "tree guide).", "m", 0.0, 5.0),
    ParamSpec("trigger_at_arming", False, "true: a maneuver's condition that already holds when the robot "
              "is armed (or armed again) fires at once. false (default): the trigger waits until it has seen "
              "its condition clear, so a robot armed in a corridor does not spin on the spot (measured: "
              "corridor B passes 0/4 with true, 3/4 with false)."),
    ParamSpec("trigger_repeat", False, "true: a front trigger (A, C) whose condition still holds when its "
              "maneuver ends fires again, so the robot turns until its front is clear (the lab). B never "
              "repeats: a spin in a corridor leaves the robot as squeezed as before."),
    ParamSpec("trigger_clear_away", 1.5, "A clearing re-arms a maneuver's trigger only this far (straight "
              "line, odometry) from where it last fired: spinning on the spot or shuttling around one spot is "
              "no new situation.", "m", 0.0, 100.0),
    ParamSpec("trigger_rearm_distance", 5.0, "A maneuver's trigger also re-arms after the robot has driven "
              "this far since it fired, even if its condition never cleared (0: only by clearing).", "m",
              0.0, 100.0),
    ParamSpec("close_distance", 0.3, "The robot's free path ahead shorter than this (or the front unknown): "
              "stop and rotate in place towards the side with room.", "m", 0.05, 10.0),
    ParamSpec("far_distance", 0.7, "The robot's free path ahead shorter than this (but not close): keep driving "
              "and steer for the smallest turn that clears it.", "m", 0.05, 10.0),
    ParamSpec("path_half_width", 0.18, "Half the width of the corridor the robot sweeps when it drives: the "
              "close / far / none decision and the steering look for obstacles inside it along each heading "
              "(robot radius plus a margin; Burger: 0.105 m circumradius).", "m", 0.05, 1.0),
    ParamSpec("scan_mount_x", 0.0, "Where the LiDAR sits ahead of the robot's centre (the x of TF's base_link -> "
              "scan frame; TurtleBot3: -0.032): the swept corridor (close / far / none, the emergency brake) is "
              "the body's, so its points are moved by the mount. The sectors stay the LiDAR's own readings, as "
              "the lab measures them.", "m", -1.0, 1.0),
    ParamSpec("scan_mount_y", 0.0, "Where the LiDAR sits left of the robot's centre (TF's y; see scan_mount_x).",
              "m", -1.0, 1.0),
    ParamSpec("front_half_angle_deg", 20.0, "Half-width of the lab's front sector (maneuvers A and C look "
              "there): at 30 deg, walls beside the path in narrow passages read as ahead and A fires ~3x as "
              "often (measured: A passes 92 % of the grid at 30 deg, 100 % at 20 deg).", "deg", 1.0, 180.0),
    ParamSpec("side_center_deg", 15.0, "Centre of the left sector (the right one mirrors it); the default "
              "left/right sectors are the halves of the front cone, as the homework suggests.", "deg",
              0.0, 180.0),
    ParamSpec("side_half_angle_deg", 15.0, "Half-width of the left and right sectors (homework profile: "
              "0-60 deg, so the turn direction sees the robot's shoulders).", "deg", 1.0, 180.0),
    ParamSpec("min_valid_beams", 3, "A sector with fewer valid beams is unknown (treated as close).",
              "", 1, 1000),
    ParamSpec("scan_timeout", 0.5, "No scan newer than this: stop until a fresh one arrives.", "s",
              0.05, 10.0),
    ParamSpec("odom_timeout", 0.5, "Odometry older than this: maneuvers integrate the commanded rate "
              "instead (open loop).", "s", 0.05, 10.0),
    ParamSpec("pivot_side_reading", "free_path", "How maneuver C reads the clearer side: free_path (how far "
              "the robot's width could drive after the quarter turn, along +-90 deg) or side_sectors (the nearest "
              "return in the left and right sectors, the lab's literal rule).", choices=("free_path", "side_sectors")),
    # --- motion ------------------------------------------------------------------------------------
    ParamSpec("creep_speed", 0.05, "Lab mode: the slow forward speed while no maneuver runs (the lab's template "
              "drives at 0.05 m/s).", "m/s", 0.0, 0.5),
    ParamSpec("aeb_distance", 0.10, "Lab mode, automatic emergency braking: the robot's swept path (its width, "
              "path_half_width) blocked within this much travel stops the creep; the robot then waits aeb_hold "
              "and turns in place towards the side with more room until the path is clear again.", "m", 0.0, 2.0),
    ParamSpec("aeb_hold", 1.0, "Lab mode: how long the robot stands after an emergency stop before it turns "
              "away (a person walking past has moved on by then).", "s", 0.0, 60.0),
    ParamSpec("actuation_latency", 0.0, "Expected time between a command and the wheels (0.1-0.15 s on a real "
              "TurtleBot3): maneuvers predict the turn already commanded but not yet done, so they stop on their "
              "angle, and hold still this long after it before they end.", "s", 0.0, 1.0),
    ParamSpec("max_linear_speed", 0.22, "Forward speed with nothing ahead (TurtleBot3 Burger: 0.22).",
              "m/s", 0.0, 2.0),
    ParamSpec("slow_linear_speed", 0.2, "Forward speed while steering away with the path blocked at "
              "close_distance; it rises (quadratically) to max_linear_speed at far_distance.", "m/s",
              0.0, 2.0),
    ParamSpec("angular_speed", 2.5, "Turn rate for rotating in place and peak rate of steering. On a real "
              "Burger the wheels cannot turn this fast at full speed: set wheel_speed_limit (the turtlebot3 "
              "profile does) so the command is slowed along its arc instead of widening it.", "rad/s",
              0.05, 3.0),
    ParamSpec("maneuver_angular_speed", 2.84, "Peak turn rate during an evasive maneuver (the Burger's spin "
              "limit: a 180 deg maneuver costs about 1.5 s of the mission).", "rad/s", 0.05, 3.0),
    ParamSpec("maneuver_tolerance_deg", 3.0, "A maneuver is done when the remaining angle is smaller.",
              "deg", 0.1, 30.0),
    ParamSpec("maneuver_time_margin", 2.0, "A maneuver may take its nominal time plus this much; then "
              "it stops and fails.", "s", 0.0, 60.0),
    ParamSpec("wheel_speed_limit", 0.0, "Per-wheel speed limit of the base (0: none, an ideal unicycle). When "
              "set, a command that would need a wheel faster than this is scaled down as a whole, keeping its "
              "curvature, so the robot follows the arc the tree chose instead of the wider one a saturated "
              "wheel would drive (TurtleBot3 Burger: 0.2272).", "m/s", 0.0, 2.0, in_tree=False),
    ParamSpec("wheel_separation", 0.160, "Distance between the wheels, for wheel_speed_limit (Burger: 0.160).",
              "m", 0.05, 2.0, in_tree=False),
    ParamSpec("random_seed", -1, "Seed of maneuver A's random choices; -1 draws one from the OS.", "",
              -1, 2**31 - 1, live=False),
    # --- the ROS edge (not read by the tree) --------------------------------------------------------
    ParamSpec("tick_rate_hz", 20.0, "Tree ticks per second (node clock, so sim time when use_sim_time).",
              "Hz", 1.0, 200.0, live=False, in_tree=False),
    ParamSpec("arm_service", "arm", "Name of the std_srvs/SetBool service that arms (true) and disarms (false) "
              "the robot; relative names follow the node's namespace, and a remap of the default (-r "
              "arm:=...) still works. config/lab.yaml sets toggle_navigation, the lab's name, so the lab's "
              "service exists with its params file alone.", live=False, in_tree=False),
    ParamSpec("cmd_vel_stamped", False, "Publish geometry_msgs/TwistStamped instead of Twist "
              "(TurtleBot3 on Jazzy).", live=False, in_tree=False),
    ParamSpec("frame_id", "base_link", "frame_id of stamped commands.", live=False, in_tree=False),
    ParamSpec("stats_period", 10.0, "Seconds between tick-statistics log lines (0 disables).", "s",
              0.0, 3600.0, in_tree=False),
    ParamSpec("clock_watchdog", 1.0, "Wall-clock seconds without a tick, while the last command was motion, after "
              "which the executive publishes a zero twist (a stalled /clock under use_sim_time freezes the ticks "
              "and a base keeps its last cmd_vel); 0 disables.", "s", 0.0, 60.0, in_tree=False),
    ParamSpec("trace_path", "", "Write the per-tick JSONL trace (the lock-step format, read by bt-nav replay) to "
              "this file; empty: no trace.", live=False, in_tree=False),
    ParamSpec("stats_path", "", "Write the exit tick statistics (those of the final stats log line) as JSON to "
              "this file when the executive stops; empty: none.", live=False, in_tree=False),
)

SPECS: dict[str, ParamSpec] = {spec.name: spec for spec in PARAMS}


def defaults() -> dict[str, Value]:
    """Every parameter's default value."""
    return {spec.name: spec.default for spec in PARAMS}


def cross_check(values: Mapping[str, Value]) -> str | None:
    """Return why a complete set of values is inconsistent, or None.

    Single values are checked by :meth:`ParamSpec.check`; these rules relate two parameters.
    """
    if values["close_distance"] >= values["far_distance"]:
        return (f"close_distance ({values['close_distance']}) must be smaller than far_distance "
                f"({values['far_distance']})")
    if 0.0 < values["mission_duration"] <= values["stop_margin"]:
        return (f"mission_duration ({values['mission_duration']}) must exceed stop_margin "
                f"({values['stop_margin']}), or be 0 for no deadline")
    if values["slow_linear_speed"] > values["max_linear_speed"]:
        return (f"slow_linear_speed ({values['slow_linear_speed']}) must not exceed max_linear_speed "
                f"({values['max_linear_speed']})")
    return None


def resolve(overrides: Mapping[str, Any] | None = None) -> dict[str, Value]:
    """Defaults updated with ``overrides``, checked by :func:`check_changes`; ints are accepted for floats.

    Raises:
        ValueError: naming the first unknown parameter or unacceptable value.
    """
    values, reason = check_changes(defaults(), overrides or {}, running=False)
    if reason:
        raise ValueError(reason)
    return values


def check_changes(current: Mapping[str, Value], changes: Mapping[str, Any], *,
                  running: bool = True) -> tuple[dict[str, Value], str | None]:
    """The one gate every parameter value passes: at start-up, on a live change and off-ROS alike.

    Returns ``current`` updated with ``changes`` and the reason the batch is refused (None when it is
    accepted). Each value is coerced (:func:`coerce`) and checked on its own, maneuver names are
    normalised, and the cross rules judge the combined result, so a batch may move close_distance and
    far_distance across each other's old values. With ``running``, a read-only (``live=False``)
    parameter may only be "changed" to the value it already has.
    """
    candidate: dict[str, Value] = dict(current)
    for name, raw in changes.items():
        spec = SPECS.get(name)
        if spec is None:
            return candidate, f"unknown parameter {name!r}"
        value = coerce(spec, raw)
        reason = spec.check(value)
        if reason:
            return candidate, reason
        if name == "maneuver":
            value = normalise_maneuver(value)  # a maneuver's name is its letter: the running one, not a change
        if running and not spec.live and value != current[name]:
            return candidate, f"{name} cannot change while the executive runs (restart it with the new value)"
        candidate[name] = value
    return candidate, cross_check(candidate)


def coerce(spec: ParamSpec | Value, value: Any) -> Any:
    """Accept an int where a float is expected (``-p safety_distance:=1`` on the command line).

    ``spec`` is a table entry or, for parameters outside the table (the simulator's, the referee's),
    just the default value whose type decides.
    """
    default = spec.default if isinstance(spec, ParamSpec) else spec
    if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


#: Numbers in exponent form without a dot (``1e-3``): YAML 1.1, which PyYAML follows, reads them as
#: strings, while ``ros2 run ... -p x:=1e-3`` (rcl's parser) reads a double.
_EXPONENT_NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")


def parse_assignments(items: Iterable[str]) -> dict[str, Any]:
    """``NAME=VALUE`` command-line items as a dict, each value read as a YAML scalar, as ROS reads ``-p name:=value``.

    ``50`` is an int, ``0.5`` and ``1e-3`` floats, ``true`` a bool, ``A`` or ``base_link`` a string, an
    empty value the empty string. Every bt-nav command that takes ``--set`` / ``--sim-param`` uses this.

    Raises:
        ValueError: for an item without ``=`` or without a name, or a value that is no valid YAML.
    """
    import yaml

    out: dict[str, Any] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"expected NAME=VALUE, got {item!r}")
        text = text.strip()
        if _EXPONENT_NUMBER.fullmatch(text):
            out[name.strip()] = float(text)
            continue
        try:
            out[name.strip()] = yaml.safe_load(text) if text else ""
        except yaml.YAMLError as exc:
            raise ValueError(f"{name.strip()}: {text!r} is no YAML value ({exc})".replace("\n", " ")) from None
    return out


def markdown_table() -> str:
    """The parameter table as Markdown (the docs' generated parameter reference)."""
    rows = ["| parameter | default | unit | range | live | description |", "|---|---|---|---|---|---|"]
    for spec in PARAMS:
        if spec.choices:
            allowed = " / ".join(spec.choices)
        elif spec.minimum is not None or spec.maximum is not None:
            allowed = f"{spec.minimum:g} .. {spec.maximum:g}"
        else:
            allowed = ""
        default = f"`{spec.default}`" if not isinstance(spec.default, str) else f'`"{spec.default}"`'
        rows.append(f"| `{spec.name}` | {default} | {spec.unit} | {allowed} | {'yes' if spec.live else 'no'} "
                    f"| {spec.description} |")
    return "\n".join(rows) + "\n"
