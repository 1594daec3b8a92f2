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
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import fcntl
import hashlib
import json
import logging
import math
import multiprocessing
import os
import re
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
from collections import defaultdict, deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from multiprocessing import resource_tracker
from multiprocessing.connection import wait as wait_ready
from pathlib import Path
from typing import Any

import numpy as np

from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import BRDF_FILE_TYPES, load_brdf
from ...render.preview import resolve_preview_mode
from . import worker_boot
from .collect import collect_report, failed_report, unique_names
from .options import ReportOptions
from .threads import configure_worker, threads_per_worker, usable_cores, worker_initializer
from .writer import report_files, summary_row, write_folder, write_summary

__all__ = ["BRDF_SUFFIXES", "MAX_NAME_CHARS", "TASK_TRIES", "ReportTask", "ReportOutcome", "BatchResult",
           "BatchInterrupted", "report_names", "run_task", "run_batch", "estimate_cost", "largest_first"]

#: ``progress(event, name, detail)``: event ``"start"``, ``"stage"`` (serial only), ``"retry"``
#: (worker processes: the worker of this BRDF died, ``detail`` says how; it is queued again) or ``"done"``.
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


def _failed_outcome(task: ReportTask, error: str) -> ReportOutcome:
    """A failed report of ``task`` made by the driver (its worker processes died)."""
    doc = failed_report(task.source, task.name, task.options, error)
    return ReportOutcome(task.name, False, summary_row(doc), report_files(doc, []))


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


#: Worker processes a task may use up: a task whose worker dies is retried once on a new
#: worker; when that one dies too, the task is a failed report.
TASK_TRIES = 2

#: The worker loop a report worker process runs after :func:`~.worker_boot.boot` (by name: the
#: target's module is imported only once the parent-death signal is set).
WORKER_TARGET = "shrmkit.cli.report.batch:_worker_main"

#: Seconds between two checks of a worker's thread that its driver is still there.
PARENT_POLL_SECONDS = 0.5

#: Seconds a stopped worker gets to exit after SIGTERM, then SIGKILL.
STOP_SECONDS = 5.0

_PR_SET_NAME, _PR_SET_PDEATHSIG = 15, 1  # prctl options (linux/prctl.h)

#: Name of a worker's thread that watches its driver (Linux: in ``/proc/PID/task/*/comm``, ``top -H``).
WATCH_THREAD_NAME = "shrm-ppid-watch"


def _exit_with_parent(parent_pid: int) -> None:
    """End this worker process when its driver ``parent_pid`` is gone, even killed with SIGKILL:
    the kernel's parent-death signal on Linux (SIGKILL), and on every system a daemon thread
    (:data:`WATCH_THREAD_NAME`) that polls ``os.getppid()`` (a process whose parent died is
    adopted by another)."""
    prctl = None
    if sys.platform.startswith("linux"):
        try:
            prctl = ctypes.CDLL(None, use_errno=True).prctl
            prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - a libc without prctl
            prctl = None
    if os.getppid() != parent_pid:  # the driver died before the watch was set
        os._exit(1)

    def watch() -> None:
        if prctl is not None:
            prctl(_PR_SET_NAME, WATCH_THREAD_NAME.encode()[:15], 0, 0, 0)
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL_SECONDS)
        os._exit(1)

    threading.Thread(target=watch, name="shrm-parent-watch", daemon=True).start()


def _worker_main(conn: Any, threads: int, preview_mode: str | None, parent_pid: int) -> None:
    """A worker process: take tasks from ``conn`` one at a time, send back each outcome, stop
    at ``None`` or when the driver's end of the pipe is closed."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the driver stops its workers
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _exit_with_parent(parent_pid)
    try:
        worker_initializer(threads, preview_mode)
        start_error = None
    except Exception as err:  # every task then fails with this error, instead of a worker dying per task
        start_error = f"the worker process could not start: {type(err).__name__}: {err}"
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        try:
            outcome = _failed_outcome(task, start_error) if start_error else run_task(task)
        except Exception as err:  # run_task reports a bad BRDF itself; this is anything else
            outcome = _failed_outcome(task, f"{type(err).__name__}: {err}")
        try:
            conn.send(outcome)
        except (OSError, ValueError):  # the driver is gone
            return


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT held back while a worker process starts: the worker inherits the mask, so that a
    Ctrl-C (sent to the whole process group) during its start, while it imports, leaves no
    traceback; the worker then ignores SIGINT. A SIGINT to this process meanwhile is delivered
    afterwards. (Not SIGTERM: a worker must stay stoppable by SIGTERM all along.)"""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - not POSIX
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@dataclass
class _Worker:
    process: Any
    conn: Any
    task: ReportTask | None = None


def _death(process: Any) -> str:
    """How a worker process ended: ``killed by SIGKILL``, ``exit status 1``."""
    process.join(STOP_SECONDS)
    code = process.exitcode
    if code is None:  # its pipe closed, yet it runs on: ended here
        process.kill()
        process.join(STOP_SECONDS)
        return "closed its pipe"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit status {code}"


def _stop(workers: Iterable[_Worker], kill: bool) -> None:
    """Join every worker process (``kill``: after SIGTERM; SIGKILL past :data:`STOP_SECONDS`)
    and close its pipe."""
    workers = list(workers)
    for w in [w for w in workers if w.process.pid is None]:  # not started: nothing to stop (a process
        w.conn.close()  # interrupted within its start exits by itself, its driver gone: _exit_with_parent)
    workers = [w for w in workers if w.process.pid is not None]
    for w in workers:
        if kill and w.process.is_alive():
            w.process.terminate()
    deadline = time.monotonic() + STOP_SECONDS
    for w in workers:
        w.process.join(max(0.0, deadline - time.monotonic()))
        if w.process.is_alive():
            w.process.kill()
            w.process.join(STOP_SECONDS)
        w.conn.close()


def _processes(tasks: Sequence[ReportTask], workers: int, progress: BatchProgress | None,
               retried: list[str] | None = None) -> Iterable[ReportOutcome]:
    """The tasks in ``workers`` spawned processes, largest first, one task per worker at a
    time; outcomes as they come. A worker that dies is replaced by a new one, and its task
    queued again (:data:`TASK_TRIES`; ``retried`` collects a note per retry). Leaving the
    generator early (an exception, ``close()``) terminates the workers."""
    pool = _Pool(tasks, workers, progress, retried)
    if progress is not None:
        for task in pool.pending:
            progress("start", task.name, "queued")
    finished = False
    try:
        while pool.pending or pool.running:
            while pool.pending and len(pool.running) < workers:
                pool.start_worker()
            running = pool.running
            ready = set(wait_ready([w.conn for w in running] + [w.process.sentinel for w in running]))
            for worker in [w for w in running if w.conn in ready or w.process.sentinel in ready]:
                outcome = pool.collect(worker)
                if outcome is not None:
                    yield outcome
        finished = True
    finally:
        _stop(pool.running + pool.stopping, kill=not finished)


class _Pool:
    """The worker processes of :func:`_processes`: the tasks queued (largest first), the workers
    running one task each, those told to exit, and how often each task was given out."""

    def __init__(self, tasks: Sequence[ReportTask], workers: int, progress: BatchProgress | None,
                 retried: list[str] | None) -> None:
        self.context = multiprocessing.get_context("spawn")
        self.threads = threads_per_worker(workers)
        self.preview_mode = tasks[0].preview_mode if tasks else None
        self.pending = deque(dataclasses.replace(task, nthreads=self.threads) for task in largest_first(tasks))
        self.progress, self.retried = progress, retried
        self.tries: dict[str, int] = defaultdict(int)
        self.running: list[_Worker] = []
        self.stopping: list[_Worker] = []  # sent None: exiting by themselves

    def give(self, worker: _Worker, task: ReportTask) -> None:
        """Send ``task`` to ``worker`` (a dead worker is found by the wait, and the task retried)."""
        worker.task = task
        self.tries[task.name] += 1
        try:
            worker.conn.send(task)
        except OSError:  # the worker is dead: found by the wait below, and the task retried
            pass

    def start_worker(self) -> None:
        """Spawn a worker process and give it the next queued task."""
        parent_conn, child_conn = self.context.Pipe()
        # the target's module imports nothing heavy: the parent-death signal is set before the
        # report modules load (a driver killed during a worker's imports: worker_boot.py)
        process = self.context.Process(target=worker_boot.boot, name="shrm-report-worker", daemon=True,
                                       args=(WORKER_TARGET, os.getpid(), child_conn, self.threads, self.preview_mode,
                                             os.getpid()))
        worker = _Worker(process, parent_conn)
        self.running.append(worker)  # before its start: a SIGTERM during the start still stops it
        # multiprocessing's resource tracker, which a spawn starts first, started out of the block:
        # its start unblocks SIGINT when done, and the worker started next would inherit that
        resource_tracker.ensure_running()
        with _sigint_blocked():
            process.start()
        child_conn.close()
        self.give(worker, self.pending.popleft())

    def collect(self, worker: _Worker) -> ReportOutcome | None:
        """A worker the wait found ready: its outcome (it gets the next task, or is told to exit),
        or, when it died, None with its task queued again — or the task's failed outcome after
        :data:`TASK_TRIES` deaths."""
        try:
            outcome = worker.conn.recv() if worker.conn.poll() else None
        except (EOFError, OSError):  # the pipe closed: the worker died
            outcome = None
        task, worker.task = worker.task, None
        if outcome is not None:
            if self.pending:
                self.give(worker, self.pending.popleft())
            else:
                self.running.remove(worker)
                self.stopping.append(worker)
                with contextlib.suppress(OSError):
                    worker.conn.send(None)
            return outcome
        self.running.remove(worker)  # the worker died (its pipe closed without an outcome)
        how = _death(worker.process)
        worker.conn.close()
        if task is None:
            return None
        if self.tries[task.name] < TASK_TRIES:
            self.pending.appendleft(task)
            if self.retried is not None:
                self.retried.append(f"the worker process of {task.name} died ({how}); retried")
            if self.progress is not None:
                self.progress("retry", task.name, how)
            return None
        return _failed_outcome(task, f"its worker process died {self.tries[task.name]} times (last: {how})")


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


#: Seconds between two looks at a Dask batch: finished tasks, workers the scheduler removed.
DASK_POLL_SECONDS = 0.2
#: Seconds the Dask client may stay disconnected from its scheduler before the batch stops.
DASK_SCHEDULER_LOST_SECONDS = 10.0
#: Loggers of distributed (and its tornado loop) whose tracebacks a lost worker or scheduler prints;
#: held at CRITICAL while a batch runs: the batch says what happened in one line instead.
_DASK_LOGGERS = ("distributed", "tornado")


@contextlib.contextmanager
def _quiet_dask_logs() -> Iterator[None]:
    """distributed's own loggers quieted for the batch (their levels restored after): a worker or
    scheduler that dies makes the client and the comms log 30-line tracebacks."""
    names = [name for name in list(logging.Logger.manager.loggerDict)
             if name.split(".")[0] in _DASK_LOGGERS]  # distributed's config sets levels per child logger
    loggers = [logging.getLogger(name) for name in {*_DASK_LOGGERS, *names}]
    levels = [log.level for log in loggers]
    for log in loggers:
        log.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for log, level in zip(loggers, levels, strict=True):
            log.setLevel(level)


#: Topic of the event a Dask worker logs when it starts a report task (:func:`_dask_started`).
DASK_START_TOPIC = "shrm-report-start"


def _dask_started(function: Callable[..., ReportOutcome], task: ReportTask, threads: dict[str, int],
                  driver: str) -> ReportOutcome:
    """Run ``function`` (:func:`_dask_task`) on a Dask worker after logging, to the scheduler, that
    this worker started ``task`` (:data:`DASK_START_TOPIC`): the scheduler's ``remove-worker`` event
    lists every task *assigned* to a lost worker, queued ones too; the start events tell the one
    that was running there."""
    from distributed import get_worker  # lazy: runs on a Dask worker, where distributed is loaded

    worker = get_worker()
    worker.log_event(DASK_START_TOPIC, {"key": f"shrm-report-{task.name}", "worker": worker.address})
    return function(task, threads, driver)


def _started_on(client: Any, since: float) -> dict[str, set[str]]:
    """Worker address -> keys of the report tasks started there after ``since`` (:func:`_dask_started`)."""
    started: dict[str, set[str]] = defaultdict(set)
    for stamp, message in client.get_events(DASK_START_TOPIC):
        if stamp >= since and isinstance(message, dict):
            started[str(message.get("worker", ""))].add(str(message.get("key", "")))
    return started


def _removed_workers(client: Any, since: float, seen: set[tuple[float, str]]) -> list[tuple[str, set[str]]]:
    """(worker address, keys it was running) of each worker the scheduler removed after ``since``
    (its ``remove-worker`` events, distributed's ``Scheduler.remove_worker``, whose tasks that had
    started there by :func:`_started_on`), each event once."""
    removed = []
    started = None
    for stamp, message in client.get_events("all"):
        if stamp < since or not isinstance(message, dict) or message.get("action") != "remove-worker":
            continue
        event = (stamp, str(message.get("worker", "")))
        if event in seen:
            continue
        seen.add(event)
        started = _started_on(client, since) if started is None else started
        keys = {str(k) for k in message.get("processing-tasks", ())} & started.get(event[1], set())
        removed.append((event[1], keys))
    return removed


def _dask(tasks: Sequence[ReportTask], scheduler: str, progress: BatchProgress | None,
          retried: list[str] | None = None, task_function: Callable[..., ReportOutcome] | None = None,
          ) -> Iterable[ReportOutcome]:
    """The tasks on a Dask cluster, largest first; outcomes as they come. A worker that dies while
    it computes a task (the scheduler's ``remove-worker`` event lists the task) costs one retry,
    which the scheduler makes on another worker: ``progress("retry", …)`` and a note in
    ``retried``; a second death of the task's worker is one failed report (:data:`TASK_TRIES`), as
    is a task the scheduler gives up on itself (``KilledWorker``). The other tasks go on. A
    scheduler that cannot be reached for :data:`DASK_SCHEDULER_LOST_SECONDS` stops the batch with
    one ``RuntimeError`` line (``run_batch`` marks the reports without a result as failed).
    ``task_function`` replaces :func:`_dask_task` (tests)."""
    try:  # lazy: Dask is an optional extra (shrmkit[dask]), loaded only for --dask-scheduler
        from distributed import Client, as_completed as dask_completed  # noqa: I001
    except ImportError:  # pragma: no cover - depends on the installation
        raise BadInputError(None, "--dask-scheduler needs dask.distributed: pip install 'shrmkit[dask]'") from None
    function = task_function or _dask_task
    with _quiet_dask_logs():
        try:
            client = Client(scheduler, set_as_default=False, timeout="30s")
        except (OSError, TimeoutError, ValueError) as err:
            raise BadInputError(scheduler, f"cannot connect to the Dask scheduler: {err}") from None
        try:
            yield from _dask_run(client, dask_completed, function, tasks, scheduler, progress, retried)
        finally:
            with contextlib.suppress(Exception):  # a lost scheduler: nothing left to close cleanly
                client.close(timeout=5)


def _dask_run(client: Any, dask_completed: Any, function: Callable[..., ReportOutcome], tasks: Sequence[ReportTask],
              scheduler: str, progress: BatchProgress | None, retried: list[str] | None) -> Iterator[ReportOutcome]:
    """The body of :func:`_dask` on a connected ``client``."""
    since = time.time()
    threads, driver = _dask_threads(client), _this_process()
    ordered = largest_first(tasks)
    futures = [client.submit(_dask_started, function, task, threads, driver, pure=False,
                             key=f"shrm-report-{task.name}", priority=len(ordered) - i)
               for i, task in enumerate(ordered)]
    running = {future.key: (future, task) for future, task in zip(futures, ordered, strict=True)}
    if progress is not None:
        for task in ordered:
            progress("start", task.name, "submitted")
    deaths_seen = _DaskDeaths(client, since, scheduler, running, progress, retried)
    completed = dask_completed(futures, loop=client.loop)
    while running:
        batch = completed.next_batch(block=False)
        for future in batch:
            entry = running.pop(future.key, None)
            if entry is None:  # cancelled here after a second death: already reported
                continue
            yield _dask_outcome(client, scheduler, future, entry[1])
        if running:
            yield from deaths_seen()
            if not batch:
                time.sleep(DASK_POLL_SECONDS)
    yield from deaths_seen(final=True)  # deaths of tasks whose retry finished between two looks


def _dask_outcome(client: Any, scheduler: str, future: Any, task: ReportTask) -> ReportOutcome:
    """The outcome of a Dask future that is done: its result, or a failed report saying why
    (``KilledWorker``, the task's exception, a cancelled task); a ``RuntimeError`` when the client
    gave up reconnecting to the scheduler."""
    if future.status == "finished":
        return future.result()
    if future.status == "cancelled" and client.status != "running":  # the client gave up reconnecting
        raise RuntimeError(f"lost the Dask scheduler {scheduler} (the client could not reconnect)")
    err = future.exception() if future.status == "error" else None
    why = (f"its Dask worker died too often (KilledWorker: {err})" if type(err).__name__ == "KilledWorker"
           else f"{type(err).__name__}: {err}" if err is not None else f"the Dask task was {future.status}")
    return _failed_outcome(task, why)


class _DaskDeaths:
    """The deaths of report tasks on a Dask cluster, counted at each look (:meth:`__call__`) from the
    scheduler's ``remove-worker`` events; the scheduler's silence is timed here too."""

    def __init__(self, client: Any, since: float, scheduler: str, running: dict[str, tuple[Any, ReportTask]],
                 progress: BatchProgress | None, retried: list[str] | None) -> None:
        self.client, self.since, self.scheduler, self.running = client, since, scheduler, running
        self.progress, self.retried = progress, retried
        self.by_key = {key: task for key, (_, task) in running.items()}
        self.deaths: dict[str, int] = defaultdict(int)
        self.seen: set[tuple[float, str]] = set()
        self.disconnected: float | None = None

    def __call__(self, final: bool = False) -> Iterator[ReportOutcome]:
        """Count the task deaths of the workers removed since the last look: a first is one retry line
        (also for a task whose second run has finished meanwhile), a second a failed report."""
        try:
            removed = _removed_workers(self.client, self.since, self.seen)
            self.disconnected = None
        except Exception as err:  # noqa: BLE001 - any comm failure: the scheduler is gone or restarting
            if final:
                return
            self.disconnected = self.disconnected or time.monotonic()
            if (time.monotonic() - self.disconnected > DASK_SCHEDULER_LOST_SECONDS
                    or self.client.status in ("closed", "closing")):
                raise RuntimeError(f"lost the Dask scheduler {self.scheduler} ({type(err).__name__}: "
                                   f"{str(err).splitlines()[0][:120] if str(err) else 'no answer'})") from None
            return
        for worker, keys in removed:
            for key in sorted(keys & set(self.by_key)):
                task = self.by_key[key]
                self.deaths[key] += 1
                if self.deaths[key] < TASK_TRIES:
                    if self.retried is not None:
                        self.retried.append(f"the Dask worker of {task.name} died ({worker}); retried on another "
                                            "worker")
                    if self.progress is not None:
                        self.progress("retry", task.name, f"Dask worker {worker} was lost")
                elif key in self.running:
                    future, _ = self.running.pop(key)
                    future.cancel()
                    yield _failed_outcome(task, f"its Dask worker died {self.deaths[key]} times (last: {worker})")


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
    - ``workers=N``: N worker processes of our own (:func:`_processes`), started with the
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
      ``remove-worker`` event, and the task's own start event, :func:`_dask_started`) costs that task
      one retry, which the scheduler makes on another worker (one ``progress("retry", …)`` line and
      a note); a second death, or the scheduler's own ``KilledWorker``, is one failed report, and the
      other tasks go on. A scheduler lost for :data:`DASK_SCHEDULER_LOST_SECONDS` stops the batch
      with one line ("lost the Dask scheduler …"), the reports without a result failed in the
      summary; distributed's loggers are held at CRITICAL meanwhile (no 30-line tracebacks).
    - The temporary files and folders of a run killed while writing (``.NAME.XXXXXXXX.tmp``,
      ``.NAME.XXXXXXXX.old``, ``.summary.csv.XXXXXXXX.csv``, ``.index.html.XXXXXXXX.html``) are
      removed by the next run into the same folder, unless another run into that folder is
      alive: each run holds a lock on its own ``.shrm-report-run.XXXXXXXX.lock`` there, removed
      when it ends (:func:`_remove_stale_temporaries`).
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


# ------------------------------------------------------------------------ the output folder

#: A run's lock file in its output folder (its own, held for the run, removed at the end).
_RUN_LOCK_PREFIX, _RUN_LOCK_SUFFIX = ".shrm-report-run.", ".lock"
#: The random part of a temporary name: ``tempfile``'s 8 characters of ``[a-z0-9_]``, or
#: hexadecimal digits (``secrets.token_hex``) of up to 128 bits.
_RANDOM = r"[a-z0-9_]{8,32}"
#: Temporary folders of :func:`~.writer.write_folder` (``.NAME.XXXXXXXX.tmp``, and ``.old``
#: holding the report it replaces), temporary files of the summary (``atomic_path``), and
#: the lock files of runs: report names never start with ``.`` (:func:`report_names`).
_TEMP_FOLDER = re.compile(rf"\..+\.{_RANDOM}\.(tmp|old)")
_TEMP_FILE = re.compile(rf"\.(summary\.csv\.{_RANDOM}\.csv|index\.html\.{_RANDOM}\.html)")
_RUN_LOCK = re.compile(rf"{re.escape(_RUN_LOCK_PREFIX)}{_RANDOM}{re.escape(_RUN_LOCK_SUFFIX)}")


def _lock_run(out: Path) -> tuple[int, Path] | None:
    """This run's lock file in ``out``, created and locked (``flock``, exclusive) for the whole
    run: another run that finds it locked leaves the temporaries there alone. None if the
    folder cannot be written (the report folders then fail and say why)."""
    for _ in range(3):
        try:
            fd, name = tempfile.mkstemp(prefix=_RUN_LOCK_PREFIX, suffix=_RUN_LOCK_SUFFIX, dir=out)
        except OSError:
            return None
        fcntl.flock(fd, fcntl.LOCK_EX)
        try:  # still ours? (another run's cleanup may have taken it for a dead run's before the flock)
            if os.stat(name).st_ino == os.fstat(fd).st_ino:
                return fd, Path(name)
        except OSError:
            pass
        os.close(fd)
    return None  # pragma: no cover - lost three times to other runs' cleanups


def _unlock_run(lock: tuple[int, Path] | None) -> None:
    if lock is not None:
        with contextlib.suppress(OSError):
            lock[1].unlink()
        os.close(lock[0])


def _dead_run(path: str) -> bool:
    """Whether the run of lock file ``path`` is over (then the file is removed): nobody holds its lock."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return True  # removed meanwhile
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # locked: that run is alive
        os.close(fd)
        return False
    with contextlib.suppress(OSError):
        os.unlink(path)
    os.close(fd)
    return True


def _remove_stale_temporaries(out: Path, own_lock: Path | None) -> list[str]:
    """Remove what runs killed while writing left in ``out``: the temporary report folders and
    summary files of :data:`_TEMP_FOLDER` and :data:`_TEMP_FILE`, and their lock files; nothing
    while another run into ``out`` is alive (its lock file is locked). A report that a killed
    run had moved aside (``.old``) and not yet replaced is put back first. Returns the names
    removed."""
    try:
        entries = list(os.scandir(out))
    except OSError:
        return []
    stale: list[os.DirEntry[str]] = []
    removed: list[str] = []
    for entry in entries:
        if _RUN_LOCK.fullmatch(entry.name):
            if own_lock is not None and entry.name == own_lock.name:
                continue
            if not _dead_run(entry.path):
                return removed  # another run into this folder is alive: its temporaries are its own
            removed.append(entry.name)
        elif (_TEMP_FOLDER.fullmatch(entry.name) and entry.is_dir(follow_symlinks=False)) or (
                _TEMP_FILE.fullmatch(entry.name) and entry.is_file(follow_symlinks=False)):
            stale.append(entry)
    for entry in stale:
        try:
            if entry.name.endswith(".old"):
                for kept in os.scandir(entry.path):  # the report a killed run had moved aside
                    if not (out / kept.name).exists():
                        os.replace(kept.path, out / kept.name)
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
            removed.append(entry.name)
        except OSError:
            continue  # not ours to remove after all (permissions): left as it is
    return removed


def _write_index(out: Path, rows: list[dict[str, Any]], notes: list[str], wait: bool = True) -> None:
    """``summary.csv`` and ``index.html`` of every report in ``out``: this run's rows (input order),
    then those of the other report folders already there (earlier or concurrent runs into the
    same ``--out``), rebuilt from their ``report.json``, under an exclusive lock on the folder, so
    two runs at once never lose a row (issue 28: the last writer's index listed 2 of 3). Not
    ``wait``: nothing written when another run holds the lock (``BlockingIOError``)."""
    fd = os.open(out, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
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
