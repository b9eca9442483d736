"""``bt-nav video BAG -o mission.mp4``: film a recorded mission (H.264 MP4, yuv420p) from its rosbag2 bag.

The frame shows the world, robot, scan, trajectory, the 1.5 m circle, the active branch, sim time and
distance, the tree coloured by status and the mission's log lines (:mod:`bt_nav.media.video`). The
encoder is imageio-ffmpeg's bundled ffmpeg: no system ffmpeg needed. ``--still`` writes one frame as
PNG and ``--plot`` the trajectory picture (:func:`bt_nav.media.plot.plot_run`) from the same bag. Every time
shown, and ``--at``, counts sim seconds since the bag's first /clock (:data:`bt_nav.media.video.TIME_BASE`). Every
frame says it is a simulation (:data:`bt_nav.media.console.SIM_LABEL`); a hand-in's film, with the student's
terminal as its console, is ``bt-nav demo --exe``'s (:mod:`bt_nav.grading.handin_film`).

A bag with no ground truth (a real TurtleBot's: rosbag2 sqlite3 or MCAP, or a ROS 1 .bag) is filmed from what the
robot recorded (:mod:`bt_nav.media.robotfilm`): its odometry path, its scans laid out into a picture of the room,
its command and, with ``--maneuver`` (or ``--node``), the check-off's lines at the times they were decided; every
frame says where the data came from ("real robot bag", or a simulated bag that says so on /synthetic).
"""

from __future__ import annotations

import argparse
import sys

from bt_nav.media.bag import BagError


def main(argv: list[str] | None = None) -> int:
    """``bt-nav video``; exit 2 (with a message naming the file) for a bag that cannot be read."""
    parser = argparse.ArgumentParser(prog="bt-nav video", description=__doc__.splitlines()[0])
    parser.add_argument("bag", help="a rosbag2 directory (or its .mcap file) from bt-nav record/lockstep/demo")
    parser.add_argument("-o", "--output", default="mission.mp4", help="the MP4 to write (default mission.mp4)")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per second of sim time (default 10)")
    parser.add_argument("--still", metavar="PNG", help="also write one frame as PNG (at --at)")
    parser.add_argument("--at", type=float, default=None, help="time of the still, s since the bag's first /clock "
                        "(the time every frame shows; default: mid-bag); a robot's bag: s since its first /odom, "
                        "/scan or /cmd_vel message, and past its end the verdict card the film ends on")
    parser.add_argument("--plot", metavar="PNG", help="also write the trajectory picture")
    parser.add_argument("--no-video", action="store_true", help="only --still / --plot")
    robot = parser.add_argument_group("a robot's bag (no ground truth)")
    robot.add_argument("--maneuver", help="judge the run as this maneuver and show the check-off's lines")
    robot.add_argument("--node", help="the student's node file: its '# CHOICE: X' line names the maneuver")
    robot.add_argument("--console-log", action="store_true", help="also write every frame's texts beside the "
                       "video (<video>.console.json)")
    args = parser.parse_args(argv)
    if args.fps <= 0:
        parser.error("--fps must be positive")
    from bt_nav.media.robotrun import is_robot_bag

    if is_robot_bag(args.bag):
        return _robot(args)
    if args.maneuver or args.node:
        print(f"bt-nav video: --maneuver/--node judge a robot's bag; {args.bag} is a simulator's (the check-off "
              "is in its /rosout lines)", file=sys.stderr)
        return 2
    from bt_nav.media.bagread import read_bag
    from bt_nav.media.video import TIME_BASE, plot_bag, renderer_for, world_of, write_video

    try:
        record = read_bag(args.bag)
    except BagError as exc:
        print(f"bt-nav video: {exc}", file=sys.stderr)
        return 2
    if record.truncated:
        print(f"bt-nav video: {args.bag} was cut short; filming the {record.duration:.1f} s it holds",
              file=sys.stderr)
    world = world_of(record)
    if args.still:
        at = args.at if args.at is not None else max(0.0, record.end - record.origin) / 2
        renderer_for(record, world).frame(record.origin + at).save(args.still)
        print(f"still: {args.still} (t = {at:.2f} s {TIME_BASE})")
    if args.plot:
        print(f"picture: {plot_bag(record, args.plot, world)}")
    if not args.no_video:
        stats = write_video(record, args.output, args.fps, world)
        print(f"video: {stats.path}: {stats.frames} frames at {stats.fps:g} fps "
              f"({record.duration:.1f} s of sim time) rendered in {stats.seconds:.1f} s")
    return 0


def _robot(args: argparse.Namespace) -> int:
    """Film a robot's bag (module docstring); exit 2 for an unreadable bag or an unknown maneuver."""
    from bt_nav.cli.checkoff import _maneuver
    from bt_nav.media.console import console_log_path
    from bt_nav.media.robotfilm import RobotFilmRenderer, write_robot_video
    from bt_nav.media.robotrun import ROBOT_TIME_BASE, load_robot_run

    try:
        maneuver = _maneuver(args) if args.maneuver or args.node else None
        run = load_robot_run(args.bag, maneuver)
    except (BagError, ValueError) as exc:
        print(f"bt-nav video: {exc}", file=sys.stderr)
        return 2
    print(f"bt-nav video: {args.bag}: {run.source}; {len(run.rec.odom)} poses, {len(run.rec.scans)} scans, "
          f"{len(run.rec.commands)} commands over {run.end - run.origin:.1f} s")
    for note in run.notes:
        print(f"note: {note}")
    if args.plot:
        print("bt-nav video: --plot draws a simulator's bag; a robot's film shows its path", file=sys.stderr)
    if args.still:
        at = args.at if args.at is not None else (run.end - run.origin) / 2
        card = at > run.end - run.origin and bool(run.lines)  # past the end: the film's last frame, its verdict card
        RobotFilmRenderer(run).frame(min(run.origin + at, run.end), card).save(args.still)
        print(f"still: {args.still} (t = {min(at, run.end - run.origin):.2f} {ROBOT_TIME_BASE}"
              + ("; the verdict card held at the film's end" if card else "") + ")")
    if not args.no_video:
        sidecar = console_log_path(args.output) if args.console_log else None
        stats = write_robot_video(run, args.output, args.fps, sidecar)
        print(f"video: {stats.path}: {stats.frames} frames at {stats.fps:g} fps "
              f"({run.end - run.origin:.1f} s of the robot's time) rendered in {stats.seconds:.1f} s"
              + (f"; texts per frame: {sidecar}" if sidecar else ""))
    return 0
