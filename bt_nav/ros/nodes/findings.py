"""What the graph audit (:class:`bt_nav.ros.nodes.audit.GraphAudit`) found, as data: each finding's kind, topic and
first clause beside the sentence a student reads.

Why: the sentence is for people and may be reworded; a program that decides on a finding (the check-off's strict
findings, :mod:`bt_nav.judge.findings`; the judge's own verdict) reads its ``kind`` instead.
The verdict JSON carries both: ``findings`` (the sentences) and ``finding_kinds`` (:meth:`Finding.record`, in the
same order). Pure (no rclpy), so the grader reads the kinds without ROS.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: Nothing but the simulator and the judge ever appeared on the graph.
NO_NODE = "no_node"
#: No foreign node subscribed to an input topic (``scan``, ``/clock``).
NO_SUBSCRIBER = "no_subscriber"
#: No foreign node published on the command topic.
NO_PUBLISHER = "no_publisher"
#: The arm service never offered, or offered with another type.
SERVICE = "service"
#: A foreign endpoint and one of ours hold a topic with different message types.
TYPE_MISMATCH = "type_mismatch"
#: A foreign endpoint and one of ours hold a topic with QoS policies that cannot match.
QOS_MISMATCH = "qos_mismatch"
#: Commands holding NaN or inf.
NON_FINITE = "non_finite"
#: More commands per sim second than any controller sends.
FLOOD = "flood"
#: The kinds after which not one message of their topic passes between the node and us, at any speed.
CUT_OFF = frozenset({NO_SUBSCRIBER, NO_PUBLISHER, TYPE_MISMATCH, QOS_MISMATCH})


@dataclass(frozen=True)
class Finding:
    """One finding: ``text`` the sentence (the verdict's ``findings``), ``kind`` one of this module's kinds,
    ``topic`` the topic or service it concerns (None: none), ``clause`` what it found without the why (a summary's
    words; the whole sentence when it has no why)."""

    kind: str
    text: str
    topic: str | None = None
    clause: str = ""

    def record(self) -> dict[str, Any]:
        """The finding as the verdict's ``finding_kinds`` holds it (the sentence is in ``findings``)."""
        return {"kind": self.kind, "topic": self.topic, "clause": self.clause or self.text}
