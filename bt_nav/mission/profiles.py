"""Mission profiles: which params files a use of bt_nav needs, read without ROS.

A profile names one use: ``homework`` (the course homework in its simulator), ``lab`` (the lab exercise)
and ``turtlebot3`` (a real or Gazebo TurtleBot3 Burger doing the homework mission). Each maps to the
params files under ``config/`` that the executive loads in that order (later files win), exactly as
``ros2 run bt_nav executive --ros-args --params-file A --params-file B`` would. The profiles themselves (files,
simulated robot, assignment) are one record each in :mod:`bt_nav.mission.assignments`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav.mission.assignments import PROFILES, profile_spec
from bt_nav.mission.resources import read_yaml, share_dir

#: The executive's node name, the section params files address.
EXECUTIVE_NAME = "bt_nav_executive"

#: profile -> params files under config/, applied in order (read from :data:`bt_nav.mission.assignments.PROFILES`).
PROFILE_FILES: dict[str, tuple[str, ...]] = {name: spec.files for name, spec in PROFILES.items()}


def config_file(name: str) -> Path | None:
    """``config/<name>`` from bt_nav's data files, or None when it does not exist."""
    try:
        path = share_dir() / "config" / name
    except FileNotFoundError:
        return None
    return path if path.is_file() else None


def file_parameters(path: str | Path, node_name: str = EXECUTIVE_NAME) -> dict[str, Any]:
    """The parameters a ROS params file gives ``node_name`` in any namespace (``/**``, ``/**/node_name``
    and the node's own section)."""
    import yaml

    try:
        data = read_yaml(path) or {}
    except (OSError, yaml.YAMLError):
        return {}
    merged: dict[str, Any] = {}
    for key in ("/**", "**", node_name, f"/{node_name}", f"/**/{node_name}"):
        section = data.get(key) if isinstance(data, dict) else None
        if isinstance(section, dict) and isinstance(section.get("ros__parameters"), dict):
            merged.update(section["ros__parameters"])
    return merged


def profile_files(profile: str) -> list[Path]:
    """The params files of ``profile`` that exist, in load order (ValueError for an unknown profile)."""
    names = profile_spec(profile).files
    return [path for path in (config_file(name) for name in names) if path is not None]


def profile_parameters(profile: str) -> dict[str, Any]:
    """Every executive parameter the profile's files set, later files winning."""
    merged: dict[str, Any] = {}
    for path in profile_files(profile):
        merged.update(file_parameters(path))
    return merged


def params_files_note(argv: list[str]) -> str:
    """What the executive says at start about its params files (``--params-file X`` in ``argv``)."""
    files = [argv[i + 1] for i, arg in enumerate(argv[:-1]) if arg == "--params-file"]
    if not files:
        return ("no params file: the package defaults (the homework tuning on an ideal robot, no maneuver); "
                "on a TurtleBot3 add config/turtlebot3.yaml")
    names = [Path(f).name for f in files]
    matches = [p for p, wanted in PROFILE_FILES.items() if list(wanted) == names]
    return f"params files {', '.join(files)}" + (f" (profile {matches[0]})" if matches else "")
