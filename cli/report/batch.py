"""Reports over a library of BRDFs: serially, in worker processes, or on a Dask cluster.

Each BRDF is one task, :func:`run_task`: it computes the report (``collect.py``) and
renders all its files (``writer.report_files``) and returns them as bytes; the driver
writes each folder atomically as results arrive and finally ``summary.csv`` and
``index.html``. The task never raises: a BRDF that fails (a corrupt file, nothing to
analyse) comes back as a ``status: failed`` report with its error, and the batch goes on.

Three engines run the same task function:

- serial (``workers=1``): in this process, with per-stage progress, every core for
  ducc0 and the BLAS (as the library functions use them);
- ``workers=N``: :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn``
  start method (no fork of a process holding threads or an OpenGL context);
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
breaks (a worker process dies), the BRDFs without a result are marked failed. In every case
the summary is written.
"""

from __future__ import annotations

import dataclasses
import fcntl
import hashlib
import json
import math
import multiprocessing
import os
import re
import socket
import time
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import BRDF_FILE_TYPES, load_brdf
from ...render.preview import resolve_preview_mode
from .collect import collect_report, failed_report, unique_names
from .options import ReportOptions
from .threads import configure_worker, threads_per_worker, usable_cores, worker_initializer
from .writer import report_files, summary_row, write_folder, write_summary

__all__ = ["BRDF_SUFFIXES", "MAX_NAME_CHARS", "ReportTask", "ReportOutcome", "BatchResult", "report_names", "run_task",
           "run_batch", "estimate_cost", "largest_first"]

#: ``progress(event, name, detail)``: event ``"start"``, ``"stage"`` (serial only) or ``"done"``.
BatchProgress = Callable[[str, str, str], None]

#: File suffixes of the BRDF files `shrm report` takes (MERL, our table, Cornell, a fitted model).
BRDF_SUFFIXES = tuple(BRDF_FILE_TYPES)  # the BRDF file-type registry's suffixes

#: Longest report folder name kept as it is; a longer one becomes its first
#: ``MAX_NAME_CHARS`` characters, ``-`` and 10 hex digits of the SHA-256 of the full stem/spec.
MAX_NAME_CHARS = 100


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
        base_path, sep, selector = source.rpartition("#")
        if sep and Path(base_path).suffix.lower() in BRDF_SUFFIXES:  # one member of a file: "abrdf.dat#12"
            raw = f"{Path(base_path).stem}-{selector}"
        else:
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


def _serial(tasks: Sequence[ReportTask], progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    for task in tasks:
        if progress is not None:
            progress("start", task.name, "")
        stage = (lambda s, n=task.name: progress("stage", n, s)) if progress is not None else None
        yield run_task(task, stage)


# ------------------------------------------------------------------------------ cost and order


def _lobe_sharpness(brdf: Any) -> list[float]:
    """Peak over mean of the cosine-weighted transfer ρ̂(·, V) over the incident hemisphere at
    the views θ_v = 0°, 35°, 70° (about s + 2 at every view for a Phong lobe cos^s, 2 for
    Lambert; growing with θ_v for a microfacet lobe, which stretches at grazing views)."""
    n = 30
    theta = (np.arange(n) + 0.5) * (np.pi / 2) / n
    phi = (np.arange(4 * n) + 0.5) * (2 * np.pi) / (4 * n)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    L = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    weight = np.sin(t) * (np.pi / 2 / n) * (2 * np.pi / (4 * n)) / (2 * np.pi)
    out = []
    for view in np.radians([0.0, 35.0, 70.0]):
        V = np.array([np.sin(view), 0.0, np.cos(view)])
        mirror = np.array([[-V[0], 0.0, V[2]]])
        grid = brdf.rho_hat(L, np.broadcast_to(V, L.shape)).mean(axis=-1)
        peak = max(float(grid.max()), float(brdf.rho_hat(mirror, V[None]).mean()))
        mean = float((grid * weight).sum())
        out.append(max(2.0, peak / mean) if mean > 0.0 and math.isfinite(peak) else 2.0)
    return out


#: estimated seconds per MB of a table file (a MERL table of 35 MB: 5 + 10.5 s)
_TABLE_SECONDS_PER_MB = 0.3


def estimate_cost(source: str) -> float:
    """A rough, cheap estimate of a report's cost (about the seconds of a quick report on one
    core), only used to start the costly BRDFs first.

    A table file (``.binary``, ``.npz``, ``.brdf``; not read): 5 + 0.3 s per MB (a MERL table
    ≈ 15.5). An analytic BRDF (a spec, or a fitted model's ``.json``): the orders P grow with
    the change of the lobe with the view and F with the square root of its sharpness
    (:func:`_lobe_sharpness`), so 5 + 2.5·sqrt(max sharpness)·max(0, ln(s70/s0) − 0.1): a
    Phong or Lafortune lobe, the same at every view, costs about 5 whatever its exponent, a
    microfacet lobe more the sharper it is (on 32 BRDFs the rank correlation with the
    measured time was 0.81–0.87, ``benchmarks/batch_scaling.py``). A source that cannot be read
    costs 0 (its report fails at once).
    """
    path = Path(source)
    try:
        if path.suffix.lower() in (".binary", ".npz", ".brdf") and path.is_file():
            return 5.0 + _TABLE_SECONDS_PER_MB * path.stat().st_size / 1e6
        brdf = load_brdf(source)
        if brdf.kind != "analytic":  # pragma: no cover - every table suffix is handled above
            return 5.0 + _TABLE_SECONDS_PER_MB * path.stat().st_size / 1e6
        s = _lobe_sharpness(brdf)
        return 5.0 + 2.5 * math.sqrt(max(s)) * max(0.0, math.log(s[-1] / s[0]) - 0.1)
    except Exception:  # a bad BRDF: its report fails fast, whatever its place
        return 0.0


def largest_first(tasks: Sequence[ReportTask]) -> list[ReportTask]:
    """``tasks`` by decreasing :func:`estimate_cost` (input order among equals)."""
    costs = [estimate_cost(t.source) for t in tasks]
    order = sorted(range(len(tasks)), key=lambda i: -costs[i])
    return [tasks[i] for i in order]


# ------------------------------------------------------------------------------ worker processes


def _processes(tasks: Sequence[ReportTask], workers: int, progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    threads = threads_per_worker(workers)
    preview_mode = tasks[0].preview_mode if tasks else None
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                             initializer=worker_initializer, initargs=(threads, preview_mode)) as pool:
        futures = []
        for task in largest_first(tasks):
            futures.append(pool.submit(run_task, dataclasses.replace(task, nthreads=threads)))
            if progress is not None:
                progress("start", task.name, "queued")
        for future in as_completed(futures):
            yield future.result()


# ------------------------------------------------------------------------------------- Dask


def _this_process() -> str:
    """``host:pid`` of this process (a plain string: Dask passes it through untouched)."""
    return f"{socket.gethostname()}:{os.getpid()}"


def _dask_threads(client: Any) -> dict[str, int]:
    """Threads per task of every worker the scheduler knows now: the usable cores of its
    machine over the task threads of all workers on that host (at least 1)."""
    try:
        info = client.scheduler_info(n_workers=-1)["workers"]
    except TypeError:  # pragma: no cover - distributed before 2025 lists every worker
        info = client.scheduler_info()["workers"]
    if not info:
        return {}
    cores = client.run(usable_cores, on_error="ignore")
    per_host: dict[str, int] = defaultdict(int)
    for w in info.values():
        per_host[w.get("host", "")] += int(w.get("nthreads", 1))
    return {addr: threads_per_worker(per_host[w.get("host", "")], cores.get(addr) if isinstance(
        cores.get(addr), int) else None) for addr, w in info.items()}


def _dask_task(task: ReportTask, threads: dict[str, int], driver: str) -> ReportOutcome:
    """A report task on a Dask worker: the worker process gets its threads once (not the
    driver's own process, for an in-process cluster), then :func:`run_task`."""
    from distributed import get_worker  # lazy: runs on a Dask worker, where distributed is loaded

    worker = get_worker()
    n = threads.get(worker.address) or threads_per_worker(getattr(getattr(worker, "state", worker), "nthreads", 1))
    if _this_process() != driver:
        n = configure_worker(n, preview_mode=task.preview_mode)
    return run_task(dataclasses.replace(task, nthreads=n))


def _dask(tasks: Sequence[ReportTask], scheduler: str, progress: BatchProgress | None) -> Iterable[ReportOutcome]:
    try:  # lazy: Dask is an optional extra (shrmkit[dask]), loaded only for --dask-scheduler
        from distributed import Client, as_completed as dask_completed  # noqa: I001
    except ImportError:  # pragma: no cover - depends on the installation
        raise BadInputError(None, "--dask-scheduler needs dask.distributed: pip install 'shrmkit[dask]'") from None
    try:
        client = Client(scheduler, set_as_default=False, timeout="30s")
    except (OSError, TimeoutError, ValueError) as err:
        raise BadInputError(scheduler, f"cannot connect to the Dask scheduler: {err}") from None
    try:
        threads, driver = _dask_threads(client), _this_process()
        ordered = largest_first(tasks)
        futures = [client.submit(_dask_task, task, threads, driver, pure=False, key=f"shrm-report-{task.name}",
                                 priority=len(ordered) - i) for i, task in enumerate(ordered)]
        if progress is not None:
            for task in ordered:
                progress("start", task.name, "submitted")
        for future in dask_completed(futures, loop=client.loop):
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
        n = min(workers, len(tasks))
        engine = f"{workers} processes, {threads_per_worker(n)} thread(s) each"
        outcomes = _processes(tasks, n, progress)
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
    _write_index(out, ordered, notes)
    n_failed = sum(1 for r in ordered if r["status"] != "ok")
    return BatchResult(out, ordered, n_failed, time.perf_counter() - t0, engine)


def _write_index(out: Path, rows: list[dict[str, Any]], notes: list[str]) -> None:
    """``summary.csv`` and ``index.html`` of every report in ``out``: this run's rows (input order),
    then those of the other report folders already there (earlier or concurrent runs into the
    same ``--out``), rebuilt from their ``report.json``, under an exclusive lock on the folder, so
    two runs at once never lose a row (issue 28: the last writer's index listed 2 of 3)."""
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        names = {row["name"] for row in rows}
        others = []
        for folder in sorted(p for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")):
            if folder.name in names:
                continue
            try:
                doc = json.loads((folder / "report.json").read_text(encoding="utf-8"))
                others.append(summary_row(doc))
            except (OSError, ValueError, KeyError, TypeError):
                continue  # not a report folder (or one being replaced): left out
        if others:
            notes = [*notes, f"{len(others)} more report(s) already in this folder are listed after this run's."]
        write_summary(out, rows + others, notes)
    finally:
        os.close(fd)


def _failed_row(name: str, source: str, seconds: float | None, error: str) -> dict[str, Any]:
    """A summary row for a BRDF whose report could not be written or was never made (the
    keys of :func:`~.writer.summary_row` for a failed report)."""
    return {"name": name, "status": "failed", "source": source, "error": error, "total_seconds": seconds}
