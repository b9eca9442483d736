"""Gradescope's autograder results.json, as its documentation describes it
(https://gradescope-autograders.readthedocs.io/en/latest/specs/): the keys it knows at the top and in each test,
their types and values. A hand-written check rather than a JSON Schema library: none is installed with bt_nav.
"""

from __future__ import annotations

from typing import Any

VISIBILITY = {"visible", "hidden", "after_due_date", "after_published"}
#: Gradescope's documented keys: top level, and each test.
TOP = {"score": (int, float), "execution_time": (int, float), "output": str, "output_format": str,
       "test_output_format": str, "test_name_format": str, "visibility": str, "stdout_visibility": str,
       "extra_data": dict, "tests": list, "leaderboard": list}
TEST = {"score": (int, float), "max_score": (int, float), "status": str, "name": str, "name_format": str,
        "number": str, "output": str, "output_format": str, "tags": list, "visibility": str, "extra_data": dict}


def gradescope_problems(doc: dict[str, Any]) -> list[str]:
    """What in ``doc`` Gradescope's spec does not allow (empty: it validates)."""
    problems = [f"unknown key {k}" for k in doc if k not in TOP]
    problems += [f"{k} is {type(v).__name__}" for k, v in doc.items() if k in TOP and not isinstance(v, TOP[k])]
    if "score" not in doc and not all("score" in t for t in doc.get("tests", [])):
        problems.append("no score, and a test without one")
    for key in ("visibility", "stdout_visibility"):
        if key in doc and doc[key] not in VISIBILITY:
            problems.append(f"{key} {doc[key]!r}")
    for i, test in enumerate(doc.get("tests", [])):
        problems += [f"test {i}: unknown key {k}" for k in test if k not in TEST]
        problems += [f"test {i}: {k} is {type(v).__name__}" for k, v in test.items()
                     if k in TEST and (not isinstance(v, TEST[k]) or isinstance(v, bool))]
        if test.get("visibility", "visible") not in VISIBILITY or test.get("status", "passed") not in {"passed",
                                                                                                      "failed"}:
            problems.append(f"test {i}: visibility or status {test.get('visibility')!r} {test.get('status')!r}")
        if not 0 <= test.get("score", 0) <= test.get("max_score", test.get("score", 0)):
            problems.append(f"test {i}: score {test.get('score')} outside 0..max_score")
    return problems
