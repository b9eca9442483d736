"""The options every command that runs a mission shares (demo, lockstep, grade): one spelling, one default.

Why: ``bt-nav lockstep --profile homework`` and ``bt-nav demo`` with the same profile must run the same
mission; the maneuver defaults to the profile's (:func:`bt_nav.run.settings.profile_maneuver`), ``--set``
overrides any parameter, and the seed is 0 unless given.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_nav.mission.maneuver_spec import choices_text
from bt_nav.mission.profiles import PROFILE_FILES
from bt_nav.ros.supervise import usable_cores


def add_mission_options(parser: argparse.ArgumentParser, *, grid: bool = False) -> None:
    """``--profile``, ``--set NAME=VALUE`` (repeatable) and, unless ``grid`` (which takes lists),
    ``--world``, ``--maneuver``, ``--seed``."""
    if not grid:
        parser.add_argument("--world", default="stage_4", help="bundled world name or YAML path (default stage_4)")
        parser.add_argument("--maneuver", default=None,
                            help=f"{choices_text()} or a name (default: the profile's, config/homework.yaml says C)")
        parser.add_argument("--seed", type=int, default=0, help="seed of noise, worlds and maneuver A (default 0)")
    parser.add_argument("--profile", default="homework", choices=sorted(PROFILE_FILES),
                        help="params files and simulated robot (homework, lab, turtlebot3; default homework)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="parameter override (repeatable), over the profile's params files")
    parser.add_argument("--sim-param", action="append", default=[], metavar="NAME=VALUE",
                        help="simulator setting (repeatable), e.g. actuation_latency=0.15, odom_rate_hz=20, or "
                        "lidar=NAME for a real LiDAR (lds01, lds01_cw, lds02, rplidar, ust10)")


def bag_truth_readers(bag: str | None, video: str | None) -> dict[str, int]:
    """A demo's hosted judge's ``truth_readers``: the demo's own recorder (the default), and with ``--bag`` or
    ``--video`` the bag's too, whose recording must hold the schedule from t0 (its process starts with the graph)."""
    return {"truth_readers": 2} if bag or video else {}


def bag_for(bag: str | None, video: str | None) -> str | None:
    """The bag directory of a run: ``--bag``, else next to ``--video`` (``FILE_bag``: a film is always made
    from a bag, so what it shows is what ``ros2 bag play`` would replay), else none.

    Raises:
        ValueError: when that directory exists already: a bag is never overwritten, and a film made from an
            earlier run's bag would show that run, so the run is refused before it starts.
    """
    path = bag or (str(Path(video).with_suffix("")) + "_bag" if video else None)
    if path is not None and Path(path).exists():
        raise ValueError(f"bag {path} exists already (bags are never overwritten): remove it or choose another "
                         f"{'--bag' if bag else '--video name'}")
    return path


def film(bag_dir: str, out: str, fps: float) -> None:
    """Render the bag ``bag_dir`` to the MP4 ``out`` and say so."""
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.video import world_of, write_video

    record = read_bag(bag_dir)
    stats = write_video(record, out, fps, world_of(record))
    print(f"video: {out} ({stats.frames} frames at {fps:g} fps, rendered in {stats.seconds:.1f} s)")


def jobs_arg(text: str) -> int:
    """``--jobs``: a count >= 1, or ``auto``: one run per usable core, and for ``--exe`` runs more while the cores
    stay idle (:mod:`bt_nav.grading.admission`).

    Why one per core to begin with: a lock-step run is one busy process. A ``--exe`` run is three processes that
    mostly wait for sim time (at the default ``--rtf 5`` about a third of a core: 6.1 CPU s per 14 s run on 2
    cores), so more of them fit, but only as long as the cores stay idle: a starved node answers late in sim
    time and the verdicts change with the load (docs/grading.md, 204 runs at once). A number is exactly that
    many runs at once.
    """
    if text.strip().lower() == "auto":
        from bt_nav.grading.admission import AutoJobs

        return AutoJobs(usable_cores())
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number >= 1 or auto, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1 or auto, got {value}")
    return value


def check_mission_options(opts: argparse.Namespace) -> None:
    """Refuse, before any process or run directory exists, what the graph would refuse only once started: a world
    neither bundled nor a file (the simulator's refusal would be buried in its log, behind a run directory), a
    maneuver no tree knows, a simulator setting the simulator does not have (it would be ignored) or a LiDAR it
    does not know, a negative pace, a limit that is no time, a ROS domain DDS cannot open. ValueError: one line,
    naming what is known (``bt-nav demo``'s options; its ``--exe`` and lab runs too)."""
    from bt_nav_sim.lidar import lidar_model

    from bt_nav.grading.plan import check_worlds
    from bt_nav.mission.params import normalise_maneuver, parse_assignments
    from bt_nav.ros.nodes.simulator import SimulatorNode

    if opts.rtf < 0:
        raise ValueError(f"--rtf {opts.rtf:g}: sim seconds per wall second, >= 0 (0: as fast as possible)")
    if opts.timeout <= 0:
        raise ValueError(f"--timeout {opts.timeout:g}: the judge's wall-clock limit, > 0 s")
    if opts.domain_id is not None and not 0 <= opts.domain_id <= 232:
        raise ValueError(f"--domain-id {opts.domain_id}: a ROS_DOMAIN_ID is 0 to 232")
    sim = parse_assignments(opts.sim_param)
    check_worlds([w for w in (opts.world, sim.get("world")) if w])
    if opts.maneuver is not None:
        normalise_maneuver(opts.maneuver)
    unknown = sorted(set(sim) - set(SimulatorNode.PARAMETERS))
    if unknown:
        raise ValueError(f"--sim-param {unknown[0]}: the simulator has no such setting; it has "
                         + ", ".join(sorted(SimulatorNode.PARAMETERS)))
    if sim.get("lidar"):
        lidar_model(str(sim["lidar"]))
