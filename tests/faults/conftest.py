"""The fault and bad-input suite: fixtures (the DDS harness of tests/ros, re-exported) and the outcome table.

Why a plugin: the lead pastes the suite's outcome into the README, so every case (a test, or a
sub-case of a test that runs many faults through one executive to keep the suite fast) is recorded
with its category, what was checked and how it ended, and ``runs/faults/outcomes.md`` / ``.json``
are written at the end of the session; the terminal summary prints the count.

Two ways to declare a case:

- a whole test: ``@pytest.mark.fault("category", "what is checked")`` (a parametrized test gives one
  row per parameter set; ``xfail`` tests are rows with the outcome "known bug");
- sub-cases of one test: ``with faults.case("name", "category", "what is checked") as case: ...``.
  A failing sub-case is recorded and the next one runs; the test fails at the end. ``case.note()``
  adds a finding to a row that survived (shown in the table). A case declared with ``known_bug=``
  checks the buggy behaviour with ``case.bug_check(condition, observed)``: when that check fails the
  outcome is "known bug"; when it passes the bug is gone and the case fails (as a strict xfail), so
  the declaration is removed with the fix. Any other failure inside such a case is an ordinary failure.

``BT_NAV_FAULTS_LONG=1`` (``make faults``) selects the long variant: more fuzzing examples, more bursts.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pytest

HERE = Path(__file__).resolve().parent
ROS_TESTS = HERE.parent / "ros"
REPO = HERE.parents[1]
OUT_DIR = REPO / "runs" / "faults"
#: The long variant (``make faults``): more examples and bursts. Read by the test modules.
LONG = os.environ.get("BT_NAV_FAULTS_LONG", "") not in ("", "0")

if str(ROS_TESTS) not in sys.path:
    sys.path.insert(0, str(ROS_TESTS))


def _load_ros_conftest() -> Any:
    """tests/ros/conftest.py as a module of its own name (pytest imports it as ``conftest``)."""
    spec = importlib.util.spec_from_file_location("bt_nav_ros_conftest", ROS_TESTS / "conftest.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_ros = _load_ros_conftest()
# Re-exported: the harness's own fixtures (one implementation of the DDS harness, not a copy).
ros_context = _ros.ros_context
start_executive = _ros.start_executive
executive = _ros.executive

from ros_harness import V_MAX, W_MAX, Harness  # noqa: E402  (tests/ros is on sys.path now)

CASES_KEY = pytest.StashKey[list["CaseRecord"]]()
TWISTS_KEY = pytest.StashKey[list[int]]()  # [executives, twists checked, insane twists]
ITEM_CASES_KEY = pytest.StashKey["FaultCases"]()
PHASES_KEY = pytest.StashKey[list[pytest.TestReport]]()


# ---------------------------------------------------------------------------------------------- records
@dataclass
class CaseRecord:
    """One row of the outcome table."""

    case: str
    category: str
    checked: str
    outcome: str  # "survived" | "known bug" | "failed" | "skipped"
    detail: str = ""
    test: str = ""
    seconds: float = 0.0


class KnownBugObservedError(AssertionError):
    """The check of a declared known bug failed: the bug is still there."""


@dataclass
class CaseNotes:
    """What a running sub-case may add: findings shown next to a "survived", the check of a known bug."""

    findings: list[str] = field(default_factory=list)
    bug_checked: bool = False

    def note(self, finding: str) -> None:
        """A finding that does not fail the case (a documented gap or a design observation)."""
        self.findings.append(finding)

    def bug_check(self, fixed: bool, observed: str) -> None:
        """The one assertion a known bug breaks: ``fixed`` is what correct code gives."""
        self.bug_checked = True
        if not fixed:
            raise KnownBugObservedError(observed)


def first_line(exc: BaseException) -> str:
    """The first non-empty line of an exception, for a table cell."""
    text = str(exc).strip() or type(exc).__name__
    return text.splitlines()[0][:300]


class FaultCases:
    """The sub-cases of one test (the ``faults`` fixture)."""

    def __init__(self, test: str) -> None:
        self.test = test
        self.records: list[CaseRecord] = []
        self.failures: list[str] = []

    @contextmanager
    def case(self, name: str, category: str, checked: str, *, known_bug: str | None = None) -> Iterator[CaseNotes]:
        """Run one sub-case: a failure is recorded (and fails the test at the end) instead of stopping the rest."""
        notes = CaseNotes()
        started = time.monotonic()
        record = CaseRecord(name, category, checked, "survived", test=self.test)
        try:
            yield notes
        except KnownBugObservedError as exc:
            if known_bug is not None:
                record.outcome, record.detail = "known bug", f"{known_bug} (observed: {first_line(exc)})"
            else:
                record.outcome, record.detail = "failed", first_line(exc)
                self.failures.append(f"{name}: {first_line(exc)}")
        except Exception as exc:  # AssertionError mostly; anything else is a failure of the case too
            record.outcome, record.detail = "failed", first_line(exc)
            self.failures.append(f"{name}: {first_line(exc)}")
        else:
            if known_bug is not None:
                record.outcome = "failed"
                record.detail = (f"known bug no longer reproduces ({known_bug}): fixed? drop known_bug"
                                 if notes.bug_checked else "a known-bug case must call case.bug_check()")
                self.failures.append(f"{name}: {record.detail}")
            else:
                record.detail = "; ".join(notes.findings)
        finally:
            record.seconds = round(time.monotonic() - started, 2)
            self.records.append(record)


# ---------------------------------------------------------------------------------------------- fixtures
@pytest.fixture
def faults(request: pytest.FixtureRequest) -> FaultCases:
    """Sub-cases of this test (see the module docstring)."""
    cases = FaultCases(request.node.nodeid)
    request.node.stash[ITEM_CASES_KEY] = cases
    return cases


@pytest.fixture
def make_harness(ros_context: Any, request: pytest.FixtureRequest) -> Iterator[Callable[..., Harness]]:
    """tests/ros's factory, plus a count of the twists it checked for the session's summary row."""
    made: list[Harness] = []

    def make(**kwargs: Any) -> Harness:
        harness = Harness(ros_context, **kwargs)
        made.append(harness)
        return harness

    yield make
    for harness in made:
        for server in harness.__dict__.get("fault_servers", []):  # faultkit.EvaluationServer: a node of its own
            server.close()
        harness.close()
    totals = request.config.stash.setdefault(TWISTS_KEY, [0, 0, 0])
    for harness in made:
        totals[0] += 1
        totals[1] += len(harness.samples)
        totals[2] += sum(1 for s in harness.samples if not twist_is_sane(s.linear, s.angular))
    for harness in made:
        harness.assert_sane()


def twist_is_sane(linear: float, angular: float) -> bool:
    """Finite and within the default limits (ros_harness.V_MAX, W_MAX)."""
    return (math.isfinite(linear) and math.isfinite(angular) and abs(linear) <= V_MAX + 1e-9
            and abs(angular) <= W_MAX + 1e-9)


# ---------------------------------------------------------------------------------------------- the plugin
def pytest_configure(config: pytest.Config) -> None:
    """Register the ``fault`` marker (--strict-markers)."""
    config.addinivalue_line("markers", "fault(category, checked): a test that is one case of the fault suite")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Every test here that uses the DDS harness is a ``ros`` test (``-m 'not ros'`` skips them)."""
    for item in items:
        if HERE in item.path.parents and {"make_harness", "executive", "start_executive"} & set(
                getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.ros)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Any:
    """A test whose sub-cases failed fails, after all of them ran."""
    result = yield
    cases = item.stash.get(ITEM_CASES_KEY, None)
    if cases is not None and cases.failures:
        raise AssertionError(f"{len(cases.failures)} of {len(cases.records)} fault cases failed:\n  "
                             + "\n  ".join(cases.failures))
    return result


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """Collect each phase's report; after teardown, turn the test into rows."""
    report: pytest.TestReport = yield
    item.stash.setdefault(PHASES_KEY, []).append(report)
    if report.when == "teardown":
        _record_item(item)
    return report


def _record_item(item: pytest.Item) -> None:
    """Rows for one finished test: its sub-cases, or the test itself when it is marked ``fault``."""
    rows = item.config.stash.setdefault(CASES_KEY, [])
    reports = item.stash.get(PHASES_KEY, [])
    failed = next((r for r in reports if r.failed), None)
    cases = item.stash.get(ITEM_CASES_KEY, None)
    if cases is not None and cases.records:
        rows.extend(cases.records)
        if failed is not None and not cases.failures:  # e.g. a teardown check (insane twist) failed
            rows.append(CaseRecord(f"{item.name} (test)", "harness", "setup/teardown checks", "failed",
                                   _report_line(failed), item.nodeid))
        return
    marker = item.get_closest_marker("fault")
    if marker is None and cases is None:
        return
    category = str(marker.args[0]) if marker is not None and marker.args else "misc"
    checked = str(marker.args[1]) if marker is not None and len(marker.args) > 1 else ""
    name = _case_name(item)
    call = next((r for r in reports if r.when == "call"), None)
    if failed is not None:
        outcome, detail = "failed", _report_line(failed)
    elif call is not None and hasattr(call, "wasxfail"):
        outcome, detail = "known bug", str(call.wasxfail).removeprefix("reason: ")
    elif any(r.skipped for r in reports):
        outcome, detail = "skipped", _report_line(next(r for r in reports if r.skipped))
    else:
        outcome, detail = "survived", ""
    seconds = sum(r.duration for r in reports)
    rows.append(CaseRecord(name, category, checked, outcome, detail, item.nodeid, round(seconds, 2)))


def _case_name(item: pytest.Item) -> str:
    """``test_signal_mid_maneuver[SIGINT]`` -> ``signal mid maneuver [SIGINT]``."""
    base = getattr(item, "originalname", item.name).removeprefix("test_").replace("_", " ")
    spec = getattr(item, "callspec", None)
    return f"{base} [{spec.id}]" if spec is not None else base


def _report_line(report: pytest.TestReport) -> str:
    """One line from a failed or skipped report."""
    if report.skipped and isinstance(report.longrepr, tuple):
        return str(report.longrepr[2])[:300]
    crash = getattr(report.longrepr, "reprcrash", None)
    if crash is not None:
        return str(crash.message).splitlines()[0][:300]
    return str(report.longrepr).strip().splitlines()[-1][:300] if report.longrepr else ""


def _summary_row(config: pytest.Config) -> CaseRecord | None:
    """The session row for "every twist of every case was finite and within the limits"."""
    executives, twists, insane = config.stash.get(TWISTS_KEY, [0, 0, 0])
    if not executives:
        return None
    return CaseRecord("every cmd_vel of every DDS case", "commands",
                      f"all {twists} twists published by {executives} executives (observed by the harness node) "
                      "finite and within max_linear_speed / max(angular_speed, maneuver_angular_speed)",
                      "survived" if insane == 0 else "failed",
                      "" if insane == 0 else f"{insane} insane twists", "session")


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


#: Table order: the categories of the issue, then anything else in the order run.
CATEGORY_ORDER = ("scan", "timing", "services", "process", "parameters", "mission", "commands")


def write_outcomes(rows: list[CaseRecord], directory: Path) -> tuple[Path, Path]:
    """``outcomes.md`` (the README table, rows by category) and ``outcomes.json`` in ``directory``."""
    directory.mkdir(parents=True, exist_ok=True)
    rank = {category: i for i, category in enumerate(CATEGORY_ORDER)}
    rows = sorted(rows, key=lambda row: rank.get(row.category, len(rank)))
    counts = outcome_counts(rows)
    lines = [f"Fault suite{' (long variant)' if LONG else ''}: {len(rows)} cases, {counts['survived']} survived"
             + counts_tail(counts), "",
             "| case | category | what was checked | outcome |", "|---|---|---|---|"]
    for row in rows:
        outcome = row.outcome + (f": {row.detail}" if row.detail else "")
        lines.append(f"| {_cell(row.case)} | {_cell(row.category)} | {_cell(row.checked)} | {_cell(outcome)} |")
    md = directory / "outcomes.md"
    md.write_text("\n".join(lines) + "\n")
    js = directory / "outcomes.json"
    js.write_text(json.dumps({"long": LONG, "counts": counts, "cases": [asdict(r) for r in rows]}, indent=2) + "\n")
    return md, js


def counts_tail(counts: dict[str, int]) -> str:
    """``, 5 known bugs, 1 failed`` (only the outcomes that occurred)."""
    parts = []
    for key in ("known bug", "failed", "skipped"):
        if counts[key]:
            parts.append(f", {counts[key]} {key}{'s' if key == 'known bug' and counts[key] != 1 else ''}")
    return "".join(parts)


def outcome_counts(rows: list[CaseRecord]) -> dict[str, int]:
    """Rows per outcome (every outcome key present)."""
    counts = {"survived": 0, "known bug": 0, "failed": 0, "skipped": 0}
    for row in rows:
        counts[row.outcome] = counts.get(row.outcome, 0) + 1
    return counts


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Write the outcome table when any fault case ran."""
    rows = list(session.config.stash.get(CASES_KEY, []))
    if not rows:
        return
    summary = _summary_row(session.config)
    if summary is not None:
        rows.append(summary)
    session.config.stash[CASES_KEY] = rows
    write_outcomes(rows, OUT_DIR)


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    """``fault suite: N cases, N survived ...`` and where the table is."""
    rows = config.stash.get(CASES_KEY, [])
    if not rows:
        return
    counts = outcome_counts(rows)
    terminalreporter.write_sep("=", "fault suite")
    terminalreporter.write_line(f"fault suite{' (long)' if LONG else ''}: {len(rows)} cases, "
                                f"{counts['survived']} survived{counts_tail(counts)} -> {OUT_DIR / 'outcomes.md'}")
    for row in rows:
        if row.outcome in ("failed", "known bug"):
            terminalreporter.write_line(f"  {row.outcome}: {row.case}: {row.detail}")
