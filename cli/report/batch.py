"""Reports over a library of BRDFs: serially, in worker processes, or on a Dask cluster.

Each BRDF is one task, :func:`run_task`: it computes the report (``collect.py``) and
renders all its files (``writer.report_files``) and returns them as bytes; the driver
writes each folder atomically as results arrive and finally ``summary.csv`` and
``index.html``. The task never raises: a BRDF that fails (a corrupt file, nothing to
analyse) comes back as a ``status: failed`` report with its error, and the batch goes on.

Three engines run the same task function:

- serial (``workers=1``): in this process, with per-stage progress;
- ``workers=N``: :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn``
  start method (no fork of a process holding threads or an OpenGL context);
- ``scheduler=ADDRESS``: a Dask ``distributed`` cluster (``Client(ADDRESS).map``); the
  workers need shrmkit installed and the BRDF files readable at the same paths. Results
  come back to this process, which writes them, so workers need no shared output folder.

Results do not depend on the engine (every random choice is seeded per BRDF).

Folder names are the file stem or the sanitized spec (:func:`report_names`), at most
:data:`MAX_NAME_CHARS` characters: a longer one is cut and a short hash of the full stem or
spec is added, so a 245-character file name still gives a folder (and its temporary
siblings) the file system accepts, and two long names that share their first characters
stay apart. A folder that cannot be written fails that BRDF alone; if the engine itself
breaks (a worker process dies), the BRDFs without a result are marked failed. In every case
the summary is written.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import re
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...brdf_io.errors import BadInputError
from ...render.preview import resolve_preview_mode
from .collect import collect_report, failed_report, unique_names
from .options import ReportOptions
from .writer import report_files, summary_row, write_folder, write_summary

__all__ = ["BRDF_SUFFIXES", "MAX_NAME_CHARS", "ReportTask", "ReportOutcome", "BatchResult", "report_names", "run_task",
           "run_batch"]

#: ``progress(event, name, detail)``: event ``"start"``, ``"stage"`` (serial only) or ``"done"``.
BatchProgress = Callable[[str, str, str], None]

#: File suffixes of the BRDF files `shrm report` takes (MERL, our table, Cornell, a fitted model).
BRDF_SUFFIXES = (".binary", ".npz", ".brdf", ".json")

#: Longest report folder name kept as it is; a longer one becomes its first
#: ``MAX_NAME_CHARS`` characters, ``-`` and 10 hex digits of the SHA-256 of the full stem/spec.
MAX_NAME_CHARS = 100


@dataclass(frozen=True)
class ReportTask:
    """One BRDF to report on: its source (file or spec), folder name, options, and the
    preview mode already resolved (``gl``, ``cpu`` or ``none``)."""

    source: str
    name: str
    options: ReportOptions
    preview_mode: str


@dataclass(frozen=True)
class ReportOutcome:
    """What a task returns: the summary row and every file of the report folder."""

    name: str
    ok: bool
    row: dict[str, Any]
    files: dict[str, bytes]


@dataclass(frozen=True)
class BatchResult:
    """Rows of the summary (input order), the output folder, and the number that failed."""

    out_dir: Path
    rows: list[dict[str, Any]]
    n_failed: int
    seconds: float
    engine: str

    @property
    def ok(self) -> bool:
        return self.n_failed == 0


def _is_file_name(path: Path) -> bool:
    try:
        return path.exists()
    except OSError:  # e.g. a spec string longer than a file name may be
        return False


def _short_name(base: str, full: str) -> str:
    """``base`` (sanitized, ASCII) if short enough, else cut + a hash of the unsanitized ``full``."""
    if len(base) <= MAX_NAME_CHARS:
        return base
    digest = hashlib.sha256(full.encode("utf-8", "surrogatepass")).hexdigest()[:10]
    return f"{base[:MAX_NAME_CHARS].rstrip('._-')}-{digest}"


def report_names(sources: Sequence[str]) -> list[str]:
    """Folder names: the file stem or the sanitized spec (letters, digits, ``._-``), cut to
    :data:`MAX_NAME_CHARS` with a hash of the full stem/spec when longer, made unique with
    ``-2``, ``-3``…"""
    bases = []
    for source in sources:
        path = Path(source)
        raw = path.stem if path.suffix.lower() in BRDF_SUFFIXES or _is_file_name(path) else source
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", raw).strip("._") or "brdf"
        bases.append(_short_name(base, raw))
    return unique_names(bases)


def run_task(task: ReportTask, progress: Callable[[str], None] | None = None) -> ReportOutcome:
    """Compute and render one report; never raises for a bad BRDF (see module docstring)."""
    t0 = time.perf_counter()
    try:
        doc, previews = collect_report(task.source, task.options, name=task.name,
                                       preview_mode=task.preview_mode, progress=progress)
    except Exception as err:  # any failure of one BRDF is reported, and the batch goes on
        message = str(err) if isinstance(err, BadInputError) else f"{type(err).__name__}: {err}"
        doc, previews = failed_report(task.source, task.name, task.options, message, time.perf_counter() - t0), []
    return ReportOutcome(task.name, doc["status"] == "ok", summary_row(doc), report_files(doc, previews))


def _serial(tasks: Sequence[ReportTask], progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    for task in tasks:
        if progress is not None:
            progress("start", task.name, "")
        stage = (lambda s, n=task.name: progress("stage", n, s)) if progress is not None else None
        yield run_task(task, stage)


def _processes(tasks: Sequence[ReportTask], workers: int, progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = []
        for task in tasks:
            futures.append(pool.submit(run_task, task))
            if progress is not None:
                progress("start", task.name, "queued")
        for future in as_completed(futures):
            yield future.result()


def _dask(tasks: Sequence[ReportTask], scheduler: str, progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    try:  # lazy: Dask is an optional extra (shrmkit[dask]), loaded only for --dask-scheduler
        from distributed import Client
    except ImportError:  # pragma: no cover - depends on the installation
        raise BadInputError(None, "--dask-scheduler needs dask.distributed: pip install 'shrmkit[dask]'") from None
    try:
        client = Client(scheduler, set_as_default=False, timeout="30s")
    except (OSError, TimeoutError, ValueError) as err:
        raise BadInputError(scheduler, f"cannot connect to the Dask scheduler: {err}") from None
    try:
        futures = client.map(run_task, list(tasks), pure=False, key=[f"shrm-report-{t.name}" for t in tasks])
        if progress is not None:
            for task in tasks:
                progress("start", task.name, "submitted")
        for future in futures:  # input order (as_completed would need a default client)
            yield future.result()
    finally:
        client.close()


def run_batch(
    sources: Sequence[str],
    out_dir: str | Path,
    options: ReportOptions,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: BatchProgress | None = None,
) -> BatchResult:
    """Report on every BRDF of ``sources`` into ``out_dir/<name>/``, then write the summary.

    Parameters
    ----------
    sources
        BRDF files or spec strings.
    workers
        Parallel processes on this machine (1: serial, in this process).
    scheduler
        Address of a Dask distributed scheduler (``tcp://host:8786``, or an in-process
        ``LocalCluster``'s ``scheduler_address``); overrides ``workers``.
    progress
        ``progress(event, name, detail)`` (see :data:`BatchProgress`).

    Returns
    -------
    BatchResult
        ``n_failed`` counts the BRDFs whose report failed (they are in the summary).
    """

    if not sources:
        raise BadInputError(None, "no BRDF given")
    if workers < 1:
        raise BadInputError(None, f"workers must be >= 1, got {workers}")
    t0 = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    mode, note = resolve_preview_mode(options.preview)
    names = report_names([str(s) for s in sources])
    tasks = [ReportTask(str(s), n, options, mode) for s, n in zip(sources, names, strict=True)]
    if scheduler:
        outcomes, engine = _dask(tasks, scheduler, progress), f"dask ({scheduler})"
    elif workers > 1 and len(tasks) > 1:
        outcomes, engine = _processes(tasks, min(workers, len(tasks)), progress), f"{workers} processes"
    else:
        outcomes, engine = _serial(tasks, progress), "serial"
    rows: dict[str, dict[str, Any]] = {}
    broken = None
    try:
        for outcome in outcomes:
            row, ok = outcome.row, outcome.ok
            try:
                write_folder(out, outcome.name, outcome.files)
            except OSError as err:  # this folder alone: the batch goes on
                ok = False
                row = _failed_row(outcome.name, row.get("source", ""), row.get("total_seconds"),
                                  f"cannot write the report folder {out / outcome.name}: {err.strerror or err}")
            rows[outcome.name] = row
            if progress is not None:
                progress("done", outcome.name, "ok" if ok else "failed")
    except Exception as err:  # the engine broke (a worker died): the rest fail, the summary is written
        if isinstance(err, BadInputError) and not rows:
            raise  # bad usage (an unreachable Dask scheduler): exit 2, nothing to summarize
        reason = str(err) if isinstance(err, BadInputError) else f"{type(err).__name__}: {err}"
        broken = f"the {engine} engine stopped: {reason}"
    for task in tasks:
        if task.name not in rows:
            rows[task.name] = _failed_row(task.name, task.source, None, f"no result: {broken}")
            if progress is not None:
                progress("done", task.name, "failed")
    ordered = [rows[n] for n in names]
    notes = [f"{len(ordered)} BRDFs, engine: {engine}, profile {options.profile}, eps {options.eps:g}."]
    if note:
        notes.append(note)
    if broken:
        notes.append(f"Incomplete: {broken}.")
    write_summary(out, ordered, notes)
    n_failed = sum(1 for r in ordered if r["status"] != "ok")
    return BatchResult(out, ordered, n_failed, time.perf_counter() - t0, engine)


def _failed_row(name: str, source: str, seconds: float | None, error: str) -> dict[str, Any]:
    """A summary row for a BRDF whose report could not be written or was never made (the
    keys of :func:`~.writer.summary_row` for a failed report)."""
    return {"name": name, "status": "failed", "source": source, "error": error, "total_seconds": seconds}
