"""A hand-in's files found in its folder: the node (the sheet's ``reactive_navigator.py``, else the one Python file
defining an rclpy ``Node``), searched to any depth with a colcon workspace's outputs and hidden folders skipped.

Why its own module: both a class's hand-ins (:mod:`bt_nav.grading.handins`) and a launch check outside a class
(:mod:`bt_nav.grading.launch`, which finds the launch file the same way) search a folder alike, and the hand-ins
check their launch files through the launch package: the search sits below both.
"""

from __future__ import annotations

import ast
from pathlib import Path

#: The lab sheet's name for the node file.
NODE_NAME = "reactive_navigator.py"
#: Folders never searched: a colcon workspace's outputs, caches.
SKIPPED = {"build", "install", "log", "__pycache__", "node_modules"}


def _visible(path: Path, top: Path) -> bool:
    return not any(part.startswith(".") or part in SKIPPED for part in path.relative_to(top).parts[:-1])


def files_in(folder: Path, pattern: str) -> list[Path]:
    """The files under ``folder`` matching ``pattern``, at any depth, hidden and skipped folders left out, sorted."""
    return sorted(p for p in folder.rglob(pattern) if p.is_file() and _visible(p, folder))


def defines_node(path: Path) -> bool | None:
    """Whether ``path`` defines a class deriving from rclpy's ``Node`` (None: not parseable Python)."""
    try:
        tree = ast.parse(path.read_bytes())
    except (OSError, SyntaxError, ValueError):
        return None
    names = {"rclpy.node.Node"}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module in ("rclpy.node", "rclpy"):
            names |= {a.asname or a.name for a in node.names if a.name == "Node"}
            names |= {f"{a.asname or a.name}.Node" for a in node.names if a.name == "node"}
        elif isinstance(node, ast.Import):
            names |= {f"{a.asname}.Node" for a in node.names if a.name == "rclpy.node" and a.asname}
    return any(isinstance(n, ast.ClassDef) and any(ast.unparse(b) in names for b in n.bases) for n in ast.walk(tree))


def find_node(folder: Path) -> tuple[Path | None, str | None]:
    """(the student's node file, None) or (None, why none: what was found instead)."""
    named = files_in(folder, NODE_NAME)
    if len(named) == 1:
        return named[0], None
    if named:
        return None, f"{len(named)} files named {NODE_NAME}: " + ", ".join(str(p.relative_to(folder)) for p in named)
    sources = [p for p in files_in(folder, "*.py") if not p.name.endswith("launch.py") and p.name != "setup.py"]
    verdicts = {p: defines_node(p) for p in sources}
    nodes = [p for p, v in verdicts.items() if v]
    if len(nodes) == 1:
        return nodes[0], None
    rel = [str(p.relative_to(folder)) for p in sources]
    if nodes:
        return None, (f"no {NODE_NAME}, and {len(nodes)} Python files define an rclpy Node ("
                      + ", ".join(str(p.relative_to(folder)) for p in nodes) + f"): name the node's {NODE_NAME}")
    broken = [str(p.relative_to(folder)) for p, v in verdicts.items() if v is None]
    found = f"Python files: {', '.join(rel)}" if rel else "no Python file"
    extra = f"; not valid Python: {', '.join(broken)}" if broken else ""
    return None, f"no {NODE_NAME} and no Python file defining an rclpy Node ({found}{extra})"
