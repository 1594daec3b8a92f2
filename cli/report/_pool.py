"""The worker-process engine of a batch (``shrm report --workers N``): spawned processes, one
task at a time each over a pipe, a dead worker's task retried (:data:`~._task.TASK_TRIES`), and
the worker's side: its loop (:data:`WORKER_TARGET`) and its watch that ends it with its driver.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import defaultdict, deque
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from multiprocessing import resource_tracker
from multiprocessing.connection import wait as wait_ready
from typing import Any

from . import worker_boot
from ._cost import largest_first
from ._task import TASK_TRIES, BatchProgress, ReportOutcome, ReportTask, _failed_outcome, run_task
from .threads import threads_per_worker, worker_initializer

#: The worker loop a report worker process runs after :func:`~.worker_boot.boot` (by name: the
#: target's module is imported only once the parent-death signal is set).
WORKER_TARGET = "shrmkit.cli.report._pool:_worker_main"

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
