"""``bt_nav_referee``: the homework referee (:mod:`bt_nav.judge.referee_core`) over real DDS, in sim time.

Run: ``bt-nav referee [--json PATH] [--timeout S] [--time-scale X] [--ros-args ...]`` or
``ros2 run bt_nav referee``.

The driver (t0, the sim-time step timer, activate calls with retries, ground truth, collisions, sim_sync,
the report, the JSON, exit codes, time base of the log lines) is :class:`bt_nav.ros.nodes.judging.JudgeNode`,
shared with the lab's check-off judge; this module adds the homework's schedule and rules
(:class:`Referee`, parameters from :class:`RefereeConfig`) and the Trigger server
``/reactive_control/evaluate_mission``, answered by :meth:`Referee.on_evaluate`. ``use_sim_time`` is true
by default.

Namespaces: every name but ``/clock`` is relative, so ``--ros-args -r __ns:=/robot1`` with relative
service names (``-p activate_service:=reactive_control/activate``, ``-p
evaluate_service:=reactive_control/evaluate_mission``, what :func:`bt_nav.ros.bringup.nodes` sets for a
namespace) judges that robot alone: its ground truth, collisions and services, on its own timeline; its
``sim_sync`` name is then its fully qualified node name, so one simulator can follow several referees.

Timings can be shortened for tests: ``time_scale`` multiplies every duration of the schedule
(``static_before`` ... ``settle_after_call``, not the sampling ``window``) after the individual
parameters are applied.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import fields
from typing import Any

from std_srvs.srv import Trigger

from bt_nav.judge.referee_core import Referee, RefereeConfig, scaled
from bt_nav.mission.assignments import HOMEWORK
from bt_nav.ros.nodes.judging import DRIVER_PARAMETERS, JudgeNode, locked
from bt_nav.ros.runner import param_args, run_node

NODE_NAME = HOMEWORK.judge.node_name

_DEFAULTS = RefereeConfig()


class RefereeNode(JudgeNode):
    """The referee node (see the module docstring); rclpy must be initialised.

    Args:
        wall_start: monotonic wall time the ``timeout`` counts from (default: now).
    """

    PARAMETERS: dict[str, tuple[Any, str]] = {
        **DRIVER_PARAMETERS,
        "time_scale": (1.0, "multiplies every duration of the schedule (tests use < 1)"),
        "activate_service": (HOMEWORK.arm_service, "the robot's SetBool activate service"),
        "evaluate_service": (HOMEWORK.evaluate_service, "the Trigger service served here"),
        **{f.name: (float(getattr(_DEFAULTS, f.name)), f"RefereeConfig.{f.name}") for f in fields(_DEFAULTS)},
    }

    def __init__(self, wall_start: float | None = None, **hosting: Any) -> None:
        super().__init__(NODE_NAME, wall_start, **hosting)  # hosting: fed, cli_args (a hosted judge: JudgeNode)
        self.referee: Referee = self.judge
        self.create_service(Trigger, str(self.get_parameter("evaluate_service").value), self._on_evaluate)

    def make_judge(self, p: dict[str, Any]) -> tuple[Referee, RefereeConfig]:
        """The homework's :class:`Referee` with the parameters' config, durations scaled by ``time_scale``."""
        config = scaled(RefereeConfig(**{f.name: float(p[f.name]) for f in fields(_DEFAULTS)}), float(p["time_scale"]))
        return Referee(config), config

    def schedule_text(self) -> str:
        """The homework's schedule, sim seconds from t0."""
        c = self.config
        return (f"schedule: activate at {c.static_before:g} s, deactivate at {c.deactivate_at:g} s, reactivate at "
                f"{c.reactivate_at:g} s, evaluation by {c.evaluation_deadline:g} s (sim time from t0)")

    @locked
    def _on_evaluate(self, request: Any, response: Any) -> Any:
        now = self.now()
        response.success, response.message = self.referee.on_evaluate(now)
        self.get_logger().info(f"{self.stamp(now)}: evaluate_mission called: {response.message}")
        return response


def make_node(wall_start: float | None = None) -> RefereeNode:
    """Create the referee node (rclpy must be initialised)."""
    return RefereeNode(wall_start)


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Our own options (ROS arguments removed first): shorthands for parameters."""
    parser = argparse.ArgumentParser(prog="bt-nav referee", description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="results file (parameter json)")
    parser.add_argument("--timeout", type=float, help="wall-clock limit, s (parameter timeout)")
    parser.add_argument("--time-scale", type=float, help="scale of the schedule's durations (parameter time_scale)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav referee``: exit 0 when every check passed, 1 when one failed, 2 on timeout or bad set-up."""
    wall_start = time.monotonic()
    return run_node(NODE_NAME, argv, parse_args, build=lambda node, opts: node,
                    make_node=lambda name: make_node(wall_start), ros_defaults=["-p", "use_sim_time:=true"],
                    ros_args_of=lambda o: param_args({"json": o.json, "timeout": o.timeout,
                                                      "time_scale": o.time_scale}))


if __name__ == "__main__":
    raise SystemExit(main())
