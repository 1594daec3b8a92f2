"""Batch scaling: each worker gets its share of the cores (ducc0, BLAS, preview threads) once,
at start; tasks start largest first; the reports do not depend on threads or engine; and
`shrm report --dask-scheduler` works against an in-process LocalCluster and against a
scheduler and worker processes started as separate `dask` processes on 127.0.0.1 (the README's
commands). The Dask tests skip when `distributed` is not installed (the test extras of
`.ci/setup` install it)."""

from __future__ import annotations

import json
import multiprocessing
import os
import shutil
import socket
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from shrmkit.brdf_io.merl import write_merl
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.main import main
from shrmkit.cli.report import batch
from shrmkit.cli.report.batch import ReportTask, estimate_cost, largest_first, run_batch
from shrmkit.cli.report.collect import collect_report, strip_timings
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.threads import (
    MALLOC_ENV_VARS,
    THREAD_ENV_VARS,
    thread_report,
    threads_per_worker,
    usable_cores,
    worker_initializer,
)

CHEAP = ["phong:s=16", "lambert:albedo=0.5", "microfacet:sigma=0.4"]
FAST = ["--quick", "--preview", "none", "--models", "lafortune", "--tolerances", "0.1", "--eps", "0.1",
        "--pairs", "30", "--fit-samples", "1024", "--no-progress", "--no-plots"]


def tiny_options():
    """The options `shrm report CHEAP *FAST` builds (the quick profile's albedo nodes included), so
    that one serial run is the reference of the library's engines and of the command line."""
    return profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=30,
                   fit_samples=1024, plots=False)


def native(report: dict) -> dict:
    """What configure_worker changes in a process: not the environment, which a LocalCluster of
    processes changes in its caller by itself (distributed's nanny sets OMP_NUM_THREADS…)."""
    return {k: report[k] for k in ("configured", "ducc0", "blas", "malloc_restored", "pid")}


def reports(out: Path) -> dict[str, dict]:
    return {d.name: strip_timings(json.loads((d / "report.json").read_text())) for d in sorted(out.iterdir())
            if d.is_dir()}


@pytest.fixture(scope="module")
def serial_reports(tmp_path_factory):
    out = tmp_path_factory.mktemp("scaling") / "serial"
    assert run_batch(CHEAP, out, tiny_options()).n_failed == 0
    return reports(out)


def test_threads_per_worker_shares_the_cores():
    assert threads_per_worker(16, cores=16) == 1
    assert threads_per_worker(4, cores=16) == 4
    assert threads_per_worker(3, cores=16) == 5
    assert threads_per_worker(3, cores=2) == 1  # never 0
    assert threads_per_worker(1) == usable_cores() >= 1


def test_worker_process_is_limited_once_at_start():
    """A spawned worker with the pool's initializer: ducc0's pool, every BLAS loaded and the
    thread variables (llvmpipe, VTK SMP, OpenMP…) at its share, 1 thread; the report modules
    and VTK's rendering modules imported (warm); the caller's own process untouched."""
    before = thread_report()
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=worker_initializer,
                             initargs=(1, "gl")) as pool:
        seen = pool.submit(thread_report).result()
        # a builtin, not a function of this module: unpickling one imports this test module in the worker
        # (and with it the report modules whose warm-up is checked here), and fails where the worker cannot
        # import ``tests`` (ModuleNotFoundError, seen in whole runs under xdist)
        warm = pool.submit(eval, "sorted(__import__('sys').modules)").result()
    assert seen["pid"] != os.getpid()
    assert seen["configured"] == 1 and seen["ducc0"] == 1
    assert seen["blas"] and set(seen["blas"]) == {1}, seen["blas"]
    assert all(seen["env"][v] == "1" for v in THREAD_ENV_VARS)
    assert {"shrmkit.cli.report.collect", "shrmkit.render.preview", "matplotlib",
            "vtkmodules.vtkRenderingOpenGL2"} <= set(warm)
    # glibc's dynamic mmap threshold is left alone unless a MALLOC_*_ variable had switched it off
    assert seen["malloc_restored"] is (sys.platform.startswith("linux") and any(v in os.environ for v in
                                                                                MALLOC_ENV_VARS))
    assert thread_report() == before and before["configured"] is None


def test_reports_do_not_depend_on_ducc0_threads():
    """The SHTs give the same numbers on 1 thread as on every core: report.json is equal."""
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.03,), n_pairs=60,
                      fit_samples=1024, albedo_nodes=16)  # the main eps 0.03 only: F = 22, P = 6 SHTs
    a, _ = collect_report("microfacet:sigma=0.3", options, nthreads=0)
    b, _ = collect_report("microfacet:sigma=0.3", options, nthreads=1)
    assert strip_timings(a) == strip_timings(b)


def test_costly_brdfs_are_estimated_costlier(tmp_path):
    """A lobe that changes with the view costs more the sharper it is; a Phong lobe (the same
    at every view) or Lambert costs little whatever its exponent; a MERL-size table sits in
    between; a bad source costs 0 (it fails at once)."""
    table = write_merl(tmp_path / "t.binary", load_brdf("phong:s=16"))
    costs = [estimate_cost(s) for s in ("cook-torrance:kd=0.2,alpha=0.1", "microfacet:sigma=0.2", str(table),
                                        "microfacet:sigma=0.5", "lambert:albedo=0.5")]
    assert costs == sorted(costs, reverse=True) and costs[-1] > 0, costs
    assert estimate_cost("phong:s=256") == pytest.approx(estimate_cost("lambert:albedo=0.5"), rel=0.2)
    assert estimate_cost(str(tmp_path / "missing.binary")) == 0.0
    assert estimate_cost("nonsense:x=1") == 0.0
    sources = ("lambert:albedo=0.5", "microfacet:sigma=0.4", "phong:s=16", "cook-torrance:kd=0.2,alpha=0.1")
    tasks = [ReportTask(s, s, tiny_options(), "none") for s in sources]
    assert [t.source for t in largest_first(tasks)] == [sources[3], sources[1], sources[0], sources[2]]


class TestAgainstSerial:
    """The tests of the serial_reports fixture: one unit of work under xdist (tests/conftest.py), one serial run."""

    def test_worker_processes_start_largest_first_and_match_serial(self, tmp_path, serial_reports):
        """--workers 2: the tasks are queued largest first, each worker has its share of the
        cores, the summary keeps the input order, and the reports equal the serial ones."""
        events = []
        result = run_batch(CHEAP, tmp_path / "w", tiny_options(), workers=2, progress=lambda *e: events.append(e))
        assert result.n_failed == 0
        assert result.engine == f"2 processes, {threads_per_worker(2)} thread(s) each"
        queued = [e[1] for e in events if e[0] == "start"]
        assert queued == ["microfacet_sigma_0.4", "phong_s_16", "lambert_albedo_0.5"]
        assert [r["name"] for r in result.rows] == ["phong_s_16", "lambert_albedo_0.5", "microfacet_sigma_0.4"]
        assert reports(tmp_path / "w") == serial_reports

    def test_in_process_dask_worker_leaves_the_caller_alone(self, tmp_path, serial_reports):
        """An in-process LocalCluster runs the tasks in the caller's process: its threads are
        not limited (ducc0 gets the share per call instead). One task runs there as well as three."""
        distributed = pytest.importorskip("distributed")
        before = thread_report()
        with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                      dashboard_address=":0") as cluster:
            result = run_batch(CHEAP[:1], tmp_path / "d", tiny_options(), scheduler=cluster.scheduler_address)
        assert result.n_failed == 0 and result.engine.startswith("dask")
        assert reports(tmp_path / "d") == {"phong_s_16": serial_reports["phong_s_16"]}
        assert native(thread_report()) == native(before)

    def test_cli_on_separate_dask_scheduler_and_workers(self, tmp_path, serial_reports):
        """The README's commands: `dask scheduler` and `dask worker ADDRESS --nthreads 1 --nworkers 2`
        as separate processes on 127.0.0.1, then `shrm report … --dask-scheduler ADDRESS`; the
        reports equal the serial ones (``tiny_options`` is what FAST builds); each worker process
        (2 × 1 thread, under a nanny as in a LocalCluster of processes) was configured with
        cores // 2 threads at its first task; the caller's process, which holds the client, keeps
        its own threads. (One test for both multi-process Dask setups: each costs ~30 s of worker
        start-up on 2 cores.)"""
        distributed = pytest.importorskip("distributed")
        dask_cli = shutil.which("dask", path=str(Path(sys.executable).parent)) or shutil.which("dask")
        if dask_cli is None:
            pytest.skip("the dask command is not installed")
        port = _free_port()
        address = f"tcp://127.0.0.1:{port}"
        env = dict(os.environ)
        procs = []
        try:
            procs.append(subprocess.Popen([dask_cli, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                           "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, cwd=tmp_path))
            procs.append(subprocess.Popen([dask_cli, "worker", address, "--nthreads", "1", "--nworkers", "2",
                                           "--host", "127.0.0.1", "--no-dashboard"], env=env,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path))
            deadline = time.monotonic() + 120
            client = None
            while client is None:
                try:
                    client = distributed.Client(address, set_as_default=False, timeout="5s")
                except (OSError, TimeoutError):
                    if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                        pytest.fail("the dask scheduler did not start")
                    time.sleep(0.5)
            before = thread_report()
            with client:
                client.wait_for_workers(2, timeout=120)
                out = tmp_path / "rep"
                assert main(["report", *CHEAP, "--out", str(out), "--dask-scheduler", address, *FAST]) == 0
                seen = client.run(thread_report)
            assert reports(out) == serial_reports
            share = threads_per_worker(2)
            used = [s for s in seen.values() if s["configured"] is not None]
            assert used, seen  # at least one worker ran a task
            for s in used:
                assert s["configured"] == share and s["ducc0"] == share and set(s["blas"]) == {share}, s
                # the nanny's MALLOC_TRIM_THRESHOLD_ had switched off glibc's dynamic mmap threshold
                assert s["env"]["OMP_NUM_THREADS"] == str(share)
                assert s["malloc_restored"] is sys.platform.startswith("linux")
            assert native(thread_report()) == native(before)
        finally:
            for p in reversed(procs):
                p.terminate()
            for p in reversed(procs):
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_serial_engine_keeps_input_order_and_every_core(tmp_path, monkeypatch):
    """The serial engine is unchanged: input order, every core (nthreads 0), in this process
    (the spy is called here; it stands in for the report, which the other tests make)."""
    seen = []

    def spy(task, progress=None):
        seen.append((task.name, task.nthreads))
        row = {"name": task.name, "status": "ok", "source": task.source, "total_seconds": 0.0, "error": None}
        return batch.ReportOutcome(task.name, True, row, {"report.json": b"{}\n"})

    monkeypatch.setattr(batch, "run_task", spy)
    result = run_batch(["lambert:albedo=0.5", "phong:s=256"], tmp_path / "s", tiny_options())
    assert seen == [("lambert_albedo_0.5", 0), ("phong_s_256", 0)]
    assert result.engine == "serial" and [r["name"] for r in result.rows] == ["lambert_albedo_0.5", "phong_s_256"]
