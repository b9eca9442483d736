"""Bad command-line input gets a clear error and exit 2, pipes closed early are quiet, help is plain text."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bt_nav.cli import COMMANDS, plain
from bt_nav.cli.replay import main as replay

ROOT = Path(__file__).resolve().parent.parent


def bt_nav(*args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "bt_nav.cli", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=60, **kwargs)


@pytest.fixture
def trace(tmp_path: Path) -> Path:
    """A three-tick trace of the 'none' tree (what a run writes, trimmed)."""
    path = tmp_path / "trace.jsonl"
    lines = [{"header": {"maneuver": "none"}}]
    for tick in (1, 2, 3):
        lines.append({"tick": tick, "time": tick * 0.05, "tip": "FullSpeed", "statuses": {"Mission": "RUNNING"},
                      "cmd": {"linear": 0.2, "angular": 0.0}})
    path.write_text("\n".join(json.dumps(line) for line in lines) + "\n")
    return path


@pytest.mark.parametrize("option", ["--tick", "--from", "--to"])
def test_replay_refuses_a_tick_outside_the_trace(trace: Path, option: str, capsys: pytest.CaptureFixture) -> None:
    assert replay([str(trace), option, "99999"]) == 2
    err = capsys.readouterr().err
    assert f"{option} 99999 is outside the trace's ticks 1..3" in err


def test_replay_shows_a_tick_inside_the_trace(trace: Path, capsys: pytest.CaptureFixture) -> None:
    assert replay([str(trace), "--tick", "2", "--compact"]) == 0
    assert capsys.readouterr().out.startswith("tick     2")


def test_replay_picture_format_follows_the_extension(trace: Path, tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exc:
        replay([str(trace), "--tick", "1", "--svg", str(tmp_path / "x.jpg")])
    assert exc.value.code == 2
    result = bt_nav("replay", str(trace), "--tick", "1", "--svg", str(tmp_path / "x.gif"))
    assert result.returncode == 2 and "unknown picture format" in result.stderr
    import shutil

    if shutil.which("dot"):
        png = tmp_path / "x.png"
        assert replay([str(trace), "--tick", "1", "--svg", str(png)]) == 0
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"  # a real PNG, not SVG text in a .png


def test_piping_into_head_is_quiet(tmp_path: Path) -> None:
    """A reader that stops early (``| head -1``) ends the command without a BrokenPipe traceback (the
    output is far larger than a pipe's buffer, so the writer does hit the closed pipe)."""
    trace = tmp_path / "long.jsonl"
    lines = [json.dumps({"header": {"maneuver": "C"}})] + [json.dumps(
        {"tick": t, "time": t * 0.05, "tip": "FullSpeed", "statuses": {}, "cmd": {}}) for t in range(1, 3001)]
    trace.write_text("\n".join(lines) + "\n")
    shell = f"{sys.executable} -m bt_nav.cli replay {trace} | head -1"
    result = subprocess.run(["bash", "-o", "pipefail", "-c", shell], cwd=ROOT, capture_output=True, text=True,
                            timeout=60)
    assert "Traceback" not in result.stderr and "BrokenPipe" not in result.stderr, result.stderr
    assert result.returncode == 0, result.stderr


def test_broken_pipe_is_handled_for_every_command_in_the_dispatcher(monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_nav.cli as cli

    class Module:
        @staticmethod
        def main(argv: list[str]) -> int:
            raise BrokenPipeError

    monkeypatch.setattr(cli.importlib, "import_module", lambda name: Module)
    monkeypatch.setattr(cli, "_silence_stdout", lambda: None)
    assert cli.run("dump-tree", []) == 0


@pytest.mark.parametrize("command", ["demo", "replay", "watch", "dump-tree", "sim-run", "arm"])
def test_help_is_plain_text(command: str) -> None:
    result = bt_nav(command, "--help")
    assert result.returncode == 0 and result.stdout.startswith("usage: bt-nav")
    for markup in ("``", ":func:", ":mod:", ":class:"):
        assert markup not in result.stdout, f"{command} --help shows {markup}"
    assert command in COMMANDS


def test_plain_reduces_rst_markup() -> None:
    assert plain("``bt-nav demo`` uses :func:`bt_nav.media.plot.plot_run` and :mod:`~x.y`") == \
        "bt-nav demo uses bt_nav.media.plot.plot_run and x.y"


@pytest.mark.parametrize(("args", "said"), [
    (["--world", "nosuchworld"], "unknown world 'nosuchworld'; bundled worlds: cluttered, "),
    (["--profile", "lab", "--world", "nosuchworld"], "unknown world 'nosuchworld'; bundled worlds: "),
    (["--exe", "true", "--world", "nosuchworld"], "unknown world 'nosuchworld'; bundled worlds: "),
    (["--sim-param", "lidar=foo"], "unknown lidar 'foo'; choose one of lds01, "),
    (["--sim-param", "nope=1"], "--sim-param nope: the simulator has no such setting; it has "),
    (["--rtf", "-2"], "--rtf -2: sim seconds per wall second, >= 0"),
    (["--domain-id", "999"], "--domain-id 999: a ROS_DOMAIN_ID is 0 to 232"),
    (["--exe", ""], "--exe: an empty command"),
])
def test_demo_refuses_a_bad_option_before_anything_starts(args: list[str], said: str, tmp_path: Path) -> None:
    """One line, exit 2, nothing printed as started and no run directory (the simulator would refuse an unknown
    world only once the graph ran, behind a run directory; an unknown setting it would ignore)."""
    result = bt_nav("demo", *args, "--out", str(tmp_path / "runs"), "--timeout", "5")
    assert result.returncode == 2, result.stdout + result.stderr
    assert result.stdout == "" and result.stderr.count("\n") == 1, result.stdout + result.stderr
    assert result.stderr.startswith(f"bt-nav demo: {said}"), result.stderr
    assert not (tmp_path / "runs").exists()
