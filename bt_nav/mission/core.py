"""The mission core: the tree, its blackboard and one safe ``tick()``, with no ROS in sight.

Both drivers of the tree use this class, so they cannot drift apart:
- the ROS executive (:mod:`bt_nav.ros.executive`) feeds it scans and odometry from subscriptions,
  passes its node to ``setup`` (the arm server and evaluation client are created there) and
  publishes the command each tick returns;
- the lock-step engine (:mod:`bt_nav.run.lockstep`) feeds it the simulator's scans and applies the
  command to the same physics, without DDS.

py_trees' blackboard is process-global; each MissionCore owns a blackboard of its own
(:class:`bt_nav.mission.boards.OwnBoard`) and switches it in at every entry point, so several cores can
live in one process (one per robot) and nothing outside swaps the blackboard.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Mapping
from typing import Any

import py_trees

from bt_nav.mission import params as P
from bt_nav.mission.behaviours import ArmService, EvaluateMission
from bt_nav.mission.behaviours.base import EventLogger
from bt_nav.mission.behaviours.control import compile_tick
from bt_nav.mission.boards import OwnBoard
from bt_nav.mission.datatypes import STOP, Clock, Command, OdomSample, keep_wheels_within
from bt_nav.mission.scan import Scan
from bt_nav.mission.snapshot import SNAPSHOT_KEYS, jsonable, tree_snapshot
from bt_nav.mission.tree import load_tree

Status = py_trees.common.Status
_BLACKBOARD = py_trees.blackboard.Blackboard
_STORAGE = _BLACKBOARD.storage  # the process-global key -> value dict

_ANSI = re.compile(r"\x1b\[[0-9;]*m")

#: Blackboard keys the drivers write (besides the parameters).
INPUT_KEYS = ("scan", "scan_stamp", "odom")
#: Blackboard keys the drivers and the trace read.
OUTPUT_KEYS = ("cmd_vel", "armed", "first_armed_at", "mission_over", "scan_ok", "scan_status",
               "maneuver_active", "evaluation_result")


def strip_ansi(text: str) -> str:
    """Remove terminal colour codes (py_trees' unicode display uses them)."""
    return _ANSI.sub("", text)


def find_leaf(root: py_trees.behaviour.Behaviour, cls: type) -> Any:
    """The one behaviour of class ``cls`` in the tree (None when absent)."""
    return next((node for node in root.iterate() if isinstance(node, cls)), None)


def culprit(exc: BaseException) -> str:
    """Name of the innermost behaviour on the exception's traceback ("?" when none): the ``self`` of a
    behaviour's method, or the ``node`` a compiled tick function
    (:func:`~bt_nav.mission.behaviours.control.compile_tick`) works on."""
    name, tb = "?", exc.__traceback__
    while tb is not None:
        frame_locals = tb.tb_frame.f_locals
        for owner in (frame_locals.get("self"), frame_locals.get("node")):  # a method, or a compiled tick
            if isinstance(owner, py_trees.behaviour.Behaviour):
                name = owner.name
                break
        tb = tb.tb_next
    return name


class MissionCore:
    """The mission tree, ready to tick.

    Args:
        overrides: parameter values over :mod:`bt_nav.mission.params` defaults (checked; ValueError if bad).
        clock: mission-clock seconds (node clock on the ROS path, simulated time in lock-step).
        node: an rclpy node for the leaves that own ROS services, or None off-ROS.
        evaluation_client: an object with rclpy Client's interface, used instead of creating one.
        events: logger for the one-line event messages (rclpy logger on the ROS path).
        tree_path: another tree file (default: the installed ``trees/mission.xml``).
    """

    def __init__(self, overrides: Mapping[str, Any] | None = None, *, clock: Clock, node: Any = None,
                 evaluation_client: Any = None, events: EventLogger | None = None,
                 tree_path: str | None = None) -> None:
        self.params: dict[str, P.Value] = P.resolve(overrides)
        self.clock = clock
        self.events: EventLogger = events or logging.getLogger("bt_nav")
        self.own_board = OwnBoard()  # this tree's blackboard, entered by every method that touches it
        self.own_board.enter()
        py_trees.blackboard.Blackboard.clear()
        self.root = load_tree(str(self.params["maneuver"]), tree_path)
        self.tree = py_trees.trees.BehaviourTree(self.root)
        self.board = py_trees.blackboard.Client(name="MissionCore")
        for key in INPUT_KEYS + tuple(s.name for s in P.PARAMS if s.in_tree):
            self.board.register_key(key=f"/{key}", access=py_trees.common.Access.WRITE)
        for key in OUTPUT_KEYS:
            self.board.register_key(key=f"/{key}", access=py_trees.common.Access.READ)
        for spec in P.PARAMS:
            if spec.in_tree:
                self.board.set(f"/{spec.name}", self.params[spec.name])
        self.board.set("/odom", OdomSample())
        seed = int(self.params["random_seed"])
        self.announcements: list[dict[str, Any]] = []  # the leaves' events since the driver last took them
        #: The leaves' events since the trace's last line (:class:`bt_nav.mission.trace.TraceRecorder` sets it to a
        #: list and takes from it; None: no trace, nothing kept)
        self.traced_announcements: list[dict[str, Any]] | None = None
        self.tree.setup(node=node, clock=clock, events=self.events, evaluation_client=evaluation_client,
                        random_seed=None if seed < 0 else seed, arm_service=str(self.params["arm_service"]),
                        announce=self._announce)
        self._fast_tick = compile_tick(self.root)
        self.nodes: list[py_trees.behaviour.Behaviour] = list(self.root.iterate())  # the shape is fixed from here on
        self.arm_leaf: ArmService = find_leaf(self.root, ArmService)
        self.evaluate_leaf: EvaluateMission | None = find_leaf(self.root, EvaluateMission)
        self.ticks = 0
        self.faults = 0
        self.last_command: Command = STOP
        self._snapshot_key: tuple[Any, ...] | None = None

    # ------------------------------------------------------------------ inputs
    def _put(self, key: str, value: Any) -> None:
        """Write one of the keys this core registered for writing (absolute ``key``): straight into the
        blackboard's storage, as py_trees' client would after its permission check (done once, at
        registration), unless py_trees' activity stream is on and wants to see the write."""
        if _BLACKBOARD.activity_stream is None:
            _STORAGE[key] = value
        else:
            self.board.set(key, value)

    def feed_scan(self, scan: Scan, stamp: float | None = None) -> None:
        """The newest scan and when it arrived (default: now on the mission clock)."""
        self.own_board.enter()
        self._put("/scan", scan)
        self._put("/scan_stamp", float(self.clock() if stamp is None else stamp))

    def feed_odom(self, yaw: float, stamp: float | None = None, x: float = math.nan, y: float = math.nan) -> None:
        """The newest odometry pose (yaw in rad; x, y in m, NaN when the source has none) and when it arrived."""
        self.own_board.enter()
        self._put("/odom", OdomSample(float(yaw), float(self.clock() if stamp is None else stamp), float(x), float(y)))

    def request_arm(self, data: bool) -> tuple[bool, str]:
        """Same as a call of the ``arm`` service: (success, message)."""
        self.own_board.enter()
        return self.arm_leaf.handle(bool(data))

    def set_param(self, name: str, value: Any) -> str | None:
        """Change one parameter; returns why it was refused, or None when applied (see :meth:`set_params`)."""
        return self.set_params({name: value})

    def check_params(self, values: Mapping[str, Any]) -> str | None:
        """Why this batch of changes would be refused, or None; nothing is applied.

        The same gate as at start-up (:func:`bt_nav.mission.params.check_changes`), with the read-only
        parameters (``live=False``, they shape the tree or the wiring) refused while running.
        """
        return P.check_changes(self.params, values)[1]

    def set_params(self, values: Mapping[str, Any]) -> str | None:
        """Apply a batch of changes all or nothing; returns why it was refused, or None when applied."""
        candidate, reason = P.check_changes(self.params, values)
        if reason:
            return reason
        self.own_board.enter()
        for name, value in candidate.items():
            if value != self.params[name]:
                self.params[name] = value
                if P.SPECS[name].in_tree:
                    self.board.set(f"/{name}", value)
        return None

    # ------------------------------------------------------------------ ticking
    def tick(self) -> Command:
        """Tick the tree once and return the command to publish: always finite and within limits.

        An exception inside a leaf is logged with the leaf's name, the tree is reset and the command
        is a stop; the next tick starts afresh. The caller never sees the exception.
        """
        self.ticks += 1
        self.own_board.enter()
        try:
            self._tick_tree()
            command = self.value("cmd_vel", STOP)
        except Exception as exc:  # one bad tick must not kill the node or leave the robot moving
            self.faults += 1
            self.events.error(f"tick {self.ticks}: exception in leaf '{culprit(exc)}': {exc!r}; "
                              "publishing a stop and resetting the tree")
            try:
                self.root.stop(Status.INVALID)
            except Exception as stop_exc:
                self.events.error(f"resetting the tree after the exception failed too: {stop_exc!r}")
            command = Command(0.0, 0.0, f"exception in {culprit(exc)}")
        self.last_command = self.limit(command)
        return self.last_command

    def _tick_tree(self) -> None:
        """One tick of the tree: the compiled ticker (:func:`~bt_nav.mission.behaviours.control.compile_tick`)
        unless py_trees' own tick has something more to do (visitors or tick handlers on the tree, debug
        logging on: then its debug lines are wanted), where py_trees ticks it."""
        tree = self.tree
        if (tree.visitors or tree.pre_tick_handlers or tree.post_tick_handlers
                or py_trees.logging.level == py_trees.logging.Level.DEBUG):
            tree.tick()
            return
        self._fast_tick()
        tree.count += 1

    def limit(self, command: Command) -> Command:
        """Clamp to the configured limits (per wheel too, when set); anything non-finite becomes a stop."""
        if not command.is_finite():
            self.events.error(f"non-finite command from {command.source}: publishing a stop")
            return Command(0.0, 0.0, f"non-finite from {command.source}")
        v_max = float(self.params["max_linear_speed"])
        w_max = max(float(self.params["angular_speed"]), float(self.params["maneuver_angular_speed"]))
        linear = min(v_max, max(-v_max, command.linear))
        angular = min(w_max, max(-w_max, command.angular))
        linear, angular = keep_wheels_within(linear, angular, float(self.params["wheel_speed_limit"]),
                                             float(self.params["wheel_separation"]))
        if (linear, angular) == (command.linear, command.angular):
            return command
        return Command(linear, angular, command.source)

    def shutdown(self) -> Command:
        """Stop every running leaf (a pending evaluation request is dropped) and return a stop."""
        self.own_board.enter()
        try:
            self.tree.interrupt()
            if self.evaluate_leaf is not None:
                self.evaluate_leaf.cancel()
        except Exception as exc:
            self.events.error(f"interrupting the tree at shutdown failed: {exc!r}")
        self.last_command = Command(0.0, 0.0, "shutdown")
        return self.last_command

    # ------------------------------------------------------------------ introspection
    def value(self, key: str, default: Any = None) -> Any:
        """A blackboard value the core reads (see OUTPUT_KEYS) or writes (a plain lookup: the core's
        client has every such key registered and no remapping, so py_trees' checks add nothing)."""
        self.own_board.enter()
        if _BLACKBOARD.activity_stream is not None:
            return self.board.get(f"/{key}") if self.board.exists(f"/{key}") else default
        return _STORAGE.get(f"/{key}", default)

    @property
    def tip(self) -> str:
        """Name of the tree's tip after the last tick."""
        tip = self.root.tip()
        return tip.name if tip is not None else ""

    def statuses(self) -> dict[str, str]:
        """Every node's status after the last tick, by name."""
        return {node.name: node.status.value for node in self.nodes}

    def status_key(self) -> tuple[Any, ...]:
        """Every node's status and the tip, as a cheap comparable value: it changes exactly when
        :meth:`statuses` or :attr:`tip` does (for deciding whether a new snapshot is worth making)."""
        return (*(node.status for node in self.nodes), self.root.tip())

    def snapshot(self) -> dict[str, Any]:
        """The tree after the last tick as a structured document (:func:`bt_nav.mission.snapshot.tree_snapshot`):
        what ``~/tree`` carries and a lock-step bag holds; :func:`~bt_nav.mission.snapshot.render_art` draws it."""
        board = {key: jsonable(self.value(key)) for key in SNAPSHOT_KEYS}
        return tree_snapshot(self.root, tick=self.ticks, t=round(float(self.clock()), 6),
                             maneuver=str(self.params["maneuver"]), board=board)

    def changed_snapshot(self) -> dict[str, Any] | None:
        """:meth:`snapshot` when a status or the tip changed since the last call, else None: the one rule of when
        the tree is worth sending (``~/tree`` over DDS, a lock-step bag), so both hold the same snapshots."""
        key = self.status_key()
        if key == self._snapshot_key:
            return None
        self._snapshot_key = key
        return self.snapshot()

    def _announce(self, record: dict[str, Any]) -> None:
        """A leaf's event (:meth:`~bt_nav.mission.behaviours.base.Leaf.announce`), kept for the driver; a maneuver's
        is stamped with the maneuver this tree was built for (one maneuver per tree)."""
        if record.get("event") == "maneuver":
            record = {**record, "maneuver": str(self.params["maneuver"])}
        self.announcements.append(record)
        if self.traced_announcements is not None:
            self.traced_announcements.append(record)

    def take_announcements(self) -> list[dict[str, Any]]:
        """The events since the last call, oldest first (the driver publishes or keeps them)."""
        taken, self.announcements = self.announcements, []
        return taken

    @property
    def mission_over(self) -> bool:
        """The deadline has latched."""
        return bool(self.value("mission_over", False))

    @property
    def evaluation_calls(self) -> int:
        """Successful evaluation calls so far (0 or 1)."""
        return self.evaluate_leaf.successful_calls if self.evaluate_leaf is not None else 0

