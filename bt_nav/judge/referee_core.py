"""The homework referee as a pure, clock-driven state machine (no rclpy).

The course's evaluation script is a ROS node that calls the robot's activate service on a schedule,
serves ``evaluate_mission`` and checks ground truth. Keeping its logic here, free of ROS, lets one
implementation serve two drivers that must not disagree:

- the ROS referee node (:mod:`bt_nav.ros.nodes.referee`) drives it with sim time, real service calls and
  ground-truth odometry;
- the lock-step runner (:mod:`bt_nav.run.lockstep`) drives it in-process with the simulator's state.

The driver calls :meth:`Referee.step` at ``rate_hz`` and performs the :class:`Activate` actions it
returns, reporting each answer with :meth:`Referee.on_activate_result`; it forwards every ground-truth
pose to :meth:`Referee.observe`, every collision event to :meth:`Referee.on_collision`, and answers the
evaluation service with :meth:`Referee.on_evaluate`. Every time is absolute (the driver's clock); the
schedule is measured from :meth:`Referee.start`'s ``t0``.

Schedule (relative to t0), as in the homework's evaluator:

====================  =====================================================================
0 - 5 s               the robot must be static (nobody has activated it)
5 s -                 ``activate(true)`` on every step until an answer says success
first step >= 20 s    ``activate(false)``; 20 - 23 s grace to brake; 23 - 30 s must be static
30 s -                ``activate(true)`` again, on every step until success
first evaluation call the schedule ends; 3 s later: "static at the end" is checked over the last
                      window, the report is made and ``activate(false)`` is requested
56 s, no call yet     "evaluation service called" fails; the report is made at once
====================  =====================================================================

"Moving" is judged on consecutive ground-truth samples: a pair whose planar speed exceeds
``moving_linear`` or whose turn rate exceeds ``moving_angular`` is motion. A static period passes
when no pair lying inside it moves; "static at the end" looks at the last ``window`` seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from bt_nav.mission.geometry import wrap_angle  # the +-pi seam is not a 2 pi jump


@dataclass(frozen=True)
class RefereeConfig:
    """Timing and thresholds of the homework's evaluation (seconds are relative to t0)."""

    static_before: float = 5.0  # t < 5 s the robot must be static; from 5 s activate(true) until success
    deactivate_at: float = 20.0  # first step at/after this: activate(false)
    grace: float = 3.0  # after the deactivation request the robot may still brake this long
    reactivate_at: float = 30.0  # activate(true) again (until success)
    evaluation_deadline: float = 56.0  # no evaluate_mission call by then -> that check fails, run ends
    settle_after_call: float = 3.0  # report this long after the first evaluation call
    min_distance_from_start: float = 1.5  # m
    min_travelled: float = 8.0  # m
    moving_linear: float = 0.01  # m/s
    moving_angular: float = 0.01  # rad/s
    window: float = 0.5  # s, the "static at the end" window
    rate_hz: float = 2.0  # how often the driver calls step()


#: RefereeConfig fields that are durations of the schedule, scaled by ``time_scale``. ``window`` is not:
#: it is how much ground truth the "static at the end" check needs, and at 30 Hz a scaled-down window
#: would hold no pair of samples to judge.
TIME_FIELDS = ("static_before", "deactivate_at", "grace", "reactivate_at", "evaluation_deadline",
               "settle_after_call")


def scaled(config: RefereeConfig, scale: float) -> RefereeConfig:
    """``config`` with every duration multiplied by ``scale`` (thresholds and rates unchanged)."""
    if scale == 1.0:
        return config
    return replace(config, **{name: getattr(config, name) * scale for name in TIME_FIELDS})


@dataclass(frozen=True)
class Activate:
    """An action for the driver: call the robot's activate (SetBool) service with ``data``."""

    data: bool


#: How an activate call ended, as the driver saw it: a response came (``success`` says armed or refused), none came
#: in time, the service was not there, or the call raised.
ANSWERED, UNANSWERED, UNAVAILABLE = "answered", "unanswered", "unavailable"


@dataclass
class ServiceAnswers:
    """What came back from the robot's activate service for each request (``data`` True/False): a refusal (a
    response with ``success`` False) is not silence, and a student must read which it was."""

    refused: dict[bool, int] = field(default_factory=lambda: {True: 0, False: 0})
    refusal: dict[bool, str] = field(default_factory=dict)  # the node's last message with a refusal
    silent: dict[bool, dict[str, int]] = field(default_factory=lambda: {True: {}, False: {}})

    def record(self, data: bool, success: bool, answer: str = ANSWERED, message: str = "") -> None:
        if answer != ANSWERED:
            self.silent[data][answer] = self.silent[data].get(answer, 0) + 1
        elif not success:
            self.refused[data] += 1
            self.refusal[data] = message

    def failed_text(self, name: str, data: bool) -> str:
        """Why ``name(data)`` never succeeded: ``toggle_navigation(false) refused 3 times ('busy')``, ``... never
        answered (2 calls unanswered)``, or ``... never answered`` when it was not even asked."""
        call = f"{name}({str(data).lower()})"
        if self.refused[data]:
            n = self.refused[data]
            said = f" ({self.refusal[data]!r})" if self.refusal.get(data) else ""
            return f"{call} refused {n} time{'s' if n != 1 else ''}{said}: the node answered success false"
        silent = ", ".join(f"{n} call{'s' if n != 1 else ''} {how}" for how, n in self.silent[data].items())
        return f"{call} never answered" + (f" ({silent})" if silent else "")


#: Check names, in report order.
CHECKS = (
    "static at the end",
    "static before activation",
    "static after deactivation",
    "minimum distance from start",
    "minimum travelled distance",
    "evaluation service called",
    "no collision",
)


class Verdict:
    """The verdict bookkeeping every judge here shares (the homework's referee, the lab's check-off judge):
    the report is made once, at :meth:`_finish`; before it, :meth:`results` is provisional, judged at the
    last ground-truth sample. Inputs stamped after the report are ignored; those stamped before it that arrive
    after it (queued behind a busy driver's clock) are kept, and :meth:`catch_up` judges them. A subclass
    provides ``_evaluate(now)``, ``_t`` (sample times) and ``t0``."""

    report_time: float | None = None
    _results: dict[str, Any] | None = None
    _t: list[float]
    t0: float | None

    def _evaluate(self, now: float) -> dict[str, Any]:
        raise NotImplementedError

    @property
    def done(self) -> bool:
        """The report is made."""
        return self.report_time is not None

    @property
    def passed(self) -> bool:
        """Every check passed (False until the report is made)."""
        return self.done and bool(self.results()["passed"])

    def _finish(self, t: float) -> None:
        self.report_time = float(t)
        self._results = self._evaluate(t)

    def _late(self, t: float) -> bool:
        """Stamped after the report (an input stamped before it but delivered after it still counts)."""
        return self.report_time is not None and t > self.report_time

    def catch_up(self) -> None:
        """Judge again at the report time, with the inputs stamped before it that arrived after it (a driver
        whose inputs queue up behind its clock calls this before it reports; in lock-step it changes nothing)."""
        if self.report_time is not None:
            self._results = self._evaluate(self.report_time)

    def results(self) -> dict[str, Any]:
        """The verdict as a JSON-able dict (provisional, judged at the last sample, before :attr:`done`)."""
        if self._results is not None:
            return self._results
        now = self._t[-1] if self._t else (self.t0 or 0.0)
        return self._evaluate(now)


class Referee(Verdict):
    """The homework referee: schedule, ground-truth bookkeeping and the final checks."""

    def __init__(self, config: RefereeConfig = RefereeConfig()) -> None:  # noqa: B008 - frozen dataclass
        self.config = config
        self.t0: float | None = None
        # ground truth (absolute times); kept whole: a 60 s run at 30 Hz is 1800 samples
        self._t: list[float] = []
        self._x: list[float] = []
        self._y: list[float] = []
        self._yaw: list[float] = []
        self.travelled = 0.0
        self.max_distance = 0.0
        self.collisions: list[tuple[float, float, float]] = []
        # schedule state
        self.activation_requested: float | None = None
        self.activated: float | None = None
        self.deactivation_requested: float | None = None
        self.deactivated: float | None = None
        self.reactivation_requested: float | None = None
        self.reactivated: float | None = None
        self.evaluation_called: float | None = None
        self.evaluation_calls = 0
        self.report_time: float | None = None
        self._resend_false = False
        self._results: dict[str, Any] | None = None
        self.answers = ServiceAnswers()

    # ------------------------------------------------------------------ driver inputs
    def start(self, t0: float) -> None:
        """The robot's activate service exists: the schedule starts at ``t0``."""
        if self.t0 is None:
            self.t0 = float(t0)

    def observe(self, t: float, x: float, y: float, yaw: float) -> None:
        """One ground-truth pose sample; out-of-order samples and those stamped after the report are ignored.

        Travelled distance accumulates from the first activation request (the robot cannot move
        legitimately before it), the distance from the start is measured from the first sample.
        """
        if self._late(t) or (self._t and t <= self._t[-1]):
            return
        if self._t:
            if self.activation_requested is not None and t > self.activation_requested:
                self.travelled += math.hypot(x - self._x[-1], y - self._y[-1])
            self.max_distance = max(self.max_distance, math.hypot(x - self._x[0], y - self._y[0]))
        self._t.append(float(t))
        self._x.append(float(x))
        self._y.append(float(y))
        self._yaw.append(float(yaw))

    def on_collision(self, t: float, x: float, y: float) -> None:
        """A collision event (the start of one contact, not every blocked physics step)."""
        if not self._late(t):
            self.collisions.append((float(t), float(x), float(y)))

    def on_evaluate(self, t: float) -> tuple[bool, str]:
        """The ``evaluate_mission`` handler: the first call ends the schedule; returns (success, message)."""
        self.evaluation_calls += 1
        if self.done:
            return False, "the evaluation is already over"
        if self.evaluation_called is not None:
            return True, f"evaluation already requested at t={self._rel(self.evaluation_called):.2f} s"
        self.evaluation_called = float(t)
        return True, (f"evaluation requested at t={self._rel(t):.2f} s; the robot must stay static, "
                      f"report in {self.config.settle_after_call:.0f} s")

    def on_activate_result(self, t: float, data: bool, success: bool, answer: str = ANSWERED,
                           message: str = "") -> None:
        """The answer to an :class:`Activate` action (``success`` False also for a failed call: ``answer`` says
        whether a response came, ``message`` is the node's)."""
        self.answers.record(data, success, answer, message)
        if data:
            if not success:
                return  # step() asks again
            if self.deactivation_requested is None:
                if self.activated is None:
                    self.activated = float(t)
            elif self.reactivation_requested is not None and self.reactivated is None:
                self.reactivated = float(t)
        else:
            if success:
                if self.deactivation_requested is not None and self.deactivated is None:
                    self.deactivated = float(t)
                self._resend_false = False
            else:
                self._resend_false = True

    def step(self, t: float) -> list[Activate]:
        """Advance the schedule to ``t`` (call at ``rate_hz``); returns the service calls to make now."""
        if self.t0 is None or self.done:
            return []
        cfg = self.config
        rel = since_t0(t, self.t0)
        if self.evaluation_called is not None:
            if t >= self.evaluation_called + cfg.settle_after_call:
                self._finish(t)
                return [Activate(False)]
            return []
        if rel >= cfg.evaluation_deadline:
            self._finish(t)
            return [Activate(False)]
        if rel >= cfg.reactivate_at:
            if self.reactivation_requested is None:
                self.reactivation_requested = float(t)
            return [] if self.reactivated is not None else [Activate(True)]
        if rel >= cfg.deactivate_at:
            if self.deactivation_requested is None:
                self.deactivation_requested = float(t)
                return [Activate(False)]
            if self._resend_false:
                self._resend_false = False
                return [Activate(False)]
            return []
        if rel >= cfg.static_before:
            if self.activation_requested is None:
                self.activation_requested = float(t)
            return [] if self.activated is not None else [Activate(True)]
        return []

    # ------------------------------------------------------------------ verdict
    def _rel(self, t: float | None) -> float | None:
        """``t`` in seconds since t0 (None stays None)."""
        if t is None:
            return None
        return t - (self.t0 or 0.0)

    def max_motion(self, start: float, end: float) -> tuple[float, float, int]:
        """(peak planar speed, peak turn rate, pairs seen) over sample pairs lying inside [start, end]."""
        return peak_motion(self._t, self._x, self._y, self._yaw, start, end)

    def _name_unanswered(self, checks: list[dict[str, Any]]) -> None:
        """A failed check whose cause is the service's answer says so: never armed (the distances), or the
        deactivation not taken (the stop after it): refused or never answered, as it was."""
        causes = {}
        if self.activation_requested is not None and self.activated is None:
            causes.update(dict.fromkeys(("minimum distance from start", "minimum travelled distance"), True))
        if self.deactivation_requested is not None and self.deactivated is None:
            causes["static after deactivation"] = False
        for check in checks:
            if not check["passed"] and check["name"] in causes:
                check["detail"] += f" ({self.answers.failed_text('activate', causes[check['name']])})"

    def _static_check(self, name: str, start: float | None, end: float | None, missing: str) -> dict[str, Any]:
        """A "must be static over [start, end]" check (see :func:`static_check`)."""
        cfg = self.config
        return static_check(name, (self._t, self._x, self._y, self._yaw), start, end, missing,
                            (cfg.moving_linear, cfg.moving_angular), self.t0 or 0.0)

    def _evaluate(self, now: float) -> dict[str, Any]:
        cfg = self.config
        t0 = self.t0 or 0.0
        checks = [self._static_check("static at the end", now - cfg.window, now, "no ground truth")]
        checks.append(self._static_check(
            "static before activation", t0, self.activation_requested if self.activation_requested is not None
            else now, "never activated"))
        deact_start = None if self.deactivation_requested is None else self.deactivation_requested + cfg.grace
        deact_end = min(now, self.reactivation_requested if self.reactivation_requested is not None
                        else t0 + cfg.reactivate_at)
        checks.append(self._static_check("static after deactivation", deact_start, deact_end,
                                         "the run ended before the deactivation test"))
        far_enough = self.max_distance >= cfg.min_distance_from_start
        checks.append({"name": "minimum distance from start", "passed": far_enough,
                       "value": round(self.max_distance, 4), "required": cfg.min_distance_from_start,
                       "detail": f"reached {self.max_distance:.2f} m, required {cfg.min_distance_from_start} m"})
        checks.append({"name": "minimum travelled distance", "passed": self.travelled >= cfg.min_travelled,
                       "value": round(self.travelled, 4), "required": cfg.min_travelled,
                       "detail": f"travelled {self.travelled:.2f} m, required {cfg.min_travelled} m"})
        called = self.evaluation_called is not None and self.evaluation_called <= t0 + cfg.evaluation_deadline
        call_rel = self._rel(self.evaluation_called)
        checks.append({"name": "evaluation service called", "passed": called, "value": call_rel,
                       "required": f"by t={cfg.evaluation_deadline} s",
                       "detail": f"first call at t={call_rel:.2f} s" if call_rel is not None else "never called"})
        n = len(self.collisions)
        checks.append({"name": "no collision", "passed": n == 0, "value": n, "required": 0,
                       "detail": f"{n} collision{'s' if n != 1 else ''}"
                       + ("" if not n else " at " + ", ".join(f"t={c[0] - t0:.1f} s ({c[1]:.2f}, {c[2]:.2f})"
                                                            for c in self.collisions[:5]))})
        self._name_unanswered(checks)
        return {
            "passed": all(c["passed"] for c in checks),
            "checks": checks,
            "travelled": round(self.travelled, 4),
            "max_distance_from_start": round(self.max_distance, 4),
            "collisions": n,
            "collision_events": [{"t": c[0] - t0, "x": c[1], "y": c[2]} for c in self.collisions],
            "times": {
                "t0": self.t0,
                "activation_requested": self._rel(self.activation_requested),
                "activated": self._rel(self.activated),
                "deactivation_requested": self._rel(self.deactivation_requested),
                "deactivated": self._rel(self.deactivated),
                "reactivation_requested": self._rel(self.reactivation_requested),
                "reactivated": self._rel(self.reactivated),
                "evaluation_called": call_rel,
                "report": self._rel(now),
            },
            "evaluation_calls": self.evaluation_calls,
            "samples": len(self._t),
            "done": self.done,
        }

    def report_lines(self) -> list[str]:
        """One line per check, as the homework's evaluator prints them, then the overall verdict."""
        res = self.results()
        lines = []
        for check in res["checks"]:
            label = check["name"]
            if label == "minimum distance from start":
                label += f" (reached {res['max_distance_from_start']:.2f} m, " \
                         f"required {self.config.min_distance_from_start} m)"
            elif label == "minimum travelled distance":
                label += f" (travelled {res['travelled']:.2f} m, required {self.config.min_travelled} m)"
            elif label == "no collision":
                label += f" ({res['collisions']} collision{'s' if res['collisions'] != 1 else ''})"
            lines.append(f"{label}: {'PASSED' if check['passed'] else 'FAILED'}")
        lines.append(f"overall: {'PASSED' if res['passed'] and self.done else 'FAILED'}")
        return lines


def peak_motion(ts: list[float], xs: list[float], ys: list[float], yaws: list[float], start: float,
                end: float) -> tuple[float, float, int]:
    """(peak planar speed, peak turn rate, pairs seen) over ground-truth sample pairs lying inside
    [start, end]: the one definition of "moving" for the homework referee and the lab's judge."""
    peak_v = peak_w = 0.0
    pairs = 0
    for i in range(1, len(ts)):
        if ts[i - 1] < start - 1e-9:
            continue
        if ts[i] > end + 1e-9:
            break
        dt = ts[i] - ts[i - 1]
        if dt <= 0.0:
            continue
        pairs += 1
        peak_v = max(peak_v, math.hypot(xs[i] - xs[i - 1], ys[i] - ys[i - 1]) / dt)
        peak_w = max(peak_w, abs(wrap_angle(yaws[i] - yaws[i - 1])) / dt)
    return peak_v, peak_w, pairs


def since_t0(t: float, t0: float) -> float:
    """Seconds of the schedule at sim time ``t`` (``t - t0``, to the nanosecond).

    Why round: over DDS both are node-clock nanoseconds times 1e-9, and the difference of two such floats can come
    out a hair under a schedule time the step timer fires exactly on (t0 14.500000000000002, step at 19.5: 4.999...
    s), which put the action off to the next step, 0.5 s late (1 in 65 check-offs; 66 of 4000 (t0, deadline) pairs).
    Lock-step starts at t0 0 and its instants never fall under, so its runs are unchanged.
    """
    return round(t - t0, 9)


def static_check(name: str, samples: tuple[list[float], list[float], list[float], list[float]],
                 start: float | None, end: float | None, missing: str, limits: tuple[float, float],
                 t0: float) -> dict[str, Any]:
    """A "must be static over [start, end]" check dict on ground truth ``samples`` (t, x, y, yaw lists):
    fails when the interval is missing (``missing`` says why) or holds no sample pair to judge.
    ``limits``: (linear m/s, angular rad/s) above which a pair is motion; times in details are from t0."""
    linear, angular = limits
    required = f"<= {linear} m/s and <= {angular} rad/s"
    if start is None or end is None or end < start:
        return {"name": name, "passed": False, "value": None, "required": required, "detail": missing}
    peak_v, peak_w, pairs = peak_motion(*samples, start, end)
    span = f"t={start - t0:.2f}-{end - t0:.2f} s"
    if pairs == 0:
        return {"name": name, "passed": False, "value": None, "required": required,
                "detail": f"no ground truth over {span}"}
    passed = peak_v <= linear and peak_w <= angular
    detail = f"peak {peak_v:.3f} m/s, {peak_w:.3f} rad/s over {span}"
    return {"name": name, "passed": passed, "value": round(peak_v, 6), "required": required, "detail": detail}


#: What a failed check means, in the words of the assignments (the check's detail adds the judge's figures).
CHECK_WORDS = {
    "static at the end": "still moving at the end (the robot must stop before it asks for the evaluation)",
    "static before activation": "moved before it was activated",
    "static after deactivation": "did not stop and stay still after the deactivation",
    "minimum distance from start": "did not get far enough from the start",
    "minimum travelled distance": "did not travel far enough",
    "evaluation service called": "did not call the evaluation service in time",
    "no collision": "hit an obstacle",
    "toggle_navigation answered": "did not answer toggle_navigation",
    "maneuvers performed": "performed no maneuver",
    "recovery turns": "drove forward while turning away after an emergency stop",
}


def check_reason(check: dict[str, Any]) -> str:
    """One failed check in a sentence a student can act on, with the judge's figures: the check's own ``reason``
    when it gives one (a maneuver's), else the meaning of its name and its detail."""
    if check.get("reason"):
        return str(check["reason"])
    words = CHECK_WORDS.get(check["name"], f"{check['name']} not met")
    return f"{words} ({check['detail']})" if check.get("detail") else words


def failure_reason(checks: list[dict[str, Any]]) -> str:
    """Why a verdict failed, for a summary line: every failed check's reason, the maneuvers' first one only
    (with how many more failed)."""
    failed = [c for c in checks if not c.get("passed")]
    maneuvers = [c for c in failed if c["name"].startswith("maneuver ") and c["name"] != "maneuvers performed"]
    parts = [check_reason(c) for c in failed if c not in maneuvers]
    if maneuvers:
        more = len(maneuvers) - 1
        parts.append(check_reason(maneuvers[0]) + (f" (and {more} more maneuver{'s' if more > 1 else ''} failed)"
                                                   if more else ""))
    return "failed: " + "; ".join(parts) if parts else "failed"
