"""``bt_nav_checkoff``: the lab's check-off judge (:mod:`bt_nav.judge.checkoff_core`) over real DDS, in sim time.

Run: ``bt-nav checkoff --maneuver C --world lab_object [--json PATH] [--timeout S] [--ros-args ...]`` or
``ros2 run bt_nav checkoff``; ``bt-nav demo --profile lab`` and ``launch/lab_checkoff.launch.py`` start it
beside the simulator and the executive.

It judges any robot node with the lab's interface, not only bt_nav's: it calls its ``toggle_navigation``
(std_srvs/SetBool; parameter ``activate_service``, relative so a namespace or a remap moves it) as the
judge's schedule says (static 5 s, true, 60 s armed with one toggle cycle inside: false 1 s after the first maneuver
ends and true 5 s later, false, 1 s grace, 3 s static, report); it reads
ground truth (``ground_truth_odom``), the simulator's ``collisions`` and every ``cmd_vel`` the robot
publishes (Twist or TwistStamped, found on the graph; ``cmd_vel_type`` forces one); and it casts its
noise-free trigger readings in its own copy of the simulator's world (parameters ``world`` and ``seed``, as
given to the simulator; objects that appear are revealed from the poses it observes). It prints the
judge's report lines (``name (detail): PASSED|FAILED``, ``overall: ...``), writes the verdict JSON
(``json``) and exits 0 when the check-off passed, 1 when it failed, 2 without a verdict.

What the robot node logs (``/rosout``, rcl_interfaces/Log; any node not bt_nav's own infrastructure, the judge's and
the simulator's lines excluded) goes to the judge as announcements (``on_announcement``): any words, only their
times count, as marks where the node began a new maneuver within one continuous rotation. A line is placed in sim
time from its own stamp: rclpy stamps a ``/rosout`` line with the wall clock even under ``use_sim_time`` (rcutils'
system time; measured), so the stamp is mapped onto the sim clock by the wall and sim times the judge saw together
as ground truth came (:class:`bt_nav.judge.segments.ClockMap`), not timed by its arrival (a busy machine delivers it
late); a stamp within ``LOG_STAMP_SLACK`` s of the judge's clock (a node that logs on sim time) is taken as it is,
and one the map cannot place is timed by its arrival.

The driver (t0, sim-time steps, calls with retries, sim_sync, time base of the log lines: ``sim 12.30 s (t0 +
7.30 s)``) is :class:`bt_nav.ros.nodes.judging.JudgeNode`, the referee's. ``use_sim_time`` is true by default.
Every :class:`bt_nav.judge.checkoff_core.CheckoffConfig` field is a parameter of the same name (``armed_for``,
``safety_distance``, ``pivot_distance``, ...): the trigger distances must be the robot's.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import fields
from typing import Any

from bt_nav_sim.truth import truth_feed
from bt_nav_sim.world import load_world
from rcl_interfaces.msg import Log
from rclpy.qos import QoSProfile, ReliabilityPolicy

from bt_nav.judge.checkoff_core import CheckoffConfig, CheckoffJudge
from bt_nav.judge.checkoff_schedule import schedule_words
from bt_nav.judge.segments import ClockMap
from bt_nav.mission.assignments import LAB
from bt_nav.mission.maneuver_spec import letters_text
from bt_nav.mission.params import normalise_maneuver
from bt_nav.ros.nodes.audit import is_ours
from bt_nav.ros.nodes.judging import DRIVER_PARAMETERS, JudgeNode, locked
from bt_nav.ros.runner import param_args, run_node

NODE_NAME = LAB.judge.node_name

_DEFAULTS = CheckoffConfig()
#: s: a log line stamped further than this from the judge's clock (rclpy's wall-clock stamps) is timed by its arrival.
LOG_STAMP_SLACK = 2.0


def _config_parameters() -> dict[str, tuple[Any, str]]:
    """Every CheckoffConfig field as a parameter (its type kept: maneuver a string, min_maneuvers an int)."""
    return {f.name: (getattr(_DEFAULTS, f.name), f"CheckoffConfig.{f.name}") for f in fields(_DEFAULTS)}


class CheckoffNode(JudgeNode):
    """The check-off judge node (see the module docstring); rclpy must be initialised."""

    PARAMETERS: dict[str, tuple[Any, str]] = {
        **DRIVER_PARAMETERS,
        "activate_service": (LAB.arm_service, "the robot's SetBool service that starts (true) and stops it"),
        "world": ("lab_object", "the simulator's world (name or YAML path), for the judge's own ray casts"),
        "seed": (0, "the simulator's seed (generated worlds); -1: random, refused for a generated world"),
        **_config_parameters(),
    }
    wants_commands = True
    required_parameters = ("safety_distance",)  # the check-off's `ros2 param list` step

    def __init__(self, wall_start: float | None = None, **hosting: Any) -> None:
        self.clocks = ClockMap()  # the wall and sim times seen together: a log line's wall stamp onto the sim clock
        super().__init__(NODE_NAME, wall_start, **hosting)  # hosting: fed, cli_args (a hosted judge: JudgeNode)

    def _take_truth(self, t: float, x: float, y: float, yaw: float) -> None:
        """A ground-truth pose, as the judge driver takes it; its stamp and the wall clock now are one pair of the
        clock map (a hosted judge's pose is its step's: the pair is exact)."""
        self.clocks.add(time.time(), t)
        super()._take_truth(t, x, y, yaw)

    def _create_interfaces(self, p: dict[str, Any]) -> None:
        """The driver's interfaces, and ``/rosout`` for the robot node's lines (the announcements)."""
        super()._create_interfaces(p)
        self.create_subscription(Log, "/rosout", self._on_log,
                                 QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE))

    @locked
    def _on_log(self, msg: Log) -> None:
        """One logged line: the judged node's goes to the judge, timed by its stamp (see the module docstring)."""
        if not self.started or any(is_ours(part) for part in str(msg.name).split(".") if part):
            return
        now = self.now()
        stamp = msg.stamp.sec + msg.stamp.nanosec * 1e-9
        clocks = getattr(self, "clocks", None)
        placed = clocks.sim_at(stamp) if clocks is not None else None
        t = stamp if abs(stamp - now) <= LOG_STAMP_SLACK else placed if placed is not None else now
        self.judge.on_announcement(t, str(msg.name), str(msg.msg))

    def make_judge(self, p: dict[str, Any]) -> tuple[CheckoffJudge, CheckoffConfig]:
        """The judge for the parameters' config, fed the simulator's truth in its own copy of the world (which it
        reveals appearing objects in from the poses it observes; ValueError/FileNotFoundError: refused)."""
        values = {f.name: type(getattr(_DEFAULTS, f.name))(p[f.name]) for f in fields(_DEFAULTS)}
        values["maneuver"] = normalise_maneuver(str(values["maneuver"]))  # randomizer, a, ... are A
        config = CheckoffConfig(**values)
        seed = int(p["seed"])
        world = load_world(str(p["world"]), seed=None if seed < 0 else seed)
        if world.checkoff_maneuvers and config.maneuver not in world.checkoff_maneuvers:
            self.get_logger().warning(f"world {world.name} lists check-offs of {', '.join(world.checkoff_maneuvers)}, "
                                      f"not {config.maneuver}: its trigger may never hold here")
        self.world_name = world.name
        return CheckoffJudge(config, truth_feed(config, world, update_world=True)), config

    def schedule_text(self) -> str:
        """The lab's schedule, sim seconds from t0."""
        c = self.config
        call = self.call_name
        cycle = (f"{call}(false) {c.toggle_off_after:g} s after the first maneuver and (true) {c.toggle_off_for:g} s "
                 "later, " if c.toggle_off_for > 0 else "")
        return (f"check-off of maneuver {c.maneuver} in {self.world_name}: {call}(true) at {c.activate_at:g} s, "
                f"{cycle}{call}({schedule_words(c)}), the report {c.grace + c.static_after:g} s after it (sim time "
                "from t0)")


def make_node(wall_start: float | None = None) -> CheckoffNode:
    """Create the check-off judge node (rclpy must be initialised)."""
    return CheckoffNode(wall_start)


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Our own options (ROS arguments removed first): shorthands for parameters."""
    parser = argparse.ArgumentParser(prog="bt-nav checkoff", description=__doc__.split("\n\n")[0])
    parser.add_argument("--maneuver", help=f"the maneuver to check off: {letters_text()} (parameter maneuver)")
    parser.add_argument("--world", help="the simulator's world (parameter world)")
    parser.add_argument("--seed", type=int, help="the simulator's seed (parameter seed)")
    parser.add_argument("--json", help="results file (parameter json)")
    parser.add_argument("--timeout", type=float, help="wall-clock limit, s (parameter timeout)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav checkoff``: exit 0 when the check-off passed, 1 when it failed, 2 on timeout or bad set-up."""
    wall_start = time.monotonic()
    return run_node(NODE_NAME, argv, parse_args, build=lambda node, opts: node,
                    make_node=lambda name: make_node(wall_start), ros_defaults=["-p", "use_sim_time:=true"],
                    ros_args_of=lambda o: param_args({"maneuver": o.maneuver, "world": o.world, "seed": o.seed,
                                                      "json": o.json, "timeout": o.timeout}))


if __name__ == "__main__":
    raise SystemExit(main())
