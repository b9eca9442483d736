"""Live parameter changes of the executive, through the one gate of :mod:`bt_nav.mission.params`.

rclpy offers three callbacks around ``set_parameters``; this class fills them so that a change is
judged exactly as a start-up value is (:func:`bt_nav.mission.params.check_changes`, reached through
``MissionCore.check_params``), refused with the reason in the ``SetParametersResult``, logged in one
line, and applied to the core only once rclpy has accepted it.
"""

from __future__ import annotations

from typing import Any, Protocol

from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from bt_nav.mission import params as P
from bt_nav.ros.rosutil import as_double


class ParameterOwner(Protocol):
    """What the gate needs of :class:`~bt_nav.mission.core.MissionCore`."""

    def check_params(self, values: dict[str, Any]) -> str | None: ...  # noqa: D102
    def set_params(self, values: dict[str, Any]) -> str | None: ...  # noqa: D102


class ParameterGate:
    """Installs the pre-set, on-set and post-set callbacks of ``node`` for the parameters of ``core``.

    Args:
        node: the executive's node (its parameters are declared already).
        core: the owner of the values (the mission core).
        log: the node's logger.
    """

    def __init__(self, node: Node, core: ParameterOwner, log: Any) -> None:
        self.node = node
        self.core = core
        self.log = log
        self._refusal_logged: str | None = None  # set by the pre-set callback, so a refusal is logged once
        node.add_pre_set_parameters_callback(self._before_set_parameters)
        node.add_on_set_parameters_callback(self._on_set_parameters)
        node.add_post_set_parameters_callback(self._after_set_parameters)

    def check(self, parameters: list[Parameter]) -> str | None:
        """Why this batch of changes is refused (table, cross rules, read-only, unknown name), or None."""
        for p in parameters:
            if p.name not in P.SPECS and not self.node.has_parameter(p.name):
                return f"unknown parameter {p.name!r}: not a bt_nav parameter (typo?)"
        values = {p.name: p.value for p in parameters if p.name in P.SPECS}
        return self.core.check_params(values) if values else None

    def _before_set_parameters(self, parameters: list[Parameter]) -> list[Parameter]:
        """Accept integers for float parameters, and log a refusal before rclpy makes it silently.

        rclpy checks the descriptors (range, type, read-only) before the on-set callback runs and
        refuses without a word in the node's log; our rules match the descriptors, so the reason
        is known here already and logged in the same one line as our own refusals.
        """
        parameters = [as_double(P.SPECS[p.name], p) if p.name in P.SPECS else p for p in parameters]
        self._refusal_logged = self.check(parameters)
        if self._refusal_logged:
            self.log.warning(f"parameter change refused: {self._refusal_logged}")
        return parameters

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate a change (the batch as a whole); applied only in the post-set callback."""
        reason = self.check(parameters)
        if reason and reason != self._refusal_logged:
            self.log.warning(f"parameter change refused: {reason}")
        self._refusal_logged = None
        return SetParametersResult(successful=reason is None, reason=reason or "")

    def _after_set_parameters(self, parameters: list[Parameter]) -> None:
        """Apply an accepted change; the tree sees it on the next tick."""
        values = {p.name: p.value for p in parameters if p.name in P.SPECS}
        if not values:
            return
        reason = self.core.set_params(values)
        if reason:  # cannot happen after a successful check; say so loudly if it ever does
            self.log.error(f"accepted parameter change could not be applied: {reason}")
            return
        changes = ", ".join(f"{name}={value!r}" for name, value in values.items())
        self.log.info(f"parameters changed: {changes}")
