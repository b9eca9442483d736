"""What a lock-step run produced: per robot a :class:`MissionResult`, for the run a :class:`RunResult`.

A run of one robot is a :class:`RunResult` of one; the commands print and write the same things for any
number of robots from it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_nav_sim.world import World

from bt_nav.media.plot import Trajectory, plot_robots, plot_run, start_circle
from bt_nav.run.lab import checkoff_summary


@dataclass
class MissionResult:
    """Everything one robot's lock-step mission produced."""

    world: str
    maneuver: str
    seed: int
    profile: str
    kinematics: str
    results: dict[str, Any]  # the referee's results()
    passed: bool
    travelled: float
    efficiency: float  # travelled / (max_linear_speed * active_time)
    active_time: float  # s the robot was armed before the deadline stop
    collisions: int
    wall_time: float  # s of real time the run took
    sim_time: float  # s of simulated time
    branch_ticks: dict[str, int]  # ticks per branch label (FullSpeed, TurnAway, ...) while armed
    maneuvers: int  # maneuver starts
    report_lines: list[str]
    trajectory: Trajectory = field(repr=False)
    faults: int = 0  # ticks that raised inside a leaf
    world_model: World | None = field(default=None, repr=False)  # the world as simulated (for plots)
    events: list[tuple[float, str, str]] = field(default_factory=list, repr=False)  # (sim t, level, line)
    announcements: list[dict[str, Any]] = field(default_factory=list, repr=False)  # the tree's events (fields)
    parameters: dict[str, Any] = field(default_factory=dict, repr=False)  # every parameter's effective value
    robot: str = "robot1"

    @property
    def failed_checks(self) -> list[str]:
        """Names of the referee checks that failed."""
        return [c["name"] for c in self.results.get("checks", ()) if not c["passed"]]

    def summary(self) -> dict[str, Any]:
        """JSON-able summary without the trajectory (one grid cell of ``bt-nav grade``)."""
        return {
            "world": self.world, "maneuver": self.maneuver, "seed": self.seed, "profile": self.profile,
            "kinematics": self.kinematics,
            "passed": self.passed, "travelled": round(self.travelled, 4), "efficiency": round(self.efficiency, 4),
            "active_time": round(self.active_time, 3), "collisions": self.collisions,
            "max_distance_from_start": self.results.get("max_distance_from_start"),
            "failed_checks": self.failed_checks, "wall_time": round(self.wall_time, 4),
            "sim_time": round(self.sim_time, 4), "branch_ticks": dict(self.branch_ticks),
            "maneuvers": self.maneuvers, "faults": self.faults,
            **({"checkoff": checkoff_summary(self.results, self.announcements)}
               if "recovery_turns" in self.results else {}),
        }

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """Summary, the referee's full results, every parameter's value and (optionally) the trajectory.

        Times in ``results`` and ``events`` are sim seconds from the run's start (the referee's t0 is 0)."""
        out = {**self.summary(), "time_base": "sim time, s", "parameters": dict(self.parameters),
               "results": self.results, "report": self.report_lines}
        if trajectory:
            out["trajectory"] = self.trajectory.to_dict()
        return out

    def verdict(self) -> str:
        """PASSED or FAILED."""
        return "PASSED" if self.passed else "FAILED"

    def line(self) -> str:
        """The one-line account the commands print."""
        ticks = ", ".join(f"{name} {n}" for name, n in sorted(self.branch_ticks.items(), key=lambda kv: -kv[1]))
        return (f"{self.world}, maneuver {self.maneuver}, seed {self.seed} ({self.profile}, {self.kinematics} "
                f"kinematics): {self.verdict()}; travelled {self.travelled:.2f} m, efficiency "
                f"{self.efficiency:.3f} over {self.active_time:.1f} s armed, {self.collisions} collisions, "
                f"{self.maneuvers} maneuvers; ticks: {ticks}")


@dataclass
class RunResult:
    """Every robot's :class:`MissionResult`, by name, and the run's wall time (one robot: a list of one)."""

    names: list[str]
    results: list[MissionResult]
    wall_time: float

    @property
    def passed(self) -> bool:
        """Every robot passed."""
        return all(r.passed for r in self.results)

    @property
    def sim_time(self) -> float:
        """Simulated seconds of the run."""
        return max(r.sim_time for r in self.results)

    def summary_line(self) -> str:
        """One line for all robots: ``summary: 2/2 robots PASSED (robot1 PASSED, robot2 PASSED)``."""
        good = sum(r.passed for r in self.results)
        each = ", ".join(f"{n} {r.verdict()}" for n, r in zip(self.names, self.results, strict=True))
        return f"summary: {good}/{len(self.results)} robots {'PASSED' if self.passed else 'FAILED'} ({each})"

    def report_lines(self) -> list[str]:
        """The referee's verdict lines; with several robots each prefixed with its name, then the summary."""
        if len(self.results) == 1:
            return list(self.results[0].report_lines)
        lines = [f"{n}: {line}" for n, r in zip(self.names, self.results, strict=True) for line in r.report_lines]
        return [*lines, self.summary_line()]

    def to_dict(self, trajectory: bool = False) -> dict[str, Any]:
        """JSON-able. One robot: its :meth:`MissionResult.to_dict` (the file format of one-robot runs);
        several: per robot its dict under ``robots``, and the overall verdict."""
        if len(self.results) == 1:
            return self.results[0].to_dict(trajectory)
        return {"passed": self.passed, "summary": self.summary_line(), "wall_time": round(self.wall_time, 4),
                "time_base": "sim time, s",
                "robots": {n: r.to_dict(trajectory) for n, r in zip(self.names, self.results, strict=True)}}

    def plot(self, path: str | Path) -> Path:
        """The picture: one robot's path coloured by branch, several robots' each in its colour."""
        r0 = self.results[0]
        title = f"{r0.world}, maneuver {r0.maneuver}, seed {r0.seed}"
        if len(self.results) == 1:
            return plot_run(r0.world_model, r0.trajectory, r0.results, path, title=title,
                            min_distance=start_circle(r0.profile))
        runs = [(n, r.trajectory, r.results) for n, r in zip(self.names, self.results, strict=True)]
        return plot_robots(r0.world_model, runs, path, title=f"{title}, {len(self.results)} robots")
