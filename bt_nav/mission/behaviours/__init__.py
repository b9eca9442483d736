"""bt_nav's behaviours, grouped by family, and the registry the XML parser builds the tree from.

| module | leaves |
|---|---|
| ``control`` | ReactiveSequence, ReactiveFallback, ForceSuccess (BehaviorTree.CPP tags) |
| ``mission`` | ArmService, IsArmed, MissionDeadline, EvaluateMission |
| ``perception`` | ProcessScan, ScanHealthy, ObstacleClose, ObstacleFar |
| ``triggers`` | FrontTrigger, SqueezeTrigger (the maneuvers' conditions, on their rising edge) |
| ``motion`` | Stop, DriveForward, TurnAway, RotateInPlace |
| ``lab`` | InMode, Creep, PathBlocked, EmergencyStop (lab mode: the creep and its emergency braking) |
| ``maneuvers`` | ManeuverActive, the lab maneuvers' leaves (named in ``bt_nav.mission.maneuver_spec``), AlwaysFailure |

To add a leaf: subclass :class:`~bt_nav.mission.behaviours.base.Leaf` (or ``Condition``), declare
``INPUT_PORTS`` / ``OUTPUT_PORTS``, add it to :data:`REGISTRY` and declare it in the tree file's
``TreeNodesModel`` (a test checks that the two agree).
"""

from __future__ import annotations

from py_trees.ports import PortsMixin, get_ports_registry

from bt_nav.mission.behaviours import maneuvers as _maneuvers
from bt_nav.mission.behaviours.control import ForceSuccess, ReactiveFallback, ReactiveSequence
from bt_nav.mission.behaviours.lab import Creep, EmergencyStop, InMode, PathBlocked
from bt_nav.mission.behaviours.maneuvers import AlwaysFailure, ManeuverActive, RotationManeuver
from bt_nav.mission.behaviours.mission import ArmService, EvaluateMission, IsArmed, MissionDeadline
from bt_nav.mission.behaviours.motion import DriveForward, RotateInPlace, Stop, TurnAway
from bt_nav.mission.behaviours.perception import ObstacleClose, ObstacleFar, ProcessScan, ScanHealthy
from bt_nav.mission.behaviours.triggers import FrontTrigger, SqueezeTrigger
from bt_nav.mission.maneuver_spec import MANEUVER_SPECS


def maneuver_leaf(name: str) -> type[RotationManeuver]:
    """The maneuver leaf class a maneuver spec names: bt_nav's own (``behaviours.maneuvers``), else any concrete
    :class:`RotationManeuver` subclass defined elsewhere (py_trees registers those by class name), so a maneuver
    added to the spec needs no entry here. Raises ValueError when no such class exists."""
    cls = getattr(_maneuvers, name, None) or get_ports_registry().get(name)
    if not (isinstance(cls, type) and issubclass(cls, RotationManeuver)):
        raise ValueError(f"maneuver leaf {name!r} is no RotationManeuver subclass defined anywhere")
    return cls


_CLASSES: tuple[type[PortsMixin], ...] = (
    ReactiveSequence, ReactiveFallback, ForceSuccess,
    ArmService, IsArmed, MissionDeadline, EvaluateMission,
    ProcessScan, ScanHealthy, ObstacleClose, ObstacleFar, FrontTrigger, SqueezeTrigger,
    Stop, DriveForward, TurnAway, RotateInPlace,
    InMode, Creep, PathBlocked, EmergencyStop,
    ManeuverActive, *(maneuver_leaf(spec.leaf) for spec in MANEUVER_SPECS.values()), AlwaysFailure,
)

REGISTRY: dict[str, type[PortsMixin]] = {cls.__name__: cls for cls in _CLASSES}
"""Tag -> class, handed to py_trees' XML parser (only these tags, plus py_trees' own decorators)."""

LEAF_CLASSES = {name: cls for name, cls in REGISTRY.items() if cls not in (ReactiveSequence, ReactiveFallback,
                                                                           ForceSuccess)}

__all__ = ["REGISTRY", "LEAF_CLASSES", "RotationManeuver", "maneuver_leaf", *(n for n in REGISTRY if n in globals())]
