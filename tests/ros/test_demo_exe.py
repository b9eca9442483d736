"""``bt-nav demo --exe``: a student's own node (plain rclpy, nothing of bt_nav) run, judged and filmed.

The hand-in: the terminal shows the judge's service calls, the node's own log lines at the sim time it logged
them (the same time the bag holds for that line, from /rosout), and the verdict; the run directory holds the bag
and the video, whose caption says what the robot does while it turns (not "Stopped": the node has no tree).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
from simtools import REPO, Proc

from bt_nav.media.bagread import read_bag
from bt_nav.media.video import VideoRenderer

NODE = f"{sys.executable} {REPO / 'tests' / 'fixtures' / 'homework_node.py'}"
LINE = re.compile(r"^\[sim +(?P<t>[\d.]+) s\] \[INFO\] \[(?P<node>[^\]]+)\]: evaluate_mission called$")


def test_demo_films_a_foreign_node(tmp_path: Path) -> None:
    demo = Proc("demo", "--exe", NODE, "--out", str(tmp_path), "--name", "hand-in", "--timeout", "120")
    code = demo.wait(180.0)
    out = demo.output()
    assert code in (0, 1) and re.search(r"^bt-nav demo: (PASSED|FAILED): ", "\n".join(demo.stdout), re.M), out
    assert any(line.endswith('std_srvs/srv/SetBool "{data: true}"') for line in demo.stdout), out  # the judge's call
    assert any(line.startswith("overall: ") for line in demo.stdout), out  # the judge's report
    [shown] = [float(m["t"]) for m in map(LINE.match, demo.stdout) if m]
    [run_dir] = (tmp_path / "hand-in").iterdir()
    assert (run_dir / "video.mp4").stat().st_size > 10_000, out

    record = read_bag(run_dir / "bag")
    [logged] = [t for t, text in record.events if text.endswith("evaluate_mission called")]
    assert abs(shown - logged) <= 0.3, f"terminal {shown:.2f} s, bag {logged:.2f} s"
    renderer = VideoRenderer(record)
    turning = record.truth.t[np.abs(record.truth.w) > 0.5]
    assert turning.size, "the node never turned"
    caption = renderer.text(float(turning[len(turning) // 2])).lines()[1]
    assert "turning" in caption.split(";")[0] and "Stopped" not in caption, caption


def test_the_hand_in_films_the_maneuver_the_node_declares(tmp_path: Path) -> None:
    """The README's hand-in (``demo --exe ... --profile lab``, no ``--maneuver``) of a right C node whose file says
    ``# CHOICE: C``: filmed doing the Smart Pivot in lab_object, and passed."""
    source = (REPO / "tests" / "fixtures" / "lab_student_node.py").read_text()
    node = tmp_path / "reactive_navigator.py"
    node.write_text(re.sub(r"^# CHOICE: given on the command line.*$", "# CHOICE: C", source, count=1, flags=re.M))
    demo = Proc("demo", "--exe", f"{sys.executable} {node}", "--profile", "lab", "--out", str(tmp_path),
                "--name", "hand-in", "--timeout", "120")
    code = demo.wait(240.0)
    out = demo.output()
    assert demo.stdout and ", lab judge, lab_object, maneuver C, seed 0, " in demo.stdout[0], out
    assert code == 0 and "bt-nav demo: PASSED: passed" in demo.stdout, out
    assert (tmp_path / "hand-in" / "lab_object_C_seed0" / "video.mp4").is_file(), out
