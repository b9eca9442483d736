"""The tree snapshot and the events as structured data (:mod:`bt_nav.mission.snapshot`): one producer, fields for
readers."""

from __future__ import annotations

import json

from bt_nav.mission.snapshot import (
    EVENT_FORMAT,
    SNAPSHOT_FORMAT,
    read_event,
    read_snapshot,
    render_art,
    snapshot_json,
    snapshot_nodes,
)
from bt_nav.testing import TickHarness


def maneuver_a_running() -> TickHarness:
    h = TickHarness("A")
    h.tick()
    h.arm()
    h.tick()
    h.see((0.0, 0.45))
    h.tick(3)
    return h


def test_the_path_runs_from_the_root_to_the_tip_through_parents() -> None:
    h = maneuver_a_running()
    snapshot = h.core.snapshot()
    nodes = snapshot_nodes(snapshot)
    path = snapshot["path"]
    assert snapshot["format"] == SNAPSHOT_FORMAT and snapshot["tip"] == h.core.tip == "Randomizer"
    assert path[0] == 0 and nodes[path[-1]].name == "Randomizer" and nodes[path[-1]].status == "RUNNING"
    assert all(nodes[child].parent == parent for parent, child in zip(path, path[1:], strict=False))
    assert {n.name for n in nodes} == {n.name for n in h.core.nodes} and len(nodes) == len(h.core.nodes)
    assert snapshot["blackboard"]["maneuver_active"] is True and snapshot["blackboard"]["armed"] is True
    assert snapshot["blackboard"]["cmd_vel"]["source"] == "Randomizer"
    assert read_snapshot(snapshot_json(snapshot)) == snapshot
    assert read_snapshot("[-] Mission [*]") is None and read_snapshot('{"format": "other"}') is None


def test_a_maneuver_announces_itself_once_with_its_fields() -> None:
    h = maneuver_a_running()
    events = h.core.take_announcements()
    assert h.core.take_announcements() == [], "taken once"
    (event,) = events
    assert event["format"] == EVENT_FORMAT and event["event"] == "maneuver" and event["leaf"] == "Randomizer"
    assert event["maneuver"] == "A" and event["side"] in ("left", "right")
    assert 90.0 <= event["angle_deg"] <= 180.0 and event["angle_deg"] == round(event["angle_deg"])
    assert event["readings"]["front"] is not None and abs(event["readings"]["front"] - 0.45) < 0.05
    assert read_event(snapshot_json(event)) == event and read_event(snapshot_json(h.core.snapshot())) is None


def test_only_a_changed_status_or_tip_makes_a_new_snapshot() -> None:
    h = TickHarness("none")
    h.tick()
    assert h.core.changed_snapshot() is not None
    h.tick()
    assert h.core.changed_snapshot() is None, "nothing changed: nothing to send"
    h.tick()
    h.arm()
    h.tick()
    assert h.core.changed_snapshot()["tip"] == "FullSpeed"


def test_art_is_drawn_from_the_document_alone() -> None:
    """A renamed node, a new status and a field this code does not know reach the art without a change here."""
    snapshot = json.loads(snapshot_json(maneuver_a_running().core.snapshot()))
    tip = snapshot["nodes"][snapshot["path"][-1]]
    tip.update(name="Wiggle", status="SKIPPED", colour="teal")
    art = render_art(snapshot)
    assert "    --> Wiggle [?] -- " in art and "--> Randomizer" not in art


def test_watch_draws_the_document_and_says_when_a_message_is_not_one() -> None:
    from bt_nav.cli.watch import shown

    snapshot = maneuver_a_running().core.snapshot()
    assert shown(snapshot_json(snapshot), as_json=False) == render_art(snapshot).rstrip("\n")
    assert shown(snapshot_json(snapshot), as_json=True) == snapshot_json(snapshot)
    assert shown("[-] Mission [*]", as_json=False).startswith("(not a bt_nav tree snapshot; printed as received)")
