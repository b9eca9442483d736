"""A judge hosted in the simulator's process: ``bt-nav sim --judge referee|checkoff --judge-args '[...]'``, the
world and its judge of a ``bt-nav grade --exe`` run.

Why one process: a judge of its own process reads ``/clock`` and 30 Hz ground truth over DDS, wakes its executor
~100 times per sim second for them, and starts a Python process and a DDS participant per run; on two cores that was
a fifth of a graded run's CPU (measured: the referee 1.6 of 6.9 CPU s), taken from the node being graded. Hosted, the
judge (the same :class:`bt_nav.ros.nodes.judging.JudgeNode`, ``fed``) is fed by the simulator's loop at the instant
each pose, collision and step happens (:meth:`JudgeNode.feed`), so it is never late either. What concerns the robot
stays on DDS exactly as it sees it: the arm service the judge calls, ``cmd_vel``, the graph audit, the homework's
evaluation service the judge serves, the log lines on ``/rosout`` under the judge's own node name.

The judge node gets its own ROS arguments (``--judge-args``: a JSON list, what its
:class:`bt_nav.ros.bringup.NodeSpec` would be started with) and none of the process's, which are the simulator's. The
process does not end at the verdict: the world runs on until the process is stopped, so a graded node is stopped while
its clock still runs (:mod:`bt_nav.grading.exe.run` stops the node first). The verdict is the judge's JSON file
(written whole: it appears complete or not at all) and its report lines on stdout; the exit code is the simulator's.
"""

from __future__ import annotations

import importlib
import json
from typing import Any

from bt_nav_sim.core import StepOutput

from bt_nav.ros.nodes.judging import JudgeNode
from bt_nav.ros.rosutil import ConfigError

#: ``--judge`` values: the judge node class of each (module, class).
JUDGE_NODES = {"referee": ("bt_nav.ros.nodes.referee", "RefereeNode"),
               "checkoff": ("bt_nav.ros.nodes.checkoff", "CheckoffNode")}


def make_hosted_judge(kind: str, ros_args: list[str], wall_start: float) -> JudgeNode:
    """The judge node ``kind`` (a key of :data:`JUDGE_NODES`) with its own ROS arguments, fed by its host.

    Raises:
        ConfigError: an unknown kind; ValueError/FileNotFoundError: a judge refusing its parameters.
    """
    if kind not in JUDGE_NODES:
        raise ConfigError(f"--judge must be one of {', '.join(JUDGE_NODES)}, got {kind!r}")
    module, name = JUDGE_NODES[kind]
    cls = getattr(importlib.import_module(module), name)
    return cls(wall_start, fed=True, cli_args=list(ros_args))


def parse_judge_args(text: str) -> list[str]:
    """``--judge-args``: a JSON list of strings (ConfigError otherwise)."""
    try:
        args = json.loads(text or "[]")
    except ValueError as exc:
        raise ConfigError(f"--judge-args is not JSON: {exc}") from None
    if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
        raise ConfigError("--judge-args must be a JSON list of strings")
    return args


class HostedJudge:
    """The runner's wiring of a simulator with its judge (the Finishing protocol of :mod:`bt_nav.ros.runner`, plus
    ``extra_nodes`` for the executor). ``sim``: the :class:`bt_nav.ros.nodes.simulator.SimulatorNode` (not imported
    here: its command line imports this module), whose loop must not have started yet.

    Raises:
        ConfigError: more than one robot (a hosted judge judges the one robot of today's topic names).
    """

    def __init__(self, sim: Any, judge: JudgeNode) -> None:
        if len(sim.robots) != 1 or sim.robots[0].prefix:
            raise ConfigError("a hosted judge judges one robot at the root topics")
        self.sim, self.judge = sim, judge
        self.extra_nodes = (judge,)
        self._walkers = sim.sim.walkers if len(sim.sim.walkers) else None
        judge.sync_sink = sim.follow_report
        judge.arm_sink = sim.robot_armed
        judge.start_gate = self._robot_followed
        judge.clock_matched = self._clock_matched
        sim.observers.append(self._on_outputs)
        sim.set_judging(False)  # until its t0

    def _clock_matched(self) -> bool:
        """Whether the simulator's ``/clock`` publisher has matched every ``/clock`` subscription on the graph: the
        robot's node then gets the next sample, and the judge need not let its subscription settle for
        ``robot_clock_settle`` wall seconds as a judge of its own process must (it cannot see the matching)."""
        on_graph = len(self.sim.get_subscriptions_info_by_topic("/clock"))
        return on_graph > 0 and self.sim.clock_pub.get_subscription_count() >= on_graph

    def _robot_followed(self) -> str | None:
        """What t0 still waits for here: a judge that waits for the robot's first command, in a simulator that follows
        commands, starts once the simulator follows them too (its own reader can hear the first command later than the
        judge's; from t0 on sim time follows the judge, and without the robot it would run ahead of a node that has
        not caught up: seen as 13 sim s unfollowed and 1.7 m less travelled in two demos at once)."""
        if not (self.judge.wait_for_cmd_vel and self.sim.follow) or self.sim.follows(self.sim.robots[0].follower):
            return None
        return "the simulator following cmd_vel"

    def _on_outputs(self, outs: list[StepOutput]) -> None:
        """The loop's step, as the judge would read it from the simulator's topics (loop thread)."""
        out = outs[0]
        state = self.sim.core.state
        walkers = self._walkers.circles() if out.odom and self._walkers is not None else None
        self.judge.feed(out.t_ns, truth=(state.x, state.y, state.yaw) if out.odom else None,
                        collision=(state.x, state.y) if out.collision else None, walkers=walkers)

    def poll(self) -> bool:
        """The judge's duties between spins; True once the simulator's loop has ended (never at the verdict)."""
        self._judging()  # before: the judge's poll may make its verdict, which is no longer judged time
        self.judge.poll()
        self._judging()
        return self.sim.poll()

    def _judging(self) -> None:
        """Tell the simulator whether the judge is judging: from its t0 until its schedule is done (its last window
        closed), not until its verdict is made. Making it (a long run's creep check casts a reading at every armed
        sample, in this process) held the loop up to 0.6 s while the run counted as judged, and a node that never
        crept, standing 66 s, fell behind real time in every run and ended NOT GRADED."""
        self.sim.set_judging(self.judge.started and not self.judge.finished and not self.judge.judge.done)

    def close(self) -> None:
        """The judge first (stopped before its verdict, it says so and lets the world go), then the loop."""
        try:
            self.judge.close()
        finally:
            self.sim.close()

    @property
    def exit_code(self) -> int:
        """The simulator's: 1 when its loop died, else 0 (the verdict is the judge's JSON)."""
        return self.sim.exit_code
