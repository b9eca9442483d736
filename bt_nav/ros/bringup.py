"""The one definition of bt_nav's node graph per profile (``bt-nav sim-run``, :mod:`bt_nav.cli.sim_run`, starts it).

:func:`nodes` returns plain data (:class:`NodeSpec`: console-script name, node name, parameters,
parameter files, remappings, arguments) so that every way of starting the system reads the same
table: ``bt-nav sim-run`` and ``bt-nav demo`` (subprocesses, no ``ros2 launch`` needed) and the
``launch/*.launch.py`` files, which turn each spec into a ``launch_ros.actions.Node``::

    Node(package="bt_nav", executable=s.executable, name=s.name, arguments=s.arguments,
         parameters=[*s.parameter_files, s.parameters], remappings=s.remappings)

Profiles (each assignment's files, services and judge are its record in :mod:`bt_nav.mission.assignments`):

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

import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav_sim.lidar import lidar_model

from bt_nav.mission.assignments import ASSIGNMENTS, HOMEWORK, LAB, Assignment
from bt_nav.mission.maneuver_spec import LiveMap, default_arenas, letters_text
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

#: The graphs (``--profile`` of sim-run): each assignment without its judge, then each with it (``eval``, ``checkoff``:
#: :attr:`bt_nav.mission.assignments.Assignment.graph`), as (assignment, judged).
GRAPHS: dict[str, tuple[Assignment, bool]] = {**{a.name: (a, False) for a in (LAB, HOMEWORK)},
                                              **{a.graph: (a, True) for a in (HOMEWORK, LAB)}}
PROFILES = tuple(GRAPHS)

#: The lab arena a check-off runs in by default, per maneuver (each lists the maneuver in its
#: ``checkoff_maneuvers``): the first of its spec's arenas (:mod:`bt_nav.mission.maneuver_spec`), a live view.
CHECKOFF_WORLDS = LiveMap(default_arenas)
#: The executables that judge a run (print a verdict, then exit): the homework's referee, the lab's judge.
JUDGES = tuple(a.judge.executable for a in ASSIGNMENTS.values())

#: The homework's service names (what the course's evaluator calls and serves; the assignment's record).
HOMEWORK_ACTIVATE = HOMEWORK.arm_service
HOMEWORK_EVALUATE = str(HOMEWORK.evaluate_service)
#: The lab's arm service name (the teleop-style toggle used on the real robot).
LAB_ARM = LAB.arm_service

#: Simulator speed cap (as-fast-as-possible mode) before the referee joins, in the profiles with a referee.
SOLO_RTF = 5.0
#: /clock floor of these graphs (the simulator's ``clock_rate_hz``): every node on sim time here is bt_nav's and a
#: follower (the executive, the judge), which the simulator gives a sample at each of its deadlines; the other
#: samples go out with the messages (odometry at 30 Hz). A third of the /clock traffic of one sample per physics
#: step, which every subscriber's executor handled (measured: bt-nav demo 21x -> 25-31x real time).
CLOCK_RATE_HZ = 10.0

#: Node names (the console scripts are ``executive``, ``sim``, ``referee`` and ``checkoff``).
SIM_NAME = "bt_nav_sim"
REFEREE_NAME = HOMEWORK.judge.node_name
CHECKOFF_NAME = LAB.judge.node_name
#: The judges' node names (a judge hosted by the simulator logs under its own name in the simulator's output).
JUDGE_NODE_NAMES = tuple(a.judge.node_name for a in ASSIGNMENTS.values())


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
def _sim_spec(world: str | None, assignment: Assignment, seed: int | None, rtf: float | None, stamped: bool | None,
              with_referee: bool, sim: dict[str, Any] | None) -> NodeSpec:
    """The simulator node of :func:`nodes` (its arguments as there; ``stamped`` as the executive's)."""
    sim_params: dict[str, Any] = {"world": world or "stage_4", "profile": assignment.name,
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
        maneuver: the executive's evasive maneuver (none, a lab maneuver's letter or a name).
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
    if profile not in GRAPHS:
        raise ValueError(f"unknown profile {profile!r}; choose one of {', '.join(PROFILES)}")
    assignment, judged = GRAPHS[profile]
    with_referee = judged if with_referee is None else with_referee
    if with_referee and profile == "lab":
        raise ValueError("the referee judges the homework interface: use profile homework or eval "
                         "(or checkoff: the lab's judge)")
    if profile == "checkoff":
        maneuver, world = _checkoff_choices(maneuver, world)

    exe_params: dict[str, Any] = {"use_sim_time": include_sim}
    files: list[str] = []
    cfg = config_file(assignment.files[0])
    if cfg is not None:
        files.append(str(cfg))
    if maneuver is not None:
        exe_params["maneuver"] = maneuver
    if seed is not None:
        exe_params["random_seed"] = int(seed)
    if include_sim and (sim or {}).get("lidar"):  # where the simulated LiDAR sits, as a robot's TF would say
        exe_params.update(lidar_model(str(sim["lidar"])).mount_params())
    exe_params.update(executive or {})
    remaps = list(assignment.remaps(namespace=namespace is not None))
    specs = [NodeSpec("executive", EXECUTIVE_NAME, exe_params, remaps, parameter_files=files)]

    stamped = exe_params.get("cmd_vel_stamped")
    if stamped is None and cfg is not None:
        stamped = file_parameters(cfg).get("cmd_vel_stamped")
    if include_sim:
        specs.insert(0, _sim_spec(world, assignment, seed, rtf, stamped, with_referee, sim))

    if with_referee:
        specs.append(_judge_spec(assignment, include_sim, namespace is not None, world, maneuver, seed, stamped,
                                 results_json, referee))
    for spec in specs:
        spec.namespace = (namespace or "").strip("/")
    return specs


def _judge_spec(assignment: Assignment, include_sim: bool, namespaced: bool, world: str | None,
                maneuver: str | None, seed: int | None, stamped: Any, results_json: str | None,
                referee: dict[str, Any] | None) -> NodeSpec:
    """The assignment's judge: the homework's referee (``namespaced``: its activate and evaluate names relative, in
    the robot's namespace), or the lab's check-off judge on the simulator's world and seed and the executive's
    maneuver."""
    # t0 once the executive ticks (its first cmd_vel), not merely once its service exists: at many
    # times real time, a process still starting up would otherwise lose seconds of the schedule.
    params: dict[str, Any] = {"use_sim_time": include_sim, "wait_for_cmd_vel": True}
    checkoff = assignment.judge.executable == "checkoff"
    if namespaced and not checkoff:
        services = dict(assignment.remaps(namespace=True))
        params.update({"activate_service": services["arm"], "evaluate_service": services["evaluate_mission"]})
    if checkoff:
        params.update({"activate_service": assignment.arm_service, "world": world, "maneuver": maneuver,
                       **({"seed": int(seed)} if seed is not None else {})})
    if stamped:
        params["cmd_vel_stamped"] = True
    if results_json:
        params["json"] = str(results_json)
    params.update(referee or {})
    return NodeSpec(assignment.judge.executable, assignment.judge.node_name, params)


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

    cfg = config_file(LAB.files[0])
    chosen = normalise_maneuver(str(maneuver if maneuver is not None else
                                    (file_parameters(cfg).get("maneuver", "none") if cfg is not None else "none")))
    if chosen not in CHECKOFF_WORLDS:
        raise ValueError(f"a check-off judges maneuver {letters_text()}, not {chosen!r}")
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
