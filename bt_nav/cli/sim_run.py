"""``bt-nav sim-run``: start bt_nav's node graph of a profile (simulator, executive, and the referee or the lab's
check-off judge) as subprocesses over DDS on this machine, without ``ros2 launch``; Ctrl-C stops them all.

The graph is :func:`bt_nav.ros.bringup.nodes` (the table the launch files read); starting, watching and stopping it
is :func:`bt_nav.run.rosmission.run_graph` (on a :class:`bt_nav.run.session.MissionSession`, in the domain of a
:class:`bt_nav.run.session.DomainLease`). This module parses the options and prints.
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path

from bt_nav.mission.maneuver_spec import choices_text, names_text
from bt_nav.mission.params import normalise_maneuver, parse_assignments
from bt_nav.ros.bringup import JUDGES, PROFILES, NodeSpec, nodes
from bt_nav.ros.supervise import Child, StopRequest
from bt_nav.run.rosmission import run_graph
from bt_nav.run.session import DomainLease


def build_parser(prog: str = "bt-nav sim-run") -> argparse.ArgumentParser:
    """Options of ``bt-nav sim-run``."""
    parser = argparse.ArgumentParser(prog=prog, description="Start the simulator and the executive (and the "
                                     "referee) as subprocesses over DDS on this machine; Ctrl-C stops them all.")
    parser.add_argument("--profile", choices=PROFILES, default="homework",
                        help="which graph: homework (executive), lab, eval (+ the referee), checkoff (+ the lab's "
                             "judge); default homework")
    parser.add_argument("--world", help="simulator world: name or YAML path (default stage_4)")
    parser.add_argument("--maneuver", help=f"evasive maneuver: {choices_text()} (or {names_text()})")
    parser.add_argument("--seed", type=int, help="one seed for sensor noise, generated worlds and maneuver A")
    parser.add_argument("--rtf", type=float, help="simulator real-time factor (default 1; 0 = as fast as possible)")
    parser.add_argument("--with-referee", action="store_true", help="add the referee (implied by --profile eval; "
                        "--profile checkoff adds the lab's judge)")
    parser.add_argument("--json", help="referee results file")
    parser.add_argument("--sim-param", action="append", default=[], metavar="NAME=VALUE",
                        help="extra simulator parameter (repeatable), e.g. physics_rate_hz=50")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                        help="extra executive parameter (repeatable), e.g. safety_distance=0.4")
    parser.add_argument("--domain-id", type=int, help="ROS_DOMAIN_ID (default: $ROS_DOMAIN_ID, else one no "
                        "other run on this machine holds, from $BT_NAV_DOMAIN_RANGE or 100-199)")
    parser.add_argument("--print", action="store_true", dest="print_only",
                        help="print the commands instead of running them")
    return parser


def bt_nav_command() -> str:
    """How the user types ``bt-nav`` for this installation: the venv's script (relative to the current
    directory when inside it, e.g. ``.venv/bin/bt-nav``), ``bt-nav`` when that is what PATH finds, or
    ``python -m bt_nav.cli``. Users who installed with pip have no ``ros2``; they copy this."""
    import shutil

    script = Path(sys.executable).parent / "bt-nav"
    if not script.is_file():
        return f"{shlex.quote(sys.executable)} -m bt_nav.cli"
    found = shutil.which("bt-nav")
    if found and Path(found).resolve() == script.resolve():
        return "bt-nav"
    try:
        return str(script.relative_to(Path.cwd()))
    except ValueError:
        return str(script)


def arm_hint(specs: list[NodeSpec], domain: int) -> str | None:
    """The exact command that arms the executive of ``specs`` (None when a judge does the arming)."""
    if any(spec.executable in JUDGES for spec in specs):
        return None
    executive = next((spec for spec in specs if spec.executable == "executive"), None)
    if executive is None:
        return None
    service = dict(executive.remappings).get("arm", "arm")
    service = service if service.startswith("/") else f"/{service}"
    return f"ROS_DOMAIN_ID={domain} {bt_nav_command()} arm --service {service}"


def main(argv: list[str] | None = None) -> int:
    """``bt-nav sim-run``: exit code of the referee when there is one, else of the first node to exit;
    128 + the signal number after SIGINT/SIGTERM/SIGHUP."""
    opts = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    lease = DomainLease(opts.domain_id)
    try:
        if opts.maneuver is not None:
            opts.maneuver = normalise_maneuver(opts.maneuver)
        specs = nodes(opts.profile, world=opts.world, maneuver=opts.maneuver, seed=opts.seed, rtf=opts.rtf,
                      with_referee=True if opts.with_referee else None, results_json=opts.json,
                      executive=parse_assignments(opts.set), sim=parse_assignments(opts.sim_param))
        domain = lease.claim()
    except ValueError as exc:
        print(f"bt-nav sim-run: {exc}", file=sys.stderr)
        return 2
    with lease:
        if opts.print_only:
            print(f"export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID={domain}")
            for spec in specs:
                print(" ".join(shlex.quote(a) for a in spec.command()))
            return 0
        return _run(specs, domain, opts.profile)


def _run(specs: list[NodeSpec], domain: int, profile: str) -> int:
    """Start ``specs`` in ``domain`` and supervise them until one ends or a stop signal arrives."""
    stop = StopRequest().install()
    print(f"bt-nav sim-run: profile {profile}, ROS_DOMAIN_ID={domain} (localhost only), pid {os.getpid()}; "
          "Ctrl-C stops", flush=True)
    hint = arm_hint(specs, domain)
    if hint:
        print(f"bt-nav sim-run: the robot waits to be armed; in another terminal: {hint}", flush=True)

    def early(ended: Child) -> None:
        print(f"bt-nav sim-run: {ended.name} exited with {ended.poll()} before the referee's verdict",
              file=sys.stderr, flush=True)

    try:
        code = run_graph(specs, domain, stop, on_early_exit=early)
    finally:
        stop.restore()
    if stop.requested:
        print(f"bt-nav sim-run: {stop.name}: stopped every node", file=sys.stderr, flush=True)
        code = 128 + int(stop.signum or 2)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
