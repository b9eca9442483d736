"""The project's layers hold: no import cycle among its modules, and no module imports a layer above its own.

Every ``import``/``from ... import`` in every module counts, at module level or inside a function (a lazy
import is still a dependency, and a lazy import back is still a cycle). The layers, bottom to top, are the
ones ``docs/architecture.md`` draws; a module may import its own layer's package and any layer below.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: (layer, module prefixes), bottom first. A module belongs to the first layer with the longest matching prefix.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("mission", ("bt_nav.mission",)),
    ("judges", ("bt_nav.judge",)),
    ("simulator", ("bt_nav_sim",)),
    ("media", ("bt_nav.media",)),
    ("ros", ("bt_nav.ros",)),
    ("simulator nodes", ("bt_nav.ros.nodes",)),
    ("testing", ("bt_nav.testing",)),
    ("run", ("bt_nav.run",)),
    ("grading", ("bt_nav.grading",)),
    ("commands", ("bt_nav.cli",)),
    ("bench", ("bench",)),
]
#: Package roots scanned (directory, package name).
SOURCES = ((ROOT / "bt_nav", "bt_nav"), (ROOT / "sim" / "bt_nav_sim", "bt_nav_sim"), (ROOT / "bench", "bench"))


def module_name(path: Path, base: Path, package: str) -> str:
    """``bt_nav/run/lockstep.py`` -> ``bt_nav.run.lockstep`` (a package's ``__init__`` is the package)."""
    parts = [package, *path.relative_to(base).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules() -> dict[str, Path]:
    """Every module of the project, by dotted name."""
    return {module_name(p, base, pkg): p for base, pkg in SOURCES for p in sorted(base.rglob("*.py"))}


def resolve(target: str, modules: dict[str, Path]) -> str | None:
    """The project module an import names (``a.b.c`` where only ``a.b`` is a module: ``a.b``), or None."""
    while target:
        if target in modules:
            return target
        target = target.rpartition(".")[0]
    return None


def imports_of(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The project modules ``name`` imports anywhere in its source."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            targets = [f"{base}.{alias.name}" for alias in node.names] + [base]
        for target in targets:
            hit = resolve(target, modules)
            if hit is not None and hit != name:
                found.add(hit)
    return found


def layer_of(name: str) -> int:
    """Index of the module's layer in :data:`LAYERS` (the longest matching prefix wins)."""
    best, best_len = -1, -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    return best


def graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    modules = project_modules()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def find_cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (as a path that ends where it starts), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (cycle := visit(nxt)) is not None:
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(edges):
        if node not in state and (cycle := visit(node)) is not None:
            return cycle
    return None


def test_every_module_has_a_layer() -> None:
    unplaced = [name for name in graph() if layer_of(name) < 0 and name not in ("bt_nav",)]
    assert not unplaced, f"modules in no layer (add them to LAYERS and docs/architecture.md): {unplaced}"


def test_no_import_cycle() -> None:
    cycle = find_cycle(graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_no_upward_import() -> None:
    upward = [f"{name} ({LAYERS[layer_of(name)][0]}) imports {dep} ({LAYERS[layer_of(dep)][0]})"
              for name, deps in sorted(graph().items()) for dep in sorted(deps)
              if name != "bt_nav" and layer_of(dep) > layer_of(name)]
    assert not upward, "imports against the layers:\n" + "\n".join(upward)


def test_nothing_outside_the_commands_imports_them() -> None:
    commands = layer_of("bt_nav.cli")
    users = [f"{name} imports {dep}" for name, deps in sorted(graph().items()) for dep in sorted(deps)
             if layer_of(dep) == commands and layer_of(name) != commands]
    assert not users, "\n".join(users)


def test_the_checker_sees_a_cycle_and_an_upward_import() -> None:
    """The checks can fail: a made-up cycle is found, and a made-up upward import is."""
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert layer_of("bt_nav.cli.demo") > layer_of("bt_nav.run.lockstep") > layer_of("bt_nav.mission.core")
    assert layer_of("bt_nav.ros.nodes.simulator") > layer_of("bt_nav.ros.runner") > layer_of("bt_nav_sim.core")


#: The folders the layers live in, each a top-level folder of a package (a sub-folder belongs to its parent's):
#: a folder may import its own and the ones below it, so a reader finds the layers in the tree as well.
FOLDERS: list[tuple[str, str]] = [
    ("bt_nav/mission", "bt_nav.mission"),
    ("bt_nav/judge", "bt_nav.judge"),
    ("sim/bt_nav_sim", "bt_nav_sim"),
    ("bt_nav/media", "bt_nav.media"),
    ("bt_nav/ros", "bt_nav.ros"),
    ("bt_nav (testing)", "bt_nav.testing"),
    ("bt_nav/run", "bt_nav.run"),
    ("bt_nav/grading", "bt_nav.grading"),
    ("bt_nav/cli", "bt_nav.cli"),
    ("bench", "bench"),
]


def folder_of(name: str) -> int:
    """Index of the module's folder in :data:`FOLDERS` (the longest matching package wins); -1 for none."""
    best, best_len = -1, -1
    for index, (_, package) in enumerate(FOLDERS):
        if (name == package or name.startswith(package + ".")) and len(package) > best_len:
            best, best_len = index, len(package)
    return best


def folder_graph() -> dict[str, set[str]]:
    """Folder -> the other folders its modules import."""
    edges: dict[str, set[str]] = {}
    for name, deps in graph().items():
        here = folder_of(name)
        if here < 0:
            continue
        targets = {FOLDERS[folder_of(dep)][0] for dep in deps if folder_of(dep) >= 0 and folder_of(dep) != here}
        edges.setdefault(FOLDERS[here][0], set()).update(targets)
    return edges


def test_every_module_lives_in_a_layer_folder() -> None:
    unplaced = [name for name in graph() if folder_of(name) < 0 and name != "bt_nav"]
    assert not unplaced, f"modules in no folder of FOLDERS: {unplaced}"


def test_folders_follow_the_layers() -> None:
    """No loop between folders (the simulator's nodes once sat in sim/ and imported bt_nav/ros, which imports sim/),
    and no folder importing one above it."""
    edges = folder_graph()
    cycle = find_cycle(edges)
    assert cycle is None, "folder loop: " + " -> ".join(cycle or [])
    order = [folder for folder, _ in FOLDERS]
    upward = [f"{a} imports {b}" for a, targets in sorted(edges.items()) for b in sorted(targets)
              if order.index(b) > order.index(a)]
    assert not upward, "folders importing upwards:\n" + "\n".join(upward)
    assert find_cycle({"sim": {"ros"}, "ros": {"sim"}}) == ["ros", "sim", "ros"]  # the check can fail


#: What the judges may import from the project: themselves and the mission core (their rules' parameters and
#: maneuver records); never the simulator, ROS, the media, the runs or the grading they serve.
JUDGE_MAY_IMPORT = ("bt_nav.judge", "bt_nav.mission")
#: What the simulator may import from the judges: the feed protocol and the readings it builds its truth feed from.
SIM_MAY_IMPORT_FROM_JUDGE = ("bt_nav.judge.feeds", "bt_nav.judge.readings")


def external_imports(path: Path) -> set[str]:
    """The top-level names of every absolute import in ``path`` (``rclpy`` of ``from rclpy.node import Node``)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            found |= {alias.name.partition(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            found.add(node.module.partition(".")[0])
    return found


def _within(name: str, packages: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in packages)


def test_the_judges_import_only_the_mission_core() -> None:
    """The judge package is pure: the same judge reads the simulator's truth, a bag and a live robot, so it imports
    neither rclpy nor the simulator (the simulator hands it a feed), only itself and bt_nav.mission."""
    modules = project_modules()
    judges = [name for name in modules if _within(name, ("bt_nav.judge",))]
    assert "bt_nav.judge.checkoff_core" in judges and "bt_nav.judge.referee_core" in judges
    wrong = [f"{name} imports {dep}" for name in judges for dep in sorted(imports_of(name, modules[name], modules))
             if not _within(dep, JUDGE_MAY_IMPORT)]
    wrong += [f"{name} imports {root}" for name in judges for root in sorted(external_imports(modules[name]))
              if root in ("rclpy", "bt_nav_sim", "rosbags", "launch", "launch_ros") or root.endswith("_msgs")]
    assert not wrong, "\n".join(wrong)


def test_no_module_under_sim_defines_a_judge_or_a_check() -> None:
    """sim/ holds the simulator and its worlds: no judge is defined or named there (the check-off judge and the
    referee live in bt_nav.judge), and the simulator takes from the judges only the feed protocol it builds its truth
    feed on."""
    sources = sorted((ROOT / "sim").rglob("*.py"))
    assert sources
    named = [str(p.relative_to(ROOT)) for p in sources if re.search(r"CheckoffJudge|class Referee", p.read_text())]
    assert not named, f"modules under sim/ defining or naming a judge: {named}"
    modules = project_modules()
    taken = [f"{name} imports {dep}" for name in modules if _within(name, ("bt_nav_sim",))
             for dep in sorted(imports_of(name, modules[name], modules))
             if _within(dep, ("bt_nav.judge",)) and not _within(dep, SIM_MAY_IMPORT_FROM_JUDGE)]
    assert not taken, "\n".join(taken)


#: The launch-file checking room and the entry points it offers (its ``__init__``).
LAUNCH_ROOM = "bt_nav.grading.launch"


def test_launch_file_checking_is_one_room_used_through_its_entry_points() -> None:
    """Reading, evaluating (with its stand-ins), reports and targets of launch files live in one package, and
    everything outside it imports that package's entry points, never a module inside it."""
    modules = project_modules()
    room = {name for name in modules if name.startswith(LAUNCH_ROOM + ".")}
    assert {f"{LAUNCH_ROOM}.{m}" for m in ("check", "evaluate", "standins", "static", "report", "target")} <= room
    flat = [name for name in modules if name.startswith("bt_nav.grading.launch") and not _within(name, (LAUNCH_ROOM,))]
    assert not flat, f"launch-file modules outside {LAUNCH_ROOM}: {flat}"
    inside = [f"{name} imports {dep}" for name in sorted(modules) if not _within(name, (LAUNCH_ROOM,))
              for dep in sorted(imports_of(name, modules[name], modules)) if dep in room]
    assert not inside, "import the launch room's entry points (bt_nav.grading.launch), not its modules:\n" + \
        "\n".join(inside)
