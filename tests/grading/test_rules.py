"""The page "what your node must do" (``bt_nav.grading.rules``): rendered from the judges' configs (a changed value
changes the page), covering every check and the grader's real names, printed by ``bt-nav rules`` and written into
every grade beside the report that links it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bt_nav.grading.exe.run import ExeSettings, exe_graph
from bt_nav.grading.grid import Job
from bt_nav.grading.rules import RULES_FILE, GradeSetup, grader_checkoff, rules_markdown
from bt_nav.judge.checkoff_core import CHECKS as LAB_CHECKS
from bt_nav.judge.checkoff_core import CheckoffConfig
from bt_nav.judge.referee_core import CHECKS as HOMEWORK_CHECKS
from bt_nav.judge.referee_core import RefereeConfig
from bt_nav.ros.bringup import HOMEWORK_ACTIVATE, HOMEWORK_EVALUATE, LAB_ARM

ROOT = Path(__file__).resolve().parents[2]


def _section(page: str, heading: str) -> str:
    """The text under ``heading`` up to the next heading of any level."""
    return page.split(heading + "\n", 1)[1].split("\n#", 1)[0]


def test_a_changed_config_value_changes_the_page() -> None:
    default = rules_markdown("lab", maneuvers=["C"])
    assert "`pivot_distance` 0.30 m" in default and "0.25" not in default
    page = rules_markdown("lab", maneuvers=["C"], checkoff=CheckoffConfig(pivot_distance=0.25))
    assert "`pivot_distance` 0.25 m" in page and "pivot_distance 0.30" not in page
    assert "late: only once every one of them read < 0.25 m" in page  # the judge's own rule line, live
    wide = rules_markdown("lab", maneuvers=["A"], checkoff=CheckoffConfig(angle_tolerance_deg=5.0))
    assert "turn 85-185 deg either side" in wide and "80-190" not in wide
    slow = rules_markdown("homework", referee=RefereeConfig(evaluation_deadline=40.0, min_travelled=6.0))
    assert "by 40 s (35 s after the first activation call)" in slow and "travel at least 6 m" in slow
    assert "56 s" not in slow


def test_a_node_parameter_moves_the_trigger_as_the_grade_s_judge_gets_it(tmp_path: Path) -> None:
    """``--node-param safety_distance=0.6``: the page triggers at 0.60 m, as the judge a grade starts does."""
    params = (("safety_distance", 0.6),)
    page = rules_markdown("lab", maneuvers=["A"], setup=GradeSetup(node_params=params))
    assert "front < `safety_distance` 0.60 m" in page and "the grade gives it 0.6 m" in page
    assert "-p safety_distance:=0.6" in page  # what is appended to the node's command
    settings = ExeSettings("python3 node.py", "lab", tmp_path, node_params=params)
    sim = exe_graph(Job("lab_object", "A", 0, "lab"), settings, tmp_path / "verdict.json")
    judge_args = json.loads(sim.arguments[sim.arguments.index("--judge-args") + 1])
    assert f"safety_distance:={grader_checkoff('A', dict(params)).safety_distance!r}" in judge_args


def test_every_check_of_each_judge_has_its_line() -> None:
    lab, homework = rules_markdown("lab"), rules_markdown("homework")
    for name in (*LAB_CHECKS, "parameters declared"):
        assert f"\n| {name} | " in _section(lab, "## The lab: the checks"), name
    for name in HOMEWORK_CHECKS:
        assert f"\n| {name} | " in _section(homework, "## The homework: the checks"), name
    for maneuver, name in (("A", "the Randomizer"), ("B", "the Retreat"), ("C", "the Smart Pivot")):
        assert f"### {maneuver}: {name}\n" in lab


def test_the_page_names_the_interface_the_grader_uses() -> None:
    lab, homework = rules_markdown("lab"), rules_markdown("homework")
    assert f"| service | `{LAB_ARM}` | `std_srvs/srv/SetBool` |" in lab
    assert f"| service | `{HOMEWORK_ACTIVATE}` | `std_srvs/srv/SetBool` |" in homework
    assert f"| service | `{HOMEWORK_EVALUATE}` | `std_srvs/srv/Trigger` | calls it once" in homework
    for page in (lab, homework):
        assert "| topic | `scan` | `sensor_msgs/msg/LaserScan` | subscribes |" in page
        assert "| topic | `cmd_vel` | `geometry_msgs/msg/Twist` (not TwistStamped) | publishes |" in page
        assert "`lds01`: TurtleBot3 LDS-01" in page and "`rplidar`: TurtleBot4 RPLIDAR A1" in page
    assert "| `safety_distance` | declares it" in lab
    # the schedule as long as its checks need (issue 52; was "| 5 | ..." and "| 69 | the report |"): armed at 2 s, the
    # final false once the re-armed node drove on, 62 s at the latest
    assert "| 2 | `toggle_navigation` `data: true`" in lab and "| F + 4 | the report |" in lab
    assert "| F = R + 4.5 (later while a turn you began goes on" in lab and "62 at the latest" in lab
    assert "| creep while armed | armed, never standing still 3 s or more" in lab
    assert "-r arm:=/toggle_navigation" in lab and "-r evaluate_mission:=/reactive_control/evaluate_mission" in homework


def test_both_assignments_on_one_page_and_a_refused_profile() -> None:
    page = rules_markdown(note="<!-- note -->")
    assert page.startswith("# What your node must do\n\n<!-- note -->\n")
    assert "\n## The lab: what your node must do\n" in page and "\n## The homework: what your node must do\n" in page
    assert "\n### The lab: interface\n" in page and "\n#### C: the Smart Pivot\n" in page
    with pytest.raises(ValueError, match="lab or homework"):
        rules_markdown("turtlebot3")
    with pytest.raises(ValueError, match="not D"):
        rules_markdown("lab", maneuvers=["D"])


def test_the_page_s_grade_defaults_are_bt_nav_grade_s() -> None:
    from bt_nav.cli.grade import _parser

    args = _parser().parse_args([])
    assert (args.rtf, args.timeout) == (GradeSetup().rtf, GradeSetup().limit)


def test_the_lab_page_names_each_choice_s_cells_as_a_grade_plans_them() -> None:
    """A student reads which arenas their choice is graded in (and the parameter a cell passes) from the page, the
    same cells `bt-nav grade --exe` plans; a grade given --worlds has no such line."""
    from bt_nav.cli.grade import _parser
    from bt_nav.grading.plan import build_jobs

    page = rules_markdown("lab", setup=GradeSetup())
    for choice in "ABC":
        args = _parser().parse_args(["--exe", "python3 n.py", "--profile", "lab", "--maneuvers", choice])
        jobs = build_jobs(args, ["lab_beside", "lab_dead_end", "lab_hallway", "lab_slant", "lab_object"], [0])
        cells = list(dict.fromkeys(f"`{j.world}`" + "".join(f" (`-p {k}:={v:g}`)" for k, v in j.node_params or ())
                                   for j in jobs))
        assert f"{choice}: " + ", ".join(cells) in page
    assert "graded only in the cells" not in rules_markdown("lab", setup=GradeSetup(worlds=("lab_object",)))


def _bt_nav(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "bt_nav.cli", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=60)


def test_bt_nav_rules_prints_the_page() -> None:
    done = _bt_nav("rules", "--profile", "lab", "--maneuvers", "smart_pivot", "--node-param", "safety_distance=0.4")
    assert done.returncode == 0, done.stderr
    assert done.stdout == rules_markdown("lab", maneuvers=["C"], setup=GradeSetup((("safety_distance", 0.4),)))
    assert "### C: the Smart Pivot" in done.stdout and "### A:" not in done.stdout
    both = _bt_nav("rules")
    assert both.returncode == 0 and both.stdout == rules_markdown()
    refused = _bt_nav("rules", "--maneuvers", "none")
    assert refused.returncode == 2 and "the lab's maneuvers are A, B, C, not none" in refused.stderr
    helped = _bt_nav("rules", "--help")
    assert helped.returncode == 0 and helped.stdout.startswith("usage: bt-nav rules")
    assert not any(markup in helped.stdout for markup in ("``", ":mod:", ":func:"))


def test_a_grade_writes_the_rules_and_its_failures_link_them(tmp_path: Path) -> None:
    from bt_nav.grading.report import write_exe_report

    out = tmp_path / "grade"
    rows = []
    for seed, passed in ((0, True), (1, False)):
        run_dir = out / f"lab_object_C_lds02_seed{seed}"
        run_dir.mkdir(parents=True)
        rows.append({"job": f"lab_object|C|{seed}", "world": "lab_object", "maneuver": "C", "lidar": "lds02",
                     "seed": seed, "passed": passed, "outcome": "verdict", "verdict": None,
                     "reason": "passed" if passed else "failed: maneuver 1 turned 45 deg left",
                     "run_dir": str(run_dir), "wall_time": 14.0})
    settings = ExeSettings("python3 node.py", "lab", out, maneuvers=True, record="off", videos="off",
                           node_params=(("safety_distance", 0.45),), rtf=3.0)
    write_exe_report(rows, settings, workers=1)
    rules = (out / RULES_FILE).read_text(encoding="utf-8")
    assert rules.startswith("# The lab: what your node must do\n\nThe rules this grade judged your node by")
    assert "### C: the Smart Pivot" in rules and "### A:" not in rules  # the grade's maneuver only
    assert "`safety_distance` 0.45 m" in rules and "at 3x real time" in rules
    assert "- `lds02`: TurtleBot3 LDS-02" in rules and "`lds01`" not in rules  # the grade's LiDAR only
    assert "It runs the world `lab_object` (this grade's, `--worlds`)" in rules
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert "What your node must do: [rules.md](rules.md)" in _section(summary, "## Failures")
    page = (out / "report.html").read_text(encoding="utf-8")
    why = page.split("<h2>Why runs failed</h2>", 1)[1].split("<h2>", 1)[0]
    assert '<a href="rules.md">rules.md</a>' in why
