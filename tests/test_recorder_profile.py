"""The Fast DDS profile every graded run's processes share is written safely by runs starting at once.

A grid starts its runs in threads of one process; each writes the profile if it is missing. With a temporary
name made of the pid alone, two threads shared it: one moved it into place and the other's move failed with
FileNotFoundError, and the run was lost to "bt_nav failed to run it" (seen on a fresh machine, first batch).
"""

from __future__ import annotations

import tempfile
import threading
from pathlib import Path

import pytest

from bt_nav.ros.supervise import DISCOVERY_PROFILE, discovery_profile


def test_runs_starting_at_once_all_get_the_profile(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(tempfile, "gettempdir", lambda: str(tmp_path))
    errors: list[BaseException] = []

    def start() -> None:
        try:
            assert discovery_profile().read_text(encoding="utf-8") == DISCOVERY_PROFILE
        except BaseException as exc:  # noqa: BLE001 - every failure of a thread is the finding
            errors.append(exc)

    for _ in range(150):  # each round from a missing file, 6 runs starting together
        (tmp_path / "bt_nav_discovery_fastdds.xml").unlink(missing_ok=True)
        threads = [threading.Thread(target=start) for _ in range(6)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert not errors, f"{len(errors)} failed, first: {errors[0]!r}"
    assert [p.name for p in tmp_path.iterdir()] == ["bt_nav_discovery_fastdds.xml"], "temporary files left behind"


def test_every_child_gets_the_profile_unless_the_user_named_one(monkeypatch: pytest.MonkeyPatch) -> None:
    """The demo's and the grader's processes alike announce themselves every 0.25 s; a user's own profile stays."""
    from bt_nav.ros.supervise import PROFILE_VARIABLES, child_env

    for name in PROFILE_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    env = child_env(7)
    assert all(env[name] == str(discovery_profile()) for name in PROFILE_VARIABLES)
    assert env["ROS_DOMAIN_ID"] == "7" and env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    monkeypatch.setenv("FASTDDS_DEFAULT_PROFILES_FILE", "/etc/mine.xml")
    env = child_env(7)
    assert env["FASTDDS_DEFAULT_PROFILES_FILE"] == "/etc/mine.xml" and "FASTRTPS_DEFAULT_PROFILES_FILE" not in env
