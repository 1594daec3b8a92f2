"""The Dask engine of a batch (``shrm report --dask-scheduler ADDRESS``): the tasks submitted to
a ``distributed`` cluster, each worker's share of the cores, a lost worker's task retried once
(the scheduler's ``remove-worker`` events), a lost scheduler stopping the batch in one line.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import os
import socket
import time
from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

from ...brdf_io.errors import BadInputError
from ._cost import largest_first
from ._task import TASK_TRIES, BatchProgress, ReportOutcome, ReportTask, _failed_outcome, run_task
from .threads import configure_worker, threads_per_worker, usable_cores


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
