"""Child processes that end with their parent, even when the parent is killed with SIGKILL.

    die_with_parent(parent_pid)     call first thing in a child (a forked worker, the render child)

A child forked or spawned by sarfe outlives a parent that is killed with SIGKILL (no ``finally``,
no ``atexit`` runs): the process-pool workers of :mod:`sarfe.util.workers` then sat blocked on
their task pipe for good (150 MB each). Two guards end the child instead:

1. Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` through ctypes — the kernel sends the child
   SIGKILL when the thread that created it exits. sarfe creates its children from the thread that
   waits for them, so that is the parent's death.
2. Everywhere (and the second guard on Linux): a daemon thread that reads ``os.getppid()`` every
   :data:`POLL_S` seconds and ends the process (``os._exit``) once it is no longer
   ``parent_pid`` (the child was re-parented to init or a subreaper).

A parent already gone when the call is made (it died between the fork and this call) ends the
child at once. This module imports nothing from sarfe.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
import time

POLL_S = 1.0              # the watchdog's period [s]: a dead parent's child is gone within it
PR_SET_PDEATHSIG = 1      # <linux/prctl.h>
EXIT_PARENT_GONE = 70     # the child's exit status when the watchdog ends it


def _set_parent_death_signal(signum: int) -> bool:
    """prctl(PR_SET_PDEATHSIG, signum) on Linux; False where there is no such call."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signum), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent_pid: int, period_s: float) -> None:
    while True:
        if os.getppid() != parent_pid:
            os._exit(EXIT_PARENT_GONE)
        time.sleep(period_s)


def die_with_parent(parent_pid: int | None = None, period_s: float = POLL_S) -> bool:
    """End this process when ``parent_pid`` (default: the current parent) ends (module
    docstring). Returns whether the kernel's parent-death signal was set (else only the watchdog
    thread guards)."""
    parent_pid = os.getppid() if parent_pid is None else int(parent_pid)
    kernel = _set_parent_death_signal(signal.SIGKILL)
    if os.getppid() != parent_pid:      # the parent died before the signal was armed
        os._exit(EXIT_PARENT_GONE)
    threading.Thread(target=_watch, args=(parent_pid, period_s), name="sarfe-parent-watch",
                     daemon=True).start()
    return kernel


__all__ = ["die_with_parent", "POLL_S", "EXIT_PARENT_GONE"]
