"""The two check-off judges on a subset of the grader suite's lab nodes (tests/fixtures/lab_student_node.py: right
variants and mistakes), graded over DDS by ``bt-nav grade --exe`` with the real-robot effects on (see
:mod:`bench.judge_agreement`): the grader's verdict is the simulator's judge's (ground truth), and each run's bag is
judged again from its /odom, /scan, /cmd_vel and /rosout alone, with the grader's toggle_navigation calls as the
schedule (as ``bt-nav checkoff --robot --call-toggle`` knows its own).

The grader's bag leaves /odom out (:data:`bt_nav.grading.exe.bag.RUN_TOPICS`: its pictures draw ground truth);
this benchmark records it too: each grade runs as ``bt-nav grade`` in a process of its own that first adds /odom to
that tuple (:data:`GRADE_WITH_ODOM`).

    python -m bench.judge_agreement_nodes DIR [--rtf 1] [--out table.md]
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from bench.judge_agreement import EFFECTS, Row, compare
from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.judge.recorded import ServiceCall, judge_recording
from bt_nav.media.robotbag import read_robot_bag

#: ``python -c`` code: ``bt-nav grade`` with /odom in its runs' bags (the module docstring), argv after it.
GRADE_WITH_ODOM = ("import sys; import bt_nav.grading.exe.bag as bag; from bt_nav.media.bag import ODOM; "
                   "bag.RUN_TOPICS = (*bag.RUN_TOPICS, ODOM); from bt_nav.cli import main; "
                   "raise SystemExit(main(['grade', *sys.argv[1:]]))")

#: (label, maneuver, arena, the fixture's options): right variants and mistakes the grader must fail.
NODES = [
    ("right c_beams", "C", "lab_object", "--variant c_beams"),
    ("right c_clock_timed", "C", "lab_object", "--variant c_clock_timed"),
    ("right a_short_turns", "A", "lab_object", "--variant a_short_turns"),
    ("right a_stands_first", "A", "lab_object", "--variant a_stands_first"),
    ("right b_spins_left", "B", "lab_dead_end", "--variant b_spins_left"),
    ("right b_clock_timed", "B", "lab_dead_end", "--variant b_clock_timed"),
    ("mistake half_angle C", "C", "lab_object", "--choice C --mistake half_angle"),
    ("mistake wrong_side C", "C", "lab_object", "--choice C --mistake wrong_side"),
    ("mistake forward_while_turning C", "C", "lab_object", "--choice C --mistake forward_while_turning"),
    ("mistake half_angle B", "B", "lab_dead_end", "--choice B --mistake half_angle"),
    ("mistake spins_360 A", "A", "lab_object", "--choice A --mistake spins_360"),
    ("mistake ignores_toggle_off C", "C", "lab_object", "--choice C --mistake ignores_toggle_off"),
]
#: Real time, as on the robot: a Twist has no stamp, so the bag times /cmd_vel by its arrival at the recorder,
#: which at the grader's 5x real time lags the commands by up to half a sim second (a turn's first 12 deg were
#: missed so once); at 1x the lag is what a robot's recorder sees (milliseconds).
RTF = 1.0
#: The verdict's (request, answer) time names of each toggle_navigation call, and the data sent.
CALL_TIMES = [("activation_requested", "activated", True), ("cycle_off_requested", "cycle_off", False),
              ("cycle_on_requested", "cycle_on", True), ("deactivation_requested", "deactivated", False)]


def calls_of(verdict: dict[str, Any]) -> list[ServiceCall]:
    """The grader's toggle_navigation calls on the sim clock (its verdict's times are from t0_sim)."""
    t0, times = float(verdict["t0_sim"]), verdict["times"]
    out = []
    for asked, answered, data in CALL_TIMES:
        if times.get(asked) is not None:
            done = times.get(answered)
            out.append(ServiceCall(t0 + times[asked], data, None if done is None else t0 + done, done is not None))
    return out


def grade_one(label: str, maneuver: str, world: str, options: str, out: Path, effects: dict[str, Any],
              rtf: float = RTF) -> Row:
    """Grade one node in one cell (seed 0, LDS-02, the effects, at ``rtf``); the
    :class:`bench.judge_agreement.Row`."""
    command = f"{shlex.quote(sys.executable)} tests/fixtures/lab_student_node.py {options}"
    params = [a for name, value in effects.items() if name != "lidar" for a in ("--sim-param", f"{name}={value}")]
    run_dir = out / label.replace(" ", "_")
    argv = ["--profile", "lab", "--exe", command, "--maneuvers", maneuver, "--worlds", world, "--seeds", "1",
            "--lidars", str(effects["lidar"]), "--videos", "off", "--record", "on", "--out", str(run_dir),
            "--rtf", f"{rtf:g}", *(["--realtime-check", "off"] if rtf == 1 else []), *params]
    # the grader's own report is progress, not this table: to stderr
    subprocess.run([sys.executable, "-c", GRADE_WITH_ODOM, *argv], stdout=sys.stderr, check=False)
    (cell,) = [p for p in run_dir.iterdir() if (p / "verdict.json").is_file()]
    truth = json.loads((cell / "verdict.json").read_text())
    rec = read_robot_bag(cell / "bag")
    rec.calls = calls_of(truth)
    odo = judge_recording(rec, CheckoffConfig(maneuver=maneuver, lidar=str(effects["lidar"])))
    return compare(f"{label} ({world})", truth, odo, float(truth["t0_sim"]), float(odo["feed"]["t0"]))


def nodes_table(out: Path, rtf: float = RTF) -> str:
    """The subset (:data:`NODES`), graded and judged twice, as a Markdown table."""
    started = time.perf_counter()
    rows = []
    for label, maneuver, world, options in NODES:
        row = grade_one(label, maneuver, world, options, out, EFFECTS, rtf)
        rows.append(row)
        print(f"{row.cell}: truth {'PASSED' if row.truth else 'FAILED'}, odometry "
              f"{'PASSED' if row.odometry else 'FAILED'}" + (f" ({row.cause})" if row.cause else ""),
              file=sys.stderr, flush=True)
    lines = ["| lab node (grader suite) | ground truth | odometry | maneuvers: same verdict | largest angle / motion "
             "difference |", "|---|---|---|---|---|"]
    for r in rows:
        same = sum(a == b for a, b, _, _ in r.maneuvers)
        angle = max((d for _, _, d, _ in r.maneuvers), default=0.0)
        move = max((m for _, _, _, m in r.maneuvers), default=0.0)
        lines.append(f"| {r.cell} | {'PASSED' if r.truth else 'FAILED'} | {'PASSED' if r.odometry else 'FAILED'} | "
                     f"{same}/{len(r.maneuvers)}" + (f" (+{r.unmatched} not judged from odometry)" if r.unmatched
                                                     else "") + f" | {angle:.2f} deg / {move:.3f} m |")
    agree = sum(r.truth == r.odometry for r in rows)
    causes = [f"- {r.cell}: {r.cause}" for r in rows if r.cause]
    lines += ["", f"{agree}/{len(rows)} verdicts agree; {len(rows)} graded runs (DDS at {rtf:g}x real time, seed 0, "
              f"the same effects) in {time.perf_counter() - started:.0f} s.", *causes]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Grade the subset into DIR, print the table (and write it with ``--out``)."""
    parser = argparse.ArgumentParser(prog="python -m bench.judge_agreement_nodes", description=__doc__.splitlines()[0])
    parser.add_argument("dir", help="a new or empty directory for the grades")
    parser.add_argument("--rtf", type=float, default=RTF, help="the graded runs' real-time factor (default 1: a bag's "
                        "unstamped /cmd_vel is timed by its arrival, as on a robot)")
    parser.add_argument("--out", help="also write the Markdown table here")
    args = parser.parse_args(argv)
    text = nodes_table(Path(args.dir), args.rtf)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
