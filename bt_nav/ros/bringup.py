"""The one definition of bt_nav's node graph per profile, and ``bt-nav sim-run`` which starts it.

:func:`nodes` returns plain data (:class:`NodeSpec`: console-script name, node name, parameters,
parameter files, remappings, arguments) so that every way of starting the system reads the same
table: ``bt-nav sim-run`` and ``bt-nav demo`` here (subprocesses, no ``ros2 launch`` needed) and the
``launch/*.launch.py`` files, which turn each spec into a ``launch_ros.actions.Node``::

    Node(package="bt_nav", executable=s.executable, name=s.name, arguments=s.arguments,
         parameters=[*s.parameter_files, s.parameters], remappings=s.remappings)

Profiles:

``lab``       the executive on the lab's interface (``arm`` is ``toggle_navigation``) with
              ``config/lab.yaml`` when present, plus the simulator with the LDS-01 profile;
``homework``  the executive on the homework's interface (``arm`` -> ``/reactive_control/activate``,
              ``evaluate_mission`` -> ``/reactive_control/evaluate_mission``) with
              ``config/homework.yaml`` when present, in sim time, plus the simulator in stage_4 with
              the homework LiDAR;
``eval``      ``homework`` plus the referee;
``checkoff``  ``lab`` plus the lab's check-off judge (``bt_nav_checkoff``), in sim time; its world is by
              default the lab arena for the maneuver (:data:`CHECKOFF_WORLDS`) and the judge gets the
              simulator's world and seed and the executive's maneuver.

Namespaces (``namespace=``, one robot of several): every node of the profile goes into it and the service
names become relative (``reactive_control/activate`` is ``/robot1/reactive_control/activate`` there); without
a namespace the names stay today's absolute ones. :func:`robot_nodes` is the several-robots graph: one
simulator hosting every robot, and an executive and a referee per robot, each in its robot's namespace.

This module imports neither rclpy nor launch, so launch files and tools can read it anywhere.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav_sim.lidar import lidar_model

from bt_nav.mission.params import parse_assignments  # noqa: F401 - re-exported (demo, sim-run)
from bt_nav.mission.profiles import EXECUTIVE_NAME, config_file, file_parameters  # noqa: F401 - re-exported

# Processes and DDS isolation have one home, bt_nav.ros.supervise; re-exported for demo, bench and tests.
from bt_nav.ros.supervise import (  # noqa: F401
    Child,
    Launcher,
    StopRequest,
    child_env,
    choose_domain_id,
    publish_zero_twist,
)

PROFILES = ("lab", "homework", "eval", "checkoff")

#: The lab arena a check-off runs in by default, per maneuver (each lists the maneuver in its
#: ``checkoff_maneuvers``): an object in the path for A and C, a dead-end passage for B.
CHECKOFF_WORLDS = {"A": "lab_object", "B": "lab_dead_end", "C": "lab_object"}
#: The executables that judge a run (print a verdict, then exit): the homework's referee, the lab's judge.
JUDGES = ("referee", "checkoff")

#: The homework's service names (what the course's evaluator calls and serves).
HOMEWORK_ACTIVATE = "/reactive_control/activate"
HOMEWORK_EVALUATE = "/reactive_control/evaluate_mission"
#: The lab's arm service name (the teleop-style toggle used on the real robot).
LAB_ARM = "toggle_navigation"

#: Simulator speed cap (as-fast-as-possible mode) before the referee joins, in the profiles with a referee.
SOLO_RTF = 5.0
#: /clock floor of these graphs (the simulator's ``clock_rate_hz``): every node on sim time here is bt_nav's and a
#: follower (the executive, the judge), which the simulator gives a sample at each of its deadlines; the other
#: samples go out with the messages (odometry at 30 Hz). A third of the /clock traffic of one sample per physics
#: step, which every subscriber's executor handled (measured: bt-nav demo 21x -> 25-31x real time).
CLOCK_RATE_HZ = 10.0

#: Node names (the console scripts are ``executive``, ``sim``, ``referee`` and ``checkoff``).
SIM_NAME = "bt_nav_sim"
REFEREE_NAME = "bt_nav_referee"
CHECKOFF_NAME = "bt_nav_checkoff"
#: The judges' node names (a judge hosted by the simulator logs under its own name in the simulator's output).
JUDGE_NODE_NAMES = (REFEREE_NAME, CHECKOFF_NAME)


@dataclass
class NodeSpec:
    """One node to start: what ``launch_ros.actions.Node`` needs, and what ``bt-nav`` needs."""

    executable: str  # console script of package bt_nav, and the ``bt-nav`` subcommand of the same name
    name: str  # node name
    parameters: dict[str, Any] = field(default_factory=dict)
    remappings: list[tuple[str, str]] = field(default_factory=list)
    arguments: list[str] = field(default_factory=list)  # non-ROS arguments, before ``--ros-args``
    parameter_files: list[str] = field(default_factory=list)  # applied before ``parameters``
    namespace: str = ""  # the node's namespace, without the leading slash (empty: none)

    def ros_args(self) -> list[str]:
        """``--ros-args`` for this node: name, namespace, parameter files, parameters, remappings (in that
        order, so explicit parameters override the files)."""
        args = ["--ros-args", "-r", f"__node:={self.name}"]
        if self.namespace:
            args += ["-r", f"__ns:=/{self.namespace.strip('/')}"]
        for path in self.parameter_files:
            args += ["--params-file", str(path)]
        for name, value in self.parameters.items():
            args += ["-p", param_arg(name, value)]
        for src, dst in self.remappings:
            args += ["-r", f"{src}:={dst}"]
        return args

    def command(self, python: str | None = None) -> list[str]:
        """The subprocess command line: ``python -m bt_nav.cli <executable> <arguments> --ros-args ...``.

        ``-m bt_nav.cli`` instead of the console script, so the child uses the same interpreter and
        package as the parent even when the venv's ``bin`` is not on PATH.
        """
        return [python or sys.executable, "-m", "bt_nav.cli", self.executable, *self.arguments, *self.ros_args()]


def param_arg(name: str, value: Any) -> str:
    """``name:=value`` for ``-p`` with the value typed as meant: rcl reads it as YAML, so strings are
    double-quoted (``"1.5"`` stays a string, ``stage_4`` cannot turn into something else), floats
    always carry a decimal point (``1.0``, not ``1``, or rclpy refuses a double parameter) and
    non-finite floats use YAML's spelling."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, int):
        text = str(value)
    elif isinstance(value, float):
        if math.isnan(value):
            text = ".nan"
        elif math.isinf(value):
            text = ".inf" if value > 0 else "-.inf"
        else:
            text = repr(value)
    elif isinstance(value, str):
        text = json.dumps(value)
    elif isinstance(value, list | tuple):
        text = json.dumps(list(value))
    else:
        raise TypeError(f"parameter {name}: unsupported value type {type(value).__name__}")
    return f"{name}:={text}"


# ---------------------------------------------------------------------------------------------- the table
def _sim_spec(world: str | None, homework: bool, seed: int | None, rtf: float | None, stamped: bool | None,
              with_referee: bool, sim: dict[str, Any] | None) -> NodeSpec:
    """The simulator node of :func:`nodes` (its arguments as there; ``stamped`` as the executive's)."""
    sim_params: dict[str, Any] = {"world": world or "stage_4", "profile": "homework" if homework else "lab",
                                  "clock_rate_hz": CLOCK_RATE_HZ}
    if seed is not None:
        sim_params["seed"] = int(seed)
    if rtf is not None:
        sim_params["real_time_factor"] = float(rtf)
    if stamped is not None:
        sim_params["cmd_vel_stamped"] = bool(stamped)
    if with_referee:
        # Until the referee follows the simulation (its t0), nothing is judged: no need to race.
        sim_params["solo_rtf"] = SOLO_RTF
    sim_params.update(sim or {})
    return NodeSpec("sim", SIM_NAME, sim_params)


def nodes(
    profile: str,
    *,
    world: str | None = None,
    maneuver: str | None = None,
    seed: int | None = None,
    rtf: float | None = None,
    with_referee: bool | None = None,
    include_sim: bool = True,
    results_json: str | None = None,
    executive: dict[str, Any] | None = None,
    sim: dict[str, Any] | None = None,
    referee: dict[str, Any] | None = None,
    namespace: str | None = None,
) -> list[NodeSpec]:
    """The nodes of ``profile`` (lab | homework | eval), with the given overrides.

    Args:
        profile: which graph (see the module docstring).
        world: simulator world (name or YAML path); default stage_4.
        maneuver: the executive's evasive maneuver (none, A, B, C or a name).
        seed: one seed for everything random: sensor noise, generated worlds, maneuver A's choices.
        rtf: simulator real-time factor (0 = as fast as the executive keeps up).
        with_referee: add the judge (default: only in ``eval``, the referee, and ``checkoff``, the lab's judge).
        include_sim: add the simulator; without it (a real robot) the executive uses wall time.
        results_json: where the referee (or the lab's judge) writes its verdict.
        executive: further executive parameters (override the params file and the profile's values).
        sim: further simulator parameters.
        referee: further parameters of the judge (the referee, or the lab's judge).
        namespace: put every node in this namespace, with relative service names ("" for a namespace
            chosen later, e.g. by a launch argument); None: no namespace, the homework's absolute names.
    """
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r}; choose one of {', '.join(PROFILES)}")
    homework = profile in ("homework", "eval")
    with_referee = (profile in ("eval", "checkoff")) if with_referee is None else with_referee
    if with_referee and profile == "lab":
        raise ValueError("the referee judges the homework interface: use profile homework or eval "
                         "(or checkoff: the lab's judge)")
    if profile == "checkoff":
        maneuver, world = _checkoff_choices(maneuver, world)

    exe_params: dict[str, Any] = {"use_sim_time": include_sim}
    files: list[str] = []
    cfg = config_file("homework.yaml" if homework else "lab.yaml")
    if cfg is not None:
        files.append(str(cfg))
    if maneuver is not None:
        exe_params["maneuver"] = maneuver
    if seed is not None:
        exe_params["random_seed"] = int(seed)
    if include_sim and (sim or {}).get("lidar"):  # where the simulated LiDAR sits, as a robot's TF would say
        exe_params.update(lidar_model(str(sim["lidar"])).mount_params())
    exe_params.update(executive or {})
    activate, evaluate = (HOMEWORK_ACTIVATE, HOMEWORK_EVALUATE) if namespace is None else \
        (HOMEWORK_ACTIVATE.lstrip("/"), HOMEWORK_EVALUATE.lstrip("/"))
    if homework:
        remaps = [("arm", activate), ("evaluate_mission", evaluate)]
    else:
        remaps = [("arm", LAB_ARM)]
    specs = [NodeSpec("executive", EXECUTIVE_NAME, exe_params, remaps, parameter_files=files)]

    stamped = exe_params.get("cmd_vel_stamped")
    if stamped is None and cfg is not None:
        stamped = file_parameters(cfg).get("cmd_vel_stamped")
    if include_sim:
        specs.insert(0, _sim_spec(world, homework, seed, rtf, stamped, with_referee, sim))

    if with_referee:
        services = (activate, evaluate) if homework and namespace is not None else None
        specs.append(_judge_spec(homework, include_sim, services, world, maneuver, seed, stamped, results_json,
                                 referee))
    for spec in specs:
        spec.namespace = (namespace or "").strip("/")
    return specs


def _judge_spec(homework: bool, include_sim: bool, services: tuple[str, str] | None, world: str | None,
                maneuver: str | None, seed: int | None, stamped: Any, results_json: str | None,
                referee: dict[str, Any] | None) -> NodeSpec:
    """The judge of the graph: the homework's referee (``services``: its activate and evaluate names in a
    namespace), or the lab's check-off judge on the simulator's world and seed and the executive's maneuver."""
    # t0 once the executive ticks (its first cmd_vel), not merely once its service exists: at many
    # times real time, a process still starting up would otherwise lose seconds of the schedule.
    params: dict[str, Any] = {"use_sim_time": include_sim, "wait_for_cmd_vel": True}
    if services is not None:
        params.update({"activate_service": services[0], "evaluate_service": services[1]})
    if not homework:
        params.update({"activate_service": LAB_ARM, "world": world, "maneuver": maneuver,
                       **({"seed": int(seed)} if seed is not None else {})})
    if stamped:
        params["cmd_vel_stamped"] = True
    if results_json:
        params["json"] = str(results_json)
    params.update(referee or {})
    return NodeSpec("referee", REFEREE_NAME, params) if homework else NodeSpec("checkoff", CHECKOFF_NAME, params)


def host_judge(specs: list[NodeSpec]) -> list[NodeSpec]:
    """``specs`` with the judge hosted by the simulator (:mod:`bt_nav.ros.nodes.hosting`): the simulator's spec gets
    ``--judge KIND --judge-args JSON`` (the judge's own ROS arguments, off sim time: its clock is the loop's), the
    judge's spec is dropped. ValueError without exactly one simulator and one judge."""
    sims = [s for s in specs if s.executable == "sim"]
    judges = [s for s in specs if s.executable in JUDGES]
    if len(sims) != 1 or len(judges) != 1:
        raise ValueError("a hosted judge needs one simulator and one judge in the graph")
    judge = judges[0]
    own = NodeSpec(judge.executable, judge.name, {**judge.parameters, "use_sim_time": False}, judge.remappings,
                   parameter_files=judge.parameter_files, namespace=judge.namespace)
    sims[0].arguments += ["--judge", judge.executable, "--judge-args", json.dumps(own.ros_args())]
    return [s for s in specs if s is not judge]


def _checkoff_choices(maneuver: str | None, world: str | None) -> tuple[str, str]:
    """The check-off's maneuver (given, else ``config/lab.yaml``'s) and world (given, else the maneuver's arena)."""
    from bt_nav.mission.params import normalise_maneuver

    cfg = config_file("lab.yaml")
    chosen = normalise_maneuver(str(maneuver if maneuver is not None else
                                    (file_parameters(cfg).get("maneuver", "none") if cfg is not None else "none")))
    if chosen not in CHECKOFF_WORLDS:
        raise ValueError(f"a check-off judges maneuver A, B or C, not {chosen!r}")
    return chosen, world or CHECKOFF_WORLDS[chosen]


def robot_nodes(profile: str, names: list[str], *, seed: int | None = None,
                results_json: dict[str, str] | None = None, executive: dict[str, Any] | None = None,
                **kwargs: Any) -> list[NodeSpec]:
    """Several robots in one world: one simulator (no namespace) hosting ``names``, then per robot the
    executive (and referee) of ``profile`` in the robot's namespace; ``results_json`` maps a robot to
    its referee's verdict file. Robot ``i`` > 0 gets maneuver A's seed ``seed + i * ROBOT_SEED_STRIDE``
    (as lock-step), so two robots do not make the same random choices."""
    from bt_nav_sim.multi import ROBOT_SEED_STRIDE

    specs: list[NodeSpec] = []
    for i, name in enumerate(names):
        exe = dict(executive or {})
        if seed is not None:
            exe.setdefault("random_seed", (int(seed) + i * ROBOT_SEED_STRIDE) % 2**31)
        per_robot = nodes(profile, seed=seed, executive=exe, namespace=name,
                          results_json=(results_json or {}).get(name), **kwargs)
        sims = [s for s in per_robot if s.executable == "sim"]
        if i == 0 and sims:
            sims[0].namespace = ""
            sims[0].parameters.update({"robots": len(names), "robot_names": ",".join(names)})
            specs.extend(sims)
        specs.extend(s for s in per_robot if s.executable != "sim")
    return specs


# ---------------------------------------------------------------------------------------------- bt-nav sim-run
def build_parser(prog: str = "bt-nav sim-run") -> argparse.ArgumentParser:
    """Options of ``bt-nav sim-run``."""
    parser = argparse.ArgumentParser(prog=prog, description="Start the simulator and the executive (and the "
                                     "referee) as subprocesses over DDS on this machine; Ctrl-C stops them all.")
    parser.add_argument("--profile", choices=PROFILES, default="homework",
                        help="which graph: homework (executive), lab, eval (+ the referee), checkoff (+ the lab's "
                             "judge); default homework")
    parser.add_argument("--world", help="simulator world: name or YAML path (default stage_4)")
    parser.add_argument("--maneuver", help="evasive maneuver: none, A, B, C (or randomizer, retreat, smart_pivot)")
    parser.add_argument("--seed", type=int, help="one seed for sensor noise, generated worlds and maneuver A")
    parser.add_argument("--rtf", type=float, help="simulator real-time factor (default 1; 0 = as fast as possible)")
    parser.add_argument("--with-referee", action="store_true", help="add the referee (implied by --profile eval; "
                        "--profile checkoff adds the lab's judge)")
    parser.add_argument("--json", help="referee results file")
    parser.add_argument("--sim-param", action="append", default=[], metavar="NAME=VALUE",
                        help="extra simulator parameter (repeatable), e.g. physics_rate_hz=50")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="extra executive parameter (repeatable), e.g. safety_distance=0.4")
    parser.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID, else one no "
                        "other run on this machine holds, from $BT_NAV_DOMAIN_RANGE or 100-199)")
    parser.add_argument("--print", action="store_true", dest="print_only",
                        help="print the commands instead of running them")
    return parser


def bt_nav_command() -> str:
    """How the user types ``bt-nav`` for this installation: the venv's script (relative to the current
    directory when inside it, e.g. ``.venv/bin/bt-nav``), ``bt-nav`` when that is what PATH finds, or
    ``python -m bt_nav.cli``. Users who installed with pip have no ``ros2``; they copy this."""
    import shutil

    script = Path(sys.executable).parent / "bt-nav"
    if not script.is_file():
        return f"{shlex.quote(sys.executable)} -m bt_nav.cli"
    found = shutil.which("bt-nav")
    if found and Path(found).resolve() == script.resolve():
        return "bt-nav"
    try:
        return str(script.relative_to(Path.cwd()))
    except ValueError:
        return str(script)


def arm_hint(specs: list[NodeSpec], domain: int) -> str | None:
    """The exact command that arms the executive of ``specs`` (None when a judge does the arming)."""
    if any(spec.executable in JUDGES for spec in specs):
        return None
    executive = next((spec for spec in specs if spec.executable == "executive"), None)
    if executive is None:
        return None
    service = dict(executive.remappings).get("arm", "arm")
    service = service if service.startswith("/") else f"/{service}"
    return f"ROS_DOMAIN_ID={domain} {bt_nav_command()} arm --service {service}"


def cmd_vel_stamped(specs: list[NodeSpec]) -> bool:
    """Whether the executive of ``specs`` publishes TwistStamped (explicit parameter, else its params file)."""
    for spec in specs:
        if spec.executable == "executive":
            if "cmd_vel_stamped" in spec.parameters:
                return bool(spec.parameters["cmd_vel_stamped"])
            for path in spec.parameter_files:
                if "cmd_vel_stamped" in file_parameters(Path(path)):
                    return bool(file_parameters(Path(path))["cmd_vel_stamped"])
    return False


def main(argv: list[str] | None = None) -> int:
    """``bt-nav sim-run``: exit code of the referee when there is one, else of the first node to exit;
    128 + the signal number after SIGINT/SIGTERM/SIGHUP."""
    opts = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if opts.maneuver is not None:
            from bt_nav.mission.params import normalise_maneuver

            opts.maneuver = normalise_maneuver(opts.maneuver)
        specs = nodes(opts.profile, world=opts.world, maneuver=opts.maneuver, seed=opts.seed, rtf=opts.rtf,
                      with_referee=True if opts.with_referee else None, results_json=opts.json,
                      executive=parse_assignments(opts.set), sim=parse_assignments(opts.sim_param))
        domain = choose_domain_id(opts.domain_id)
    except ValueError as exc:
        print(f"bt-nav sim-run: {exc}", file=sys.stderr)
        return 2
    if opts.print_only:
        print(f"export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID={domain}")
        for spec in specs:
            print(" ".join(shlex.quote(a) for a in spec.command()))
        return 0
    return _run(specs, domain, opts.profile)


def _run(specs: list[NodeSpec], domain: int, profile: str) -> int:
    """Start ``specs`` in ``domain`` and supervise them until one ends or a stop signal arrives."""
    stop = StopRequest().install()
    stamped = cmd_vel_stamped(specs)
    launcher = Launcher(child_env(domain), stop=stop,
                        last_word=lambda: publish_zero_twist(domain, stamped=stamped))
    print(f"bt-nav sim-run: profile {profile}, ROS_DOMAIN_ID={domain} (localhost only), pid {os.getpid()}; "
          "Ctrl-C stops", flush=True)
    hint = arm_hint(specs, domain)
    if hint:
        print(f"bt-nav sim-run: the robot waits to be armed; in another terminal: {hint}", flush=True)
    code = 0
    try:
        for spec in specs:
            launcher.start(spec)
        referee = next((c for c in launcher.children if c.spec.executable in JUDGES), None)
        while not stop.requested:
            ended = launcher.wait_any(timeout=0.5)
            if ended is None:
                continue
            if referee is not None and ended is not referee:
                print(f"bt-nav sim-run: {ended.name} exited with {ended.poll()} before the referee's verdict",
                      file=sys.stderr, flush=True)
                code = ended.poll() or 1
            else:
                code = ended.poll() or 0
            break
    except KeyboardInterrupt:
        stop.signum = stop.signum or 2
    finally:
        stop.closing = True
        launcher.shutdown()
        stop.restore()
    if stop.requested:
        print(f"bt-nav sim-run: {stop.name}: stopped every node", file=sys.stderr, flush=True)
        code = 128 + int(stop.signum or 2)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
