"""bt-nav arm: arm (or, with --off, disarm) a running bt_nav executive through its SetBool service.

For users who installed with pip and have no ros2 command line: this is

    ros2 service call /reactive_control/activate std_srvs/srv/SetBool "{data: true}"

without ros2. bt-nav sim-run prints the exact command for its run (the ROS domain included). The
executive's reply is printed as it comes: success or refusal, and the reason, in mission time.
Exit status: 0 when the executive accepted, 1 when it refused, 2 when no service answered in time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

#: The homework profile's arm service (``bt-nav sim-run`` and ``sim.launch.py``); the lab uses /toggle_navigation.
DEFAULT_SERVICE = "/reactive_control/activate"


def build_parser() -> argparse.ArgumentParser:
    """Options of ``bt-nav arm``."""
    parser = argparse.ArgumentParser(prog="bt-nav arm", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--off", action="store_true", help="disarm instead (the robot stops)")
    parser.add_argument("--service", default=DEFAULT_SERVICE,
                        help=f"SetBool service (default {DEFAULT_SERVICE}; the lab: /toggle_navigation)")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="seconds to wait for the service and its reply (default 10)")
    parser.add_argument("--domain-id", type=int,
                        help="ROS_DOMAIN_ID of the run (default: $ROS_DOMAIN_ID, else 0 as in ROS)")
    return parser


def call(service: str, data: bool, timeout: float, domain_id: int) -> tuple[int, str]:
    """One SetBool call from a private node in ``domain_id`` (localhost only); (exit status, line to print)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions
    from std_srvs.srv import SetBool

    from bt_nav.ros.supervise import use_domain_here

    use_domain_here(domain_id)
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id, signal_handler_options=SignalHandlerOptions.NO)
    try:
        node = rclpy.create_node("bt_nav_arm", context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        client = node.create_client(SetBool, service)
        end = time.monotonic() + timeout
        if not client.wait_for_service(timeout_sec=timeout):
            return 2, (f"no service {service} in ROS_DOMAIN_ID {domain_id} within {timeout:g} s: is the executive "
                       "running? (bt-nav sim-run prints the domain and the exact arm command)")
        future = client.call_async(SetBool.Request(data=data))
        while not future.done() and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        if not future.done():
            return 2, f"{service} did not answer within {timeout:g} s"
        reply = future.result()
        verb = "accepted" if reply.success else "refused"
        return (0 if reply.success else 1), f"{service}: {verb}: {reply.message}"
    finally:
        rclpy.try_shutdown(context=context)


def main(argv: list[str] | None = None) -> int:
    """``bt-nav arm [--off] [--service NAME] [--timeout S] [--domain-id N]``."""
    opts = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    if opts.timeout <= 0:
        print("bt-nav arm: --timeout must be > 0", file=sys.stderr)
        return 2
    domain = opts.domain_id
    if domain is None:
        text = os.environ.get("ROS_DOMAIN_ID", "").strip()
        domain = int(text) if text.isdigit() else 0
    service = opts.service if opts.service.startswith("/") else f"/{opts.service}"
    code, line = call(service, not opts.off, opts.timeout, domain)
    print(line, file=sys.stdout if code != 2 else sys.stderr, flush=True)
    return code
