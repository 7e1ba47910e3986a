"""Worker processes that end with the process that started them.

A ``kill -9`` of ``drape generate`` or ``drape train`` gives its worker processes (a process pool's,
a device's, a DataLoader's) no chance to be told: without more, they run on as orphans, holding
memory, CPU cores and GPUs. :func:`die_with_parent`, called first thing in a worker, asks the Linux
kernel to send the worker SIGKILL when its parent ends (``prctl(PR_SET_PDEATHSIG)``), and ends the
worker at once if the parent has already gone. Elsewhere (macOS, Windows) it does nothing.

Linux sends the signal when the *thread* that started the worker ends; drape starts its workers
from the main thread (process pools submit from it, DataLoaders iterate in it).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import multiprocessing
import os
import signal
import sys

log = logging.getLogger(__name__)

PR_SET_PDEATHSIG = 1
"""``prctl`` option: the signal this process gets when its parent ends (linux/prctl.h)."""


def die_with_parent(parent_pid: int | None = None) -> bool:
    """Have this process killed (SIGKILL) when its parent ends; returns whether that is armed.

    Args:
        parent_pid: the parent's pid as the parent knew it (default: multiprocessing's parent, else the
            current parent). If the parent is no longer it (it died before this ran), this process
            ends now.
    """
    if not sys.platform.startswith("linux"):
        return False
    if parent_pid is None:
        parent = multiprocessing.parent_process()
        parent_pid = parent.pid if parent is not None else os.getppid()
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            log.debug("prctl(PR_SET_PDEATHSIG) failed: errno %d", ctypes.get_errno())
            return False
    except (OSError, AttributeError):
        return False
    if os.getppid() != parent_pid:  # the parent died between our start and the prctl: nobody will signal
        os.kill(os.getpid(), signal.SIGKILL)
    return True


def die_with_parent_worker(_worker_id: int = 0) -> None:
    """:func:`die_with_parent` in the form of a torch DataLoader ``worker_init_fn``."""
    die_with_parent()
