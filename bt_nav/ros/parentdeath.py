"""The kernel's signal to a process whose parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``), asked for by every process
bt_nav starts (:func:`bt_nav.ros.supervise.child_preexec`) or forks (:mod:`bt_nav.ros.forkserver`)."""

from __future__ import annotations

import ctypes
from collections.abc import Callable

#: ``prctl``'s option: the signal this process gets when the thread that made it ends.
PR_SET_PDEATHSIG = 1


def libc_prctl() -> Callable[..., int] | None:
    """libc's ``prctl``, looked up in the parent (nothing but the call itself may run after a fork); None where there is
    none (not Linux: the watchdog pipe still covers the launcher's death)."""
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None
