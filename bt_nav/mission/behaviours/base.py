"""What every bt_nav leaf shares: the injected clock, the event logger and command output.

Leaves get their outside world through ``setup(**kwargs)`` (py_trees passes the same keyword arguments
to every behaviour): ``clock`` (seconds, sim-time aware), ``events`` (a logger with info/warning/error,
the rclpy node logger on the ROS path), ``node`` (an rclpy node, or None off-ROS). Everything else
flows through blackboard ports declared in the tree file.
"""

from __future__ import annotations

import logging
import math
from typing import Any, Protocol, get_origin

import py_trees
from py_trees.ports import BehaviourWithPorts, PortInformation

from bt_nav.mission.datatypes import Clock, Command
from bt_nav.mission.snapshot import event, jsonable

_DEFAULT_EVENTS = logging.getLogger("bt_nav")
_BLACKBOARD = py_trees.blackboard.Blackboard
_STORAGE = _BLACKBOARD.storage  # the process-global key -> value dict


class EventLogger(Protocol):
    """The subset of rclpy's and Python's loggers that leaves use."""

    def info(self, msg: str) -> Any: ...  # noqa: D102
    def warning(self, msg: str) -> Any: ...  # noqa: D102
    def error(self, msg: str) -> Any: ...  # noqa: D102


def _no_clock() -> float:
    raise RuntimeError("no clock injected: call tree.setup(clock=...) before ticking")


def port(data_type: Any, description: str = "", default: Any = None, required: bool = True
         ) -> PortInformation:
    """Shorthand for a port declaration."""
    return PortInformation(data_type=data_type, description=description, default_value=default,
                           required=required)


CMD_PORT = {"cmd_vel": port(Command, "the velocity command this leaf chooses")}


class Leaf(BehaviourWithPorts):
    """Base of bt_nav's leaves (abstract: it declares no ports, so the parser does not register it)."""

    def __init__(self, name: str, **kwargs: Any) -> None:
        super().__init__(name=name, **kwargs)
        self.clock: Clock = _no_clock
        self.events: EventLogger = _DEFAULT_EVENTS
        self.node: Any = None
        self._announce: Any = None  # the driver's sink for structured events (MissionCore's), None: nobody listens
        #: The figures behind the feedback a snapshot carries as the node's ``data`` (:mod:`bt_nav.mission.snapshot`)
        self.snapshot_data: dict[str, Any] = {}
        self._port_keys: dict[str, str] = {}
        self._output_keys: dict[str, tuple[str, type]] = {}
        self._read_back_keys: dict[str, str] = {}  # last_output's resolved keys

    def get_input(self, port_name: str, default: Any = None) -> Any:
        """Read an input port: a direct blackboard lookup once the port's key is known.

        py_trees' ``get_input`` re-resolves the remapping and re-checks the type on every read, which
        was half the tick's cost (26 reads a tick). Values are type-checked where they are written
        (output ports, the parameter table), so the fast path reads the resolved key directly and
        falls back to the full ``get_input`` (defaults, errors) when the key holds nothing yet.
        """
        key = self._port_keys.get(port_name)
        if key is None:
            if port_name not in self.input_ports():
                return super().get_input(port_name, default)
            key = self._port_keys[port_name] = self._get_blackboard_key(port_name)
        value = _STORAGE.get(key)
        if value is None:
            return super().get_input(port_name, default)
        return value

    def read_optional(self, port_name: str) -> Any:
        """An input port's value, or None when its key holds nothing (no default, no exception): for
        optional inputs such as the newest scan, which py_trees' client would look up twice."""
        key = self._port_keys.get(port_name)
        if key is None:
            if not self.blackboard_client.exists(port_name):
                return None
            return self.get_input(port_name)  # resolves and remembers the key
        return _STORAGE.get(key)

    def last_output(self, port_name: str, default: Any = None) -> Any:
        """What an output port's key holds now (``default`` when nothing): a value written on an earlier
        tick, by this leaf or another writer of the same key (py_trees has no port both in and out)."""
        key = self._read_back_keys.get(port_name)
        if key is None:  # resolved once, as get_input does (a remapping is fixed when the tree is built)
            key = self._read_back_keys[port_name] = self._get_blackboard_key(port_name)
        value = _STORAGE.get(key)
        return default if value is None else value

    def _set_output(self, port_name: str, value: Any) -> None:
        """Write an output port: a direct blackboard store once the port has been written through py_trees.

        py_trees' ``_set_output`` re-checks the port, its type and the client's write permission and
        resolves the remapping on every write (a few microseconds, several writes a tick). The first
        write of each port takes that full path (which raises for an undeclared port or a missing
        permission); later writes keep the type check (same TypeError as py_trees) and store directly.
        With py_trees' activity stream on, every write takes the full path, so the stream sees it.
        """
        cached = self._output_keys.get(port_name)
        if cached is None or _BLACKBOARD.activity_stream is not None or not isinstance(value, cached[1]):
            super()._set_output(port_name, value)
            if cached is None:
                port_type = self.output_ports()[port_name].data_type
                if isinstance(port_type, type) and get_origin(port_type) is None:
                    self._output_keys[port_name] = (self._get_blackboard_key(port_name), port_type)
            return
        _STORAGE[cached[0]] = value

    def setup(self, **kwargs: Any) -> None:
        """Take the clock, the event logger and (on the ROS path) the node."""
        self.clock = kwargs.get("clock") or self.clock
        self.events = kwargs.get("events") or self.events
        self.node = kwargs.get("node")
        self._announce = kwargs.get("announce")

    def announce(self, kind: str, **fields: Any) -> None:
        """Tell the drivers about a decision as an event with fields (:func:`bt_nav.mission.snapshot.event`),
        beside its log line: readers (the lab's angle check, the terminal, bags) take the fields, never the text."""
        if self._announce is not None:
            self._announce(event(kind, self.clock(), self.label, **fields))

    def tell(self, kind: str, message: str, *, warn: bool = False, **fields: Any) -> None:
        """Log ``<label>: <message>`` (a warning with ``warn``) and announce it as an event ``kind`` with
        ``fields``, the line (``text``) and its level: the lab's terminal shows the event's line, never the log's."""
        line = f"{self.label}: {message}"
        if warn:  # two call sites: rclpy refuses one call site with two severities
            self.events.warning(line)
        else:
            self.events.info(line)
        figures = {key: jsonable(value) if isinstance(value, float) else value for key, value in fields.items()}
        self.announce(kind, **figures, level="WARN" if warn else "INFO", text=line)

    @property
    def label(self) -> str:
        """The leaf's short name (the parser prefixes parents' names) for log lines."""
        return self.name.rsplit(".", 1)[-1]

    def command(self, linear: float, angular: float) -> None:
        """Write this leaf's velocity command; a non-finite value becomes a stop (never published)."""
        if not (math.isfinite(linear) and math.isfinite(angular)):
            self.events.error(f"{self.label}: non-finite command ({linear}, {angular}) replaced by a stop")
            linear, angular = 0.0, 0.0
        self._set_output("cmd_vel", Command(float(linear), float(angular), self.label))


class Condition(Leaf):
    """A leaf that answers a question: SUCCESS for yes, FAILURE for no, never RUNNING."""

    def answer(self) -> bool:
        """The question's answer this tick."""
        raise NotImplementedError

    def update(self) -> py_trees.common.Status:
        """SUCCESS when :meth:`answer` is yes."""
        return py_trees.common.Status.SUCCESS if self.answer() else py_trees.common.Status.FAILURE
