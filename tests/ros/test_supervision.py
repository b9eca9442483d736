"""Launchers cannot leave orphans, and the robot is told to stop on the way out (real DDS, real signals).

``bt-nav sim-run`` is started as a user would, armed with ``bt-nav arm`` (no ros2 needed), and then
ended by SIGTERM, by SIGKILL (nothing of the launcher runs: the children must notice by themselves)
and by SIGINT while it runs as a background job of a non-interactive shell (which starts it with
SIGINT ignored). Every case: no child of the launcher is left after 5 s, and the last command on
/cmd_vel is a zero twist. Domains: claimed in 140-159, separate from the harness's.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from bt_nav.ros.supervise import child_env, claim_domain_id
from bt_nav.testing import wait_until

REPO = Path(__file__).resolve().parents[2]
DOMAIN = claim_domain_id(140, 159)
ORPHAN_LIMIT = 5.0


def _stat(pid: int | str) -> list[str] | None:
    """The fields of ``/proc/<pid>/stat`` after the command name (state first, then the parent), None: gone."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat[stat.rindex(")") + 2:].split()


def _parent(pid: int) -> int:
    """``pid``'s parent (0: gone)."""
    fields = _stat(pid)
    return int(fields[1]) if fields is not None else 0


def descendants(pid: int) -> set[int]:
    """Every live (non-zombie) process below ``pid``."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        fields = _stat(entry.name) if entry.name.isdigit() else None
        if fields is not None and fields[0] != "Z":
            parents[int(entry.name)] = int(fields[1])
    found: set[int] = set()
    frontier = {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def alive(pids: set[int]) -> set[int]:
    """Those of ``pids`` still running (zombies count as gone)."""
    return {pid for pid in pids if (fields := _stat(pid)) is not None and fields[0] != "Z"}


class CmdProbe:
    """Records every /cmd_vel (Twist) in DOMAIN from a private rclpy context."""

    def __init__(self) -> None:
        import rclpy
        from geometry_msgs.msg import Twist
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rclpy.signals import SignalHandlerOptions

        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=DOMAIN, signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node("supervision_probe", context=self.context)
        self.commands: list[tuple[float, float]] = []
        self.node.create_subscription(Twist, "/cmd_vel", self._on_cmd,
                                      QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE))
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _on_cmd(self, msg) -> None:
        self.commands.append((msg.linear.x, msg.angular.z))

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.executor.spin_once(timeout_sec=0.02)

    def close(self) -> None:
        import rclpy

        self._stop.set()
        self._thread.join(timeout=2.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def start_sim_run(background: bool) -> tuple[subprocess.Popen, list[str]]:
    """``bt-nav sim-run`` (directly, or as a background job of a non-interactive bash); its output lines."""
    command = [sys.executable, "-m", "bt_nav.cli", "sim-run", "--profile", "homework"]
    if background:
        command = ["bash", "-c", " ".join(command) + " & wait"]
    env = child_env(DOMAIN)
    env.pop("BT_NAV_WATCHDOG_FD", None)
    proc = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(line.rstrip() for line in proc.stdout), daemon=True).start()
    return proc, lines


@pytest.mark.slow
@pytest.mark.parametrize("how", ["SIGTERM", "SIGKILL", "SIGINT-background"])
def test_launcher_end_leaves_no_child_and_a_stopped_robot(how: str) -> None:
    probe = CmdProbe()
    proc, lines = start_sim_run(background=how.endswith("background"))
    output = lambda: "\n".join(lines)  # noqa: E731
    try:
        wait_until(lambda: any("scan usable again" in line for line in lines), 60, "the executive's first scan", output,
                   interval=0.05)
        launcher = int(re.search(r"pid (\d+)", next(line for line in lines if "ROS_DOMAIN_ID=" in line))[1])
        hint = next(line for line in lines if "in another terminal:" in line)
        assert f"ROS_DOMAIN_ID={DOMAIN} " in hint and "arm --service /reactive_control/activate" in hint
        arm = subprocess.run([sys.executable, "-m", "bt_nav.cli", "arm", "--domain-id", str(DOMAIN)], cwd=REPO,
                             env=child_env(DOMAIN), capture_output=True, text=True, timeout=60)
        assert arm.returncode == 0 and "accepted: armed" in arm.stdout, arm.stdout + arm.stderr
        wait_until(lambda: any(v != 0.0 for v, _ in probe.commands[-5:]), 30, "the robot to drive", output,
                   interval=0.05)
        children = descendants(launcher)
        assert len(children) >= 2, f"sim and executive below the launcher: {children}"
        signum = {"SIGTERM": signal.SIGTERM, "SIGKILL": signal.SIGKILL}.get(how, signal.SIGINT)
        killed_at = time.monotonic()
        os.kill(launcher, signum)
        wait_until(lambda: not alive(children), ORPHAN_LIMIT, f"every child gone after {how}",
                   lambda: f"left: {alive(children)}\n{output()}", interval=0.05)
        assert time.monotonic() - killed_at <= ORPHAN_LIMIT
        time.sleep(0.3)  # the last messages in flight
        assert probe.commands and probe.commands[-1] == (0.0, 0.0), probe.commands[-5:]
        if how != "SIGKILL":
            proc.wait(timeout=10)
            assert any("stopped every node" in line for line in lines), output()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=10)
        probe.close()


@pytest.mark.slow
def test_arm_without_an_executive_says_where_it_looked() -> None:
    arm = subprocess.run([sys.executable, "-m", "bt_nav.cli", "arm", "--domain-id", str(DOMAIN), "--timeout", "1",
                          "--service", "/nobody_here"], cwd=REPO, env=child_env(DOMAIN), capture_output=True,
                         text=True, timeout=60)
    assert arm.returncode == 2
    assert f"no service /nobody_here in ROS_DOMAIN_ID {DOMAIN} within 1 s" in arm.stderr


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_text().replace("\0", " ")
    except OSError:
        return ""


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM])
def test_a_grade_ended_by_a_signal_leaves_no_fork_server_no_simulator_and_no_node(signum: int, tmp_path: Path) -> None:
    """A grade's simulators are forked from its fork server (bt_nav.ros.forkserver): killed or terminated, the grade
    takes the server, the forked simulators and the started nodes with it, as it takes processes it starts."""
    node = REPO / "tests" / "fixtures" / "lab_student_node.py"
    command = [sys.executable, "-m", "bt_nav.cli", "grade", "--exe", f"{sys.executable} {node} --choice C",
               "--profile", "lab", "--maneuvers", "C", "--worlds", "lab_object", "--lidars", "lds01,rplidar",
               "--seeds", "1", "--out", str(tmp_path / "grade"), "--progress", "off", "--jobs", "2"]
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    env.pop("BT_NAV_WATCHDOG_FD", None)
    proc = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        def forked() -> bool:  # a simulator below the fork server below the grade
            return any("-m bt_nav.cli sim " in _cmdline(pid) and "forkserver" in _cmdline(_parent(pid))
                       for pid in descendants(proc.pid))

        wait_until(forked, 60, "a forked simulator", lambda: "\n".join(_cmdline(p) for p in descendants(proc.pid)))
        children = descendants(proc.pid)
        kinds = " ".join(_cmdline(pid) for pid in children)
        assert "bt_nav.ros.forkserver" in kinds and "lab_student_node.py" in kinds, kinds
        os.kill(proc.pid, signum)
        wait_until(lambda: not alive(children), 15.0, f"every process of the grade gone after {signum!r}",
                   lambda: "\n".join(f"{pid} {_cmdline(pid)}" for pid in alive(children)))
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
