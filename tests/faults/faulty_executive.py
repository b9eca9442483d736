"""The real executive with the faults of ``BT_NAV_FAULT_INJECT`` armed on its tree (test-only entry point).

Run as ``python tests/faults/faulty_executive.py [executive arguments]``; everything else is
``bt-nav executive``. The faults are armed right after the tree is built, before the first tick, and
the node warns in one line that they are.
"""

from __future__ import annotations

import os
import sys
from typing import Any

from faultinject import FAULT_INJECT_ENV, inject_faults

from bt_nav.ros import executive


class FaultyExecutive(executive.Executive):
    """The executive, plus the test-only faults armed on its tree."""

    def __init__(self, node: Any, **kwargs: Any) -> None:
        super().__init__(node, **kwargs)
        spec = os.environ.get(FAULT_INJECT_ENV, "")
        if spec.strip():
            armed = inject_faults(self.core.root, spec)  # ConfigError: main refuses to start
            self.log.warning(f"test-only fault injection armed ({FAULT_INJECT_ENV}): {', '.join(armed)} "
                             "will raise once each")


if __name__ == "__main__":
    executive.Executive = FaultyExecutive  # main() builds the node's executive through this name
    sys.exit(executive.main())
