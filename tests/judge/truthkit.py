"""The check-off judge in a test's world: the judge (:mod:`bt_nav.judge.checkoff_core`) fed the simulator's truth
feed (:mod:`bt_nav_sim.truth`), as the ROS node and the lock-step runner put them together."""

from __future__ import annotations

from bt_nav_sim.truth import truth_feed
from bt_nav_sim.world import World

from bt_nav.judge.checkoff_core import CheckoffConfig, CheckoffJudge


def truth_judge(config: CheckoffConfig, world: World, *, update_world: bool = True) -> CheckoffJudge:
    """A check-off judge reading its triggers cast in ``world`` (``update_world``: it reveals appearing objects from
    the poses it observes, as the node's own copy of the world; False: the simulator sharing it does)."""
    return CheckoffJudge(config, truth_feed(config, world, update_world=update_world))
