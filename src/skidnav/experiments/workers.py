"""Pool workers that do not outlive the ``skidnav run`` process that started them.

A ``ProcessPoolExecutor`` worker blocks on its task queue, whose pipe it holds both ends of, so it
never notices that its parent is gone: after a SIGKILL of the parent (which runs no cleanup) the
workers, and multiprocessing's resource tracker whose pipe they keep open, would wait forever.
:func:`init_worker`, the pool's initializer, guards against that twice:

* on Linux, ``prctl(PR_SET_PDEATHSIG, SIGTERM)`` (prctl(2)): the kernel sends the worker SIGTERM
  the moment its parent dies, even while the worker is inside a compiled kernel;
* everywhere, a daemon thread that polls ``os.getppid()`` and sends the worker SIGTERM once the
  parent has changed (the worker was re-parented), for systems without prctl and for a parent that
  died before prctl took effect.

Once the workers are gone the resource tracker reads end-of-file and exits on its own.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import signal
import sys
import threading
import time

logger = logging.getLogger(__name__)

PR_SET_PDEATHSIG = 1
"""prctl(2) option: signal to receive when the parent dies (linux/prctl.h)."""
WATCH_INTERVAL_S = 1.0
"""How often the watchdog thread checks the parent [s]."""


def set_parent_death_signal(signum: int = signal.SIGTERM) -> bool:
    """Ask the kernel to send ``signum`` to this process when its parent dies (Linux only).

    Returns True if it was set, False where prctl is unavailable (other systems, restricted
    sandboxes).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return bool(libc.prctl(PR_SET_PDEATHSIG, int(signum), 0, 0, 0) == 0)
    except (OSError, AttributeError):
        return False


def watch_parent(parent_pid: int, interval: float = WATCH_INTERVAL_S) -> threading.Thread:
    """Start a daemon thread that sends this process SIGTERM once its parent is no longer
    ``parent_pid``; returns the thread."""

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(interval)
        logger.warning("parent process %d is gone; worker %d stops", parent_pid, os.getpid())
        os.kill(os.getpid(), signal.SIGTERM)

    thread = threading.Thread(target=watch, name="skidnav-parent-watch", daemon=True)
    thread.start()
    return thread


def init_worker(parent_pid: int) -> None:
    """Initializer of a pool worker started by process ``parent_pid``: Ctrl-C is left to the
    parent (which cancels the pool), and the worker ends when the parent dies (module docs)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    set_parent_death_signal(signal.SIGTERM)
    watch_parent(parent_pid)
