"""Process-wide locks for the libraries a report task uses that are not thread-safe.

A Dask worker runs several report tasks in threads of one process (``dask worker`` uses
several threads by default, and so does a ``LocalCluster`` with ``threads_per_worker`` > 1).
Two pieces of a report share state across the whole process:

- **matplotlib**: the mathtext parser and the text-metrics caches behind ``tight_layout``
  and log-axis tick labels are module globals; two figures laid out at once in two threads
  fail with ``ParseException`` (matplotlib issue #26289). Every figure of a report is built,
  laid out and encoded under :data:`MATPLOTLIB_LOCK` (``plots.make_plots``).
- **OpenGL / VTK**: an offscreen context is current per thread and VTK's pipeline keeps
  global state; previews are rendered one at a time under :data:`OPENGL_LOCK`
  (``collect.collect_report``).

The numerical work (ducc0, BLAS, nlopt's deterministic BOBYQA) needs no lock. In worker
*processes* (``--workers N``) each process has its own copy of these globals and the locks
are never contended.
"""

from __future__ import annotations

import threading

__all__ = ["MATPLOTLIB_LOCK", "OPENGL_LOCK"]

#: Held while any matplotlib figure of a report is created, drawn and saved.
MATPLOTLIB_LOCK = threading.RLock()

#: Held while a preview is rendered (VTK offscreen context or the CPU fallback).
OPENGL_LOCK = threading.RLock()
