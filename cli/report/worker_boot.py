"""The first code a report worker process runs (``shrm report --workers N``): it ties the process
to its driver *before* the heavy imports.

A worker process is started with the ``spawn`` method; its target's module is imported when the
process object is unpickled. With :func:`~shrmkit.cli.report._pool._worker_main` as the target,
that meant importing the report modules (numpy, scipy, matplotlib: 1.5 s of CPU, about 3 s on a
loaded machine) before the parent-death signal was set, so a driver killed in those seconds left
its workers running until their imports ended (issue 30). This module imports only the standard
library: :func:`boot` sets ``PR_SET_PDEATHSIG`` (Linux, ``prctl(2)``) and checks that the driver is
still there, then imports its target by name (the process engine's worker loop) and runs it.
"""

from __future__ import annotations

import ctypes
import importlib
import os
import signal
import sys
from typing import Any

__all__ = ["boot"]

_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def boot(target: str, parent_pid: int, *args: Any) -> None:
    """A worker process tied to its driver ``parent_pid`` from its first line (SIGKILL on the driver's
    death; exit at once if it is already gone), then ``target`` (``"module:function"``, imported only
    now: the heavy imports run under the parent-death signal) called with ``args``.

    ``shrm report --workers N`` starts ``boot("shrmkit.cli.report._pool:_worker_main", pid, conn,
    threads, preview_mode, pid)``; that loop also starts the watch thread of systems without
    ``prctl``."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - a libc without prctl
            pass
    if os.getppid() != parent_pid:  # the driver died before the signal was set
        os._exit(1)
    module, _, function = target.partition(":")
    getattr(importlib.import_module(module), function)(*args)
