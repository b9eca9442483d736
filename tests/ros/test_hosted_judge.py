"""A judge hosted by the simulator's process (:mod:`bt_nav.ros.nodes.hosting`): fed by the loop, not by DDS.

The referee here is the real node (``fed``), its robot a real SetBool service over DDS; the test feeds the physics
steps itself, as the simulator's loop does, and checks the schedule's instants, the holds told to the follower table
and the verdict file.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from std_srvs.srv import SetBool

from bt_nav.ros.bringup import host_judge, nodes
from bt_nav.ros.nodes.referee import RefereeNode

STEP_NS = 10_000_000  # the simulator's 100 Hz physics step


def test_a_fed_referee_acts_on_the_steps_of_its_host(ros_context: Any, tmp_path: Path) -> None:
    verdict = tmp_path / "verdict.json"
    args = ["--ros-args", "-p", "activate_service:=/hosted/activate", "-p", "evaluate_service:=/hosted/evaluate",
            "-p", "audit:=false", "-p", f"json:={verdict}", "-p", "time_scale:=0.1", "-p", "timeout:=60.0"]
    judge = RefereeNode(fed=True, cli_args=args, context=ros_context)
    robot = Node("hosted_robot", context=ros_context)
    requests: list[tuple[bool, int]] = []  # (data, the judge's clock when the robot got it)

    def serve(request: Any, response: Any) -> Any:
        requests.append((bool(request.data), judge._fed_ns))
        response.success = True
        return response

    robot.create_service(SetBool, "/hosted/activate", serve)
    told: list[tuple[str, int, bool, bool]] = []
    judge.sync_sink = lambda who, t_ns, hold, leave: told.append((who, t_ns, hold, leave))
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(judge)
    executor.add_node(robot)
    try:
        t_ns = 0
        while not judge.started:  # t0: the service found (discovery takes wall time, sim time waits)
            t_ns = STEP_NS
            judge.feed(t_ns, truth=(0.0, 0.0, 0.0))
            judge.poll()
            executor.spin_once(timeout_sec=0.02)
        t0 = judge.judge.t0
        assert t0 == t_ns * 1e-9 and judge.json_path == str(verdict)
        for _ in range(3000):
            if judge.poll():
                break
            t_ns += STEP_NS
            judge.feed(t_ns, truth=(min(3.0, (t_ns * 1e-9 - t0) * 0.5), 0.0, 0.0))
            while judge._pending:  # the simulator holds its step while a call is out (sync)
                executor.spin_once(timeout_sec=0.05)
                judge.poll()
            executor.spin_once(timeout_sec=0)
        config = judge.config
        sent = [(data, round(ns * 1e-9 - t0, 6)) for data, ns in requests]
        # each request leaves on the step the schedule names (t0 + k / rate_hz), not a step later
        assert sent[:3] == [(True, round(config.static_before, 6)), (False, round(config.deactivate_at, 6)),
                            (True, round(config.reactivate_at, 6))], sent
        assert any(hold for _, _, hold, leave in told if not leave), "a call in flight holds the host's time"
        assert told[-1][3], "the judge leaves the follower table at its verdict"
        result = json.loads(verdict.read_text())
        assert result["t0_sim"] == t0 and result["activate_calls"] >= 3
        distance = next(c for c in result["checks"] if c["name"].startswith("minimum distance"))
        assert distance["value"] > 1.0, "the fed poses were judged"
    finally:
        executor.shutdown()
        judge.destroy_node()
        robot.destroy_node()


def test_the_judge_moves_into_the_simulators_command_line() -> None:
    specs = host_judge(nodes("eval", seed=3, results_json="/tmp/v.json"))
    assert [s.executable for s in specs] == ["sim", "executive"]
    sim = specs[0]
    at = sim.arguments.index("--judge")
    assert sim.arguments[at + 1] == "referee"
    own = json.loads(sim.arguments[at + 3])
    assert own[:3] == ["--ros-args", "-r", "__node:=bt_nav_referee"]
    assert "use_sim_time:=false" in own and 'json:="/tmp/v.json"' in own, own


def test_the_host_runs_at_its_unjudged_pace_before_t0_and_after_the_schedule() -> None:
    """:meth:`HostedJudge.poll` tells the simulator whether its judge is judging: from its t0 until its schedule is
    done, before the verdict is made (making it can hold the loop up: no window of the run is open then). The
    simulator's pace between those instants is the only one a verdict depends on."""
    from types import SimpleNamespace

    from bt_nav.ros.nodes.hosting import HostedJudge

    said: list[bool] = []
    sim = SimpleNamespace(robots=[SimpleNamespace(prefix="")], sim=SimpleNamespace(walkers=[]), observers=[],
                          follow_report=None, robot_armed=None, set_judging=said.append, poll=lambda: False)
    core = SimpleNamespace(done=False)
    judge = SimpleNamespace(started=False, finished=False, judge=core)

    def poll() -> None:  # the verdict is made in the judge's poll once its schedule is done
        judge.finished = judge.finished or core.done

    judge.poll = poll
    hosted = HostedJudge(sim, judge)  # type: ignore[arg-type]
    hosted.poll()
    judge.started = True
    hosted.poll()
    core.done = True  # the last window closed (the step timer): the verdict comes in the next poll
    hosted.poll()
    assert said == [False, False, False, True, True, False, False], said
