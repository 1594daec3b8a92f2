"""Thread budgets of report workers: each worker process gets its share of the cores.

A report task runs three kinds of native threads:

- ducc0's spherical-harmonic transforms (``prefilter``/``lighting_coefficients``
  ``nthreads``; 0 means every core);
- the BLAS behind numpy and scipy (OpenBLAS starts one thread per core);
- the OpenGL preview: Mesa's llvmpipe rasterizer and VTK's SMP tools (one per core).

Left alone, N worker processes on a machine of C cores each use C threads of every kind (16
processes on 16 cores: some 256 threads). :func:`configure_worker` gives every worker
:func:`threads_per_worker` = C // N threads (at least 1), once per process, when it starts (a Dask
worker at its first report task, ``batch.py``); the serial engine leaves the caller's threads
alone. It also restores glibc's allocator thresholds in a Dask nanny's worker
(:func:`restore_malloc_thresholds`) and imports what a report task needs ("warm" worker).
"""

from __future__ import annotations

import ctypes
import importlib
import os
import sys
import threading
import time
from typing import Any

import ducc0
from threadpoolctl import threadpool_info, threadpool_limits

__all__ = [
    "MALLOC_ENV_VARS",
    "THREAD_ENV_VARS",
    "usable_cores",
    "threads_per_worker",
    "configure_worker",
    "worker_initializer",
    "worker_threads",
    "worker_start_seconds",
    "native_thread_limits",
    "restore_malloc_thresholds",
    "thread_report",
]

#: Environment variables that cap the threads of a native library loaded after they are set:
#: OpenMP, OpenBLAS, MKL, Accelerate, numexpr, ducc0, Mesa llvmpipe, VTK SMP tools.
THREAD_ENV_VARS = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "DUCC0_NUM_THREADS",
    "LP_NUM_THREADS",
    "VTK_SMP_MAX_THREADS",
)

#: glibc variables whose presence switches off its dynamic mmap threshold (the nanny sets the first)
MALLOC_ENV_VARS = ("MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_", "MALLOC_TOP_PAD_", "MALLOC_MMAP_MAX_")
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # mallopt parameters (malloc.h)
MMAP_THRESHOLD_BYTES = 32 << 20  # glibc's DEFAULT_MMAP_THRESHOLD_MAX on 64-bit
TRIM_THRESHOLD_BYTES = 64 << 20  # twice it, as the dynamic rule sets

_lock = threading.Lock()
_malloc_restored = False
_configured: int | None = None
_start_seconds: float | None = None
_limiter: Any = None  # the threadpoolctl limits, kept for the life of the process


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity, else ``os.cpu_count()``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def threads_per_worker(workers: int, cores: int | None = None) -> int:
    """Each of ``workers`` concurrent tasks' share of ``cores`` (default :func:`usable_cores`): at least 1."""
    cores = usable_cores() if cores is None else int(cores)
    return max(1, cores // max(1, int(workers)))


#: What a report task imports, preloaded by name when a worker starts (a preload, not a code
#: dependency of this module: the report modules themselves import this one).
WARM_MODULES = (
    "shrmkit.render.pipeline",
    "shrmkit.render.preview",
    "shrmkit.cli.report.batch",
    "shrmkit.cli.report.collect",
    "shrmkit.cli.report.plots",
    "shrmkit.cli.report.writer",
)
#: VTK's rendering modules, preloaded for OpenGL previews (otherwise the first preview loads them).
WARM_GL_MODULES = (
    "vtkmodules.util.numpy_support",
    "vtkmodules.vtkCommonDataModel",
    "vtkmodules.vtkRenderingCore",
    "vtkmodules.vtkRenderingOpenGL2",
)


def _warm_imports(preview_mode: str | None) -> None:
    """Import everything a report task uses, once per process (the worker is then warm):
    the report modules (numpy, scipy, nlopt, matplotlib, trimesh), and VTK's rendering
    modules for OpenGL previews (imported lazily otherwise, by the first preview)."""
    for module in WARM_MODULES + (WARM_GL_MODULES if preview_mode == "gl" else ()):
        importlib.import_module(module)


def native_thread_limits(threads: int) -> None:
    """Cap the BLAS already loaded (threadpoolctl) and ducc0's thread pool at ``threads``."""
    global _limiter
    _limiter = threadpool_limits(limits=int(threads))  # stays in force: the limiter is never restored
    try:
        ducc0.misc.resize_thread_pool(int(threads))
    except AttributeError:  # pragma: no cover - an older ducc0 without a pool
        pass


def restore_malloc_thresholds() -> bool:
    """When a glibc ``MALLOC_*_`` variable (:data:`MALLOC_ENV_VARS`) has switched off the
    dynamic mmap threshold, set the thresholds it would reach: arrays up to 32 MiB come from
    the heap again instead of fresh pages. Returns whether it changed anything (not glibc,
    or no such variable: nothing to do).

    ``distributed``'s nanny starts every worker process with
    ``MALLOC_TRIM_THRESHOLD_=65536``. Setting any such glibc variable switches off glibc's
    dynamic mmap threshold, so every array above 128 KiB is mapped and unmapped afresh and its
    pages faulted in again: a report ran 2.6× slower in such a worker (24.4 s against 9.5 s,
    14 s of it system time). :func:`restore_malloc_thresholds` sets the thresholds glibc's
    dynamic rule would reach (mmap above 32 MiB, trim above 64 MiB) in that case only: the
    worker then keeps more freed memory for reuse (Dask's monitor counts it as unmanaged memory)
    instead of returning it at once.
    """
    global _malloc_restored
    if _malloc_restored:
        return True
    if not sys.platform.startswith("linux") or not any(v in os.environ for v in MALLOC_ENV_VARS):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # pragma: no cover - a libc without mallopt
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    _malloc_restored = bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) and bool(
        mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES))
    return _malloc_restored


def configure_worker(threads: int, *, warm: bool = True, preview_mode: str | None = None) -> int:
    """Give this worker process ``threads`` native threads of every kind, once.

    Sets :data:`THREAD_ENV_VARS`, imports the report modules when ``warm`` (and VTK's for
    ``preview_mode="gl"``; the libraries loaded by them see the variables), limits the BLAS
    and ducc0, and restores glibc's allocator thresholds where a variable had fixed them
    (:func:`restore_malloc_thresholds`: a Dask nanny's worker). Later calls return the
    number of the first without changing anything. Call it in worker processes only: the
    limits stay for the life of the process.

    Left alone, N worker processes on a machine of C cores each use C threads of every kind:
    16 processes on 16 cores could run some 256 threads. Every worker therefore gets
    :func:`threads_per_worker` = C // N threads (at least 1), set **once per process** when it
    starts, by :func:`configure_worker`: the thread variables of the environment (read by the
    libraries loaded afterwards: llvmpipe, VTK SMP, a lazily loaded BLAS), ``threadpoolctl``
    limits on the BLAS already loaded, and ducc0's thread pool; the task then passes the same
    number as ``nthreads`` to ducc0 explicitly (``ReportTask.nthreads``). The serial engine runs
    in the caller's process and leaves its threads alone (every core, as before).

    The same function configures a Dask worker process at its first report task (``batch.py``);
    a Dask worker with T task threads gets C // (all task threads of the workers on its host).

    It also imports everything a report task needs ("warm" worker), so
    the imports (VTK, matplotlib, scipy: about 2 s) happen once per process, at start, and not
    inside the first task.
    """
    global _configured, _start_seconds
    with _lock:
        if _configured is not None:
            return _configured
        t0 = time.perf_counter()
        threads = max(1, int(threads))
        restore_malloc_thresholds()
        for var in THREAD_ENV_VARS:
            os.environ[var] = str(threads)
        if warm:
            _warm_imports(preview_mode)
        native_thread_limits(threads)
        _configured = threads
        _start_seconds = time.perf_counter() - t0
        return threads


def worker_initializer(threads: int, preview_mode: str | None = None) -> None:
    """``ProcessPoolExecutor(initializer=...)``: :func:`configure_worker` at process start."""
    configure_worker(threads, preview_mode=preview_mode)


def worker_threads() -> int | None:
    """The threads :func:`configure_worker` gave this process, or None (not a configured worker)."""
    return _configured


def worker_start_seconds() -> float | None:
    """Seconds :func:`configure_worker` took in this process (imports and limits), or None."""
    return _start_seconds


def thread_report() -> dict[str, Any]:
    """This process's threads: the share :func:`configure_worker` gave (None if not a worker),
    ducc0's pool size, the threads of each BLAS loaded (threadpoolctl) and the variables."""
    return {
        "configured": _configured,
        "ducc0": int(ducc0.misc.thread_pool_size()),
        "blas": sorted({int(i["num_threads"]) for i in threadpool_info() if i.get("user_api") == "blas"}),
        "env": {var: os.environ.get(var) for var in THREAD_ENV_VARS},
        "cores": usable_cores(),
        "malloc_restored": _malloc_restored,
        "pid": os.getpid(),
    }
