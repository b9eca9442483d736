"""The lab's check-off judged from a robot's bag (``bt-nav checkoff --bag``), without DDS: SIMULATED bags
(tests/media/robotsynth.py: bt_nav_sim's physics and LDS-02 model, a scripted template node, real-robot effects laid
on top) in the three formats a lab's robot records, judged against the simulation's ground truth."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.judge.recorded import judge_recording, report_lines
from bt_nav.media.bag import BagError
from bt_nav.media.robotbag import Topics, read_robot_bag
from tests.media.robotsynth import Effects, Layout, Synth, simulate, write_rosbag1, write_rosbag2

ROOT = Path(__file__).resolve().parents[2]


def _judge(bag: Path, maneuver: str = "A") -> dict:
    return judge_recording(read_robot_bag(bag), CheckoffConfig(maneuver=maneuver))


def _truth_error(run: Synth, res: dict) -> list[float]:
    """Degrees between each judged maneuver's angle (odometry yaw) and the true turn over the same window."""
    t0 = res["feed"]["t0"]  # the report's time zero on the bag's clock (the run's own seconds here)
    return [abs(m["angle_deg"] - run.true_turn(t0 + m["t"], t0 + m["settled"])) for m in res["maneuvers"]]


@pytest.mark.parametrize("fmt", ["mcap", "sqlite3", "ros1"])
def test_a_right_node_passes_in_every_format_within_3_deg_of_the_truth(tmp_path: Path, fmt: str) -> None:
    effects = Effects()  # slip and drift in the pivot, twist spikes, stamps 0.3 s ahead, 20 % NaN, LDS-02
    run = simulate(effects=effects)
    bag = write_rosbag1(run, tmp_path / "run.bag", effects) if fmt == "ros1" else \
        write_rosbag2(run, tmp_path / "run", fmt, effects)
    res = _judge(bag)
    assert res["passed"], report_lines(res)
    assert len(res["judged_maneuvers"]) == 1
    m = res["maneuvers"][0]
    assert m["side"] == "right" and m["forward_command"] == 0.0 and m["forward_motion"] < 0.03
    errors = _truth_error(run, res)
    assert errors and max(errors) < 3.0, errors
    assert abs(m["angle_deg"]) > 100  # the pose's yaw, not the spiking twist (+-100 rad/s would read thousands)
    names = {n["name"] for n in res["not_judged"]}
    assert {"static before activation", "toggle_navigation answered", "no collision"} <= names
    assert "service calls not visible" in res["feed"]["arming"]
    assert any("ahead of their receive times" in note for note in res["feed"]["notes"])
    # the node's /rosout line at its turn reaches the judge as an announcement; the base's own line does not
    assert res["announcements"] == 1


def test_service_events_judge_the_static_checks(tmp_path: Path) -> None:
    effects = Effects(service_events=True)
    run = simulate(effects=effects)
    res = _judge(write_rosbag2(run, tmp_path / "run", "mcap", effects))
    checks = {c["name"]: c for c in res["checks"]}
    assert checks["toggle_navigation answered"]["passed"] and checks["static after deactivation"]["passed"]
    assert res["feed"]["arming"] == "toggle_navigation service events" and res["passed"]


def test_driving_forward_in_the_turn_fails_on_the_command_and_on_odometry(tmp_path: Path) -> None:
    run = simulate(forward_in_turn=0.05)
    res = _judge(write_rosbag2(run, tmp_path / "run", "mcap"))
    assert not res["passed"]
    line = next(c for c in res["checks"] if c["name"] == "maneuver 1")
    assert not line["passed"] and "drove forward during the turn" in line["reason"]
    assert res["maneuvers"][0]["forward_motion"] > 0.03


def test_a_wrong_angle_fails_for_it(tmp_path: Path) -> None:
    res = _judge(write_rosbag2(simulate(turn_deg=-45.0), tmp_path / "run", "mcap"))
    line = next(c for c in res["checks"] if c["name"] == "maneuver 1")
    assert not res["passed"] and not line["passed"] and "deg right" in line["reason"]


def test_a_gap_inside_the_maneuver_makes_it_not_judged_never_passed(tmp_path: Path) -> None:
    effects = Effects(gap=(13.0, 4.0))
    run = simulate(effects=effects)
    res = _judge(write_rosbag2(run, tmp_path / "run", "mcap", effects))
    assert not res["passed"]
    assert not res["judged_maneuvers"]
    why = " ".join(n["why"] for n in res["not_judged"] if n["name"] in ("a turn", "maneuver 1"))
    assert "turned -1" in why and ("no /scan for" in why or "no /cmd_vel for" in why), res["not_judged"]
    assert not any(f.startswith(("stuck", "moved by hand")) for f in res["flags"]), res["flags"]  # silence is not
    assert any(f.startswith("no /scan for 4.") for f in res["flags"]), res["flags"]
    performed = next(c for c in res["checks"] if c["name"] == "maneuvers")
    assert not performed["passed"] and "1 not judged" in performed["detail"] and performed["status"] == "INCOMPLETE"
    assert res["verdict"] == "INCOMPLETE" and report_lines(res)[-1].startswith("overall: INCOMPLETE (")


def test_a_person_turning_the_robot_is_named_and_not_judged(tmp_path: Path) -> None:
    effects = Effects(handled_at=14.0)
    run = simulate(effects=effects)
    res = _judge(write_rosbag2(run, tmp_path / "run", "mcap", effects))
    flag = next(f for f in res["flags"] if f.startswith("moved by hand from t="))
    assert "against the command" in flag
    assert not res["judged_maneuvers"] and not res["passed"]


def test_a_stalled_turn_is_named_and_not_judged(tmp_path: Path) -> None:
    effects = Effects(stall_at=14.0)
    run = simulate(effects=effects)
    res = _judge(write_rosbag2(run, tmp_path / "run", "sqlite3", effects))
    assert any(f.startswith("stuck from t=") and "while commanded -0.60 rad/s" in f for f in res["flags"]), res["flags"]
    assert not res["judged_maneuvers"] and not res["passed"]


def test_a_window_and_an_arming_time_are_honoured(tmp_path: Path) -> None:
    from bt_nav.judge.recorded import Window

    rec = read_robot_bag(write_rosbag2(simulate(), tmp_path / "run", "mcap"))
    before = judge_recording(rec, CheckoffConfig(maneuver="A"), Window(end=10.0))
    assert not before["maneuvers"] and not before["passed"]
    given = judge_recording(rec, CheckoffConfig(maneuver="A"), Window(armed_at=2.0))
    assert "--armed-at" in given["feed"]["arming"] and given["passed"]


def test_bad_bags_are_one_line_errors(tmp_path: Path) -> None:
    (tmp_path / "junk.bag").write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    (tmp_path / "text.mcap").write_text("not a bag")
    for path in (tmp_path / "missing", tmp_path / "junk.bag", tmp_path / "text.mcap"):
        with pytest.raises(BagError):
            read_robot_bag(path)
    bag = write_rosbag2(simulate(end=8.0), tmp_path / "run", "mcap")
    with pytest.raises(BagError, match="no /robot1/odom topic"):
        read_robot_bag(bag, Topics(namespace="robot1"))
    with pytest.raises(BagError, match="/odom is nav_msgs/msg/Odometry, not geometry_msgs"):
        read_robot_bag(bag, Topics(cmd="odom"))


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_nav.cli", "checkoff", *args], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)


def test_the_command_judges_a_bag_writes_the_json_and_refuses_what_a_bag_cannot_honour(tmp_path: Path) -> None:
    bag = write_rosbag1(simulate(), tmp_path / "run.bag")
    node = tmp_path / "reactive_navigator.py"
    node.write_text("import rclpy\n# CHOICE: A\n")
    done = _cli("--bag", str(bag), "--node", str(node), "--json", str(tmp_path / "v.json"))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "overall: PASSED" in done.stdout and "no collision: NOT JUDGED" in done.stdout
    verdict = json.loads((tmp_path / "v.json").read_text())
    assert verdict["passed"] and verdict["maneuver"] == "A" and verdict["config"]["forward_motion_max"] == 0.03
    assert verdict["report_lines"][-1] == "overall: PASSED"
    for args in (["--world", "lab_object"], ["--seed", "3"]):
        refused = _cli("--bag", str(bag), "--maneuver", "A", *args)
        assert refused.returncode == 2 and f"{args[0]} means nothing with --bag" in refused.stderr
    assert _cli("--armed-at", "3").returncode == 2
    broken = _cli("--bag", str(tmp_path / "nothing"), "--maneuver", "A")
    assert broken.returncode == 2 and "Traceback" not in broken.stderr and len(broken.stderr.splitlines()) == 1
    assert math.isfinite(verdict["maneuvers"][0]["angle_deg"])


def test_a_namespace_twiststamped_commands_and_the_lidar_mount_from_tf(tmp_path: Path) -> None:
    bag = write_rosbag2(simulate(), tmp_path / "run", "mcap",
                        layout=Layout(namespace="/tb3_1", stamped=True, tf_mount=True))
    rec = read_robot_bag(bag, Topics(namespace="tb3_1"))
    assert rec.mount == (-0.032, 0.0) and rec.commands and rec.topics["cmd"] == "/tb3_1/cmd_vel"
    res = judge_recording(rec, CheckoffConfig(maneuver="A"))
    assert res["passed"] and res["feed"]["lidar_mount"] == [-0.032, 0.0], report_lines(res)
    with pytest.raises(BagError, match="no /odom topic"):
        read_robot_bag(bag)


def test_service_events_as_rclpy_serialises_them_server_side(tmp_path: Path) -> None:
    """The events a node's introspected service publishes (REQUEST_RECEIVED, RESPONSE_SENT), serialised by rclpy
    itself, give the arming and the disarming."""
    from rclpy.serialization import serialize_message
    from std_srvs.srv import SetBool

    def event(kind: int, seq: int, t: float, data: bool | None = None, success: bool | None = None) -> bytes:
        ev = SetBool.Event()
        ev.info.event_type, ev.info.sequence_number = kind, seq
        ev.info.stamp.sec, ev.info.stamp.nanosec = int(t), int((t % 1) * 1e9)
        ev.info.client_gid = [9] * 16
        if data is not None:
            ev.request = [SetBool.Request(data=data)]
        if success is not None:
            ev.response = [SetBool.Response(success=success, message="ok")]
        return serialize_message(ev)

    topic, typename = "/toggle_navigation/_service_event", "std_srvs/srv/SetBool_Event"
    raw = ((topic, typename, 3.0, event(1, 1, 3.0, data=True)),
           (topic, typename, 3.01, event(2, 1, 3.01, success=True)),
           (topic, typename, 28.0, event(1, 2, 28.0, data=False)),
           (topic, typename, 28.01, event(2, 2, 28.01, success=True)))
    rec = read_robot_bag(write_rosbag2(simulate(), tmp_path / "run", "mcap", raw=raw))
    assert [(c.t, c.data, c.success) for c in rec.calls] == [(3.0, True, True), (28.0, False, True)]
    res = judge_recording(rec, CheckoffConfig(maneuver="A"))
    checks = {c["name"]: c for c in res["checks"]}
    t0 = rec.start  # the report's time zero: the first /odom, /scan or /cmd_vel message
    expected = f"true at t={3.01 - t0:.2f} s, false at t={28.01 - t0:.2f} s"
    assert checks["toggle_navigation answered"]["detail"] == expected
    assert checks["static after deactivation"]["passed"] and res["passed"], report_lines(res)


def test_a_turn_cut_by_the_disarm_is_not_failed_on_its_angle(tmp_path: Path) -> None:
    """Disarmed 1 s into the turn: with the service events the judge knows the disarm cut it ("interrupted");
    without them the turn ends with the run's last command, and its angle is not judged either way."""
    effects = Effects(service_events=True)
    run = simulate(disarm_at=14.5, end=18.0, effects=effects)
    seen = _judge(write_rosbag2(run, tmp_path / "events", "mcap", effects))
    assert seen["maneuvers"][0]["rule"] == "interrupted by the disarm (angle not judged)"
    unseen = _judge(write_rosbag2(run, tmp_path / "plain", "mcap"))
    (entry,) = [n for n in unseen["not_judged"] if n["name"] == "maneuver 1"]
    assert "ended with the run's last command" in entry["why"] and abs(unseen["maneuvers"][0]["angle_deg"]) < 80
    assert not unseen["passed"]  # no complete maneuver: never a pass


def test_a_toggle_cycle_in_the_service_events_is_the_judges_toggle_cycle(tmp_path: Path) -> None:
    """true, false, true, false: the robot stopped between the middle two is not armed there (its stop is no
    "did not move on"), and the last false is the disarm."""
    effects = Effects(service_events=True)
    run = simulate(pause=(18.5, 22.0), effects=effects)
    res = _judge(write_rosbag2(run, tmp_path / "run", "mcap", effects))
    answered = next(c for c in res["checks"] if c["name"] == "toggle_navigation answered")
    assert "toggle cycle" in answered["detail"] and answered["passed"], answered
    assert res["passed"] and len(res["judged_maneuvers"]) == 1, report_lines(res)
    assert res["times"]["deactivation_requested"] == pytest.approx(28.0 - res["feed"]["t0"], abs=0.05)
    assert not res["flags"], res["flags"]  # a node disarmed by the cycle may fall silent
