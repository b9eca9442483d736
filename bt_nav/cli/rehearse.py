"""``bt-nav rehearse``: lab day's check-off rehearsed on this computer, no robot needed. A SIMULATED TurtleBot3
(:mod:`bt_nav.ros.nodes.fakerobot`: bt_nav_sim's physics and LDS-02 model, the sheet's template node driving it,
publishing only /odom, /scan and /cmd_vel, stamps 0.3 s ahead) on a ROS domain of its own, on localhost, and
``bt-nav checkoff --robot`` beside it on the same domain, exactly as a TA runs it beside the real robot; the judge's
output is printed as it comes, and its exit code is this command's (0 passed, 1 failed, 2 refused, 3 INCOMPLETE).

``--robot-only`` runs the simulated robot alone, in this shell's own ROS domain, to rehearse the other half by hand
(``bt-nav checkoff --robot`` in a second shell with the same ROS_DOMAIN_ID and discovery range).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, field


def _turns() -> dict[str, tuple[float, float]]:
    """The simulated runs, by maneuver (those the sheet triggers on the front: the simulated node reads no sides):
    the template node's turn (deg, - = right: 120 deg, or the rule's nearest angle) and its trigger (m: the
    ``safety_distance`` default, which the judge accepts for every front trigger)."""
    from bt_nav.mission.maneuver_spec import MANEUVER_SPECS

    return {letter: (-min(max(120.0, spec.angle.low_deg), spec.angle.high_deg), 0.5)
            for letter, spec in MANEUVER_SPECS.items() if spec.trigger.reads == "front"}


#: The simulated runs, by maneuver (:func:`_turns`).
TURNS = _turns()
#: s of the simulated run: armed at 1 s, disarmed at 9 s.
ARM_AT, DISARM_AT, RUN_END = 1.0, 9.0, 10.0


@dataclass(frozen=True)
class _Command:
    """One of bt_nav's commands as a child process (what :class:`bt_nav.ros.supervise.Launcher` starts)."""

    executable: str
    args: list[str] = field(default_factory=list)

    def command(self, python: str | None = None) -> list[str]:
        return [python or sys.executable, "-m", "bt_nav.cli", self.executable, *self.args]


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="bt-nav rehearse", description=__doc__.split("\n\n")[0].replace("``", ""))
    p.add_argument("--maneuver", default=min(TURNS), choices=sorted(TURNS),
                   help=f"the simulated node's maneuver (default {min(TURNS)})")
    p.add_argument("--duration", type=float, default=20.0, help="s the judge listens (default 20; the run is 10 s)")
    p.add_argument("--domain-id", type=int, help="the rehearsal's ROS domain (default: a free one, 100-199)")
    p.add_argument("--robot-only", action="store_true", help="only the simulated robot, in this shell's domain")
    return p


def main(argv: list[str] | None = None) -> int:
    """``bt-nav rehearse`` (module docstring)."""
    opts = parser().parse_args(argv)
    from bt_nav_sim.synthrobot import simulate

    turn, trigger = TURNS[opts.maneuver]
    run = simulate(turn_deg=turn, trigger=trigger, creep=0.15, rate=1.2, arm_at=ARM_AT, disarm_at=DISARM_AT,
                   end=RUN_END)
    if opts.robot_only:
        from bt_nav.ros.nodes.fakerobot import drive

        drive(run, lambda line: print(f"simulated robot: {line}", flush=True))
        return 0
    return _rehearse(opts)


def _rehearse(opts: argparse.Namespace) -> int:
    """The simulated robot and the live judge on a domain of their own; the judge's exit code."""
    from bt_nav.ros.supervise import Launcher, child_env
    from bt_nav.run.session import DomainLease

    with DomainLease(opts.domain_id, user_env=False) as lease:
        domain = lease.claim()
        env = child_env(domain)
        judge = ["--robot", "--maneuver", opts.maneuver, "--duration", f"{opts.duration:g}"]
        print(f"bt-nav rehearse: a SIMULATED TurtleBot3 (not a robot) publishing /odom, /scan, /cmd_vel on "
              f"ROS_DOMAIN_ID={domain} (localhost only), and beside it: bt-nav checkoff {' '.join(judge)}", flush=True)

        def sink(name: str, line: str) -> None:
            print(line, flush=True)  # the judge's lines as the TA sees them; the robot's say "simulated robot:"

        launcher = Launcher(env, sink)
        try:
            checkoff = launcher.start(_Command("checkoff", judge))
            launcher.start(_Command("rehearse", ["--robot-only", "--maneuver", opts.maneuver]))
            code = checkoff.popen.wait()
        except KeyboardInterrupt:
            code = 130
        finally:
            launcher.shutdown(grace=3.0)
    return int(code)
