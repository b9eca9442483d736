"""``bt-nav record DIR``: record the live ROS graph into a rosbag2 bag (MCAP), like ``ros2 bag record``.

For users without the ros2 CLI. It runs in its own process (never inside the executive's), subscribes
raw to the mission's topics as they appear (:class:`bt_nav.ros.graphtap.GraphTap`), stamps every
message with its sim time at the source (its header stamp, else the sim time it was sent: not when this
process got round to it, which lags by seconds at 20x on a busy machine) and hands the CDR bytes to
:class:`bt_nav.media.bag.MissionBag`. The executive's and referee's ``/rosout`` lines become
``/bt_nav/events``, and ``/bt_nav/mission`` says which world and seed the simulator runs (asked from its
parameters), so a DDS bag looks like a lock-step one and ``bt-nav video`` can draw the world. It prints
``recording ...`` once it listens and ``first TOPIC at sim T s`` when a topic's first message arrives, so a
launcher can wait until the bag covers what it needs (``bt-nav grade --exe`` does before it starts the judge).

Stops on Ctrl-C / SIGTERM (the bag is closed properly) or after ``--duration`` wall seconds; the bag is
flushed every second, so even a kill -9 leaves everything up to the last second readable.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from typing import Any

from bt_nav.media.bag import EVENTS, MISSION, TOPICS, BagError, MissionBag

#: What is recorded by default: the mission bag's topics, with /rosout turned into /bt_nav/events.
DEFAULT_TOPICS = [t for t in TOPICS if t not in (EVENTS, MISSION)] + ["/rosout"]
SIM_NODE = "/bt_nav_sim"


def ask_simulator(node: Any, timeout: float = 3.0) -> dict[str, Any]:
    """The simulator's world, seed and profile from its parameters ({} when no simulator answers)."""
    from rclpy.parameter_client import AsyncParameterClient

    client = AsyncParameterClient(node, SIM_NODE)
    if not client.wait_for_services(timeout_sec=timeout):
        return {}
    future = client.get_parameters(["world", "seed", "profile"])
    deadline = time.monotonic() + timeout
    while not future.done() and time.monotonic() < deadline:
        time.sleep(0.02)
    if not future.done() or future.result() is None:
        return {}
    values = [v.string_value if v.type == 4 else v.integer_value for v in future.result().values]
    return dict(zip(("world", "seed", "profile"), values, strict=False))


class BagRecorder:
    """The recording: a GraphTap feeding a MissionBag, on a private node spinning in a thread."""

    def __init__(self, path: str, topics: list[str], mission: dict[str, Any], sim_time: bool = True,
                 events: bool = False) -> None:
        from bt_nav.ros.graphtap import GraphTap
        from bt_nav.ros.rosutil import ThreadedNode

        self.bag = MissionBag(path, flush_every=1.0)
        self.lock = threading.Lock()
        self.ros = ThreadedNode("bt_nav_recorder", events=events)
        try:
            self.tap = GraphTap(self.ros.node, topics, self._write, sim_time=sim_time, message_info=not events)
        except BaseException:
            self.ros.close()
            self.bag.close()
            raise
        self.ros.node.create_timer(1.0, self._flush)
        self.mission = mission

    def start(self, ask_sim: bool) -> None:
        """Start spinning, then write what the simulator says of the run on /bt_nav/mission."""
        self.ros.start()
        info = {**(ask_simulator(self.ros.node) if ask_sim else {}), **self.mission, "source": "dds"}
        with self.lock:
            self.bag.mission(self.tap.now_ns() * 1e-9, info)

    def _write(self, topic: str, msgtype: str, t_ns: int, data: bytes, qos: Any) -> None:
        first = False
        with self.lock:
            if not self.bag.closed:
                first = topic not in self.bag.counts
                self.bag.write_raw(topic, t_ns, data, msgtype, qos)
        if first:  # a launcher waits for the line of the topic it needs (bt_nav.grading.node_bag)
            print(f"first {topic} at sim {t_ns * 1e-9:.2f} s", flush=True)

    def _flush(self) -> None:
        with self.lock:
            if not self.bag.closed:
                self.bag.flush()

    def close(self) -> dict[str, int]:
        """Stop the node, close the bag; returns the message counts."""
        self.ros.close()
        with self.lock:
            self.bag.close()
        return dict(self.bag.counts)


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
        counts = recorder.close()
    print(f"bag {args.bag}: " + ", ".join(f"{t} {n}" for t, n in sorted(counts.items())), flush=True)
    return 0


def start_process(bag: str, env: dict[str, str] | None = None, *extra: str) -> Any:
    """``bt-nav record BAG`` as a process of its own (for ``bt-nav demo --bag``): recording never runs in
    the executive's process, nor in the demo's. Stop it with :func:`stop_process`."""
    import subprocess

    return subprocess.Popen([sys.executable, "-m", "bt_nav.cli", "record", str(bag), *extra], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def stop_process(proc: Any, timeout: float = 10.0) -> str:
    """SIGINT (the bag is closed properly), SIGKILL after ``timeout``; returns a one-line outcome."""
    import subprocess

    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5.0)
    err = (proc.stderr.read() if proc.stderr else "").strip()
    return "bag closed" if proc.returncode == 0 else f"recorder exited with {proc.returncode}: {err[-300:]}"
