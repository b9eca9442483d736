"""``make judge-agreement``: do the check-off's two judges agree? Simulator runs with a real robot's effects on, each
judged twice: by the simulator's judge from ground truth and ray casts (what ``bt-nav checkoff`` does in the
simulator), and by the robot judge from the run's odometry, recorded scans and commands alone (what
``bt-nav checkoff --bag`` / ``--robot`` does on a TurtleBot: :func:`bt_nav.judge.recorded.judge_recording`).

The runs: bt_nav's own executive in lock-step (:class:`bt_nav.run.lockstep.Lockstep`, the lab profile), over the
lab's arenas x maneuvers A, B, C x seeds, with the effects real TurtleBot3 bags show: an LDS-02 (its beam count
varies scan to scan), 0.12 s actuation latency, odometry slip (1 % per sample, the simulator's noise) plus a pivot's
yaw over-read (``odom_yaw_scale``) and sideways drift (``odom_turn_drift``). What the robot judge gets is what a bag
of the run holds: /odom (the simulator's wheel odometry, never ground truth), /scan as published, /cmd_vel, the
executive's log lines, and the toggle_navigation calls (the judge's own, as ``--robot --call-toggle`` knows them).

Agreement: per run, the overall verdict; per maneuver, PASSED/FAILED and its angle (within 3 deg) and forward
motion. A run the odometry passes and ground truth fails is listed with its cause; so is every disagreement.
Collisions: a robot's recording has no contact sensor, so a run that fails from ground truth only on "no collision"
is counted apart (the TA sees contact), not as an agreement or a disagreement of the verdicts' rules.

A subset of the grader suite's lab nodes (right variants and mistakes), graded over DDS with the same effects and
judged twice, is :mod:`bench.judge_agreement_nodes` (``make judge-agreement`` runs both).

    python -m bench.judge_agreement [--seeds 4] [--out table.md]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav_sim.world import list_worlds

from bt_nav.judge.checkoff_core import CheckoffConfig, CheckoffJudge
from bt_nav.judge.recorded import Recording, ServiceCall, judge_recording
from bt_nav.mission.scan import Scan
from bt_nav.run.lockstep import Lockstep

#: The real-robot effects of every run (simulator parameters; docstring).
EFFECTS = {"lidar": "lds02", "actuation_latency": 0.12, "odom_yaw_scale": 1.015, "odom_turn_drift": 0.008}
ANGLE_TOLERANCE, MOTION_TOLERANCE = 3.0, 0.02  # deg, m: the figures of the two judges must be this close


class _Tap:
    """A lock-step sink that keeps what a bag of the run would hold (the robot's topics, no ground truth)."""

    def __init__(self) -> None:
        self.poses: list[tuple[float, float, float, float]] = []
        self.scans: list[tuple[float, Scan]] = []
        self.cmds: list[tuple[float, float, float]] = []
        self.lines: list[tuple[float, str, str]] = []

    def odom(self, t: float, x: float, y: float, yaw: float, v: float, w: float) -> None:
        self.poses.append((t, x, y, yaw))

    def scan(self, t: float, scan: Scan) -> None:
        self.scans.append((t, scan))

    def cmd(self, t: float, v: float, w: float) -> None:
        self.cmds.append((t, v, w))

    def announce(self, t: float, record: dict[str, Any]) -> None:
        if record.get("text"):
            self.lines.append((t, "bt_nav_executive", str(record["text"])))

    def __getattr__(self, name: str) -> Any:
        return lambda *args, **kwargs: None  # clock, ground_truth, tree, event, walkers: not a robot's topics


class _Calls:
    """Wraps the ground-truth judge: records its toggle_navigation calls and their answers (the schedule)."""

    def __init__(self, judge: CheckoffJudge) -> None:
        self.judge = judge
        self.calls: list[ServiceCall] = []

    def on_activate_result(self, t: float, data: bool, ok: bool, **kwargs: Any) -> None:
        self.calls.append(ServiceCall(t, data, t, ok, str(kwargs.get("message", ""))))
        self.judge.on_activate_result(t, data, ok, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.judge, name)


@dataclass
class Row:
    """One run judged twice."""

    cell: str
    truth: bool
    odometry: bool
    collided: bool
    maneuvers: list[tuple[bool, bool, float, float]] = field(default_factory=list)  # truth ok, odom ok, dangle, dmove
    unmatched: int = 0
    cause: str = ""


def run_once(world: str, maneuver: str, seed: int) -> Row:
    """One lock-step lab run with the effects, judged from ground truth and from odometry."""
    from bt_nav_sim.world import load_world

    from bt_nav.run.lab import lab_judge

    tap = _Tap()
    arena = load_world(world, seed=seed)
    wrapped: list[_Calls] = []

    def referee(_index: int, _name: str) -> Any:
        wrapped.append(_Calls(lab_judge(maneuver, arena, lidar=EFFECTS["lidar"])(0, "")))
        return wrapped[-1]

    run = Lockstep(arena, maneuver, seed, profile_name="lab", sink=tap, referee=referee, sim_params=EFFECTS)
    run.run()
    truth = wrapped[0].judge.results()
    body = run.robots[0].sim
    rec = Recording(tap.poses, tap.scans, tap.cmds, wrapped[0].calls, (body.model.mount_x, body.model.mount_y),
                    announcements=tap.lines)
    odo = judge_recording(rec, CheckoffConfig(maneuver=maneuver, lidar=EFFECTS["lidar"]))
    return compare(f"{world} {maneuver} seed {seed}", truth, odo)


def compare(cell: str, truth: dict[str, Any], odo: dict[str, Any], truth_t0: float = 0.0,
            odo_t0: float | None = None) -> Row:
    """The two verdicts side by side, maneuvers matched by their start (within 1 s) on one clock: each verdict's
    times count from its own time zero (``truth_t0``; the odometry verdict's ``feed.t0`` by default)."""
    shift = (float(odo["feed"]["t0"]) if odo_t0 is None else odo_t0) - truth_t0
    collided = any(c["name"] == "no collision" and not c["passed"] for c in truth["checks"])
    rules_truth = all(c["passed"] for c in truth["checks"] if c["name"] != "no collision") and \
        len(truth["maneuvers"]) >= 1
    row = Row(cell, bool(truth["passed"]), bool(odo["passed"]), collided)
    judged = list(odo["judged_maneuvers"])
    for m in truth["maneuvers"]:
        twin = [o for o in judged if abs(o["t"] + shift - m["t"]) <= 1.0]
        if not twin:
            row.unmatched += 1
            continue
        o = twin[0]
        judged.remove(o)
        row.maneuvers.append((bool(m["passed"]), bool(o["passed"]), abs(m["angle_deg"] - o["angle_deg"]),
                              abs(m["forward_motion"] - o["forward_motion"])))
    if row.odometry and not row.truth:
        failed = [c["name"] for c in truth["checks"] if not c["passed"]]
        row.cause = "ground truth fails " + ", ".join(failed) + ("" if rules_truth or not collided else "")
    elif row.odometry != rules_truth:
        failed_t = [c["name"] for c in truth["checks"] if not c["passed"]]
        failed_o = [c["name"] for c in odo["checks"] if not c["passed"]] + [n["name"] for n in odo["not_judged"]
                                                                            if n["name"].startswith("maneuver")]
        row.cause = f"truth fails {failed_t or 'nothing'}; odometry fails/not judged {failed_o or 'nothing'}"
    return row


def table(rows: list[Row], seconds: float) -> str:
    """The Markdown report: the totals, then every run where the two judges differ."""
    agree = sum(r.truth == r.odometry for r in rows)
    collided = [r for r in rows if r.collided]
    false_pass = [r for r in rows if r.odometry and not r.truth]
    pairs = [m for r in rows for m in r.maneuvers]
    same = sum(a == b for a, b, _, _ in pairs)
    worst_angle = max((d for _, _, d, _ in pairs), default=math.nan)
    worst_move = max((d for _, _, _, d in pairs), default=math.nan)
    close = sum(d <= ANGLE_TOLERANCE and m <= MOTION_TOLERANCE for _, _, d, m in pairs)
    out = [f"| runs | verdicts agree | odometry passes, ground truth fails | ground truth collided | maneuvers "
           f"matched | same PASSED/FAILED | within {ANGLE_TOLERANCE:g} deg and {MOTION_TOLERANCE:g} m | largest "
           "angle / motion difference |",
           "|---|---|---|---|---|---|---|---|",
           f"| {len(rows)} | {agree} ({100 * agree / max(1, len(rows)):.1f} %) | {len(false_pass)} | {len(collided)} "
           f"| {len(pairs)} (+{sum(r.unmatched for r in rows)} unmatched) | {same} | {close} | "
           f"{worst_angle:.2f} deg / {worst_move:.3f} m |", ""]
    differ = [r for r in rows if r.truth != r.odometry or r.unmatched or any(a != b for a, b, _, _ in r.maneuvers)]
    if differ:
        out += ["| run | ground truth | odometry | cause |", "|---|---|---|---|"]
        for r in differ:
            cause = r.cause or (f"{r.unmatched} maneuver(s) of ground truth not judged from odometry" if r.unmatched
                                else "a maneuver's verdict differs")
            out.append(f"| {r.cell} | {'PASSED' if r.truth else 'FAILED'} | {'PASSED' if r.odometry else 'FAILED'} "
                       f"| {cause} |")
        out.append("")
    effects = ", ".join(f"{k}={v}" for k, v in EFFECTS.items())
    out.append(f"Effects: {effects}; simulator noise on (LiDAR noise, 1 % odometry slip). {len(rows)} lock-step "
               f"runs in {seconds:.0f} s.")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Run the grid, print the table (and write it with ``--out``)."""
    parser = argparse.ArgumentParser(prog="python -m bench.judge_agreement", description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=4, help="seeds per arena and maneuver (default 4)")
    parser.add_argument("--worlds", default="", help="comma-separated lab arenas (default: every lab_* world)")
    parser.add_argument("--maneuvers", default="ABC")
    parser.add_argument("--out", help="also write the Markdown table here")
    args = parser.parse_args(argv)
    worlds = [w for w in args.worlds.split(",") if w] or list_worlds("lab")
    started = time.perf_counter()
    rows = []
    for world in worlds:
        for maneuver in args.maneuvers:
            for seed in range(args.seeds):
                row = run_once(world, maneuver, seed)
                rows.append(row)
                print(f"{row.cell}: truth {'PASSED' if row.truth else 'FAILED'}, odometry "
                      f"{'PASSED' if row.odometry else 'FAILED'}" + (f" ({row.cause})" if row.cause else ""),
                      file=sys.stderr, flush=True)
    text = table(rows, time.perf_counter() - started)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
