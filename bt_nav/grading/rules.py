"""What a graded node must do, per assignment, as one Markdown page rendered from the judges' own rules.

Why generated: a student must find in two minutes the topics, services and parameters their node needs, each
maneuver's trigger, angle, side and tolerances, and the schedule. Typed by hand into a guide, those drift from
what the judges do (the Smart Pivot's 0.3 m sat inside one bullet of the lab's page, the homework's service names
only in remap strings). Here every value is read where the judges and the grader hold it: the lab's
:class:`~bt_nav.judge.checkoff_core.CheckoffConfig` (``trigger_rule``, ``angle_rule``, its tolerances and schedule),
the homework's :class:`~bt_nav.judge.referee_core.RefereeConfig`, the checks' words (``CHECK_WORDS``), the service
names of :mod:`bt_nav.ros.bringup`, what ``bt-nav grade --exe`` appends and runs (:mod:`bt_nav.grading.exe.run`,
:mod:`bt_nav.grading.plan`). What only the ROS edge holds (the simulator's QoS, the graph audit's topics: rclpy
modules, which this pure module does not import) is a constant here, and ``tests/ros/test_node_rules.py`` checks
each against its source.

One function, :func:`rules_markdown`, serves the page three ways: the docs' ``reference/node-rules.md``
(``docs/_ext/bt_nav_reference.py``), ``bt-nav rules``, and every ``--exe`` grade's ``rules.md``
(:func:`grade_rules`, with the grade's own maneuvers, LiDARs and ``--node-param`` values), which its
``summary.md`` and ``report.html`` link from their failures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from bt_nav_sim.lidar import LIDARS

from bt_nav.grading.exe.pace import speed_words
from bt_nav.grading.exe.run import ROBOT_CLOCK_WAIT, START_WAIT, ExeSettings, exe_ros_args, profile_remaps
from bt_nav.grading.plan import EXE_LIDARS, EXE_WORLDS, checked_cells
from bt_nav.judge.chains import ANNOUNCE_WINDOW
from bt_nav.judge.checkoff_core import CHECKS as LAB_CHECKS
from bt_nav.judge.checkoff_core import INTERRUPT_SLACK, MANEUVER_NAMES, CheckoffConfig
from bt_nav.judge.checkoff_creep import CREEP_CHECK, CREEP_SHEET
from bt_nav.judge.checkoff_schedule import schedule_words
from bt_nav.judge.referee_core import CHECK_WORDS, RefereeConfig
from bt_nav.judge.referee_core import CHECKS as HOMEWORK_CHECKS
from bt_nav.mission.assignments import LAB
from bt_nav.mission.params import LAB_MANEUVERS
from bt_nav.ros.bringup import HOMEWORK_ACTIVATE, HOMEWORK_EVALUATE, LAB_ARM, param_arg
from bt_nav.run.terminal import shell_text

#: The page's name in a grade's directory (its summary.md and report.html link it).
RULES_FILE = "rules.md"
#: The profiles the page covers, in its order.
PROFILES = ("lab", "homework")

# The interface the simulator and the graph audit give a graded node (bt_nav/ros/nodes/simulator.py, audit.py,
# checkoff.py), held here for a module without rclpy; tests/ros/test_node_rules.py checks each against its source.
#: (topic, message type) the node subscribes and publishes; names relative, so in no namespace ``/scan`` etc.
SCAN = ("scan", "sensor_msgs/msg/LaserScan")
COMMAND = ("cmd_vel", "geometry_msgs/msg/Twist")
CLOCK = ("/clock", "rosgraph_msgs/msg/Clock")
ODOM = ("odom", "nav_msgs/msg/Odometry")
SET_BOOL = "std_srvs/srv/SetBool"
TRIGGER = "std_srvs/srv/Trigger"
#: (reliability, durability, depth) the simulator offers ``scan`` with (its SCAN_QOS) and reads ``cmd_vel`` with in
#: a grade (its cmd_vel_qos under FOLLOW_NODE).
SCAN_QOS = ("reliable", "volatile", 5)
COMMAND_QOS = ("best_effort", "volatile", 10)
#: The parameters the lab's judge asks the node to declare (CheckoffNode.required_parameters).
LAB_PARAMETERS = ("safety_distance",)
#: The simulator's ``cmd_vel_timeout`` in a grade (its parameter's default): 0, the last command holds.
COMMAND_TIMEOUT = 0.0

#: What each homework check requires, in words with the config's values (every referee check has a line).
_HOMEWORK_REQUIRED = {
    "static at the end": lambda c: f"still over the last {c.window:g} s before the report, which comes "
                                   f"{c.settle_after_call:g} s after the first evaluation call",
    "static before activation": lambda c: f"still from t0 until the first activation call ({c.static_before:g} s)",
    "static after deactivation": lambda c: f"still from {c.grace:g} s after the deactivation call "
                                           f"({c.deactivate_at + c.grace:g} s) until the reactivation "
                                           f"({c.reactivate_at:g} s)",
    "minimum distance from start": lambda c: f"at least {c.min_distance_from_start:g} m from the start, once",
    "minimum travelled distance": lambda c: f"at least {c.min_travelled:g} m of path, counted from the first "
                                            "activation call",
    "evaluation service called": lambda c: f"the first call by {c.evaluation_deadline:g} s",
    "no collision": lambda c: "no contact with anything",
}
#: What each lab check requires (every check-off check has a line; "parameters declared" is the judge node's).
_LAB_REQUIRED = {
    "static before activation": lambda c: f"still from t0 until the first `{LAB_ARM}` call ({c.activate_at:g} s)",
    "toggle_navigation answered": lambda c: "every call (`data: true`; the toggle cycle's `data: false` and "
                                            "`data: true`; the final `data: false`) answered with `success: true`",
    "maneuvers performed": lambda c: f"at least {c.min_maneuvers} turn judged as the maneuver",
    "maneuver": lambda c: "each turn: its trigger held, not late, its angle and side, no forward motion (moving on "
                          "after it: a finding)",
    "back-to-back maneuvers": lambda c: "none by default: maneuvers made one after another without moving on are a "
                                        "finding (a Retreat (B) that never drives out too: the sheet only implies "
                                        "it), a failure only with `--strict-findings back_to_back`",
    "recovery turns": lambda c: "no forward command or motion",
    CREEP_CHECK: lambda c: f"armed, never standing still {c.creep_still:g} s or more while no reading of your trigger "
                           f"holds and the front is clear beyond `safety_distance` (+{c.trigger_margin:.2f} m): keep "
                           f"creeping (not counted: the first {c.creep_start:g} s after each `data: true`, a turn and "
                           f"{c.creep_settle:g} s after it, a stop with the path blocked)",
    "no collision": lambda c: "no contact with anything",
    "static after deactivation": lambda c: f"still from {c.grace:g} s after each disarm call (the toggle cycle's, "
                                           "and the final one) for "
                                           f"{c.static_after:g} s",
    "parameters declared": lambda c: f"a node of yours declares `{LAB_PARAMETERS[0]}` (`ros2 param list`)",
}
#: A failure's words for the lab's checks that CHECK_WORDS does not hold (a maneuver's are its rules' own).
_LAB_WORDS = {"maneuver": "one sentence per rule it broke, e.g. its angle and the rule's",
              "back-to-back maneuvers": "never moved on: N Retreats back to back (D deg in place), with the "
                                        "trigger's readings at each start",
              CREEP_CHECK: f"stood still for S s while armed with nothing triggering (front D m clear beyond "
                           f"safety_distance X m): {CREEP_SHEET}",
              "parameters declared": f"no node declares the parameter {LAB_PARAMETERS[0]}"}


@dataclass(frozen=True)
class GradeSetup:
    """What a grade runs a node with, as far as the page says it (defaults: a plain ``bt-nav grade --exe``'s,
    whose ``--rtf`` and ``--timeout`` defaults are :class:`ExeSettings`'s)."""

    node_params: tuple[tuple[str, Any], ...] = ()  # --node-param NAME=VALUE
    lidars: tuple[str, ...] = EXE_LIDARS
    rtf: float = ExeSettings.rtf
    limit: float = ExeSettings.limit  # wall seconds per run
    worlds: tuple[str, ...] = ()  # a grade's own; empty: the profile's default (plan.EXE_WORLDS)
    rtf_max: float = ExeSettings.rtf_max  # --rtf-max: the cap of rtf 0

    @property
    def params(self) -> dict[str, Any]:
        """``node_params`` as a dict (name -> value)."""
        return dict(self.node_params)


def grader_checkoff(maneuver: str, node_params: Mapping[str, Any] | None = None,
                    base: CheckoffConfig | None = None) -> CheckoffConfig:
    """The check-off config a grade judges ``maneuver`` by: ``base`` (the judge's defaults) with the
    ``safety_distance`` the node was given (``--node-param``), as :func:`bt_nav.grading.exe.run.exe_graph` passes
    it to the judge: the trigger the node was given is the one it is judged by."""
    config = replace(base or CheckoffConfig(), maneuver=maneuver)
    given = dict(node_params or {})
    if "safety_distance" in given:
        config = replace(config, safety_distance=float(given["safety_distance"]))
    return config


def rules_markdown(profile: str | None = None, *, maneuvers: Sequence[str] | None = None,
                   setup: GradeSetup | None = None, checkoff: CheckoffConfig | None = None,
                   referee: RefereeConfig | None = None, note: str = "") -> str:
    """The page: one assignment's rules (``profile`` lab or homework) or, with None, both, as the grader judges them
    (``maneuvers``: the lab's to list, default all; ``setup``: how the grade runs the node; ``checkoff`` and
    ``referee``: the judges' configs, default theirs; ``note``: a line under the title). ValueError: an unknown
    profile or maneuver."""
    chosen = PROFILES if profile is None else (profile,)
    if any(p not in PROFILES for p in chosen):
        raise ValueError(f"the rules cover --profile {' or '.join(PROFILES)}, not {profile!r}")
    unknown = [m for m in maneuvers or () if m not in LAB_MANEUVERS]
    if unknown:
        raise ValueError(f"the lab's maneuvers are {', '.join(LAB_MANEUVERS)}, not {', '.join(unknown)}")
    setup = setup or GradeSetup()
    level = 1 if len(chosen) == 1 else 2
    out = [] if level == 1 else ["# What your node must do", "", *([note, ""] if note else []),
                                 "What the grader (`bt-nav grade --exe`) checks a student's node for, read from the "
                                 "judges' own rules: `bt-nav rules --profile lab` or `--profile homework` prints one "
                                 "assignment, and every grade writes the one it judged as `rules.md` beside its "
                                 "report.", ""]
    for name in chosen:
        section = (_lab(level, maneuvers or LAB_MANEUVERS, setup, checkoff) if name == "lab"
                   else _homework(level, referee or RefereeConfig(), setup))
        if level == 1 and note:
            section[1:1] = ["", note]
        out += section
    return "\n".join(out).rstrip() + "\n"


def grade_rules(settings: ExeSettings, rows: Sequence[dict[str, Any]]) -> str:
    """The page for one grade: its profile, the maneuvers and LiDARs it ran, the parameters it gave the node."""
    maneuvers = sorted({r["maneuver"] for r in rows if r.get("maneuver") in LAB_MANEUVERS}) or None
    lidars = tuple(sorted({r["lidar"] for r in rows if r.get("lidar")})) or EXE_LIDARS
    worlds = tuple(sorted({r["world"] for r in rows if r.get("world")}))
    setup = GradeSetup(tuple(settings.node_params), lidars, settings.rtf, settings.limit, worlds, settings.rtf_max)
    return rules_markdown(settings.profile, maneuvers=maneuvers, setup=setup,
                          note="The rules this grade judged your node by (`bt-nav rules` prints them for any grade).")


def _h(level: int, text: str) -> str:
    return "#" * level + " " + text


def _qos(qos: tuple[str, str, int]) -> str:
    return f"{qos[0].replace('_', ' ')}, {qos[1]}, depth {qos[2]}"


def _sheet_trigger(cfg: CheckoffConfig) -> str:
    """The maneuver's trigger as the lab's sheet gives it, with the distances the judge uses (its spec's: the
    sheet's, and one more where a node may brake and turn)."""
    trigger = cfg.spec.trigger
    if trigger.or_braked_at:
        return (f"{trigger.words} < `{trigger.distance}` {cfg.distance(trigger.distance):.2f} m (the sheet's), or < "
                f"`{trigger.or_braked_at}` {cfg.distance(trigger.or_braked_at):.2f} m for a node that brakes there and "
                "pivots")
    return f"{trigger.words} < `{trigger.distance}` {cfg.distance(trigger.distance):.2f} m"


def _angle(cfg: CheckoffConfig) -> str:
    """The maneuver's angle rule as the judge words it (a clearer-side rule's side: as :func:`_side` says)."""
    return cfg.angle_rule("towards the clearer side")


def _side(cfg: CheckoffConfig) -> str:
    """Where the maneuver turns: towards the clearer side (as the judge decides it) or either way, by its spec."""
    if cfg.spec.angle.side != "clearer":
        return "either side"
    return (f"towards the clearer side: the one every reasonable reading of left and right finds farther by "
            f"{cfg.side_tie:.2f} m or more; where the readings disagree, differ by less, or both read beyond "
            f"{cfg.open_space:g} m, either side passes")


def _interface_rows(arm: str, arm_when: str) -> list[str]:
    """The interface table both assignments share: the arm service, scan, cmd_vel, /clock, odom."""
    scan_matches = "a reliable or a best-effort (sensor-data QoS) subscription matches, a transient-local one does not"
    command_matches = ("reliable, best-effort and transient-local (latched) publishers all match" if
                       COMMAND_QOS[0] == "best_effort" else "a reliable publisher matches, a best-effort one does not")
    holds = "; the last command holds until the next (publish a zero Twist to stop)" if COMMAND_TIMEOUT == 0 else ""
    return ["| what | name | type | your node | the grader's side |", "|---|---|---|---|---|",
            f"| service | `{arm}` | `{SET_BOOL}` | serves it, answers `success: true` | {arm_when} |",
            f"| topic | `{SCAN[0]}` | `{SCAN[1]}` | subscribes | published at the LiDAR's rate, "
            f"{_qos(SCAN_QOS)}: {scan_matches} |",
            f"| topic | `{COMMAND[0]}` | `{COMMAND[1]}` (not TwistStamped) | publishes | read {_qos(COMMAND_QOS)}: "
            f"{command_matches}{holds} |",
            f"| topic | `{CLOCK[0]}` | `{CLOCK[1]}` | subscribes (sim time) | the simulator's clock |",
            f"| topic | `{ODOM[0]}` | `{ODOM[1]}` | may subscribe | odometry (the judges use ground truth) |"]


def _lidar_lines(lidars: Sequence[str]) -> list[str]:
    """The LiDARs graded, each as a report names it (beam layouts and 'no return' values differ)."""
    return [f"- `{name}`: {LIDARS[name].label}" if name in LIDARS else f"- `{name}`" for name in lidars]


def _lab(level: int, maneuvers: Sequence[str], setup: GradeSetup, base: CheckoffConfig | None) -> list[str]:
    """The lab's section: in short, the interface, the schedule, each maneuver, what a turn is, the run."""
    node_params = setup.params
    configs = [grader_checkoff(m, node_params, base) for m in maneuvers]
    cfg = configs[0]
    off = cfg.activate_at + cfg.armed_for
    out = [_h(level, "The lab: what your node must do"), "", *_lab_short(cfg, configs, node_params), "",
           _h(level + 1, "The lab: interface"), "",
           *_interface_rows(LAB_ARM, f"called with `data: true` at {cfg.activate_at:g} s, `data: false` and "
                                     "`data: true` again once (the toggle cycle) and `data: false` once more, at "
                                     f"{off:g} s at the latest (schedule below)"), "",
           *_lab_parameters(cfg, node_params), "", _h(level + 1, "The lab: schedule and time limits"), "",
           *_lab_schedule(cfg, setup), "", _h(level + 1, "The lab: each maneuver"), "", *_family(cfg), ""]
    for config in configs:
        out += [_h(level + 2, f"{config.maneuver}: {MANEUVER_NAMES[config.maneuver]}"), "", *_maneuver(config), ""]
    out += [_h(level + 1, "The lab: what the judge counts as a turn"), "", *_turns(cfg), "",
            _h(level + 1, "The lab: the checks"), "",
            *_checks((*LAB_CHECKS, "parameters declared"), {n: _LAB_REQUIRED[n](cfg) for n in (*LAB_CHECKS,
                                                                                              "parameters declared")}),
            "", _h(level + 1, "The lab: run the grader on your node"), "", *_run("lab", setup), ""]
    return out


def _lab_short(cfg: CheckoffConfig, configs: Sequence[CheckoffConfig], node_params: Mapping[str, Any]) -> list[str]:
    """The two-minute answer: the numbered list a lab node must satisfy."""
    lines = [f"1. Serve `{LAB_ARM}` (`{SET_BOOL}`) and answer every call with `success: true`.",
             f"2. Stand still until it is called with `data: true` (at {cfg.activate_at:g} s); after every `data: "
             f"false` (the toggle cycle's, {cfg.toggle_off_after:g} s after your first maneuver, and the last: "
             f"{schedule_words(cfg).removeprefix('false ')}) stop within {cfg.grace:g} s and stay still; after `data: "
             "true` again go on.",
             f"3. Declare the parameter `{LAB_PARAMETERS[0]}` and use it as your trigger distance"
             + (f" (the grade gives it {float(node_params['safety_distance']):g} m)." if "safety_distance"
                in node_params else f" (default {cfg.safety_distance:g} m, the judge's)."),
             f"4. Subscribe `{SCAN[0]}` and find your sectors from `angle_min` and `angle_increment`, never by fixed "
             "index (the grader runs LiDARs whose beam layouts differ: see the end of this page).",
             f"5. Publish `{COMMAND[0]}` (`{COMMAND[1]}`): creep forward while armed (standing still "
             f"{cfg.creep_still:g} s with nothing triggering fails); when your maneuver's trigger holds, turn in "
             "place with `linear.x` 0, then creep on:"]
    lines += [f"   - **{c.maneuver}**, {MANEUVER_NAMES[c.maneuver]}: when {_sheet_trigger(c)}, turn {_angle(c)}."
              for c in configs]
    lines += ["6. Run on sim time: the grader appends `use_sim_time:=true` to your command's ROS arguments (pass "
              "them to `rclpy.init`).", "7. Hit nothing."]
    return lines


def _lab_parameters(cfg: CheckoffConfig, node_params: Mapping[str, Any]) -> list[str]:
    """The lab's parameters: the one the judge asks for, and what the grader passes."""
    given = ", ".join(f"`{k}`" for k in node_params)
    return ["| parameter | your node | the grader |", "|---|---|---|",
            f"| `{LAB_PARAMETERS[0]}` | declares it (the check-off's `ros2 param list`: a node without it fails "
            f"\"parameters declared\") and triggers at it | its judge triggers at the node's value when the grade "
            f"passes one (`--node-param {LAB_PARAMETERS[0]}=0.6`), else at {cfg.safety_distance:g} m |",
            f"| `maneuver` | may read it | passes `-p {shell_text([param_arg('maneuver', 'X')])}`: X is your file's "
            "`# CHOICE: X` or `--maneuvers X` |",
            "| `use_sim_time` | passes its arguments to `rclpy.init` | passes `true` |"] + (
        [f"| {given} | | passed by this grade (`--node-param`) |"] if given else [])


def _lab_schedule(cfg: CheckoffConfig, setup: GradeSetup) -> list[str]:
    """The lab's schedule in sim seconds from t0, and the wall-time limits of a grade: a run as long as its checks
    need (the final false once the re-armed node drove on), ``activate_at + armed_for`` at the latest."""
    off = cfg.activate_at + cfg.armed_for
    still = f"stand still (motion: over {cfg.moving_linear:g} m/s or {cfg.moving_angular:g} rad/s on ground truth)"
    early = cfg.toggle_off_for > 0 and cfg.drive_on_for > 0
    final = f"F = {off:g}"
    if early:
        final = (f"F = R + {cfg.drive_on_for:g} (later while a turn you began goes on: once no turning command came "
                 f"for {cfg.toggle_off_after:g} s, and turns back to back at most until R + {cfg.chain_for:g}; not "
                 f"before a turn was judged your maneuver), {off:g} at the latest (no toggle cycle: {off:g})")
    return [_T0, "", "| t (s) | the grader | your node |", "|---|---|---|",
            f"| 0 - {cfg.activate_at:g} | nothing | {still} |",
            f"| {cfg.activate_at:g} | `{LAB_ARM}` `data: true`, again every {1 / cfg.rate_hz:g} s until an answer "
            "says `success: true` | creep; turn when the trigger holds |",
            *_cycle_rows(cfg, still),
            f"| {final} | `data: false`, again every {1 / cfg.rate_hz:g} s until success | stop "
            f"({cfg.grace:g} s to brake) |",
            f"| F + {cfg.grace:g} - F + {cfg.grace + cfg.static_after:g} | watches | {still} |",
            f"| F + {cfg.grace + cfg.static_after:g} | the report | |", "",
            "No deadline and no evaluation service in the lab (a call to one is refused). " + _limits(LAB_ARM, setup)]


def _cycle_rows(cfg: CheckoffConfig, still: str) -> list[str]:
    """The toggle cycle's rows of the lab's schedule (none when the config has no cycle)."""
    if cfg.toggle_off_for <= 0:
        return []
    after = (f"{cfg.toggle_off_after:g} s after your first maneuver ends (no turning command since), or "
             f"{cfg.chain_for:g} s after your first turn while you turn on without such a pause")
    watched = min(cfg.grace + cfg.static_after, cfg.toggle_off_for)
    return [f"| T = {after} | the toggle cycle: `data: false`, again until success | stop ({cfg.grace:g} s to "
            "brake) |",
            f"| T + {cfg.grace:g} - T + {watched:g} | watches | {still} |",
            f"| T + {cfg.toggle_off_for:g} | `data: true` again, until success (answered at R; no cycle when T + "
            f"{2 * cfg.toggle_off_for:g} s would pass the final `data: false`) | creep on; turn when the trigger "
            "holds |"]


def _family(cfg: CheckoffConfig) -> list[str]:
    """The reasonable readings the judge accepts for "front", "left" and "right"."""
    fam = cfg.family()
    return ["The sheet gives its sectors no width, so the judge accepts every reasonable reading: a trigger did not "
            "hold only when no reading held, and it held late only when every reading held.", "",
            "| reading | what the judge accepts |", "|---|---|",
            f"| front | a sector from +-{fam.front_min_half:g} to +-{fam.front_max_half:g} deg around straight ahead |",
            f"| left, right | sectors centred {fam.side_centre_min:g}-{fam.side_centre_max:g} deg to the side, "
            f"+-{fam.side_min_half:g} to +-{fam.side_max_half:g} deg wide |",
            f"| distance | the nearest range in the sector, cast noise-free from the LiDAR's mount on the true pose; "
            f"+{cfg.trigger_margin:.2f} m for noise before \"did not hold\" |",
            f"| when | at any moment up to {cfg.scan_age:g} s before the turn's first command (and over a standstill "
            "just before it) |"]


def _maneuver(cfg: CheckoffConfig) -> list[str]:
    """One maneuver's rules: trigger, lateness, angle, side, no forward motion, moving on."""
    return ["| rule | the judge |", "|---|---|",
            f"| trigger (the sheet's) | {_sheet_trigger(cfg)} |",
            f"| trigger (the judge's words) | {cfg.trigger_rule()} |",
            f"| not late | the robot may not creep on {cfg.late_distance:g} m or more over {cfg.late_time:g} s or "
            "more while every reading holds before it turns |",
            f"| angle | {_angle(cfg)} (a tolerance of +-{cfg.angle_tolerance_deg:g} deg included), on ground truth "
            "from the turn's start until the yaw rate stays below "
            f"{cfg.settle_rate:g} rad/s for {cfg.settle_hold:g} s (at most {cfg.settle_timeout:g} s after the last "
            "turning command) |",
            f"| side | {_side(cfg)} |",
            f"| no forward motion | every command of the turn has `linear.x` within +-{cfg.forward_epsilon:g} m/s "
            f"(backwards counts too), and from {cfg.brake_allowance:g} s after the turn's start until it settles (at "
            f"most {cfg.brake_allowance:g} s after its last turning command, or until your next forward command) the "
            f"robot moves less than {cfg.forward_motion_max:g} m |",
            f"| then | move on: {cfg.move_on_distance:g} m within {cfg.move_on_within:g} s of settling, or another "
            "turn (else a finding; `--strict-findings moved_on` fails it) |"]


def _turns(cfg: CheckoffConfig) -> list[str]:
    """What the judge counts as a turn, a maneuver, a recovery turn, and how the disarm ends one."""
    return [f"- A **turn** is a run of `{COMMAND[0]}` commands with `angular.z` of {cfg.rotation_min_rate:g} rad/s or "
            "more either way while armed, whatever their `linear.x`; one that reverses by "
            f"{cfg.steer_max_deg:g} deg or more is two turns.",
            f"- **Steering** is not a turn: a run that drives faster than {cfg.turn_max_linear:g} m/s and turns the "
            f"robot less than {cfg.steer_max_deg:g} deg.",
            f"- Every turn is judged as **your maneuver**, and at least {cfg.min_maneuvers} must happen. A turn "
            f"after the robot stood {cfg.aeb_stop:g} s or more with its path ({2 * cfg.half_width:g} m wide) blocked "
            f"within {cfg.aeb_distance:g} m, that not every reading's trigger explains and that does not pass as the "
            "maneuver, is an emergency stop's **recovery turn**: judged for forward motion only.",
            f"- A turn still commanded {INTERRUPT_SLACK:g} s before the disarm or later is not judged on its angle, "
            "unless it had turned past the largest angle of its rule.",
            "- **Maneuvers back to back**: one continuous rotation is several maneuvers only where your node marks a "
            f"new one (a line it logs, within {ANNOUNCE_WINDOW:g} s: the template's `execute_rotation_maneuver` logs "
            "one; a pause; a step in the turn rate), the judge's own readings show the trigger held there, and the "
            "part before is within the angle rule (the earliest such point each time). Without such a mark it stays "
            "one turn. Maneuvers made without moving on between them are a chain, judged by the maneuver's purpose: "
            "the Randomizer and the Smart Pivot search, and may go on (a finding counts them); the Retreat is to "
            "exit the narrow space, and a chain of them that never drives out before the disarm is a finding (the "
            "sheet only implies driving out; `--strict-findings back_to_back` fails it)."]


def _checks(names: Sequence[str], required: Mapping[str, str]) -> list[str]:
    """The judge's checks, each with its requirement and the words a failure reads in."""
    rows = ["| check | required | a failure reads |", "|---|---|---|"]
    for name in names:
        rows.append(f"| {name} | {required[name]} | {CHECK_WORDS.get(name) or _LAB_WORDS.get(name, name)} |")
    return rows


#: When the schedule's clock starts (the judge's t0), as a grade's judge waits for it.
_T0 = ("Sim seconds from t0, which comes once your node offers its service and has subscribed `/clock` (without a "
       f"`/clock` subscription: {ROBOT_CLOCK_WAIT:g} s wall into the run):")


def _limits(service: str, setup: GradeSetup) -> str:
    """A grade's pace and wall-time limits, and what a node that never offers its service gets."""
    pace = f"at {speed_words(setup.rtf, setup.rtf_max)} (`--rtf`)"
    return (f"A grade runs your node {pace}, at most {setup.limit:g} s wall per run "
            f"(`--timeout`); a node that offers no `{service}` within {START_WAIT:g} s wall (less with a short "
            "`--timeout`) is not judged: the run fails.")


def _run(profile: str, setup: GradeSetup) -> list[str]:
    """How to run the grader on one's node, what it appends and what it runs by default."""
    example = "reactive_navigator.py" if profile == "lab" else "reactive_controller.py"
    appended = exe_ros_args("X" if profile == "lab" else None, profile, setup.node_params)
    worlds = setup.worlds or tuple(EXE_WORLDS[profile].split(","))
    which = "the default" if tuple(setup.lidars) == EXE_LIDARS else "this grade's"
    where = "this grade's" if setup.worlds else "by default" + ("; those that check your maneuver off" if
                                                                 profile == "lab" else "")
    return ["```console", f"$ bt-nav grade --exe \"python3 {example}\" --profile {profile}", "```", "",
            f"Appended to your command: `{shell_text(appended)}`"
            + (" (X: your file's `# CHOICE: X`, or `--maneuvers X`)" if profile == "lab" else "")
            + ". Remapping changes only a name your node uses: " + ", ".join(
                f"`{src}` becomes `{dst}`" for src, dst in profile_remaps(profile)) + ".", "",
            f"It runs the world{'s' if len(worlds) > 1 else ''} " + ", ".join(f"`{w}`" for w in worlds)
            + f" ({where}, `--worlds`) on each of these LiDARs ({which}, `--lidars`), each run in its own ROS "
            "domain, and writes `summary.md`, `report.html` and this page as `rules.md` in its output directory:", "",
            *_lidar_lines(setup.lidars),
            *(["", _lab_cells()] if profile == "lab" and not setup.worlds else [])]


def _lab_cells() -> str:
    """The default grid's cells of each lab choice (:func:`bt_nav.grading.plan.checked_cells`, as a grade plans
    them), with the parameter a cell passes."""
    def cell(world: str, params: tuple[tuple[str, float], ...]) -> str:
        return f"`{world}`" + "".join(f" (`-p {k}:={v:g}`)" for k, v in params)

    each = [f"{m}: " + ", ".join(cell(c.world, c.params) for c in checked_cells(LAB.exe_grid, m))
            for m in LAB_MANEUVERS]
    return (f"By default your maneuver is graded only in the cells that show its mistakes ({LAB.exe_grid.seeds} "
            "seeds each): "
            + "; ".join(each) + ". A parameter a cell names is appended to your command, and the judge uses it too.")


def _homework(level: int, cfg: RefereeConfig, setup: GradeSetup) -> list[str]:
    """The homework's section: in short, the interface, the schedule, the checks, the run."""
    window = cfg.evaluation_deadline - cfg.static_before
    short = [f"1. Serve `{HOMEWORK_ACTIVATE}` (`{SET_BOOL}`) and answer every call with `success: true`.",
             f"2. Stand still until the first `data: true` (at {cfg.static_before:g} s); after `data: false` (at "
             f"{cfg.deactivate_at:g} s) publish zero velocities within {cfg.grace:g} s and stay still until "
             f"`data: true` again (at {cfg.reactivate_at:g} s).",
             f"3. Subscribe `{SCAN[0]}`; publish `{COMMAND[0]}` (`{COMMAND[1]}`): drive without hitting anything.",
             f"4. Get at least {cfg.min_distance_from_start:g} m from the start and travel at least "
             f"{cfg.min_travelled:g} m.",
             f"5. Stop, then call `{HOMEWORK_EVALUATE}` (`{TRIGGER}`) by {cfg.evaluation_deadline:g} s ({window:g} s "
             f"after the first activation call) and stay still: the report comes {cfg.settle_after_call:g} s later.",
             "6. Run on sim time: the grader appends `use_sim_time:=true` (pass your arguments to `rclpy.init`)."]
    interface = _interface_rows(HOMEWORK_ACTIVATE, f"calls it on the schedule below (every {1 / cfg.rate_hz:g} s "
                                                   "until an answer says `success: true`)")
    interface.append(f"| service | `{HOMEWORK_EVALUATE}` | `{TRIGGER}` | calls it once, standing still | serves "
                     "it: the first call ends the schedule |")
    required = {name: _HOMEWORK_REQUIRED[name](cfg) for name in HOMEWORK_CHECKS}
    return [_h(level, "The homework: what your node must do"), "", *short, "",
            _h(level + 1, "The homework: interface"), "", *interface, "",
            _h(level + 1, "The homework: schedule and time limits"), "", *_homework_schedule(cfg, setup), "",
            _h(level + 1, "The homework: the checks"), "", *_checks(HOMEWORK_CHECKS, required), "",
            _h(level + 1, "The homework: run the grader on your node"), "",
            *_run("homework", setup), ""]


def _homework_schedule(cfg: RefereeConfig, setup: GradeSetup) -> list[str]:
    """The homework's schedule in sim seconds from t0."""
    still = f"stand still (motion: over {cfg.moving_linear:g} m/s or {cfg.moving_angular:g} rad/s on ground truth)"
    return [_T0, "", "| t (s) | the grader | your node |", "|---|---|---|",
            f"| 0 - {cfg.static_before:g} | nothing | {still} |",
            f"| {cfg.static_before:g} | activate `data: true` until success | drive |",
            f"| {cfg.deactivate_at:g} | `data: false` | stop within {cfg.grace:g} s |",
            f"| {cfg.deactivate_at + cfg.grace:g} - {cfg.reactivate_at:g} | watches | {still} |",
            f"| {cfg.reactivate_at:g} | `data: true` until success | drive on |",
            f"| by {cfg.evaluation_deadline:g} | serves `{HOMEWORK_EVALUATE}` | stop, call it once |",
            f"| the call + {cfg.settle_after_call:g} | the report, then `data: false` | still over its last "
            f"{cfg.window:g} s |", "",
            f"No call by {cfg.evaluation_deadline:g} s: \"evaluation service called\" fails and the report comes "
            "then. " + _limits(HOMEWORK_ACTIVATE, setup)]


#: The line a grade's summary.md and report.html give under their failures (the page beside them).
RULES_LINE_MD = f"What your node must do: [{RULES_FILE}]({RULES_FILE})"
RULES_LINE_HTML = f'<p>What your node must do: <a href="{RULES_FILE}">{RULES_FILE}</a></p>'
