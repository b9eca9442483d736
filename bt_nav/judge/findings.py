"""The check-off's findings: what a run did that the lab sheet only implies, shown as prominently as a failure but
passing unless the course makes that kind strict (pure, no rclpy).

Why: a check fails only what the sheet or its check-off states (the trigger, the angle, the side where every
reasonable reading agrees, rotation without forward motion, the service, the parameter, no collision). What the
sheet only implies is no ground to fail a student: the lab template's own B done as a level trigger (spin whenever
squeezed) failed every narrow cell with "never moved on", though the sheet's Retreat says only "perform a full 180
deg spin to exit". So such a rule yields a *finding* (its kind below), and an instructor who teaches the implied rule
makes it a failure with one option per course: the judge's ``strict_findings`` (``bt-nav grade --strict-findings
KIND[,KIND]``, or ``all``).
"""

from __future__ import annotations

from typing import Any

#: An exit maneuver (the Retreat) made back to back without ever driving out before the disarm: "never moved on".
BACK_TO_BACK = "back_to_back"
#: A search maneuver (the Randomizer, the Smart Pivot) made back to back: counted, as the search went on.
SEARCH_CHAIN = "search_chain"
#: A maneuver after which the robot stood (e.g. at a wall its brake stopped it at) instead of moving on.
MOVED_ON = "moved_on"
#: The Smart Pivot turned away from the side beside the robot (60-120 deg) reads clearer, where other reasonable
#: readings of "left" and "right" disagree (so either side passes).
SIDE = "side"

#: Every kind a judge finding may have, with what making it strict fails (the docs and ``--help`` say these).
FINDING_KINDS: dict[str, str] = {
    BACK_TO_BACK: "Retreats back to back that never drive out before the disarm (\"never moved on\")",
    MOVED_ON: "a maneuver after which the robot stood still instead of moving on",
    SIDE: "a Smart Pivot away from the clearer side beside the robot (60-120 deg) where other readings disagree",
    SEARCH_CHAIN: "Randomizers or Smart Pivots back to back (a search that went on)",
}
#: What ``strict_findings`` names to make every kind strict.
ALL = "all"


def strict_kinds(text: str) -> frozenset[str]:
    """The kinds ``text`` makes strict (comma-separated kinds, or ``all``; empty: none).

    Raises:
        ValueError: naming an unknown kind and the known ones (an option is refused, never silently ignored).
    """
    names = {part.strip() for part in str(text).split(",") if part.strip()}
    if ALL in names:
        return frozenset(FINDING_KINDS)
    unknown = sorted(names - set(FINDING_KINDS))
    if unknown:
        raise ValueError(f"unknown finding kind(s) {', '.join(unknown)} for strict_findings: use "
                         f"{', '.join(FINDING_KINDS)} or {ALL}")
    return frozenset(names)


def finding(kind: str, text: str) -> dict[str, Any]:
    """One judge finding as the verdict's ``finding_kinds`` holds it (the sentence is also in ``findings``)."""
    return {"kind": kind, "topic": None, "clause": text}


def maneuver_findings(maneuvers: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The findings of the judged maneuvers that passed a rule only the sheet implies (numbered as their lines):
    stood instead of moving on, a disputed side turned against the side beside the robot. A finding of a strict
    kind failed its maneuver instead (its line says why), so it is not repeated here."""
    out = []
    for number, e in enumerate(maneuvers, start=1):
        for kind, text in e.get("findings") or ():
            out.append(finding(kind, f"maneuver {number} {text}"))
    return out


def abeam_side(cfg: Any, r: Any) -> str | None:
    """The clearer side by the sectors beside the robot (60-120 deg, the sides a failing line shows), or None where
    they are within ``side_tie`` of each other or both open."""
    if r is None:
        return None
    left, right = r.left_abeam, r.right_abeam
    if abs(left - right) < cfg.side_tie or (left > cfg.open_space and right > cfg.open_space):
        return None
    return "left" if left > right else "right"


def implied_rules(cfg: Any, angle: float, r: Any, judged: tuple[bool, str], moved_on: tuple[bool, str]
                  ) -> tuple[bool, str, bool, list[tuple[str, str]]]:
    """A maneuver's rules that the sheet only implies, on top of its angle and side (``judged``: whether they held,
    and the rule's words) and whether it moved on (``moved_on``: held, and the figures): its angle verdict and rule,
    its moving-on verdict, and its findings as ``(kind, sentence)``. Each is a finding unless the course makes its
    kind strict (``cfg.strict``): then it fails the maneuver.

    - the side (a maneuver that turns towards the clearer side): where reasonable readings of the sides disagree,
      either side passed; a turn away from the side the sectors beside the robot read clearer is a finding;
    - moving on after the turn: the sheet asks for none (a robot its brake stopped at a wall stands there)."""
    angle_ok, rule = judged
    found: list[tuple[str, str]] = []
    turned = "left" if angle > 0 else "right"
    beside = abeam_side(cfg, r) if angle_ok and cfg.spec.angle.side == "clearer" else None
    if beside is not None and beside != turned:
        words = (f"turned {abs(angle):.0f} deg {turned}, away from the side beside the robot that reads clearer "
                 f"(60-120 deg: left {r.left_abeam:.2f} m, right {r.right_abeam:.2f} m); other reasonable readings of "
                 f"the sides (a sector reaching towards the front) read {turned} clearer, so either side passed")
        if cfg.strict(SIDE):
            angle_ok, rule = False, cfg.angle_rule(beside) + " (the side beside the robot: strict_findings side)"
        else:
            found.append((SIDE, words))
    ok, figures = moved_on
    if not ok and not cfg.strict(MOVED_ON):
        found.append((MOVED_ON, f"did not move on after the turn ({figures}): the sheet asks for none, so it passed"))
    return angle_ok, rule, ok or not cfg.strict(MOVED_ON), found
