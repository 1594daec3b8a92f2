"""The ``shrm`` command line and the report application: thin wrappers that parse, call the
public API of :mod:`shrmkit.brdf_io`, :mod:`shrmkit.analysis` and :mod:`shrmkit.render`, and
format. The top of the stack: nothing imports it.

Public API:

- The command ``shrm`` (entry point ``shrmkit.cli.main:console_main``, which calls ``main``): its
  verbs, options, exit statuses and ``--json`` documents (``data_specs/``) are the interface of this layer.
- From Python — the names in ``__all__``, importable from ``shrmkit.cli``: :class:`Report`
  (one BRDF's report, as ``shrmkit.report(...)`` returns it), :func:`run_batch` (``shrm report``
  over many BRDFs, on worker processes or a Dask cluster) → :class:`BatchResult`, with
  :class:`ReportOptions` (what a report computes).

Modules not listed here (the ``cmd_<verb>`` modules, ``main``, ``common``, everything in
``cli/report/`` but the names above) are internal: their names may change without notice.
Names are imported on first use, so the command line starts without loading the reports.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name → the module that defines it (imported on first use).
_LAZY = {
    "Report": "shrmkit.cli.report.api",
    "ReportOptions": "shrmkit.cli.report.options",
    "run_batch": "shrmkit.cli.report.batch",
    "BatchResult": "shrmkit.cli.report.batch",
}

__all__ = list(_LAZY)


# not brdf_io.lazy.lazy_exports, as the other layers: importing brdf_io loads numpy, and a report
# worker's boot module (report/worker_boot.py) imports this package before any heavy module
def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'shrmkit.cli' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
