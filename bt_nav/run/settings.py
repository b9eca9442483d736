"""One way to choose a mission's settings: the profile's params files, then ``--set NAME=VALUE``, then defaults.

Why here: ``bt-nav demo`` (over DDS), ``bt-nav lockstep``, ``bt-nav grade`` and ``bt-nav sim-run`` must run the
same mission for the same profile and overrides. The maneuver is the profile's (``config/homework.yaml``
says C) unless one is asked for, and every run records the full effective parameter table it ran with
(:func:`effective_parameters`), so two runs can be told apart by their files alone.
"""

from __future__ import annotations

from typing import Any

from bt_nav.mission import params as P
from bt_nav.mission.profiles import profile_parameters as profile_file_parameters

#: Spawn perturbation of lock-step runs: uniform within +-metres and +-degrees (None/0 for the exact spawn).
DEFAULT_JITTER = (0.05, 10.0)


def profile_parameters(profile_name: str) -> dict[str, Any]:
    """The tree parameters of the profile's params files, without its maneuver (chosen apart, see
    :func:`profile_maneuver`)."""
    values = profile_file_parameters(profile_name)
    return {k: v for k, v in values.items() if k in P.SPECS and P.SPECS[k].in_tree and k != "maneuver"}


def profile_maneuver(profile_name: str, requested: str | None = None) -> str:
    """The maneuver a run of ``profile_name`` runs: ``requested`` when given, else the profile's params
    files', else none (ValueError for an unknown profile or maneuver)."""
    if requested is not None:
        return P.normalise_maneuver(requested)
    return P.normalise_maneuver(str(profile_file_parameters(profile_name).get("maneuver", "none")))


def tree_settings(profile_name: str, maneuver: str, seed: int, overrides: dict[str, Any] | None = None
                  ) -> dict[str, Any]:
    """The overrides a mission tree gets: the profile's, ``random_seed`` from ``seed``, the user's, the
    maneuver (the user's ``--set`` wins over the profile, the maneuver argument over both)."""
    return {**profile_parameters(profile_name), "random_seed": int(seed) % 2**31, **(overrides or {}),
            "maneuver": P.normalise_maneuver(maneuver)}


def effective_parameters(settings: dict[str, Any]) -> dict[str, Any]:
    """Every parameter's value (the table's defaults under ``settings``), JSON-able: what a run records."""
    return {name: value for name, value in P.resolve(settings).items()}
