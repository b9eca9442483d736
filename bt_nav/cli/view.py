"""``bt-nav view``: watch the mission in a browser: robot, scan, trajectory and the tree, live or from a bag.

Live (default): a private node taps the graph (:class:`bt_nav.ros.graphtap.GraphTap`) and feeds
:class:`bt_nav.media.view.LiveScene`; the world is the one the simulator's parameters name. With
``--bag BAG`` the page plays the recorded mission back with a time slider instead (no ROS needed); a robot's bag
(no ground truth: rosbag2 sqlite3 or MCAP, or ROS 1) is played back from its odometry and scans, the room as its
scans saw it, with the check-off's lines given ``--maneuver`` or ``--node`` (:mod:`bt_nav.media.robotview`).
The page is served on 127.0.0.1 unless ``--host`` says otherwise (standard-library HTTP server,
server-sent events; :mod:`bt_nav.media.view`).

``--foxglove`` also starts a Foxglove WebSocket server (``foxglove-sdk``, port ``--foxglove-port``)
that forwards the same messages as ROS 2 CDR with their ``ros2msg`` schemas, so Foxglove shows them
with its own panels (LaserScan, Odometry, ...).
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from bt_nav.media.bag import TOPICS, BagError
from bt_nav.media.foxglove import FoxgloveBridge


def _world(name: str | None, seed: int) -> Any:
    from bt_nav_sim.world import load_world

    if not name:
        return None
    try:
        return load_world(name, seed=seed)
    except (OSError, ValueError, KeyError) as exc:
        print(f"bt-nav view: cannot load world {name!r}: {exc}", file=sys.stderr)
        return None


def _live(args: argparse.Namespace, feeds: list[Any]) -> tuple[Any, Any]:
    """A LiveScene fed from the graph (and the Foxglove bridge); returns (scene, node to close)."""
    from bt_nav.media.view import LiveScene
    from bt_nav.ros.graphtap import GraphTap
    from bt_nav.ros.rosutil import ThreadedNode
    from bt_nav.run.bagrecorder import DEFAULT_TOPICS, ask_simulator

    ros = ThreadedNode("bt_nav_viewer")
    scene = LiveScene()
    handlers = [scene.feed, *feeds]

    def feed(*message: Any) -> None:
        for handler in handlers:
            try:
                handler(*message)
            except Exception as exc:  # noqa: BLE001 - one undecodable message must not stop the view
                ros.node.get_logger().warning(f"dropped a message on {message[0]}: {exc!r}",
                                              throttle_duration_sec=5.0)

    GraphTap(ros.node, DEFAULT_TOPICS, feed)
    ros.start()
    info = {} if args.world else ask_simulator(ros.node)
    scene.world = _world(args.world or info.get("world"), int(args.seed if args.seed is not None
                                                               else info.get("seed", 0) or 0))
    return scene, ros


def _bag(args: argparse.Namespace, feeds: list[Any]) -> Any:
    from bt_nav.media.bagread import iter_messages, read_bag
    from bt_nav.media.robotrun import is_robot_bag
    from bt_nav.media.video import world_of
    from bt_nav.media.view import BagScene

    if is_robot_bag(args.bag):
        return _robot_bag(args, feeds)
    record = read_bag(args.bag)
    for feed in feeds:  # Foxglove gets the whole bag at once (its own player shows the time line)
        for topic, msgtype, t_ns, data in iter_messages(args.bag):
            if topic in TOPICS:
                feed(topic, msgtype, t_ns, data)
    world = _world(args.world, args.seed or 0) if args.world else world_of(record)
    return BagScene(record, world)


def _robot_bag(args: argparse.Namespace, feeds: list[Any]) -> Any:
    """A robot's bag played back (module docstring); Foxglove gets its rosbag2 messages as recorded."""
    from bt_nav.cli.checkoff import _maneuver
    from bt_nav.media.bagformats import iter_messages
    from bt_nav.media.robotrun import load_robot_run
    from bt_nav.media.robotview import RobotScene

    try:
        maneuver = _maneuver(args) if args.maneuver or args.node else None
    except ValueError as exc:
        raise BagError(str(exc)) from exc
    run = load_robot_run(args.bag, maneuver)
    for note in run.notes:
        print(f"bt-nav view: {note}", file=sys.stderr)
    if feeds and Path(args.bag).suffix == ".bag":
        print("bt-nav view: --foxglove forwards rosbag2 bags only (a ROS 1 bag's payloads are not CDR)",
              file=sys.stderr)
    elif feeds:
        for feed in feeds:
            for topic, msgtype, t_ns, data in iter_messages(args.bag):
                feed(topic, msgtype, t_ns, data)
    return RobotScene(run)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav view [--port P] [--host H] [--bag BAG] [--foxglove]``; runs until Ctrl-C."""
    from bt_nav.media.view import ViewServer

    parser = argparse.ArgumentParser(prog="bt-nav view", description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=8000, help="HTTP port (default 8000; 0: any free one)")
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this machine)")
    parser.add_argument("--bag", help="play this recorded bag back instead of the live graph")
    parser.add_argument("--world", help="world to draw (default: the simulator's, or the bag's)")
    parser.add_argument("--seed", type=int, default=None, help="seed of a generated --world")
    parser.add_argument("--foxglove", action="store_true", help="also serve Foxglove's WebSocket protocol")
    parser.add_argument("--foxglove-port", type=int, default=8765, help="Foxglove WebSocket port (default 8765)")
    parser.add_argument("--maneuver", help="a robot's bag: judge it as this maneuver and show the check-off's lines")
    parser.add_argument("--node", help="a robot's bag: the node file whose '# CHOICE: X' line names the maneuver")
    args = parser.parse_args(argv)
    bridge = FoxgloveBridge(args.host, args.foxglove_port) if args.foxglove else None
    feeds = [bridge.feed] if bridge else []
    ros = None
    try:
        if args.bag:
            scene = _bag(args, feeds)
        else:
            scene, ros = _live(args, feeds)
        server = ViewServer(scene, args.host, args.port)
    except (BagError, OSError) as exc:
        print(f"bt-nav view: {exc}", file=sys.stderr)
        if bridge:
            bridge.close()
        return 2
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    server.start()
    print(f"bt-nav view: {server.url}" + (f"  (Foxglove: ws://{args.host}:{args.foxglove_port})" if bridge else ""),
          flush=True)
    while not stop.wait(0.5):
        pass
    server.close()
    if ros is not None:
        ros.close()
    if bridge:
        bridge.close()
    return 0
