"""``bt-nav checkoff``: the lab's check-off, one judge and its rules, two ways in.

- over DDS (default): the judge node (:mod:`bt_nav.ros.nodes.checkoff`) calls ``toggle_navigation`` on a running
  robot node in the simulator and judges it from ground truth and its own ray casts;
- from a bag (``--bag BAG``): a real TurtleBot's recording (rosbag2 sqlite3 or MCAP, or a ROS 1 .bag), judged
  offline without DDS from /odom (the pose's yaw, never the twist), /scan as recorded and /cmd_vel
  (:mod:`bt_nav.media.robotbag`, :mod:`bt_nav.judge.recorded`). Same rules, same words; what the bag cannot show
  (the service calls, unless it holds their events; contact) is listed as not judged;
- live beside a real robot (``--robot``): it listens to the same topics for ``--duration`` s or until Ctrl-C
  (:mod:`bt_nav.ros.nodes.robotcheck`, never publishing, never calling the service), then judges what it heard as
  a bag of it would be judged; each maneuver's line is printed as soon as it is decided, the verdict at the end.
  It joins the user's own ROS_DOMAIN_ID and discovery range (the robot's); ``--call-toggle`` makes it call
  toggle_navigation itself (true after 3 s of listening, false at the end); ``--ros-args`` after the options are the
  listener node's (``ros2 launch bt_nav checkoff_robot.launch.py``).

Exit 0 when the check-off passed, 1 when it failed, 2 on a refused option or an unreadable bag, 3 when it is
INCOMPLETE (a real robot's data in which no maneuver could be judged: never a pass).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

#: Options of a real robot's data (a bag, or live), of a bag only, of live listening only, and of the DDS judge only.
ROBOT_ONLY = ("--bag", "--robot", "--node", "--from", "--to", "--armed-at", "--odom-topic", "--scan-topic",
              "--cmd-topic", "--service-topic", "--namespace", "--duration", "--call-toggle")
BAG_ONLY = ("--from", "--to")
LIVE_ONLY = ("--duration", "--call-toggle")
DDS_ONLY = ("--world", "--seed", "--timeout")


def parser() -> argparse.ArgumentParser:
    """Both modes' options (``--help`` shows them all)."""
    from bt_nav.cli import plain
    from bt_nav.mission.maneuver_spec import letters_text

    p = argparse.ArgumentParser(
        prog="bt-nav checkoff", allow_abbrev=False, description=plain(__doc__.split("\n\n")[0]),
        epilog="Over DDS every check-off setting is a ROS parameter too: --ros-args -p armed_for:=30.0 ... From a "
               "bag: exit 0 passed, 1 failed, 2 refused option or unreadable bag, 3 INCOMPLETE (no maneuver could "
               "be judged). A robot's times: s since t=0, the first /odom, /scan or /cmd_vel message.")
    p.add_argument("--maneuver", help=f"the maneuver to check off: {letters_text()} (parameter maneuver)")
    p.add_argument("--json", help="write the verdict JSON here (parameter json)")
    dds = p.add_argument_group("over DDS, in the simulator")
    dds.add_argument("--world", help="the simulator's world (parameter world)")
    dds.add_argument("--seed", type=int, help="the simulator's seed (parameter seed)")
    dds.add_argument("--timeout", type=float, help="wall-clock limit, s (parameter timeout)")
    bag = p.add_argument_group("a real robot: from its bag (no DDS), or live (--robot)")
    bag.add_argument("--bag", help="the recording: a rosbag2 directory (.db3 or .mcap) or file, or a ROS 1 .bag")
    bag.add_argument("--robot", action="store_true", help="listen to the robot's topics live (this ROS_DOMAIN_ID), "
                     "then judge what was heard")
    bag.add_argument("--duration", type=float, default=0.0, help="with --robot: listen this many s (0: until Ctrl-C)")
    bag.add_argument("--call-toggle", action="store_true", help="with --robot: call toggle_navigation true after 3 s "
                     "and false at the end (default: the TA calls it)")
    bag.add_argument("--node", help="the student's node file: its '# CHOICE: X' line names the maneuver")
    bag.add_argument("--from", dest="start", type=float,
                     help="the check-off starts this many s after t=0 (the first /odom, /scan or /cmd_vel message; "
                          "a window does not move it)")
    bag.add_argument("--to", dest="end", type=float, help="... and ends this many s after t=0")
    bag.add_argument("--armed-at", type=float, help="s after t=0 at which toggle_navigation(true) was called "
                     "(default: its service events, else the first non-zero command)")
    bag.add_argument("--odom-topic", default="odom", help="nav_msgs/Odometry topic (default odom)")
    bag.add_argument("--scan-topic", default="scan", help="sensor_msgs/LaserScan topic (default scan)")
    bag.add_argument("--cmd-topic", default="cmd_vel", help="Twist or TwistStamped topic (default cmd_vel)")
    bag.add_argument("--service-topic", default="toggle_navigation/_service_event",
                     help="the SetBool service events (rosbag2 service introspection)")
    bag.add_argument("--namespace", default="", help="the robot's namespace, put before relative topic names")
    return p


def _given(argv: list[str], option: str) -> bool:
    return any(a == option or a.startswith(option + "=") for a in argv)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav checkoff`` (see the module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    own = argv[:argv.index("--ros-args")] if "--ros-args" in argv else argv
    if "-h" in own or "--help" in own:
        parser().print_help()
        return 0
    modes = [o for o in ("--bag", "--robot") if _given(own, o)]
    if not modes:
        refused = [o for o in ROBOT_ONLY if _given(own, o)]
        if refused:
            print(f"bt-nav checkoff: {', '.join(refused)} only with --bag or --robot (a real robot's data to judge)",
                  file=sys.stderr)
            return 2
        from bt_nav.ros.nodes.checkoff import main as node_main

        return node_main(argv)
    refused = [o for o in DDS_ONLY if _given(own, o)] + (["--ros-args"] if own != argv and modes == ["--bag"] else [])
    refused += [o for o in (LIVE_ONLY if modes == ["--bag"] else BAG_ONLY) if _given(own, o)]
    if len(modes) > 1 or refused:
        what = "--bag and --robot exclude each other" if len(modes) > 1 else \
            f"{', '.join(refused)} mean{'s' if len(refused) == 1 else ''} nothing with {modes[0]}"
        why = " (the robot's world is the one it drove in)" if any(o in DDS_ONLY for o in refused) else ""
        print(f"bt-nav checkoff: {what}{why}", file=sys.stderr)
        return 2
    opts = parser().parse_args(own)
    opts.ros_args = argv[argv.index("--ros-args") + 1:] if own != argv else []
    return _judge_robot(opts)


def _maneuver(opts: argparse.Namespace) -> str:
    """The maneuver: --maneuver, else the node file's '# CHOICE: X' (ValueError: neither)."""
    from bt_nav.grading.exe.grid import choice_line
    from bt_nav.mission.params import normalise_maneuver

    if opts.maneuver:
        return normalise_maneuver(opts.maneuver)
    if opts.node:
        try:
            found = choice_line().search(Path(opts.node).read_text(errors="replace"))
        except OSError as exc:
            raise ValueError(f"--node {opts.node}: {exc.strerror or exc}") from exc
        if not found:
            raise ValueError(f"--node {opts.node}: no '# CHOICE: X' line in it; give --maneuver")
        return normalise_maneuver(found.group(1))
    raise ValueError("which maneuver? give --maneuver X or --node FILE (its '# CHOICE: X' line)")


def _listen_live(opts: argparse.Namespace, topics: object, config: object) -> object:
    """Listen to the robot (module docstring), printing each maneuver's line once decided; the Recording heard."""
    from bt_nav.media.bag import BagError
    from bt_nav.media.robotbag import recording_from
    from bt_nav.ros.nodes.robotcheck import LINE_MARGIN, graph_words, listen, unheard, unheard_words

    names = topics.names()  # type: ignore[attr-defined]
    began = time.monotonic()
    how_long = f"for {opts.duration:g} s" if opts.duration > 0 else "until Ctrl-C"
    print(f"bt-nav checkoff: listening to {', '.join(names.values())} on {graph_words()} ({how_long})", flush=True)
    printed: set[str] = set()

    def progress(raw: dict, calls: list) -> None:
        for line in _decided_lines(raw, calls, names, config):
            key = line.text.split(" (", 1)[0]
            if line.text.startswith("maneuver ") and key not in printed and line.t <= _latest(raw) - LINE_MARGIN:
                printed.add(key)
                print(f"bt-nav checkoff: {line.text}", flush=True)

    raw, notes, calls = listen(names, opts.duration, opts.call_toggle, progress, opts.ros_args)
    missing = unheard(raw, names)
    if missing and set(missing) & {names["odom"], names["scan"]}:  # nothing to judge: say why, not only what
        raise BagError(f"the live robot: {unheard_words(missing, time.monotonic() - began)}")
    rec = recording_from(raw, names, notes, "the live robot")
    if rec.calls is None and calls is not None:
        rec.calls = calls
    return rec


def _latest(raw: dict) -> float:
    """The newest receive time heard (s)."""
    return max((rows[-1][0] for rows in raw.values() if rows), default=0) * 1e-9


def _decided_lines(raw: dict, calls: list, names: dict, config: object) -> list:
    """The check-off's lines of what was heard so far, at their times (none while there is too little to judge)."""
    from bt_nav.judge.recorded import judge_recording
    from bt_nav.media.bag import BagError
    from bt_nav.media.robotbag import recording_from
    from bt_nav.media.robotrun import checkoff_timeline

    try:
        rec = recording_from({k: list(v) for k, v in raw.items()}, names, [], "the live robot")
        if rec.calls is None and calls:
            rec.calls = calls
        return checkoff_timeline(judge_recording(rec, config))  # type: ignore[arg-type]
    except (BagError, ValueError):
        return []


def _judge_robot(opts: argparse.Namespace) -> int:
    """Read the bag (or listen live), judge, print; the verdict JSON if asked."""
    from bt_nav.judge.checkoff_core import CheckoffConfig
    from bt_nav.judge.recorded import Window, judge_recording, odometry_config, report_lines
    from bt_nav.media.bag import BagError
    from bt_nav.media.robotbag import Topics, read_robot_bag

    source = opts.bag or "the live robot"
    try:
        config = CheckoffConfig(maneuver=_maneuver(opts))
        topics = Topics(opts.odom_topic, opts.scan_topic, opts.cmd_topic, opts.service_topic, opts.namespace)
        if opts.robot:
            rec = _listen_live(opts, topics, config)
        else:
            rec = read_robot_bag(opts.bag, topics)
        res = judge_recording(rec, config, Window(opts.start, opts.end, opts.armed_at))
    except (BagError, ValueError) as exc:
        print(f"bt-nav checkoff: {exc}", file=sys.stderr)
        return 2
    feed = res["feed"]
    print(f"check-off of maneuver {config.maneuver} from {source} (t=0: {_time_zero(rec)}): window "
          f"t={feed['window'][0]:.1f}-{feed['window'][1]:.1f} s; armed: {feed['arming']}")
    for note in feed["notes"]:
        print(f"note: {note}")
    lines = report_lines(res)
    print("\n".join(lines))
    if opts.json:
        from dataclasses import asdict

        res.update(report_lines=lines, config=asdict(odometry_config(config)), bag=str(source),
                   exit_code=_exit_code(res), time_base=f"s since t=0: {_time_zero(rec)}")
        try:
            Path(opts.json).parent.mkdir(parents=True, exist_ok=True)
            Path(opts.json).write_text(json.dumps(res, indent=2, default=str) + "\n")
        except OSError as exc:
            print(f"bt-nav checkoff: could not write {opts.json}: {exc.strerror or exc}", file=sys.stderr)
            return 2
    return _exit_code(res)


def _time_zero(rec: object) -> str:
    """The report's time zero in the words of help, terminal, JSON and film (bt_nav.judge.recorded.TIME_ZERO), with
    the topics this recording's are."""
    from bt_nav.judge.recorded import TIME_ZERO

    topics = rec.topics  # type: ignore[attr-defined]
    return TIME_ZERO.replace("/odom, /scan or /cmd_vel", f"{topics['odom']}, {topics['scan']} or {topics['cmd']}")


def _exit_code(res: dict) -> int:
    """0 passed, 1 failed, 3 incomplete (no maneuver could be judged)."""
    return {"PASSED": 0, "INCOMPLETE": 3}.get(res.get("verdict", "PASSED" if res["passed"] else "FAILED"), 1)


if __name__ == "__main__":
    raise SystemExit(main())
