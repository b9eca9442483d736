"""The speed of an ``--exe`` run: what ``--rtf`` and ``--rtf-max`` set in its simulator, the factor the run achieved
(read from the simulator's pace record, ``pace.json``), and the words for both.

Why a node sets the speed: the simulator is paced to the graded node (:data:`bt_nav.grading.exe.run.FOLLOW_NODE`):
sim time never runs ahead of the node's latest command by more than its period and the next scan it answers, so a
node on ROS time (``use_sim_time``) finds the world where it left it at any speed. At ``--rtf 0`` (the default) the
simulator therefore runs as fast as the node keeps up (``afap_max_rtf``), capped by ``--rtf-max``
(:data:`DEFAULT_RTF_MAX` unless given), and under that cap just behind the pace the node keeps (``afap_adapt``:
:class:`bt_nav_sim.pacing.StayBehind`), so the followers' bound is a safety net, not the pace: a simulator held at the
bound makes every command of the node come that late; the hosted judge sends no ``sim_sync`` of its own, so
``solo_rtf``, the cap while only ``cmd_vel`` is followed, is the same cap.
While the node says nothing (before its arming, after its stop,
a node that publishes only on change) nobody is followed and sim time runs at ``idle_rtf``: :data:`IDLE_RTF`, or
``--rtf-max`` when lower, so a silent node does not see sim time race away. Before the judge's t0 (the node starting
up) and after its verdict (the node being stopped) nothing is judged, and sim time runs at 1x (the simulator's
``unjudged_rtf``). ``--rtf N`` (N > 0) keeps a fixed factor, as before.

Each run's row carries what it achieved (:func:`with_speed`): ``rtf``, the simulator's sim seconds per wall second
over the run, and ``speed``: those seconds, and the sim and wall seconds while the node's ``cmd_vel`` was followed
(``node_rtf``: how fast the node kept up). At ``--rtf 0`` a node that kept up with less than 1x real time while
followed (for at least :data:`MIN_FOLLOWED_SIM` sim seconds) gets a finding: it would be too slow for the robot,
which moves at 1x whatever the node does. Not a failure by itself: the judge's checks say whether the run passed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bt_nav_sim.pacing import CMD_VEL, PACE_FILE, read_pace

#: Sim seconds per wall second at ``--rtf 0`` while the node is not followed (silent): the simulator's own default.
IDLE_RTF = 10.0
#: ``--rtf 0``'s cap unless ``--rtf-max`` is given (``--rtf-max 0``: none): none. Until 2026-11-27 it was 5x: with the
#: followers' bound alone the simulator ran at that bound whenever it was faster than the node, so every command came
#: the whole bound late and a node on a fast timer steered on a full odometry queue (uncapped, five right variants of
#: the grader suite failed; a 50 Hz Retreat on odometry turned 190-258 deg). Kept just behind the node
#: (:class:`bt_nav_sim.pacing.StayBehind`), the suite's 40 right nodes passed 240 of 240 runs uncapped, two CPU hogs
#: running.
DEFAULT_RTF_MAX = 0.0
#: The factor a real robot runs at: a node that keeps up with less is too slow for it.
ROBOT_RTF = 1.0
#: Sim seconds of following below which a run's ``node_rtf`` says nothing of the node (a node that spoke once; a
#: right node is followed for most of a lab run's 70 s, about 55 s of it).
MIN_FOLLOWED_SIM = 5.0


def check_speed(rtf: float, rtf_max: float | None) -> None:
    """Refuse a speed no run can keep: a negative ``--rtf`` or ``--rtf-max``, or ``--rtf-max`` beside a fixed
    ``--rtf N`` (the cap is of mode 0 only). ``rtf_max`` None: not given.

    Raises:
        ValueError: one line naming the option and what to do instead.
    """
    if rtf < 0:
        raise ValueError(f"--rtf {rtf:g}: sim seconds per wall second, >= 0 (0: as fast as the node keeps up)")
    if rtf_max is None:
        return
    if rtf_max < 0:
        raise ValueError(f"--rtf-max {rtf_max:g}: the cap of --rtf 0, >= 0 (0: no cap)")
    if rtf > 0:
        raise ValueError(f"--rtf-max caps --rtf 0 (as fast as the node keeps up); --rtf {rtf:g} is a fixed factor "
                         "already: leave one of them out")


def rtf_cap(rtf: float, rtf_max: float | None) -> float:
    """The cap a grade runs with: ``--rtf-max`` as given (0: none), else :data:`DEFAULT_RTF_MAX` at ``--rtf 0`` and
    none beside a fixed factor."""
    if rtf_max is not None:
        return float(rtf_max)
    return DEFAULT_RTF_MAX if rtf == 0.0 else 0.0


def sim_pace(rtf: float, rtf_max: float = 0.0) -> dict[str, float | bool]:
    """The simulator's pacing parameters for a grade's speed (module docstring): none at a fixed factor (``rtf`` >
    0, ``real_time_factor`` says it all); at 0 the cap ``rtf_max`` (0: none) while the node is followed, alone or
    not, the speed kept just behind the node's pace under it (``afap_adapt``:
    :class:`bt_nav_sim.pacing.StayBehind`), and :data:`IDLE_RTF` (or the cap, when lower) while it is silent."""
    if rtf > 0:
        return {}
    idle = min(IDLE_RTF, rtf_max) if rtf_max > 0 else IDLE_RTF
    return {"afap_max_rtf": float(rtf_max), "solo_rtf": float(rtf_max), "idle_rtf": float(idle), "afap_adapt": True}


def speed_words(rtf: float, rtf_max: float = 0.0) -> str:
    """A grade's speed in words: ``5x real time``, or ``as fast as the node keeps up`` (and its cap)."""
    if rtf > 0:
        return f"{rtf:g}x real time"
    return "as fast as the node keeps up" + (f" (at most {rtf_max:g}x real time)" if rtf_max > 0 else "")


def run_speed(run_dir: str | Path) -> dict[str, float] | None:
    """What a run's simulator wrote of its speed (:data:`bt_nav_sim.pacing.PACE_FILE`): ``sim_s`` and ``wall_s``
    over the run and ``rtf`` their ratio; ``node_sim_s``, ``node_wall_s`` and ``node_rtf`` while the node's
    ``cmd_vel`` was followed (``node_rtf`` None when that was under :data:`MIN_FOLLOWED_SIM`). None: no record (a
    simulator killed before its exit, or one of before the record had its wall time)."""
    record = read_pace(Path(run_dir) / PACE_FILE) if run_dir else None
    if record is None or not record.get("wall_s") or record.get("t_end") is None:
        return None
    sim_s, wall_s = float(record["t_end"]), float(record["wall_s"])
    node = (record.get("followed") or {}).get(CMD_VEL) or {}
    node_sim, node_wall = float(node.get("sim_s", 0.0)), float(node.get("wall_s", 0.0))
    return {"sim_s": round(sim_s, 2), "wall_s": round(wall_s, 2), "rtf": round(sim_s / wall_s, 2),
            "node_sim_s": round(node_sim, 2), "node_wall_s": round(node_wall, 2),
            "node_rtf": round(node_sim / node_wall, 2) if node_sim >= MIN_FOLLOWED_SIM and node_wall > 0 else None}


def too_slow_finding(node_rtf: float) -> str:
    """The finding of a node that kept up with less than 1x real time (:data:`ROBOT_RTF`)."""
    return (f"too slow for the robot: the node kept up with {node_rtf:.1f}x real time (a robot moves at 1x whatever "
            "the node does; its commands would come late there)")


def with_speed(row: dict[str, Any], rtf: float) -> dict[str, Any]:
    """``row`` of a run at the grade's ``rtf`` with what it achieved (module docstring): ``rtf`` and ``speed``
    (:func:`run_speed`), and at ``rtf`` 0 the too-slow finding. Once only: a row that has ``speed`` is returned
    as it is."""
    if "speed" in row:
        return row
    speed = run_speed(row.get("run_dir") or "")
    row["speed"] = {"set": rtf, **(speed or {})}
    if speed is None:
        return row
    row["rtf"] = speed["rtf"]
    node_rtf = speed.get("node_rtf")
    if rtf <= 0 and node_rtf is not None and node_rtf < ROBOT_RTF and row.get("outcome") not in ("stopped",):
        finding = too_slow_finding(node_rtf)
        row["findings"] = [*row.get("findings", []), finding]
        row["reason"] = f"{row['reason']}; {finding}"
    return row


def achieved(row: dict[str, Any] | None, rtf: float) -> float:
    """The factor a run went at, for words and the re-run rule: the grade's fixed ``rtf``, or at 0 the run's own
    (``rtf``: its line's figure, the simulator's sim seconds per wall second over the run; else ``node_rtf``; 1 when
    neither is known: nothing faster is shown)."""
    if rtf > 0:
        return rtf
    speed = (row or {}).get("speed") or {}
    return float(speed.get("rtf") or speed.get("node_rtf") or 1.0)


def node_factor(row: dict[str, Any] | None, rtf: float) -> float:
    """How fast the node kept up while it was followed (``node_rtf``), the pace its turns ran at; else
    :func:`achieved`."""
    speed = (row or {}).get("speed") or {}
    return float(speed["node_rtf"]) if rtf <= 0 and speed.get("node_rtf") else achieved(row, rtf)


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


def fell_behind(row: dict[str, Any] | None) -> float | None:
    """The factor a run at 1x kept while it followed the node, when under 1x (None: it kept real time, or no
    record): its simulation fell behind the wall clock, a machine too busy for it (or a node too slow for the
    robot). A node timing itself by the wall clock then turns less than it means (measured: 55-76 deg of a 90 deg
    turn at 0.92-0.99x, with 12 runs at 1x beside a test suite; 90-92 deg at 1.00-1.01x on a quiet machine)."""
    speed = (row or {}).get("speed") or {}
    if speed.get("set") != 1.0 or speed.get("node_rtf") is None:
        return None
    kept = float(speed["node_rtf"])
    return kept if kept < ROBOT_RTF else None
