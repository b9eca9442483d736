"""Session-wide test settings.

Property-based tests run derandomized under CI (``CI=true``): a CI run must not fail on an example
that no earlier run saw. Locally they explore new examples on every run (and keep failures in
``.hypothesis/``), which is where new bugs are found.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")
