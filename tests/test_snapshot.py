"""The tree snapshot and the events as structured data (:mod:`bt_nav.mission.snapshot`): one producer, fields for
readers."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_nav.mission.snapshot import (
    DEADLINE,
    DEADLINE_LEFT,
    EVENT_FORMAT,
    SNAPSHOT_FORMAT,
    TO_GO,
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


def test_countdowns_are_figures_in_the_snapshot() -> None:
    """The deadline leaf and a turning maneuver put the numbers behind their feedback into the snapshot (``data``), so
    a video counts down from figures, never from the words."""
    h = maneuver_a_running()
    h.tick(2)
    nodes = snapshot_nodes(h.core.snapshot())
    (deadline,) = [n for n in nodes if n.data.get(DEADLINE)]
    assert deadline.data[DEADLINE] == "counting" and deadline.feedback.endswith(" s left")
    assert abs(deadline.data[DEADLINE_LEFT] - float(deadline.feedback.split()[0])) <= 0.05 + 1e-6
    (turning,) = [n for n in nodes if TO_GO in n.data]
    assert turning.name == "Randomizer" and turning.feedback == f"{turning.data[TO_GO]:+.0f} deg to go"
    h.run_until(lambda r: r.tip != "Randomizer")
    assert not [n for n in snapshot_nodes(h.core.snapshot()) if n.name == "Randomizer" and n.data], "done: no figure"


def test_the_trace_carries_the_events_and_replay_shows_them(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Each trace line holds the leaves' announcements since the previous line; ``bt-nav replay`` prints their lines."""
    from bt_nav.cli.replay import main as replay
    from bt_nav.mission.trace import TraceRecorder, read_trace

    h = TickHarness("A")
    trace = TraceRecorder(h.core, tmp_path / "trace.jsonl")
    h.tick()
    h.arm()
    h.tick()
    h.see((0.0, 0.45))
    for _ in range(200):
        trace.record(h.tick().command)
    trace.close()
    _, ticks = read_trace(tmp_path / "trace.jsonl")
    events = [e for line in ticks for e in line.get("events", ())]
    assert [e["event"] for e in events][:2] == ["maneuver", "maneuver_end"], events
    assert events == [e for e in h.core.take_announcements()], "the trace holds what ~/events carried"
    assert replay([str(tmp_path / "trace.jsonl"), "--compact"]) == 0
    out = capsys.readouterr().out
    assert f"[INFO] {events[0]['text']}" in out and events[0]["text"].startswith("Randomizer: front 0.4")
