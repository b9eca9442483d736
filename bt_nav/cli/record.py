"""``bt-nav record DIR``: record the live ROS graph into a rosbag2 bag (MCAP), like ``ros2 bag record``.

For users without the ros2 CLI. It runs in its own process (never inside the executive's), subscribes
raw to the mission's topics as they appear (:class:`bt_nav.ros.graphtap.GraphTap`), stamps every
message with its sim time at the source (its header stamp, else the sim time it was sent: not when this
process got round to it, which lags by seconds at 20x on a busy machine) and hands the CDR bytes to
:class:`bt_nav.media.bag.MissionBag`. The executive's and referee's ``/rosout`` lines become
``/bt_nav/events``, and ``/bt_nav/mission`` says which world and seed the simulator runs (asked from its
parameters), so a DDS bag looks like a lock-step one and ``bt-nav video`` can draw the world. It prints
``recording ...`` once it listens and ``first TOPIC at sim T s`` when a topic's first message arrives, and notes
those times in the bag (``first_messages.json``: ``bt-nav grade --exe`` says from it how late a run's bag began).

Stops on Ctrl-C / SIGTERM (the bag is closed properly) or after ``--duration`` wall seconds; the bag is
flushed every second, so even a kill -9 leaves everything up to the last second readable.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time

from bt_nav.media.bag import BagError
from bt_nav.run.bagrecorder import DEFAULT_TOPICS, BagRecorder


def main(argv: list[str] | None = None) -> int:
    """``bt-nav record DIR [--topics ...] [--duration S]``; exit 2 when the bag cannot be written."""
    parser = argparse.ArgumentParser(prog="bt-nav record", description=__doc__.splitlines()[0])
    parser.add_argument("bag", help="the bag directory to create (must not exist)")
    parser.add_argument("--topics", nargs="+", default=DEFAULT_TOPICS,
                        help=f"topics to record (default: {' '.join(DEFAULT_TOPICS)})")
    parser.add_argument("--duration", type=float, default=0.0, help="stop after this many wall seconds (0: Ctrl-C)")
    parser.add_argument("--world", help="world name for /bt_nav/mission (default: the simulator's parameter)")
    parser.add_argument("--seed", type=int, help="seed for /bt_nav/mission (default: the simulator's)")
    parser.add_argument("--profile", help="profile for /bt_nav/mission, e.g. lab (default: the simulator's)")
    parser.add_argument("--wall-time", action="store_true", help="no /clock on this graph: stamp with wall time")
    parser.add_argument("--no-ask", action="store_true", help="do not ask the simulator for world and seed")
    parser.add_argument("--events-executor", action="store_true",
                        help="spin rclpy's experimental EventsExecutor (about half the CPU; used by grade --exe)")
    args = parser.parse_args(argv)
    mission = {k: v for k, v in (("world", args.world), ("seed", args.seed), ("profile", args.profile))
               if v is not None}
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    try:
        recorder = BagRecorder(args.bag, args.topics, mission, sim_time=not args.wall_time, events=args.events_executor)
    except BagError as exc:
        print(f"bt-nav record: {exc}", file=sys.stderr)
        return 2
    print(f"recording {' '.join(args.topics)} into {args.bag} (Ctrl-C to stop)", flush=True)
    started = time.monotonic()
    try:
        recorder.start(ask_sim=not args.no_ask)
        while not stop.wait(0.1):
            if args.duration and time.monotonic() - started >= args.duration:
                break
    finally:
        counts, torn_down = recorder.close()
    print(f"bag {args.bag}: " + ", ".join(f"{t} {n}" for t, n in sorted(counts.items())), flush=True)
    if not torn_down:  # the bag is complete; a ROS teardown stuck in native code must not hold the process
        print("bt-nav record: ROS teardown did not end within a second: exiting without it", file=sys.stderr,
              flush=True)
        os._exit(0)
    return 0
