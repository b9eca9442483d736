"""Do two commits give the same verdicts? The lock-step grids and the real recordings judged at each commit, their
verdict JSON compared byte for byte (after dropping the wall-clock fields).

Why: a change that should not change any verdict (a move of modules, a refactor of the judge's plumbing) is proven by
running the same commands on the commit before and the commit after, not by a golden file that every real change of
the judge would have to rewrite. Each commit is checked out as a detached worktree in a scratch folder and run with
its own code on ``PYTHONPATH`` (``<tree>:<tree>/sim``), through the ``bt-nav`` command line only, so the script works
on any two commits whose commands take these options:

- the lab grid in lock-step (``bt-nav grade --profile lab --worlds all --maneuvers A,B,C``, with a LiDAR axis) and
  the homework grid (``bt-nav grade --worlds all``): the grid's JSON (its rows, summary and overall);
- every cell of both grids again as one mission (``bt-nav lockstep ... --json``): the judge's whole verdict (checks,
  maneuvers, report lines), the trajectory and the parameters;
- every real recording in ``--realbags`` (``bt-nav checkoff --bag DIR --maneuver C --json``).

Dropped before comparing (they measure the machine, not the run): every ``wall_time`` and ``wall_time_mean``.

    python -m bench.verdicts_before_after BEFORE AFTER [--seeds 2] [--realbags DIR] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
#: Fields that say how long the machine took, never what the judge said.
WALL_CLOCK = frozenset({"wall_time", "wall_time_mean"})
LAB_LIDARS = "profile,lds02,rplidar"


def strip(value: Any) -> Any:
    """``value`` without its :data:`WALL_CLOCK` fields, at any depth."""
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if k not in WALL_CLOCK}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def canonical(path: Path) -> str:
    """A verdict file as canonical JSON text (sorted keys, wall clock dropped): equal text, equal verdict."""
    return json.dumps(strip(json.loads(path.read_text())), sort_keys=True, indent=1)


class Tree:
    """One commit checked out (detached) in ``folder``, whose ``bt-nav`` runs with that commit's code."""

    def __init__(self, commit: str, folder: Path) -> None:
        self.commit, self.folder = commit, folder
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "--force", str(folder), commit],
                       check=True, capture_output=True)
        self.env = {**os.environ, "PYTHONPATH": f"{folder}:{folder / 'sim'}",
                    "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}

    def bt_nav(self, *args: str, ok: tuple[int, ...] = (0, 1)) -> None:
        """``bt-nav ARGS`` at this commit (exit 1 is a failed verdict, still a verdict)."""
        proc = subprocess.run([sys.executable, "-m", "bt_nav.cli", *args], cwd=self.folder, env=self.env,
                              capture_output=True, text=True)
        if proc.returncode not in ok:
            raise RuntimeError(f"{self.commit}: bt-nav {' '.join(args)} exited {proc.returncode}:\n{proc.stderr}")

    def remove(self) -> None:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(self.folder)], check=False,
                       capture_output=True)


def grids(tree: Tree, out: Path, seeds: int) -> dict[str, Path]:
    """The two lock-step grids (their JSON), then each of their cells as one mission (its verdict JSON)."""
    found: dict[str, Path] = {}
    plans = {"lab": ["--profile", "lab", "--worlds", "all", "--maneuvers", "A,B,C", "--lidars", LAB_LIDARS],
             "homework": ["--worlds", "all"]}
    for name, plan in plans.items():
        grid = out / f"grid_{name}.json"
        tree.bt_nav("grade", *plan, "--seeds", str(seeds), "--jobs", "1", "--json", str(grid))
        found[f"grid {name}"] = grid
        for run in json.loads(grid.read_text())["runs"]:
            lidar = run.get("lidar") or ""
            key = f"{run['profile']} {run['world']} {run['maneuver']} seed {run['seed']} {lidar or 'profile'}"
            path = out / (key.replace(" ", "_") + ".json")
            args = ["--profile", run["profile"], "--world", run["world"], "--maneuver", run["maneuver"],
                    "--seed", str(run["seed"]), *(["--sim-param", f"lidar={lidar}"] if lidar else [])]
            tree.bt_nav("lockstep", *args, "--json", str(path))
            found[f"mission {key}"] = path
    return found


def recordings(tree: Tree, out: Path, realbags: Path) -> dict[str, Path]:
    """Every real recording in ``realbags`` judged as maneuver C (its verdict JSON)."""
    found: dict[str, Path] = {}
    for bag in sorted(p for p in realbags.iterdir() if p.is_dir()) if realbags.is_dir() else []:
        path = out / f"bag_{bag.name}.json"
        tree.bt_nav("checkoff", "--bag", str(bag), "--maneuver", "C", "--json", str(path))
        found[f"bag {bag.name}"] = path
    return found


def verdicts(commit: str, scratch: Path, seeds: int, realbags: Path) -> dict[str, str]:
    """Every verdict of ``commit``, by name, as canonical JSON text."""
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", commit], check=True, capture_output=True,
                         text=True).stdout.strip()
    out = scratch / f"verdicts_{sha}"
    out.mkdir(parents=True, exist_ok=True)
    tree = Tree(commit, scratch / f"tree_{sha}")
    try:
        files = {**grids(tree, out, seeds), **recordings(tree, out, realbags)}
    finally:
        tree.remove()
    print(f"{commit} ({sha}): {len(files)} verdict files in {out}", file=sys.stderr)
    return {name: canonical(path) for name, path in files.items()}


def compare(before: dict[str, str], after: dict[str, str]) -> list[str]:
    """What differs: a verdict only one side has, or one whose JSON differs."""
    problems = [f"only before: {n}" for n in sorted(before.keys() - after.keys())]
    problems += [f"only after: {n}" for n in sorted(after.keys() - before.keys())]
    problems += [f"differs: {n}" for n in sorted(before.keys() & after.keys()) if before[n] != after[n]]
    return problems


def main(argv: list[str] | None = None) -> int:
    """Run both commits, print the comparison; exit 1 on any difference."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--seeds", type=int, default=2, help="seeds 0..N-1 of both grids (default 2)")
    default_bags = os.environ.get("BT_NAV_REALBAGS", str(ROOT.parent / "shared" / "realbags"))
    parser.add_argument("--realbags", default=default_bags, help="a folder of real recordings (default "
                        "$BT_NAV_REALBAGS, else ../shared/realbags)")
    parser.add_argument("--keep", default=None, help="keep the verdict files here (default: a scratch folder, removed)")
    args = parser.parse_args(argv)
    scratch = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="verdicts_"))
    try:
        before = verdicts(args.before, scratch, args.seeds, Path(args.realbags))
        after = verdicts(args.after, scratch, args.seeds, Path(args.realbags))
    finally:
        if not args.keep:
            shutil.rmtree(scratch, ignore_errors=True)
    problems = compare(before, after)
    kinds = {kind: sum(n.startswith(kind) for n in before) for kind in ("grid", "mission", "bag")}
    same = len(before.keys() & after.keys()) - sum(p.startswith("differs") for p in problems)
    print(f"{len(before)} verdict files compared ({kinds['grid']} grids, {kinds['mission']} missions, "
          f"{kinds['bag']} recordings; wall-clock fields dropped: {', '.join(sorted(WALL_CLOCK))}): "
          f"{same} identical, {len(problems)} problems")
    print("\n".join(problems))
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main())
