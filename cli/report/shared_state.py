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

import sys
import threading

from .. import console_state

__all__ = ["MATPLOTLIB_LOCK", "OPENGL_LOCK", "lean_matplotlib"]

#: Held while any matplotlib figure of a report is created, drawn and saved.
MATPLOTLIB_LOCK = threading.RLock()

#: Held while a preview is rendered (VTK offscreen context or the CPU fallback).
OPENGL_LOCK = threading.RLock()

def _no_property_table(artist: object) -> str:
    return ""


def lean_matplotlib() -> None:
    """Before matplotlib is first imported, and only in the console script's process
    (``cli.console_state.CONSOLE_PROCESS``): skip the property tables matplotlib writes into the docstring of
    every ``Artist`` subclass's ``set`` while importing (``matplotlib.artist.kwdoc``: ~0.14 s CPU of
    the ~0.45 s import of ``matplotlib.figure`` and the Agg backend, matplotlib 3.11, this
    project's 2-core machine). Only those docstrings become empty: signatures, properties and
    drawing are unchanged (tests/cli/test_lean_matplotlib.py compares the PNG bytes). A library
    user's process (``shrmkit.report`` in a notebook) is left alone."""
    if not console_state.CONSOLE_PROCESS or "matplotlib.artist" in sys.modules:
        return
    import matplotlib.artist  # matplotlib (~0.5 s): only when a report draws its plots

    matplotlib.artist.kwdoc = _no_property_table
