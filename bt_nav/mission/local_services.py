"""An evaluation service answered in-process: rclpy's Trigger client interface without ROS.

The EvaluateMission leaf talks to "a client with rclpy Client's interface"; off-ROS (the lock-step
runner, grading, the tick-by-tick tests) this is that client. Its answers come from a script (tests)
or from a handler function (the lock-step runner hands the request to its referee).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any


@dataclass
class TriggerRequest:
    """Stand-in for std_srvs/Trigger.Request (off-ROS)."""


@dataclass
class TriggerResponse:
    """Stand-in for std_srvs/Trigger.Response (off-ROS)."""

    success: bool = False
    message: str = ""


class TriggerType:
    """Stand-in for the std_srvs/Trigger service type: what ``client.srv_type`` gives."""

    Request = TriggerRequest
    Response = TriggerResponse


class LocalFuture:
    """The part of rclpy's Future the EvaluateMission leaf uses."""

    def __init__(self) -> None:
        self._done = False
        self._result: Any = None
        self._exception: BaseException | None = None
        self.cancelled = False

    def done(self) -> bool:  # noqa: D102
        return self._done

    def result(self) -> Any:  # noqa: D102
        if self._exception is not None:
            raise self._exception
        return self._result

    def set_result(self, result: Any) -> None:  # noqa: D102
        self._result, self._done = result, True

    def set_exception(self, exc: BaseException) -> None:  # noqa: D102
        self._exception, self._done = exc, True


Handler = Callable[[TriggerRequest], TriggerResponse]


class LocalTriggerClient:
    """A Trigger client with rclpy Client's interface, answered in-process.

    ``script`` lists what successive calls get: ``"ok"``, ``"refuse"`` (success=false), ``"hang"``
    (never answered), ``"raise"`` (the future fails), or a handler function; once the script runs out,
    ``default`` answers. ``absent_until`` keeps the service "not ready" until that clock time.
    """

    srv_type = TriggerType

    def __init__(self, script: Sequence[str | Handler] = (), default: str | Handler = "ok",
                 clock: Callable[[], float] | None = None, absent_until: float = -math.inf) -> None:
        self.script = list(script)
        self.default = default
        self.clock = clock
        self.absent_until = absent_until
        self.calls: list[float] = []
        self.removed: list[LocalFuture] = []
        self.pending: list[LocalFuture] = []

    def service_is_ready(self) -> bool:  # noqa: D102
        return self.clock is None or self.clock() >= self.absent_until

    def call_async(self, request: TriggerRequest) -> LocalFuture:  # noqa: D102
        self.calls.append(self.clock() if self.clock else float(len(self.calls)))
        action = self.script.pop(0) if self.script else self.default
        future = LocalFuture()
        if callable(action):
            future.set_result(action(request))
        elif action == "ok":
            future.set_result(TriggerResponse(True, "evaluation accepted"))
        elif action == "refuse":
            future.set_result(TriggerResponse(False, "not now"))
        elif action == "raise":
            future.set_exception(RuntimeError("server died mid-call"))
        elif action == "hang":
            self.pending.append(future)
        else:
            raise ValueError(f"unknown script action {action!r}")
        return future

    def remove_pending_request(self, future: LocalFuture) -> None:  # noqa: D102
        future.cancelled = True
        self.removed.append(future)
        if future in self.pending:
            self.pending.remove(future)
