"""One report task of a batch: what a task is (:class:`ReportTask`), what it returns
(:class:`ReportOutcome`), the function every engine runs (:func:`run_task`) and the failed
outcome a driver makes when the task's workers died. The task never raises: a BRDF that fails
comes back as a ``status: failed`` report. Engines: ``batch.py`` (serial), ``_pool.py``, ``_dask_engine.py``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ...analysis.threads import with_single_threaded_blas
from ...brdf_io.errors import BadInputError
from .collect import collect_report, failed_report
from .options import ReportOptions
from .writer import report_files, summary_row

#: ``progress(event, name, detail)``: event ``"start"``, ``"stage"`` (serial only), ``"retry"``
#: (worker processes: the worker of this BRDF died, ``detail`` says how; it is queued again) or ``"done"``.
BatchProgress = Callable[[str, str, str], None]

#: Worker processes a task may use up: a task whose worker dies is retried once on a new
#: worker; when that one dies too, the task is a failed report.
TASK_TRIES = 2


@dataclass(frozen=True)
class ReportTask:
    """One BRDF to report on: its source (file or spec), folder name, options, the
    preview mode already resolved (``gl``, ``cpu`` or ``none``), and the ducc0 threads of
    its SHTs (0: every core; a worker passes its share, ``threads.py``)."""

    source: str
    name: str
    options: ReportOptions
    preview_mode: str
    nthreads: int = 0


@dataclass(frozen=True)
class ReportOutcome:
    """What a task returns: the summary row and every file of the report folder."""

    name: str
    ok: bool
    row: dict[str, Any]
    files: dict[str, bytes]



@with_single_threaded_blas
def run_task(task: ReportTask, progress: Callable[[str], None] | None = None) -> ReportOutcome:
    """Compute and render one report; never raises for a bad BRDF (see module docstring).

    BLAS runs on one thread throughout (its products here are small: a second OpenBLAS thread
    spinning between them cost a quick report 0.3 s CPU, 10 %, and gained no wall time on 2 cores;
    the batch runs reports side by side instead). ducc0's SHTs keep ``task.nthreads``."""
    t0 = time.perf_counter()
    try:
        doc, previews = collect_report(task.source, task.options, name=task.name,
                                       preview_mode=task.preview_mode, progress=progress, nthreads=task.nthreads)
    except Exception as err:  # any failure of one BRDF is reported, and the batch goes on
        message = str(err) if isinstance(err, BadInputError) else f"{type(err).__name__}: {err}"
        doc, previews = failed_report(task.source, task.name, task.options, message, time.perf_counter() - t0), []
    try:
        files = report_files(doc, previews)
    except Exception as err:  # a plot or page that cannot be made fails this BRDF, not the batch
        doc = failed_report(task.source, task.name, task.options, f"writing the report: {type(err).__name__}: {err}",
                            time.perf_counter() - t0)
        files = report_files(doc, [])
    return ReportOutcome(task.name, doc["status"] == "ok", summary_row(doc), files)


def _failed_outcome(task: ReportTask, error: str) -> ReportOutcome:
    """A failed report of ``task`` made by the driver (its worker processes died)."""
    doc = failed_report(task.source, task.name, task.options, error)
    return ReportOutcome(task.name, False, summary_row(doc), report_files(doc, []))
