"""Reports over a library of BRDFs: serially, in worker processes, or on a Dask cluster.

Each BRDF is one task, :func:`run_task`: it computes the report (``collect.py``) and
renders all its files (``writer.report_files``) and returns them as bytes; the driver
writes each folder atomically as results arrive and finally ``summary.csv`` and
``index.html``. The task never raises: a BRDF that fails (a corrupt file, nothing to
analyse) comes back as a ``status: failed`` report with its error, and the batch goes on.

:func:`run_batch` runs the tasks in this process (``workers=1``), in N worker processes of our
own (``workers=N``) or on a Dask ``distributed`` cluster (``scheduler=ADDRESS``), largest first
(:func:`estimate_cost`), each worker with its share of the cores (``threads.py``); the same
results on every engine. Its docstring states the engines, the folder names
(:func:`report_names`) and the lifetime of worker processes (retries, signals, stale temporaries).
The task is ``_task.py``, its cost ``_cost.py``; the engines ``_pool.py`` (worker processes) and
``_dask_engine.py``; the output folder's lock, temporaries and summary ``_run_folder.py``.
"""

from __future__ import annotations

import contextlib
import hashlib
import re
import signal
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import BRDF_FILE_TYPES
from ...render.preview import resolve_preview_mode
from ._cost import estimate_cost, largest_first

# the `NAME as NAME` imports: public here before the split, importable from here still (patch them where read)
from ._dask_engine import DASK_POLL_SECONDS as DASK_POLL_SECONDS
from ._dask_engine import DASK_SCHEDULER_LOST_SECONDS as DASK_SCHEDULER_LOST_SECONDS
from ._dask_engine import DASK_START_TOPIC as DASK_START_TOPIC
from ._dask_engine import _dask
from ._pool import PARENT_POLL_SECONDS as PARENT_POLL_SECONDS
from ._pool import STOP_SECONDS as STOP_SECONDS
from ._pool import WATCH_THREAD_NAME as WATCH_THREAD_NAME
from ._pool import WORKER_TARGET as WORKER_TARGET
from ._pool import _processes
from ._run_folder import _failed_row, _lock_run, _remove_stale_temporaries, _unlock_run, _write_index
from ._task import TASK_TRIES, BatchProgress, ReportOutcome, ReportTask, run_task
from .collect import unique_names
from .options import ReportOptions
from .threads import threads_per_worker
from .writer import write_folder

__all__ = ["BRDF_SUFFIXES", "MAX_NAME_CHARS", "TASK_TRIES", "ReportTask", "ReportOutcome", "BatchResult",
           "BatchInterrupted", "report_names", "run_task", "run_batch", "estimate_cost", "largest_first"]

#: File suffixes of the BRDF files `shrm report` takes (MERL, our table, Cornell, a fitted model).
BRDF_SUFFIXES = tuple(BRDF_FILE_TYPES)  # the BRDF file-type registry's suffixes

#: Longest report folder name kept as it is; a longer one becomes its first
#: ``MAX_NAME_CHARS`` characters, ``-`` and 10 hex digits of the SHA-256 of the full stem/spec.
MAX_NAME_CHARS = 100


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


class BatchInterrupted(KeyboardInterrupt):
    """A batch stopped by a signal: ``signum`` (SIGINT, SIGTERM), and, as raised by
    :func:`run_batch`, the reports ``written`` (their folders, and the summary listing them)
    out of ``total``. ``shrm report`` raises it from its SIGINT and SIGTERM handlers and exits
    with :attr:`exit_status` (128 + the signal: 130, 143)."""

    def __init__(self, signum: int = signal.SIGINT, written: int = 0, total: int = 0,
                 out_dir: Path | None = None) -> None:
        super().__init__(signum)
        self.signum, self.written, self.total, self.out_dir = int(signum), written, total, out_dir

    @property
    def signal_name(self) -> str:
        try:
            return signal.Signals(self.signum).name
        except ValueError:
            return f"signal {self.signum}"

    @property
    def exit_status(self) -> int:
        return 128 + self.signum


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
        base_path, sep, selector = source.rpartition("#")
        if sep and Path(base_path).suffix.lower() in BRDF_SUFFIXES:  # one member of a file: "abrdf.dat#12"
            raw = f"{Path(base_path).stem}-{selector}"
        else:
            path = Path(source)
            raw = path.stem if path.suffix.lower() in BRDF_SUFFIXES or _is_file_name(path) else source
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", raw).strip("._") or "brdf"
        bases.append(_short_name(base, raw))
    return unique_names(bases)



def _serial(tasks: Sequence[ReportTask], progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    for task in tasks:
        if progress is not None:
            progress("start", task.name, "")
        stage = (lambda s, n=task.name: progress("stage", n, s)) if progress is not None else None
        yield run_task(task, stage)



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

    Notes
    -----
    Three engines run the same task function:

    - serial (``workers=1``): in this process, with per-stage progress, every core for
      ducc0 and the BLAS (as the library functions use them);
    - ``workers=N``: N worker processes of our own (:func:`~._pool._processes`), started with the
      ``spawn`` method (no fork of a process holding threads or an OpenGL context), one task
      at a time each, over a pipe;
    - ``scheduler=ADDRESS``: a Dask ``distributed`` cluster (``Client.submit``); the
      workers need shrmkit installed and the BRDF files readable at the same paths. Results
      come back to this process, which writes them, so workers need no shared output folder.

    Scaling (``threads.py``): a worker process gets its share of the cores, cores // N
    threads (at least 1) for ducc0, the BLAS and the preview, set once when it starts (the
    pool's ``initializer``; a Dask worker process at its first task, with cores // the task
    threads of all workers on its host); ``ReportTask.nthreads`` passes the same number to
    ducc0. Worker processes import the report modules once, at start. Tasks are submitted
    largest first (:func:`estimate_cost`), so that a long BRDF does not start last and finish
    alone; the summary keeps the input order.

    Results do not depend on the engine or the threads (every random choice is seeded per
    BRDF, and the SHTs give the same numbers on any number of threads).

    Folder names are the file stem or the sanitized spec (:func:`report_names`), at most
    :data:`MAX_NAME_CHARS` characters: a longer one is cut and a short hash of the full stem or
    spec is added, so a 245-character file name still gives a folder (and its temporary
    siblings) the file system accepts, and two long names that share their first characters
    stay apart. A folder that cannot be written fails that BRDF alone; if the engine itself
    breaks (the Dask cluster goes away), the BRDFs without a result are marked failed. In every
    case the summary is written.

    Lifetime of worker processes (issues 28 and 30):

    - A worker process that dies (killed, out of memory) loses only its task, which is retried
      once on a new worker process (``progress("retry", …)``, a note in the summary); a task
      whose second worker dies too is a failed report (:data:`TASK_TRIES`).
    - SIGINT or SIGTERM (``shrm report`` turns both into :class:`BatchInterrupted`; a library
      caller's Ctrl-C is a ``KeyboardInterrupt``) stops the batch: the workers are terminated and
      joined, the summary lists the reports written so far, and :class:`BatchInterrupted` tells
      how many were written. Workers ignore SIGINT (Ctrl-C reaches the whole process group; the
      driver stops them), and exit by themselves when the driver is gone, even killed with
      SIGKILL (``PR_SET_PDEATHSIG`` on Linux, and a thread that watches ``os.getppid()``): no
      worker is left computing, or holding the caller's stdout/stderr pipes open.
    - On a Dask cluster (``scheduler=``), a worker that dies while it runs a task (the scheduler's
      ``remove-worker`` event, and the task's own start event, :func:`~._dask_engine._dask_started`) costs that task
      one retry, which the scheduler makes on another worker (one ``progress("retry", …)`` line and
      a note); a second death, or the scheduler's own ``KilledWorker``, is one failed report, and the
      other tasks go on. A scheduler lost for :data:`~._dask_engine.DASK_SCHEDULER_LOST_SECONDS` stops the batch
      with one line ("lost the Dask scheduler …"), the reports without a result failed in the
      summary; distributed's loggers are held at CRITICAL meanwhile (no 30-line tracebacks).
    - The temporary files and folders of a run killed while writing (``.NAME.XXXXXXXX.tmp``,
      ``.NAME.XXXXXXXX.old``, ``.summary.csv.XXXXXXXX.csv``, ``.index.html.XXXXXXXX.html``) are
      removed by the next run into the same folder, unless another run into that folder is
      alive: each run holds a lock on its own ``.shrm-report-run.XXXXXXXX.lock`` there, removed
      when it ends (:func:`~._run_folder._remove_stale_temporaries`).
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
    rows: dict[str, dict[str, Any]] = {}
    written = 0
    retried: list[str] = []
    outcomes: Iterable[ReportOutcome] = ()
    lock = _lock_run(out)
    try:
        _remove_stale_temporaries(out, lock[1] if lock else None)
        outcomes, engine = _engine(tasks, workers, scheduler, progress, retried)
        broken = None
        try:
            for outcome in outcomes:
                rows[outcome.name], ok, wrote = _write_outcome(out, outcome)
                written += wrote
                if progress is not None:
                    progress("done", outcome.name, "ok" if ok else "failed")
        except Exception as err:  # the engine broke (the Dask cluster went away): the rest fail, the summary is written
            if isinstance(err, BadInputError) and not rows:
                raise  # bad usage (an unreachable Dask scheduler): exit 2, nothing to summarize
            reason = str(err) if isinstance(err, BadInputError) else f"{type(err).__name__}: {err}"
            broken = f"the {engine} engine stopped: {reason}"
        finally:
            _close(outcomes)  # the engine's workers stop (an exception here, or a generator left early)
        _fail_unfinished(tasks, rows, broken, progress)
        ordered = [rows[n] for n in names]
        _write_index(out, ordered, _summary_notes(len(ordered), engine, options, note, retried, broken))
        n_failed = sum(1 for r in ordered if r["status"] != "ok")
        return BatchResult(out, ordered, n_failed, time.perf_counter() - t0, engine)
    except KeyboardInterrupt as stop:  # SIGINT, or SIGTERM turned into BatchInterrupted by `shrm report`
        _close(outcomes)
        raise _interrupted(stop, out, [rows[n] for n in names if n in rows], written, len(tasks)) from None
    finally:
        _unlock_run(lock)


def _summary_notes(n_reports: int, engine: str, options: ReportOptions, preview_note: str,
                   retried: list[str], broken: str | None) -> list[str]:
    """The summary's notes: the run (engine, profile, ε), the preview's note, each retry, and why
    the batch is incomplete when the engine stopped."""
    notes = [f"{n_reports} BRDFs, engine: {engine}, profile {options.profile}, eps {options.rule.eps:g}."]
    if preview_note:
        notes.append(preview_note)
    notes.extend(f"{r[0].upper()}{r[1:]}." for r in retried)
    if broken:
        notes.append(f"Incomplete: {broken}.")
    return notes


def _engine(tasks: list[ReportTask], workers: int, scheduler: str | None, progress: BatchProgress | None,
            retried: list[str]) -> tuple[Iterable[ReportOutcome], str]:
    """The outcomes of the engine that runs the batch (Dask, worker processes or serial) and its
    description for the summary."""
    if scheduler:
        return _dask(tasks, scheduler, progress, retried), f"dask ({scheduler})"
    if workers > 1 and len(tasks) > 1:
        n = min(workers, len(tasks))
        engine = f"{workers} processes, {threads_per_worker(n)} thread(s) each"
        return _processes(tasks, n, progress, retried), engine
    return _serial(tasks, progress), "serial"


def _write_outcome(out: Path, outcome: ReportOutcome) -> tuple[dict[str, Any], bool, bool]:
    """Write one report's folder: its summary row, whether the report is ok and whether its folder
    was written (a folder that cannot be written fails this BRDF alone, its row says why)."""
    row = outcome.row
    try:
        write_folder(out, outcome.name, outcome.files)
    except OSError as err:  # this folder alone: the batch goes on
        return _failed_row(outcome.name, row.get("source", ""), row.get("total_seconds"),
                           f"cannot write the report folder {out / outcome.name}: {err.strerror or err}"), False, False
    return row, outcome.ok, True


def _fail_unfinished(tasks: Sequence[ReportTask], rows: dict[str, dict[str, Any]], broken: str | None,
                     progress: BatchProgress | None) -> None:
    """A failed row for every task without a result (the engine stopped: ``broken`` says why)."""
    for task in tasks:
        if task.name not in rows:
            rows[task.name] = _failed_row(task.name, task.source, None, f"no result: {broken}")
            if progress is not None:
                progress("done", task.name, "failed")


def _interrupted(stop: KeyboardInterrupt, out: Path, done: list[dict[str, Any]], written: int, n_tasks: int
                 ) -> BatchInterrupted:
    """The :class:`BatchInterrupted` of a stopped batch, once the summary lists the reports written
    so far (best effort, never waiting on a lock held by another run)."""
    interrupted = BatchInterrupted(getattr(stop, "signum", signal.SIGINT), written, n_tasks, out)
    notes = [f"Interrupted ({interrupted.signal_name}) after {written} of {n_tasks} reports: "
             "this run's reports so far, then the other report folders already here."]
    with contextlib.suppress(Exception):  # best effort, never waiting on a lock held by another run
        _write_index(out, done, notes, wait=False)
    return interrupted


def _close(outcomes: Iterable[ReportOutcome]) -> None:
    """Close an engine's generator: its ``finally`` stops its worker processes or client."""
    close = getattr(outcomes, "close", None)
    if close is not None:
        close()
