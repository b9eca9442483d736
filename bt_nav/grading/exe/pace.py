"""The speed of an ``--exe`` run: real time (1x, the default, the verdict) or a preview (``--rtf 0`` or ``--rtf N``
above 1), what each sets in the simulator, whether a 1x run kept real time, and the words for both.

Why real time: a check-off is a real-time event. The robot, its LiDAR and the student's node all run at 1x, so a
node is graded as it will run there: its world at 1x, its own clock whatever it is (ROS time, the wall clock, scan
stamps), its CPU shared with the run's simulator as with the robot's drivers. At 1x the simulator does not wait for
the node (``follow`` off): a node that answers late answers late, as on the robot. A 1x run costs about a tenth of a
core (it waits for the wall clock), so a whole grid runs at once (:mod:`bt_nav.grading.admission`) and its wall
time is the schedule's simulated length.

A 1x run is valid only if its simulator kept real time while it was judged: it measures its own lag
(:class:`bt_nav_sim.pacing.RealTimeKeeping`, ``pace.json``'s ``realtime``); a run that fell behind
(:func:`fell_behind`) is run again, and not graded if it falls behind again (:mod:`bt_nav.grading.exe.realtime`).

The preview (:func:`preview`), for a student iterating: ``--rtf 0`` runs as fast as the node keeps up (sim time
waits for the node's commands: :data:`bt_nav.grading.exe.run.FOLLOW_NODE`, the speed kept just behind the node's
pace by :class:`bt_nav_sim.pacing.StayBehind`, at most ``--rtf-max``), ``--rtf N`` at a fixed N. Every line and
report says "preview"; a failed cell is graded again at 1x before it is shown as a failure, and a preview writes no
score.

Each run's row carries what it achieved (:func:`with_speed`): ``rtf``, the simulator's sim seconds per wall second
over the run, and ``speed``: those seconds, the sim and wall seconds while the node's ``cmd_vel`` was followed (a
preview at 0) and, at 1x, how real time was kept while judging.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav_sim.pacing import CMD_VEL, PACE_FILE, read_pace

#: The speed of a graded run: the robot's.
REAL_TIME = 1.0
#: The scheduling priority change of a 1x run's simulator (``bt-nav sim --nice``; root only, else it runs at the usual
#: one): the robot's world, its LiDAR and its base, keep real time on a robot whatever the student's node and other
#: programs do, so on a shared machine the simulator goes ahead of them. The node keeps the usual priority, as on the
#: robot's computer. Its CPU is small (a 1x lab run's simulator uses a few per cent of a core).
SIM_NICE = -10
#: Sim seconds per wall second of a preview at ``--rtf 0`` while the node is not followed (silent).
IDLE_RTF = 10.0
#: Sim seconds of following below which a preview's ``node_rtf`` says nothing of the node.
MIN_FOLLOWED_SIM = 5.0
#: A 1x run fell behind when its simulator wrote off more than this many wall seconds within any 2 s while judged
#: (:data:`bt_nav_sim.pacing.KEEPING_WINDOW_S`, about a turn): a scan of the lab's LDS-01 comes every 0.2 s, and a
#: node timing its 90 deg turn by the wall clock at 1 rad/s turns 8.6 deg too far in a world that stood still for
#: 0.15 s, most of the sheet's 10 deg tolerance ...
WINDOW_LOST_S = 0.15
#: ... or when what it wrote off adds up to more than this share of the judged time.
LOST_SHARE = 0.02


def preview(rtf: float) -> bool:
    """Whether a grade at ``rtf`` is a preview (anything but real time): its verdicts are not the grade's."""
    return rtf != REAL_TIME


def check_speed(rtf: float, rtf_max: float | None) -> None:
    """Refuse a speed no grade keeps: ``--rtf`` negative or between 0 and 1 (slower than the robot judges nothing
    a 1x run does not), ``--rtf-max`` negative or beside a fixed ``--rtf``. ``rtf_max`` None: not given.

    Raises:
        ValueError: one line naming the option and what to do instead.
    """
    if rtf < 0 or 0 < rtf < REAL_TIME:
        raise ValueError(f"--rtf {rtf:g}: 1 (the default) grades at real time; 0 or above 1 is a preview (0: as fast "
                         "as the node keeps up)")
    if rtf_max is None:
        return
    if rtf_max < 0:
        raise ValueError(f"--rtf-max {rtf_max:g}: the cap of --rtf 0, >= 0 (0: no cap)")
    if rtf > 0:
        raise ValueError(f"--rtf-max caps the preview --rtf 0 (as fast as the node keeps up); --rtf {rtf:g} is a "
                         "fixed factor already: leave one of them out")


def rtf_cap(rtf: float, rtf_max: float | None) -> float:
    """The cap a grade runs with: ``--rtf-max`` as given at ``--rtf 0`` (0: none), else none."""
    return float(rtf_max) if rtf_max is not None and rtf == 0.0 else 0.0


def sim_pace(rtf: float, rtf_max: float = 0.0) -> dict[str, float | bool]:
    """The simulator's pacing parameters for a grade's speed (module docstring): at 1x nobody is followed (the
    robot's world does not wait for its node); a preview at a fixed factor follows the node; at 0 the cap
    ``rtf_max`` (0: none), the speed kept just behind the node's pace, :data:`IDLE_RTF` (or the cap) while silent."""
    if rtf == REAL_TIME:
        return {"follow": False}
    if rtf > 0:
        return {}
    idle = min(IDLE_RTF, rtf_max) if rtf_max > 0 else IDLE_RTF
    return {"afap_max_rtf": float(rtf_max), "solo_rtf": float(rtf_max), "idle_rtf": float(idle), "afap_adapt": True}


def speed_words(rtf: float, rtf_max: float = 0.0) -> str:
    """A grade's speed in words: ``real time (1x)``, or the preview's."""
    if rtf == REAL_TIME:
        return "real time (1x, as on the robot)"
    if rtf > 0:
        return f"PREVIEW at {rtf:g}x real time (failures graded again at 1x; no score)"
    cap = f", at most {rtf_max:g}x" if rtf_max > 0 else ""
    return f"PREVIEW as fast as the node keeps up{cap} (failures graded again at 1x; no score)"


def run_speed(run_dir: str | Path) -> dict[str, Any] | None:
    """What a run's simulator wrote of its speed (:data:`bt_nav_sim.pacing.PACE_FILE`): ``sim_s`` and ``wall_s``
    over the run and ``rtf`` their ratio; ``node_sim_s``, ``node_wall_s``, ``node_rtf`` while the node's ``cmd_vel``
    was followed (a preview at 0; ``node_rtf`` None under :data:`MIN_FOLLOWED_SIM`); ``realtime``: how a fixed
    factor was kept while judged. None: no record (a simulator killed before its exit)."""
    record = read_pace(Path(run_dir) / PACE_FILE) if run_dir else None
    if record is None or not record.get("wall_s") or record.get("t_end") is None:
        return None
    sim_s, wall_s = float(record["t_end"]), float(record["wall_s"])
    node = (record.get("followed") or {}).get(CMD_VEL) or {}
    node_sim, node_wall = float(node.get("sim_s", 0.0)), float(node.get("wall_s", 0.0))
    speed: dict[str, Any] = {
        "sim_s": round(sim_s, 2), "wall_s": round(wall_s, 2), "rtf": round(sim_s / wall_s, 2),
        "node_sim_s": round(node_sim, 2), "node_wall_s": round(node_wall, 2),
        "node_rtf": round(node_sim / node_wall, 2) if node_sim >= MIN_FOLLOWED_SIM and node_wall > 0 else None}
    if isinstance(record.get("realtime"), dict):
        speed["realtime"] = record["realtime"]
    return speed


def too_slow_finding(node_rtf: float) -> str:
    """The finding of a node that kept up with less than 1x real time in a preview at 0."""
    return (f"too slow for the robot: the node kept up with {node_rtf:.1f}x real time (a robot moves at 1x whatever "
            "the node does; its commands would come late there)")


def with_speed(row: dict[str, Any], rtf: float) -> dict[str, Any]:
    """``row`` of a run at the grade's ``rtf`` with what it achieved (module docstring): ``rtf`` and ``speed``
    (:func:`run_speed`), and in a preview at 0 the too-slow finding. Once only: a row that has ``speed`` is
    returned as it is."""
    if "speed" in row:
        return row
    speed = run_speed(row.get("run_dir") or "")
    row["speed"] = {"set": rtf, **(speed or {})}
    if speed is None:
        return row
    row["rtf"] = speed["rtf"]
    node_rtf = speed.get("node_rtf")
    if rtf <= 0 and node_rtf is not None and node_rtf < REAL_TIME and row.get("outcome") not in ("stopped",):
        finding = too_slow_finding(node_rtf)
        row["findings"] = [*row.get("findings", []), finding]
        row["reason"] = f"{row['reason']}; {finding}"
    return row


def fell_behind(row: dict[str, Any] | None) -> str | None:
    """Why a 1x run is no valid real-time run (a clause), or None when its simulator kept real time while judged
    (or said nothing of it: a simulator without the record is not doubted). Not of a preview's run."""
    speed = (row or {}).get("speed") or {}
    kept = speed.get("realtime")
    if speed.get("set") != REAL_TIME or not isinstance(kept, dict):
        return None
    judged, lost = float(kept.get("judged_wall_s", 0.0)), float(kept.get("lost_s", 0.0))
    window = float(kept.get("window_lost_s", kept.get("worst_s", 0.0)))
    if window <= WINDOW_LOST_S and lost <= LOST_SHARE * max(judged, 1.0):
        return None
    return (f"its simulator fell behind real time while judged ({window:.2f} s lost within 2 s; {lost:.2f} s of "
            f"{judged:.1f} s in all): the machine was too busy for a real-time run")


def factor_text(row: dict[str, Any]) -> str:
    """A run's achieved factor for its line (``9.3x``), or "" when unknown."""
    value = row.get("rtf")
    return f"{float(value):.1f}x" if value else ""


def achieved_text(rows: list[dict[str, Any]] | tuple[dict[str, Any], ...] | Any) -> str:
    """What a grid's runs achieved, for its report's header: `` (the runs went at 7.4-12.3x, median 9.3x)``; ""
    when no run says (:func:`with_speed`)."""
    factors = sorted(float(r["rtf"]) for r in rows if r.get("rtf"))
    if not factors:
        return ""
    median = factors[len(factors) // 2]
    if factors[0] == factors[-1] or len(factors) == 1:
        return f" (the runs went at {median:.1f}x)"
    return f" (the runs went at {factors[0]:.1f}-{factors[-1]:.1f}x, median {median:.1f}x)"
