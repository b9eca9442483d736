"""``bt-nav watch`` / ``ros2 run bt_nav watch``: print the executive's tree whenever it changes.

Like py-trees-tree-watcher, for bt_nav: subscribes to the executive's ``~/tree`` topic
(``/bt_nav_executive/tree``, std_msgs/String, transient local so the current tree arrives at once)
and prints each new snapshot with the time it arrived, drawn as py_trees' unicode tree from the JSON
document the executive publishes (``--json`` prints the document itself).

Honesty: every snapshot is printed with its age, and while nothing new arrives a status line every
``--status-period`` seconds says how old the last snapshot is and whether any executive still
publishes the topic (the tree is sent only when it changes, so silence alone proves nothing). With
no publisher on the graph it says so within ``--grace`` seconds (3 by default), and again when the
executive goes away or comes back.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from bt_nav.cli import plain


def main(argv: list[str] | None = None) -> int:
    """``bt-nav watch [--topic T] [--once] [--timeout S]`` (ROS arguments are passed to rclpy)."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.utilities import remove_ros_args
    from std_msgs.msg import String

    argv = list(sys.argv[1:] if argv is None else argv)
    parser = argparse.ArgumentParser(prog="bt-nav watch", description=plain(__doc__),
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--topic", default="/bt_nav_executive/tree", help="the executive's ~/tree topic")
    parser.add_argument("--once", action="store_true", help="print the first snapshot and exit")
    parser.add_argument("--json", action="store_true", help="print each snapshot's JSON document, not the tree art")
    parser.add_argument("--timeout", type=float, default=0.0, help="give up after this many seconds (0: never)")
    parser.add_argument("--grace", type=float, default=3.0, help="seconds before saying no executive publishes")
    parser.add_argument("--status-period", type=float, default=5.0,
                        help="seconds between status lines while nothing new arrives (0: none)")
    args = parser.parse_args(remove_ros_args(["bt-nav", *argv])[1:])

    rclpy.init(args=["bt-nav-watch", *argv])
    node = rclpy.create_node("bt_nav_tree_watcher")
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    state: dict = {"last": None, "count": 0, "arrived": None, "said": time.monotonic(), "publishers": None}

    def on_tree(msg: String) -> None:
        if msg.data == state["last"]:
            return
        state["last"] = msg.data
        state["count"] += 1
        state["arrived"] = state["said"] = time.monotonic()
        stamp = time.strftime("%H:%M:%S")
        age = "latched: published before this watch joined" if state["count"] == 1 else "age 0.0 s"
        print(f"---- {stamp}  {args.topic}  (snapshot {state['count']}, {age}) ----\n{shown(msg.data, args.json)}",
              flush=True)

    node.create_subscription(String, args.topic, on_tree, qos)
    start = time.monotonic()
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
            if args.once and state["count"]:
                break
            _report_liveness(node.count_publishers(args.topic), state, args, time.monotonic() - start)
            if args.timeout and time.monotonic() - start > args.timeout:
                print(f"bt-nav watch: nothing on {args.topic} within {args.timeout:.0f} s", file=sys.stderr)
                return 1
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _report_liveness(publishers: int, state: dict, args: argparse.Namespace, elapsed: float) -> None:
    """Say when no executive publishes (after the grace period), when it goes or comes back, and how old
    the last snapshot is every ``status_period`` seconds of silence."""
    now = time.monotonic()
    alive = publishers > 0
    if elapsed >= args.grace and alive != state["publishers"]:
        if not alive:
            print(f"bt-nav watch: no executive is publishing {args.topic} (no publisher on the graph; "
                  f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID', '0')}); waiting", file=sys.stderr, flush=True)
        elif state["publishers"] is False:
            print(f"bt-nav watch: an executive publishes {args.topic} again", file=sys.stderr, flush=True)
        state["publishers"] = alive
        state["said"] = now
    if args.status_period > 0 and state["arrived"] is not None and now - state["said"] >= args.status_period:
        state["said"] = now
        who = f"{publishers} publisher(s) on the topic" if alive else "NO executive publishing"
        print(f"     (last snapshot {now - state['arrived']:.0f} s ago, unchanged since; {who})", flush=True)


def shown(data: str, as_json: bool) -> str:
    """What the watch prints of one ``~/tree`` message: the art rendered from the snapshot document (or the document
    itself with ``--json``); a message that is no snapshot document is printed as it came, with a note."""
    from bt_nav.mission.snapshot import read_snapshot, render_art

    snapshot = read_snapshot(data)
    if snapshot is None:
        return f"(not a bt_nav tree snapshot; printed as received)\n{data}"
    return data if as_json else render_art(snapshot).rstrip("\n")
