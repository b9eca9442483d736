"""A module the fork server's tests preload: its import waits until the file named by ``BT_NAV_TEST_GATE`` exists,
so a test decides when the server becomes ready."""

from __future__ import annotations

import os
import time
from pathlib import Path

_gate = Path(os.environ["BT_NAV_TEST_GATE"])
_deadline = time.monotonic() + 60.0
while not _gate.exists() and time.monotonic() < _deadline:
    time.sleep(0.01)
