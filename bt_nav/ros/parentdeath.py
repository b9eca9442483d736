"""The kernel's signal to a process whose parent dies (Linux ``prctl(PR_SET_PDEATHSIG)``), asked for by every process
bt_nav starts (:func:`bt_nav.ros.supervise.child_preexec`) or forks (:mod:`bt_nav.ros.forkserver`)."""

from __future__ import annotations

import ctypes
import os
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


def die_with_parent(prctl: Callable[..., int] | None, death_signal: int, parent_pid: int) -> bool:
    """In a child between fork and its work: ask for ``death_signal`` when its parent ends (``prctl`` from
    :func:`libc_prctl`, looked up before the fork); False when the parent ``parent_pid`` has ended already (between
    the fork and the request, which then comes too late)."""
    if prctl is not None:
        prctl(PR_SET_PDEATHSIG, int(death_signal), 0, 0, 0)
    return os.getppid() == parent_pid
