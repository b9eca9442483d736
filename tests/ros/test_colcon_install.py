"""The ROS way in: ``colcon build`` of this ament_python package, then the INSTALLED executive.

Without the ``ros2`` CLI, ``ros2 run bt_nav executive`` is: find ``lib/bt_nav/executive`` under the
install prefix, with the install's site-packages on PYTHONPATH and the prefix on AMENT_PREFIX_PATH
(what ``local_setup.bash`` would export). The executive must then load the installed copy of bt_nav
and the installed tree (share/bt_nav, found through the ament index), not the source checkout.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from ros_harness import REPO, ExecutiveProcess, Harness

COLCON = Path(sys.executable).parent / "colcon"


def prepend(env: dict[str, str], name: str, value: Path) -> None:
    """``name=value:$name``."""
    env[name] = os.pathsep.join([str(value), *([env[name]] if env.get(name) else [])])


def test_colcon_build_and_run_the_installed_executive(tmp_path: Path, start_executive: Callable[..., ExecutiveProcess],
                                                       make_harness: Callable[..., Harness]) -> None:
    build = subprocess.run(
        [str(COLCON), "--log-base", str(tmp_path / "log"), "build", "--base-paths", str(REPO),
         "--build-base", str(tmp_path / "build"), "--install-base", str(tmp_path / "install")],
        cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert build.returncode == 0, f"colcon build failed:\n{build.stdout[-4000:]}\n{build.stderr[-4000:]}"

    prefix = tmp_path / "install" / "bt_nav"  # colcon's default isolated layout: one prefix per package
    executable = prefix / "lib" / "bt_nav" / "executive"
    site_packages = prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    share = prefix / "share" / "bt_nav"
    sim_package = site_packages / "bt_nav_sim"
    for path in (executable, share / "package.xml", share / "trees" / "mission.xml", share / "config" / "lab.yaml",
                 prefix / "share" / "ament_index" / "resource_index" / "packages" / "bt_nav",
                 sim_package / "__init__.py", sim_package / "worlds" / "stage_4.yaml",
                 site_packages / "bt_nav" / "ros" / "nodes" / "simulator.py",
                 site_packages / "bt_nav" / "ros" / "executive.py"):
        assert path.exists(), f"not installed: {path.relative_to(tmp_path)}"
    assert os.access(executable, os.X_OK)
    assert executable.read_text().startswith(f"#!{sys.executable}")  # the venv's python runs it
    assert not (site_packages / "bt_nav" / "sim").exists()  # the simulator installs once, as bt_nav_sim

    env = dict(os.environ)
    env.pop("BT_NAV_SHARE", None)
    prepend(env, "PYTHONPATH", site_packages)
    prepend(env, "AMENT_PREFIX_PATH", prefix)
    process = start_executive("-r", "arm:=toggle_navigation", "--params-file", str(share / "config" / "lab.yaml"),
                              command=[str(executable)], env=env)
    harness = make_harness(arm_service="/toggle_navigation")
    harness.connect(process)
    assert harness.first_contact().is_zero  # /clock in, cmd_vel out
    response = harness.arm(True)
    assert response.success and response.message
    assert harness.tick().is_zero  # armed, but no scan yet: stopped
    assert process.has_line("arm server /toggle_navigation"), process.tail()
    assert process.has_line(f"tree {share}/trees/mission.xml"), process.tail()
    assert process.has_line(f"params files {share}/config/lab.yaml"), process.tail()
