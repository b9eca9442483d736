"""Which launch file and node a launch check is about, for the commands that check one outside a class: ``bt-nav
check-launch FILE|DIR`` and ``bt-nav grade --exe ... --launch FILE``; and the check carried in an ``--exe`` grade's
``grade.json`` the way a class's hand-in carries it (``"launch"``), so its report, feedback and Gradescope/JUnit
files hold the launch checks too.

Why here and not in the commands: one code path -- a folder is searched as a class's hand-in is
(:func:`find_launch`, :func:`bt_nav.grading.handin_files.find_node`), and the checks are
:func:`bt_nav.grading.launch.check.check_launch`, as ``bt-nav grade --class`` runs them.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bt_nav.grading.handin_files import files_in, find_node
from bt_nav.grading.launch.check import LAUNCH_NAME, LaunchReport, check_launch


def find_launch(folder: Path) -> Path | None:
    """The student's launch file: the sheet's name, else the one ``*.launch.py`` / ``*_launch.py`` (None: none)."""
    named = files_in(folder, LAUNCH_NAME)
    if named:
        return named[0]
    others = [p for p in files_in(folder, "*.py") if p.name.endswith(("launch.py", "_launch.py"))]
    return others[0] if len(others) == 1 else None


def launch_target(target: Path, node: Path | None = None) -> tuple[Path | None, Path | None, Path]:
    """(the launch file, the node file, the hand-in folder) of ``target``: a launch file (its folder is the hand-in)
    or a hand-in folder (its launch file and node found as a class's are). ValueError: no such file or folder."""
    target = Path(target)
    if not target.exists():
        raise ValueError(f"{target}: no such file or folder")
    folder = target if target.is_dir() else _package_root(target.parent)
    launch = find_launch(folder) if target.is_dir() else target
    if node is None:
        node = find_node(folder)[0]
    return launch, node, folder


def _package_root(folder: Path) -> Path:
    """The ROS package a launch file is in (``pkg/launch/x.launch.py`` -> ``pkg``: the nearest folder up to two
    levels above holding a ``package.xml``), else its own folder: where its params files and includes are found."""
    for candidate in [folder, *list(folder.resolve().parents)[:2]]:
        if (candidate / "package.xml").is_file():
            return candidate
    return folder


def check_target(target: Path, node: Path | None = None) -> LaunchReport:
    """The launch checks of ``target`` (:func:`launch_target`) for ``node`` (None: the folder's node, if any)."""
    launch, node, folder = launch_target(target, node)
    return check_launch(launch, node, folder)


def node_of_command(command: str) -> Path | None:
    """The node file an ``--exe`` command runs (its last ``.py`` word that exists), None when it names none."""
    try:
        words = shlex.split(command)
    except ValueError:
        return None
    files = [Path(w) for w in words if w.endswith(".py") and Path(w).is_file()]
    return files[-1] if files else None


def attach_launch(grid_dir: Path, report: LaunchReport | None) -> None:
    """Put the launch checks into the grid's ``grade.json`` (``"launch"``, as a hand-in's class row holds them)."""
    from bt_nav.grading.report import GRADE_FILE  # here: the evaluation's sandboxed child imports this package

    path = Path(grid_dir) / GRADE_FILE
    if report is None or not path.is_file():
        return
    doc = json.loads(path.read_text(encoding="utf-8"))
    doc["launch"] = report.to_dict()
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    tmp.replace(path)


def exit_code(report: LaunchReport) -> int:
    """``bt-nav check-launch``'s exit code: 0 every check passed, 1 one failed, 2 one not checked (none failed)."""
    if not report.passed:
        return 1
    return 0 if report.checked else 2


def exe_launch(launch: str | None, command: str, show: Callable[[str], Any] = print) -> LaunchReport | None:
    """``bt-nav grade --exe CMD --launch FILE``: FILE's checks for the node CMD runs, each line shown (None without
    ``--launch``). ValueError: FILE does not exist."""
    if launch is None:
        return None
    report = check_target(Path(launch), node_of_command(command))
    for line in [*report.lines(), *(f"note: {n}" for n in report.notes)]:
        show(f"  {line}")
    return report


def launch_passed(grid_dir: Path) -> bool:
    """Whether the grid's ``grade.json`` holds no failed launch check (True: none attached, or every one passed)."""
    from bt_nav.grading.report import GRADE_FILE  # here: the evaluation's sandboxed child imports this package

    try:
        doc = json.loads((Path(grid_dir) / GRADE_FILE).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return True
    launch = doc.get("launch") if isinstance(doc, dict) else None
    return not isinstance(launch, dict) or LaunchReport.from_dict(launch).passed
