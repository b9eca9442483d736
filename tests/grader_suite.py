"""The grader's confusion matrix: right nodes passed, mistakes failed, each for its own reason.

A grader is judged by two things: it fails every wrong node for its real reason (the mutation suite: the lab
fixture's ``--mistake`` copies) and it never fails a right one (the correct-variant suite: the fixture's
``--variant`` nodes, each a reasonable reading of the lab sheet, written the ways students write them). This
command grades both over real DDS, as an instructor grades a class (``bt-nav grade --class``, one class per lab
choice for the right nodes and one per choice for its mistakes, each on the choice's default grid: the cells a
class is graded on must catch the mistakes), and prints one table::

    python tests/grader_suite.py                      # every variant and mistake, three LiDARs, --jobs auto
    python tests/grader_suite.py --hogs 2             # the same with two CPU hogs running
    python tests/grader_suite.py --compare runs/grader-suite/confusion.json --out runs/grader-suite-loaded
    python tests/grader_suite.py --only mistakes --mistakes left_or_right,ignores_safety_distance --lidars lds01
    python tests/grader_suite.py --only generated --generated 100   # right nodes nobody wrote by hand (issue 52)
    python tests/grader_suite.py --only mixed         # issue 54's folder of four hand-ins, A, B and C mixed

``--generated N`` also grades N generated right nodes (``tests/nodegen``: seeds 0..N-1, each on a sample of its
choice's default-grid cells, every cell getting >= 20 nodes when N >= 100) and each one's mutants (the sheet's
mistakes, on the choice's default grid, each to fail for its reason: ``tests.nodegen.EXPECT``).

``--compare`` names every run whose verdict differs from an earlier suite's (the verdicts must not depend on the
machine's load). ``make grader-suite`` runs the first line. Written: ``<out>/confusion.json`` (every run's verdict)
and ``<out>/confusion.md`` (the table and every wrong result), beside each class's own pages.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import Any

from bt_nav.grading.grid import cell_label

FIXTURE = Path(__file__).resolve().parent / "fixtures" / "lab_student_node.py"
#: The mutation suite: what the grader must say of each choice's mistakes (``LAB_BY_CHOICE``) and which show on one
#: LiDAR only. Each choice's mistakes are graded in the choice's default grid (``--maneuvers X``, no ``--worlds``):
#: the grid a class is graded on must catch them.
MUTANTS = Path(__file__).resolve().parent / "ros" / "test_mutants.py"
#: Issue 54's class: a folder of four hand-ins, each on its own choice (its ``# CHOICE:`` line) and default grid;
#: how each must come out by its runs (the launch typo of ``c_safety_dist`` fails its hand-in, not its runs:
#: ``tests/ros/test_mixed_class.py`` reads that) and, for a mistake, the mutation suite's expectation it answers to.
MIXED = Path(__file__).resolve().parent / "fixtures" / "handins_mixed"
MIXED_JUDGED = {"right_c": ("right", "right_c"), "right_a": ("right", "right_a"),
                "c_safety_dist": ("right", "c_safety_dist"), "b_left_or_right": ("mistake", "B_left_or_right")}


def _load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module  # a dataclass of the module looks itself up there
    spec.loader.exec_module(module)
    return module


def fixture() -> ModuleType:
    """The lab fixture as a module (its VARIANTS and MISTAKES)."""
    return _load(FIXTURE)


Expected = dict[str, dict[str, tuple[str, str | None]]]


def expectations() -> tuple[Expected, dict[str, tuple[str, str]]]:
    """The mutation suite's table: per choice, each mistake's reason (a regex) and the cells it must fail in (a
    regex on the cell's label; None: every cell); and the (right, wrong) LiDAR of those only some LiDARs show."""
    mutants = _load(MUTANTS)
    return mutants.LAB_BY_CHOICE, mutants.BY_LIDAR


def mistake_student(choice: str, mistake: str) -> str:
    """A mistake's student name in its choice's class (and in the matrix): ``A_front_is_whole_scan``."""
    return f"{choice}_{mistake}"


def classes(node: ModuleType, variants: Sequence[str], mistakes: Sequence[str],
            choices: Sequence[str] = "ABC") -> dict[str, dict[str, Any]]:
    """The classes to grade, each on its choice's default grid: one per lab choice of the right variants, one per
    choice of that choice's mistakes (those among ``mistakes`` the mutation suite expects of it)."""
    command = f"{sys.executable} {FIXTURE}"
    out: dict[str, dict[str, Any]] = {}
    for name in variants:
        choice = node.VARIANTS[name][0]
        right = out.setdefault(f"right_{choice}", {"grid": ("--maneuvers", choice), "students": {}})
        right["students"][name] = f"{command} --variant {name}"
    table = expectations()[0]
    for choice in choices:
        wanted = [name for name in mistakes if name in table[choice]]
        if wanted:
            out[f"mistakes_{choice}"] = {"grid": ("--maneuvers", choice), "students": {
                mistake_student(choice, name): f"{command} --choice {choice} --seed 1 --mistake {name}"
                for name in wanted}}
    return out


def mixed_class() -> dict[str, Any]:
    """Issue 54's folder of hand-ins as a class of the suite: graded as a folder is, each on its own default grid."""
    return {"folder": MIXED, "grid": (), "students": dict.fromkeys(MIXED_JUDGED), "judged": MIXED_JUDGED}


def grade_class(name: str, spec: dict[str, Any], options: Sequence[str], out: Path) -> dict[str, list[dict]]:
    """Grade one class with ``bt-nav grade --class`` in a process of its own; each student's rows."""
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    manifest = folder / "class.yaml"
    manifest.write_text("".join(f"{student}: {command}\n" for student, command in spec["students"].items()))
    if spec.get("folder"):
        manifest = spec["folder"]
    argv = [sys.executable, "-m", "bt_nav.cli", "grade", "--profile", "lab", "--class", str(manifest),
            "--out", str(folder / "class"), *options, *spec["grid"]]
    with open(folder / "grade.log", "w", encoding="utf-8") as log:
        subprocess.run(argv, check=False, stdout=log, stderr=subprocess.STDOUT)
    rows = {}
    for student in spec["students"]:
        path = folder / "class" / student / "grade.json"
        rows[student] = json.loads(path.read_text())["runs"] if path.is_file() else []
    return rows


def judged(kind: str, student: str, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """One student's line of the matrix: how it came out and, where it came out wrong, why. A right node must pass
    every run; a mistake must fail every run for its own reason (:func:`expectations`), except one that only some
    LiDARs show (it must pass with the one it reads right and fail with the other)."""
    runs = [{"cell": cell_label(r), "lidar": r.get("lidar") or "", "seed": r.get("seed"), "passed": bool(r["passed"]),
             "reason": r["reason"]} for r in rows]
    if not runs:
        return {"student": student, "kind": kind, "outcome": "not graded", "runs": runs, "wrong": ["no runs"]}
    if kind == "right":  # a run not graded (a machine too busy for 1x, twice) is no verdict either way
        unjudged = [f"{cell_label(r)} seed {r['seed']}: {r['reason']}" for r in rows if r.get("not_graded")]
        wrong = [f"{cell_label(r)} seed {r['seed']}: {r['reason']}" for r in rows
                 if not r["passed"] and not r.get("not_graded")]
        outcome = "failed" if wrong else "not graded" if len(unjudged) == len(rows) else "passed"
        return {"student": student, "kind": kind, "outcome": outcome, "runs": runs, "wrong": wrong + unjudged}
    table, by_lidar = expectations()
    choice, mistake = student.split("_", 1)
    pattern, cells = table[choice][mistake]
    good, bad = by_lidar.get(mistake, (None, None))
    wrong, judged_runs = [], 0
    for r in runs:
        if cells is not None and not re.search(cells, r["cell"]):
            continue  # a cell where this mistake does not show: not held against the grader either way
        judged_runs += 1
        if r["lidar"] == good and not r["passed"]:
            wrong.append(f"{r['cell']}: failed with the LiDAR it reads right ({r['reason']})")
        elif (good is None or r["lidar"] == bad) and (r["passed"] or not re.search(pattern, r["reason"])):
            wrong.append(f"{r['cell']}: {'PASSED' if r['passed'] else r['reason']}")
    if not judged_runs:
        wrong.append(f"no run in the cells it must fail in ({cells})")
    return {"student": student, "kind": kind, "outcome": "failed for its reason" if not wrong else "wrong",
            "runs": runs, "wrong": wrong}


def matrix(lines: list[dict[str, Any]]) -> str:
    """The confusion matrix and every wrong result, as Markdown."""
    right = [x for x in lines if x["kind"] == "right"]
    mistakes = [x for x in lines if x["kind"] == "mistake"]
    runs = sum(len(x["runs"]) for x in right)
    passed = sum(r["passed"] for x in right for r in x["runs"])
    out = ["| | nodes | runs | passed | failed for its reason | wrong |", "|---|---|---|---|---|---|",
           f"| right nodes (correct variants) | {len(right)} | {runs} | {passed} | - | {runs - passed} runs |",
           f"| mistakes (mutation suite) | {len(mistakes)} | {sum(len(x['runs']) for x in mistakes)} | - | "
           f"{sum(x['outcome'] == 'failed for its reason' for x in mistakes)} nodes | "
           f"{sum(x['outcome'] != 'failed for its reason' for x in mistakes)} nodes |", ""]
    for x in lines:
        out.append(f"- {x['kind']} `{x['student']}`: {x['outcome']}" + "".join(f"\n  - {w}" for w in x["wrong"]))
    return "\n".join(out) + "\n"


def differences(lines: list[dict[str, Any]], earlier: Path) -> list[str]:
    """The runs whose verdict (passed or not) differs from an earlier suite's confusion.json."""
    before = {(x["student"], r["cell"], r["seed"]): r["passed"] for x in json.loads(earlier.read_text())
              for r in x["runs"]}
    return [f"{x['student']} {r['cell']} seed {r['seed']}: {'passed' if r['passed'] else 'failed'} now"
            for x in lines for r in x["runs"] if before.get((x["student"], r["cell"], r["seed"]), r["passed"])
            != r["passed"]]


@contextmanager
def cpu_hogs(count: int) -> Iterator[None]:
    """``count`` busy processes for the duration (each dies with this process, on any signal)."""
    from bt_nav.ros.supervise import child_preexec

    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"], preexec_fn=child_preexec(os.getpid()))
            for _ in range(count)]
    try:
        yield
    finally:
        for hog in hogs:
            hog.send_signal(signal.SIGKILL)
            hog.wait()


def generated_classes(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The classes of ``--generated N``: the generated right nodes per cell and their mutants per choice (the node
    files written under ``<out>/generated``)."""
    if args.generated <= 0:
        return {}
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run as a file: tests.nodegen from the repository
    from tests.nodegen import suite

    return suite.classes(args.generated, (args.out / "generated").resolve(), sys.executable,
                         with_mutants=not args.no_generated_mutants)


def judged_generated(student: str, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """A generated mutant's line of the matrix (:func:`tests.nodegen.suite.judged_mutant`)."""
    from tests.nodegen import suite

    return suite.judged_mutant(student, rows)


def parse(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("runs/grader-suite"))
    parser.add_argument("--only", choices=("all", "right", "mistakes", "generated", "mixed"), default="all",
                        help="generated: only the --generated nodes and their mutants; mixed: only issue 54's "
                        "folder of four hand-ins")
    parser.add_argument("--generated", type=int, default=0, metavar="N",
                        help="also grade N generated right nodes (tests/nodegen) and their mutants")
    parser.add_argument("--no-generated-mutants", action="store_true", help="grade the generated right nodes only")
    parser.add_argument("--variants", default="", help="comma-separated variant names (default: every one)")
    parser.add_argument("--mistakes", default="", help="comma-separated mistakes (default: every one the mutation "
                                                       "suite expects of a choice, each graded as that choice)")
    parser.add_argument("--choices", default="ABC", help="the lab choices whose mistakes are graded (e.g. AB)")
    parser.add_argument("--lidars", default="lds01,lds02,rplidar")
    parser.add_argument("--seeds", default="1")
    parser.add_argument("--jobs", default="auto")
    parser.add_argument("--hogs", type=int, default=0, help="CPU hogs running during the grade")
    parser.add_argument("--classes", type=int, default=4, help="classes graded at once (default 4)")
    parser.add_argument("--rtf-max", default=None, help="the grades' --rtf-max (default: theirs; 0: no cap)")
    parser.add_argument("--compare", type=Path, help="an earlier suite's confusion.json: name differing verdicts")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    """Grade, print the matrix; exit 0 only if every right node passed and every mistake failed for its reason."""
    args = parse(argv)
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    node = fixture()
    variants = [v for v in args.variants.split(",") if v] or list(node.VARIANTS)
    mistakes = [m for m in args.mistakes.split(",") if m] or sorted({m for t in expectations()[0].values() for m in t})
    todo = classes(node, variants if args.only in ("all", "right") else [],
                   mistakes if args.only in ("all", "mistakes") else [], args.choices)
    todo.update(generated_classes(args))
    if args.only in ("all", "mixed"):
        todo["mixed"] = mixed_class()
    # at the shipped default (1x, real time): a class's grid options last, so a class's own --lidars wins
    options = ["--lidars", args.lidars, "--seeds", args.seeds, "--jobs", args.jobs, "--record", "off",
               "--progress", "off", *(["--rtf-max", args.rtf_max] if args.rtf_max is not None else [])]
    lines = []
    with cpu_hogs(args.hogs), ThreadPoolExecutor(max_workers=max(1, args.classes)) as pool:
        # several classes at once: each run takes one of the machine's places (bt_nav.grading.admission), so the
        # classes share them instead of queueing behind each other's last runs
        graded = {name: pool.submit(grade_class, name, spec, options, args.out) for name, spec in todo.items()}
        for name, future in graded.items():
            kind = "mistake" if name.startswith("mistakes") else "right"
            for student, rows in future.result().items():
                if "judged" in todo[name]:  # a folder of hand-ins: each student's own expectation
                    lines.append(judged(*todo[name]["judged"][student], rows))
                    continue
                lines.append(judged_generated(student, rows) if name.startswith("gen_mutants")
                             else judged(kind, student, rows))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "confusion.json").write_text(json.dumps(lines, indent=1))
    text = matrix(lines)
    if args.compare is not None:
        changed = differences(lines, args.compare)
        text += f"\nVerdicts that differ from {args.compare}: {len(changed)}\n" + "".join(f"- {c}\n" for c in changed)
    (args.out / "confusion.md").write_text(text)
    print(text)
    ok = all(x["outcome"] in ("passed", "failed for its reason") for x in lines)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
