"""What the fork server's tests fork (``tests.forkserver_target:main``): a child that says what it was given."""

from __future__ import annotations

import os
import sys
import time


def main(argv: list[str]) -> int:
    """``say``: print the facts a child must get right, then exit with ``argv[1]``; ``sleep``: sleep ``argv[1]`` s;
    ``watch``: the same, watching the launcher's watchdog pipe; ``ros``: start rclpy (its log file is named after the
    program) and print the names in ``ROS_LOG_DIR``."""
    if argv[0] == "ros":
        import rclpy

        rclpy.init(args=[])
        rclpy.shutdown()
        print(sorted(os.listdir(os.environ["ROS_LOG_DIR"])))
        return 0
    if argv[0] in ("sleep", "watch"):
        if argv[0] == "watch":
            from bt_nav.ros.supervise import watch_parent_pipe

            assert watch_parent_pipe(), "no watchdog pipe in the environment"
        print("sleeping" if argv[0] == "sleep" else "watching", flush=True)
        time.sleep(float(argv[1]))
        return 0
    fd = int(os.environ.get("SOME_FD", "-1"))
    print(f"argv={argv!r}")
    print(f"env={os.environ.get('SOME_VAR')} leaked={os.environ.get('ONLY_THE_SERVER_HAS_THIS')}")
    print(f"cwd={os.getcwd()}")
    print(f"own_session={os.getpgid(0) == os.getpid() and os.getsid(0) == os.getpid()}")
    print(f"fd_readable={os.read(fd, 5).decode() if fd >= 0 else None}")
    print(f"sys_argv={sys.argv[1:]!r}")
    print("to stderr", file=sys.stderr)
    return int(argv[1])
