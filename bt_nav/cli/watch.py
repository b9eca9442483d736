"""``bt-nav watch`` / ``ros2 run bt_nav watch``: print the executive's tree whenever it changes.

Like py-trees-tree-watcher, for bt_nav: subscribes to the executive's ``~/tree`` topic
(``/bt_nav_executive/tree``, std_msgs/String, transient local so the current tree arrives at once)
and prints each new snapshot with the time it arrived.
"""

from __future__ import annotations

import argparse
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
    parser.add_argument("--timeout", type=float, default=0.0, help="give up after this many seconds (0: never)")
    args = parser.parse_args(remove_ros_args(["bt-nav", *argv])[1:])

    rclpy.init(args=["bt-nav-watch", *argv])
    node = rclpy.create_node("bt_nav_tree_watcher")
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    state = {"last": None, "count": 0}

    def on_tree(msg: String) -> None:
        if msg.data == state["last"]:
            return
        state["last"] = msg.data
        state["count"] += 1
        stamp = time.strftime("%H:%M:%S")
        print(f"---- {stamp}  {args.topic}  (snapshot {state['count']}) ----\n{msg.data}", flush=True)

    node.create_subscription(String, args.topic, on_tree, qos)
    start = time.monotonic()
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
            if args.once and state["count"]:
                break
            if args.timeout and time.monotonic() - start > args.timeout:
                print(f"bt-nav watch: nothing on {args.topic} within {args.timeout:.0f} s", file=sys.stderr)
                return 1
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0
