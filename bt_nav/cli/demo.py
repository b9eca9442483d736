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

When the referee has given its verdict it writes, under a run directory of its own
(``<out>/<date>-<time>_<world>_<maneuver>_seed<seed>``, or ``<out>/<name>``; a suffix keeps an
existing one from being overwritten): ``results.json`` (the referee's), ``trajectory.json``,
``trajectory.png`` (:func:`bt_nav_sim.plot.plot_run`), the tree as ``tree.dot`` and ``tree.svg``
(when graphviz is installed), and one ``<node>.log`` per process. The referee's verdict lines are
printed, then how many maneuvers fired (counted from the tree snapshots), and the exit code is the
referee's (0 = PASSED).

Isolation: the run takes a ROS domain no concurrent run holds (unless ROS_DOMAIN_ID is set), and
both the referee and the recorder check that the ground truth they judge comes from one simulator
(one publisher's sequence numbers only grow); a foreign one means no verdict (exit 2), never a
distance summed over two robots. Log lines carry one time base: sim time, wall time in brackets.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from bt_nav.cli import plain
from bt_nav.cli.record import start_process as record_start
from bt_nav.cli.record import stop_process as record_stop
from bt_nav.ros.bringup import EXECUTIVE_NAME, cmd_vel_stamped, config_file, file_parameters, nodes, parse_assignments
from bt_nav.ros.supervise import (
    Launcher,
    StopRequest,
    child_env,
    choose_domain_id,
    publish_zero_twist,
    use_domain_here,
)

#: One line of py_trees' unicode tree as the executive publishes it: indent, marker, name, [status], feedback.
_TREE_LINE = re.compile(r"^(?P<indent> *)\S+ (?P<name>.*?) \[(?P<status>[✓✕*-])\](?: -- .*)?$")
#: Extra wall time the demo allows beyond the referee's own timeout before it gives up itself.
_GRACE = 15.0
#: Wall time to wait for the recorder to see ground truth and commands before starting the referee anyway.
_STARTUP = 30.0
#: rcutils' line format for the nodes: no epoch stamp (the demo prefixes sim and wall time itself).
_LOG_FORMAT = "[{severity}] [{name}]: {message}"


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
    maneuvers: dict[str, int] = field(default_factory=dict)  # maneuver tip -> times it was entered
    foreign_truth: int = 0  # ground-truth messages from a second simulator (another run, same domain)
    truth_seq: int | None = None


class Recorder:
    """A node of the demo's own, spinning in a thread: ground truth, commands and the tree tip.

    ``robot``: the namespace of the robot to record (one of several); empty: today's root topics.
    """

    def __init__(self, robot: str = "") -> None:
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from std_msgs.msg import String

        from bt_nav.ros.rosutil import ThreadedNode

        self.ros = ThreadedNode(f"bt_nav_demo_recorder{'_' + robot if robot else ''}")
        ns = f"/{robot}/" if robot else ""
        self.node = self.ros.node
        self.data = Recording()
        self.lock = threading.Lock()
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Odometry, f"{ns}ground_truth_odom", self._on_truth, reliable)
        self.node.create_subscription(Twist, f"{ns}cmd_vel", self._on_cmd, reliable)
        self.node.create_subscription(String, f"{ns or '/'}{EXECUTIVE_NAME}/tree", self._on_tree, latched)
        self.ros.start()

    def _on_truth(self, msg: Any, info: Any = None) -> None:
        from bt_nav.ros.rosutil import yaw_from_quaternion

        q = msg.pose.pose.orientation
        d = self.data
        seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
        with self.lock:
            if seq is not None and d.truth_seq is not None and seq <= d.truth_seq:
                d.foreign_truth += 1  # one publisher's numbers only grow: this is another simulator
                return
            d.truth_seq = seq if seq is not None else d.truth_seq
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
        from bt_nav_sim.plot import branch_of_tip

        tip = tip_from_snapshot(msg.data)
        with self.lock:
            d = self.data
            if branch_of_tip(tip) == "Maneuver" and branch_of_tip(d.current_tip) != "Maneuver":
                d.maneuvers[tip] = d.maneuvers.get(tip, 0) + 1
            d.current_tip = tip
            d.tree_messages += 1

    def sim_time(self) -> float | None:
        """Latest ground-truth stamp (sim time), None before the first."""
        with self.lock:
            return self.data.t[-1] if self.data.t else None

    def close(self) -> Recording:
        """Stop spinning, destroy the node, shut the context down; returns the recording."""
        self.ros.close()
        return self.data


def build_parser() -> argparse.ArgumentParser:
    """Options of ``bt-nav demo``."""
    parser = argparse.ArgumentParser(prog="bt-nav demo", description=plain(__doc__.split("\n\n")[0]),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maneuver", help="none, A, B, C or a name (default: config/homework.yaml's)")
    parser.add_argument("--seed", type=int, default=0, help="seed of noise, worlds and maneuver A (default 0)")
    parser.add_argument("--world", default="stage_4", help="world name or YAML path (default stage_4)")
    parser.add_argument("--rtf", type=float, default=0.0,
                        help="real-time factor; 0 (default) = as fast as the executive keeps up")
    parser.add_argument("--name", help="run directory name (default: <date>-<time>_<world>_<maneuver>_seed<seed>;"
                        " never overwritten: a suffix -2, -3 ... is added)")
    parser.add_argument("--out", default="runs", help="where run directories go (default runs/)")
    parser.add_argument("--timeout", type=float, default=120.0, help="wall-clock limit of the referee, s")
    parser.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID, else one no "
                        "other run on this machine holds, from $BT_NAV_DOMAIN_RANGE or 100-199)")
    parser.add_argument("--sim-param", action="append", default=[], metavar="NAME=VALUE",
                        help="extra simulator parameter (repeatable), e.g. physics_rate_hz=50")
    parser.add_argument("--quiet", action="store_true", help="print only the verdict lines")
    parser.add_argument("--bag", metavar="DIR", help="also record the run as a rosbag2 (MCAP) bag (bt-nav record)")
    parser.add_argument("--robots", type=int, default=1, help="robots in the world (default 1); > 1: robot1, "
                        "robot2, ... each with its executive and referee in its namespace, a verdict each")
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
    """Per-node log files; the referee's report lines (anything not an rcutils log line) go to stdout.

    Every log line is prefixed with one time base: ``sim 37.65 s [wall 3.2 s]`` (the newest ground
    truth the recorder saw, and wall seconds since the demo started); report lines stay as the
    referee prints them. After the verdict nothing is echoed any more: the shutdown's own lines go
    to the files only, so the verdict is the last thing the user reads.
    """

    def __init__(self, directory: Path, echo_logs: bool, sim_time: Any = None) -> None:
        self.directory = directory
        self.echo_logs = echo_logs
        self.sim_time = sim_time or (lambda: None)
        self.wall0 = time.monotonic()
        self.files: dict[str, IO[str]] = {}
        self.verdict: list[str] = []
        self.quiet_from_now = False
        self._lock = threading.Lock()

    def stamp(self) -> str:
        """``sim 37.65 s [wall 3.2 s]`` (sim ``-`` before the first ground truth)."""
        t = self.sim_time()
        sim = f"{t:7.2f} s" if t is not None else "      - s"
        return f"sim {sim} [wall {time.monotonic() - self.wall0:5.1f} s]"

    def sink(self, name: str, line: str) -> None:
        """Launcher sink: log file always; stdout for report lines (and warnings, unless quiet)."""
        with self._lock:
            stream = self.files.get(name)
            if stream is None:
                stream = self.files[name] = open(self.directory / f"{name}.log", "w", encoding="utf-8")  # noqa: SIM115
            is_log = line.startswith("[")
            stream.write((f"{self.stamp()} {line}" if is_log else line) + "\n")
            if (name == "referee" or name.endswith("_referee")) and not is_log:
                self.verdict.append(line)
                print(line, flush=True)
            elif self.echo_logs and not self.quiet_from_now and (
                    name == "referee" or any(lvl in line for lvl in ("[WARN]", "[ERROR]", "[FATAL]"))):
                print(f"  {self.stamp()} [{name}] {line}", flush=True)

    def close(self) -> None:
        """Close every log file."""
        with self._lock:
            for stream in self.files.values():
                stream.close()


def make_run_dir(out: Path, name: str) -> Path:
    """A new directory ``out/name`` (``-2``, ``-3`` ... appended while taken): a run never overwrites
    another's files, however many run at once (``mkdir`` is atomic)."""
    out.mkdir(parents=True, exist_ok=True)
    for n in range(1, 1000):
        path = out / (name if n == 1 else f"{name}-{n}")
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path
    raise FileExistsError(f"{out / name}: 999 runs of that name already")


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
    if opts.robots != 1:
        from bt_nav.cli.demo_multi import main_multi

        return main_multi(opts)
    try:
        maneuver = effective_maneuver(opts.maneuver)
        domain = choose_domain_id(opts.domain_id)
    except ValueError as exc:
        print(f"bt-nav demo: {exc}", file=sys.stderr)
        return 2
    world_label = Path(opts.world).stem if opts.world.endswith((".yaml", ".yml")) else opts.world
    name = opts.name or f"{time.strftime('%Y%m%d-%H%M%S')}_{world_label}_{maneuver}_seed{opts.seed}"
    run_dir = make_run_dir(Path(opts.out), name)
    results_path = run_dir / "results.json"
    use_domain_here(domain)  # the recorder node in this process too
    env = child_env(domain)
    env["RCUTILS_CONSOLE_OUTPUT_FORMAT"] = _LOG_FORMAT
    specs = nodes("eval", world=opts.world, maneuver=maneuver if opts.maneuver is not None else None,
                  seed=opts.seed, rtf=opts.rtf,
                  results_json=str(results_path.resolve()), referee={"timeout": float(opts.timeout)},
                  sim=parse_assignments(opts.sim_param))
    print(f"bt-nav demo: {world_label}, maneuver {maneuver}, seed {opts.seed}, "
          f"{'as fast as possible' if opts.rtf == 0 else f'{opts.rtf:g}x real time'}, ROS_DOMAIN_ID={domain} "
          f"(localhost only)\nbt-nav demo: run directory {run_dir}/", flush=True)

    wall0 = time.monotonic()
    stop = StopRequest().install()
    recorder = Recorder()
    logs = _Logs(run_dir, echo_logs=not opts.quiet, sim_time=recorder.sim_time)
    stamped = cmd_vel_stamped(specs)
    bag = record_start(opts.bag, env, "--seed", str(opts.seed)) if opts.bag else None  # a process of its own
    launcher = Launcher(env, sink=logs.sink, stop=stop,
                        last_word=lambda: publish_zero_twist(domain, stamped=stamped))
    try:
        code = _supervise(launcher, specs, recorder, opts, run_dir, stop)
    finally:
        logs.quiet_from_now = True  # the shutdown's lines go to the log files only
        stop.closing = True
        launcher.shutdown()
        if bag is not None:
            print(f"bt-nav demo: bag {opts.bag}: {record_stop(bag)}", flush=True)
        rec = recorder.close()
        logs.close()
        stop.restore()
    return _report(run_dir, opts, maneuver, rec, results_path, code, time.monotonic() - wall0)


def _supervise(launcher: Launcher, specs: list[Any], recorder: Recorder, opts: argparse.Namespace,
               run_dir: Path, stop: StopRequest) -> int:
    """Start the nodes (the referee once the robot is seen) and wait for the verdict; the exit code."""
    try:
        for spec in specs[:-1]:
            launcher.start(spec)
        # The referee's clock starts once it sees the robot; start it once the recorder sees the robot
        # too (ground truth, and the executive ticking), so the picture has the run from its start.
        deadline = time.monotonic() + _STARTUP
        while not (rec_ready(recorder) or time.monotonic() > deadline or stop.requested or
                   any(c.poll() is not None for c in launcher.children)):
            time.sleep(0.02)
        if stop.requested:
            raise KeyboardInterrupt
        referee = launcher.start(specs[-1])
        ended = launcher.wait_any(timeout=opts.timeout + _GRACE)
        if stop.requested:
            raise KeyboardInterrupt
        if ended is None:
            print(f"bt-nav demo: no verdict within {opts.timeout + _GRACE:g} s wall; stopping", file=sys.stderr)
        elif ended is referee:
            return int(referee.poll() or 0)
        else:
            print(f"bt-nav demo: {ended.name} exited with {ended.poll()} before the verdict; see "
                  f"{run_dir / (ended.name + '.log')}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"bt-nav demo: {stop.name or 'SIGINT'}: stopping every node", file=sys.stderr)
        return 128 + int(stop.signum or 2)


def _report(run_dir: Path, opts: argparse.Namespace, maneuver: str, rec: Recording, results_path: Path,
            code: int, wall: float) -> int:
    """Write the outputs and print the summary lines (maneuvers, speed, files); the final exit code."""
    results: dict[str, Any] = {}
    if results_path.is_file():
        results = json.loads(results_path.read_text(encoding="utf-8"))
    written = _write_outputs(run_dir, opts, maneuver, rec, results)
    if rec.foreign_truth:
        print(f"bt-nav demo: {rec.foreign_truth} ground-truth messages came from another simulator in this "
              "ROS domain: this run's figures cannot be trusted; give each run its own ROS_DOMAIN_ID",
              file=sys.stderr)
        code = 2 if code == 0 else code
    fired = sum(rec.maneuvers.values())
    detail = ", ".join(f"{tip.rsplit('.', 1)[-1]} x{n}" for tip, n in sorted(rec.maneuvers.items()))
    print(f"bt-nav demo: maneuvers fired: {fired}" + (f" ({detail})" if detail else "")
          + f" (maneuver {maneuver}, counted from the tree)", flush=True)
    start, end = _mission_slice(rec, results)
    summary = [f"demo wall time {wall:.1f} s"]
    if end - start > 1:
        sim_span = rec.t[end - 1] - rec.t[start]
        wall_span = rec.wall[end - 1] - rec.wall[start]
        if wall_span > 0:
            summary.append(f"mission {sim_span:.1f} s sim in {wall_span:.1f} s wall ({sim_span / wall_span:.1f}x "
                           "real time, varies with the machine)")
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
                 "tree_messages": rec.tree_messages, "maneuvers": rec.maneuvers,
                 "foreign_truth": rec.foreign_truth})
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
