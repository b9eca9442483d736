"""``bt-nav demo`` (``make demo``): the whole homework mission over real DDS in sim time, judged and drawn.

It starts the ``eval`` profile of :mod:`bt_nav.ros.bringup` — simulator (stage_4, homework LiDAR),
executive (homework service names, ``config/homework.yaml``) and referee — as subprocesses on this
machine only, with the simulator as fast as the executive and the referee keep up (``--rtf 0``; the
simulator waits for both, see :mod:`bt_nav_sim.nodes.simulator`, so the verdict does not depend on the CPU
load). The referee is started last, once this process sees ground truth and the executive's
commands, so the recording covers the whole schedule. The demo records from its own small node:

- ``ground_truth_odom`` (the trajectory) with the tree's tip from ``/bt_nav_executive/tree`` (the
  branch that drove each sample; the executive publishes the tree whenever a status changes), and
- ``cmd_vel`` (what was commanded), kept with the trajectory.

When the referee has given its verdict it writes, under ``<out>/<name>/``: ``results.json`` (the
referee's), ``trajectory.json``, ``trajectory.png`` (:func:`bt_nav_sim.plot.plot_run`), the tree as
``tree.dot`` and ``tree.svg`` (when graphviz is installed), and one ``<node>.log`` per process. The
referee's verdict lines are printed, and the exit code is the referee's (0 = PASSED).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from bt_nav.ros.bringup import (
    EXECUTIVE_NAME,
    Launcher,
    child_env,
    choose_domain_id,
    config_file,
    file_parameters,
    nodes,
    parse_assignments,
)

#: One line of py_trees' unicode tree as the executive publishes it: indent, marker, name, [status], feedback.
_TREE_LINE = re.compile(r"^(?P<indent> *)\S+ (?P<name>.*?) \[(?P<status>[✓✕*-])\](?: -- .*)?$")
#: Extra wall time the demo allows beyond the referee's own timeout before it gives up itself.
_GRACE = 15.0
#: Wall time to wait for the recorder to see ground truth and commands before starting the referee anyway.
_STARTUP = 30.0


def rec_ready(recorder: Recorder) -> bool:
    """The recorder receives ground truth and the executive's commands."""
    with recorder.lock:
        return bool(recorder.data.t) and recorder.data.commands > 0


def tip_from_snapshot(text: str) -> str:
    """The tip of a tree snapshot (``~/tree`` text): the deepest node on the path of the last tick.

    Mirrors ``Behaviour.tip()`` from statuses alone: in every composite the child the tick ended on is
    the last one that is not INVALID (``[-]``): a selector's winner or a sequence's current child.
    Returns "" when the text cannot be parsed.
    """
    nodes_: list[tuple[int, str, str]] = []
    for line in text.splitlines():
        match = _TREE_LINE.match(line)
        if match:
            nodes_.append((len(match["indent"]), match["name"], match["status"]))
    if not nodes_:
        return ""
    index = 0
    while True:
        depth = nodes_[index][0]
        child_depth = None
        last_active = None
        for j in range(index + 1, len(nodes_)):
            d = nodes_[j][0]
            if d <= depth:
                break
            if child_depth is None:
                child_depth = d
            if d == child_depth and nodes_[j][2] != "-":
                last_active = j
        if last_active is None:
            return nodes_[index][1]
        index = last_active


@dataclass
class Recording:
    """What the demo's recorder node saw (appended from its executor thread)."""

    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    yaw: list[float] = field(default_factory=list)
    tip: list[str] = field(default_factory=list)
    wall: list[float] = field(default_factory=list)  # monotonic arrival time of each sample
    cmd_linear: list[float] = field(default_factory=list)  # latest command at each sample
    cmd_angular: list[float] = field(default_factory=list)
    commands: int = 0
    tree_messages: int = 0
    current_tip: str = ""
    current_cmd: tuple[float, float] = (0.0, 0.0)


class Recorder:
    """A node of the demo's own, spinning in a thread: ground truth, commands and the tree tip."""

    def __init__(self) -> None:
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        from bt_nav.ros.rosutil import ThreadedNode

        self.ros = ThreadedNode("bt_nav_demo_recorder")
        self.node = self.ros.node
        self.data = Recording()
        self.lock = threading.Lock()
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Odometry, "ground_truth_odom", self._on_truth, reliable)
        self.node.create_subscription(Twist, "cmd_vel", self._on_cmd, reliable)
        self.node.create_subscription(String, f"/{EXECUTIVE_NAME}/tree", self._on_tree, latched)
        self.ros.start()

    def _on_truth(self, msg: Any) -> None:
        from bt_nav.ros.rosutil import yaw_from_quaternion

        q = msg.pose.pose.orientation
        d = self.data
        with self.lock:
            d.t.append(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)
            d.x.append(msg.pose.pose.position.x)
            d.y.append(msg.pose.pose.position.y)
            d.yaw.append(yaw_from_quaternion(q.x, q.y, q.z, q.w))
            d.tip.append(d.current_tip)
            d.wall.append(time.monotonic())
            d.cmd_linear.append(d.current_cmd[0])
            d.cmd_angular.append(d.current_cmd[1])

    def _on_cmd(self, msg: Any) -> None:
        with self.lock:
            self.data.current_cmd = (float(msg.linear.x), float(msg.angular.z))
            self.data.commands += 1

    def _on_tree(self, msg: Any) -> None:
        tip = tip_from_snapshot(msg.data)
        with self.lock:
            self.data.current_tip = tip
            self.data.tree_messages += 1

    def close(self) -> Recording:
        """Stop spinning, destroy the node, shut the context down; returns the recording."""
        self.ros.close()
        return self.data


def build_parser() -> argparse.ArgumentParser:
    """Options of ``bt-nav demo``."""
    parser = argparse.ArgumentParser(prog="bt-nav demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--maneuver", help="none, A, B, C or a name (default: config/homework.yaml's)")
    parser.add_argument("--seed", type=int, default=0, help="seed of noise, worlds and maneuver A (default 0)")
    parser.add_argument("--world", default="stage_4", help="world name or YAML path (default stage_4)")
    parser.add_argument("--rtf", type=float, default=0.0,
                        help="real-time factor; 0 (default) = as fast as the executive keeps up")
    parser.add_argument("--name", help="run name (default: <world>_<maneuver>_seed<seed>)")
    parser.add_argument("--out", default="runs", help="output directory (default runs/)")
    parser.add_argument("--timeout", type=float, default=120.0, help="wall-clock limit of the referee, s")
    parser.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID or random 100-200)")
    parser.add_argument("--sim-param", action="append", default=[], metavar="NAME=VALUE",
                        help="extra simulator parameter (repeatable), e.g. physics_rate_hz=50")
    parser.add_argument("--quiet", action="store_true", help="print only the verdict lines")
    return parser


def effective_maneuver(requested: str | None) -> str:
    """The maneuver the executive will run: the requested one, else the params file's, else none."""
    from bt_nav.mission.params import normalise_maneuver

    if requested is not None:
        return normalise_maneuver(requested)
    cfg = config_file("homework.yaml")
    value = file_parameters(cfg).get("maneuver", "none") if cfg is not None else "none"
    return normalise_maneuver(str(value))


class _Logs:
    """Per-node log files; the referee's report lines (anything not an rcutils log line) go to stdout."""

    def __init__(self, directory: Path, echo_logs: bool) -> None:
        self.directory = directory
        self.echo_logs = echo_logs
        self.files: dict[str, IO[str]] = {}
        self.verdict: list[str] = []
        self._lock = threading.Lock()

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: log file always; stdout for report lines (and everything unless quiet)."""
        with self._lock:
            stream = self.files.get(name)
            if stream is None:
                stream = self.files[name] = open(self.directory / f"{name}.log", "w", encoding="utf-8")  # noqa: SIM115
            stream.write(line + "\n")
            is_log = line.startswith("[")
            if name == "referee" and not is_log:
                self.verdict.append(line)
                print(line, flush=True)
            elif self.echo_logs and (name == "referee" or any(lvl in line for lvl in ("[WARN]", "[ERROR]", "[FATAL]"))):
                print(f"  [{name}] {line}", flush=True)

    def close(self) -> None:
        """Close every log file."""
        with self._lock:
            for stream in self.files.values():
                stream.close()


def _mission_slice(rec: Recording, results: dict[str, Any]) -> tuple[int, int]:
    """Index range of the samples between the referee's t0 and its report (all samples if unknown)."""
    times = results.get("times") or {}
    t0 = times.get("t0")
    report = times.get("report")
    if t0 is None:
        return 0, len(rec.t)
    end_t = t0 + report if report is not None else math.inf
    start = next((i for i, t in enumerate(rec.t) if t >= t0), len(rec.t))
    end = next((i for i, t in enumerate(rec.t) if t > end_t), len(rec.t))
    return start, end


def main(argv: list[str] | None = None) -> int:
    """``bt-nav demo``; returns the referee's exit code (0 PASSED, 1 FAILED, 2 no verdict)."""
    opts = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        maneuver = effective_maneuver(opts.maneuver)
    except ValueError as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    world_label = Path(opts.world).stem if opts.world.endswith((".yaml", ".yml")) else opts.world
    name = opts.name or f"{world_label}_{maneuver}_seed{opts.seed}"
    run_dir = Path(opts.out) / name
    run_dir.mkdir(parents=True, exist_ok=True)
    results_path = run_dir / "results.json"
    if results_path.exists():
        results_path.unlink()  # never report a previous run's verdict

    domain = choose_domain_id(opts.domain_id)
    env = child_env(domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"  # the recorder node in this process too
    os.environ["ROS_DOMAIN_ID"] = str(domain)
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    specs = nodes("eval", world=opts.world, maneuver=maneuver if opts.maneuver is not None else None,
                  seed=opts.seed, rtf=opts.rtf,
                  results_json=str(results_path.resolve()), referee={"timeout": float(opts.timeout)},
                  sim=parse_assignments(opts.sim_param))
    print(f"bt-nav demo: {world_label}, maneuver {maneuver}, seed {opts.seed}, "
          f"{'as fast as possible' if opts.rtf == 0 else f'{opts.rtf:g}x real time'}, ROS_DOMAIN_ID={domain} "
          f"(localhost only) -> {run_dir}/", flush=True)

    wall0 = time.monotonic()
    logs = _Logs(run_dir, echo_logs=not opts.quiet)
    recorder = Recorder()
    launcher = Launcher(env, sink=logs.sink)
    code = 2
    try:
        for spec in specs[:-1]:
            launcher.start(spec)
        # The referee's clock starts once it sees the robot; start it once the recorder sees the robot
        # too (ground truth, and the executive ticking), so the picture has the run from its start.
        deadline = time.monotonic() + _STARTUP
        while not (rec_ready(recorder) or time.monotonic() > deadline or
                   any(c.poll() is not None for c in launcher.children)):
            time.sleep(0.02)
        referee = launcher.start(specs[-1])
        ended = launcher.wait_any(timeout=opts.timeout + _GRACE)
        if ended is None:
            print(f"bt-nav demo: no verdict within {opts.timeout + _GRACE:g} s wall; stopping", file=sys.stderr)
        elif ended is referee:
            code = int(referee.poll() or 0)
        else:
            print(f"bt-nav demo: {ended.name} exited with {ended.poll()} before the verdict; see "
                  f"{run_dir / (ended.name + '.log')}", file=sys.stderr)
    except KeyboardInterrupt:
        print("bt-nav demo: interrupted", file=sys.stderr)
        code = 130
    finally:
        launcher.shutdown()
        rec = recorder.close()
        logs.close()

    results: dict[str, Any] = {}
    if results_path.is_file():
        results = json.loads(results_path.read_text(encoding="utf-8"))
    written = _write_outputs(run_dir, opts, maneuver, rec, results)
    wall = time.monotonic() - wall0
    start, end = _mission_slice(rec, results)
    summary = [f"demo wall time {wall:.1f} s"]
    if end - start > 1:
        sim_span = rec.t[end - 1] - rec.t[start]
        wall_span = rec.wall[end - 1] - rec.wall[start]
        if wall_span > 0:
            summary.append(f"mission {sim_span:.1f} s sim in {wall_span:.1f} s wall ({sim_span / wall_span:.1f}x "
                           "real time)")
    print("bt-nav demo: " + "; ".join(summary), flush=True)
    print("bt-nav demo: wrote " + ", ".join(str(p) for p in written), flush=True)
    return code


def _write_outputs(run_dir: Path, opts: argparse.Namespace, maneuver: str, rec: Recording,
                   results: dict[str, Any]) -> list[Path]:
    """trajectory.json, trajectory.png and the tree files; returns what was written (notes on stderr)."""
    from bt_nav_sim import load_world
    from bt_nav_sim.plot import Trajectory, branch_of_tip, plot_run

    written: list[Path] = []
    if results:
        written.append(run_dir / "results.json")
    start, end = _mission_slice(rec, results)
    traj = Trajectory(rec.t[start:end], rec.x[start:end], rec.y[start:end], rec.yaw[start:end],
                      [branch_of_tip(tip) for tip in rec.tip[start:end]])
    data = traj.to_dict()
    data.update({"tip": rec.tip[start:end], "cmd_linear": rec.cmd_linear[start:end],
                 "cmd_angular": rec.cmd_angular[start:end], "commands": rec.commands,
                 "tree_messages": rec.tree_messages})
    path = run_dir / "trajectory.json"
    path.write_text(json.dumps(data) + "\n", encoding="utf-8")
    written.append(path)
    try:
        world = load_world(opts.world, seed=None if opts.seed < 0 else opts.seed)
        title = f"{world.name}, maneuver {maneuver}, seed {opts.seed} (ROS, sim time)"
        written.append(plot_run(world, traj, results, run_dir / "trajectory.png", title=title))
    except Exception as exc:  # a missing matplotlib must not hide the verdict
        print(f"bt-nav demo: no trajectory picture: {exc}", file=sys.stderr)
    try:
        from bt_nav.cli.dump_tree import render
    except ImportError as exc:
        print(f"bt-nav demo: no tree picture ({exc})", file=sys.stderr)
        return written
    try:
        dot = render(maneuver, "dot")
        path = run_dir / "tree.dot"
        path.write_text(dot if isinstance(dot, str) else dot.decode(), encoding="utf-8")
        written.append(path)
        svg = render(maneuver, "svg")
        path = run_dir / "tree.svg"
        path.write_bytes(svg if isinstance(svg, bytes) else svg.encode())
        written.append(path)
    except Exception as exc:  # graphviz missing: the dot file is still there
        print(f"bt-nav demo: note: tree.svg skipped: {exc}", file=sys.stderr)
    return written


if __name__ == "__main__":
    raise SystemExit(main())
