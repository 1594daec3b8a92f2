"""Batch scaling of `shrm report`: wall time and speed-up for 1, 2, 4, ... workers, worker
processes and a Dask cluster, and where the time of one report goes.

Usage::

    .venv/bin/python benchmarks/batch_scaling.py --quick                    # 32 BRDFs: 28 analytic, 4 MERL tables
    .venv/bin/python benchmarks/batch_scaling.py --quick --brdfs 8 --max-workers 2 --no-dask
    .venv/bin/python benchmarks/batch_scaling.py --quick --workers 1,2,3 --repeats 2

The library: analytic BRDFs of several families and sharpnesses (Phong, Lambert, Lafortune,
the simplified microfacet, Cook–Torrance Beckmann and GGX) and ``--tables`` MERL-size tables
(90·90·180 samples, 35 MB each, tabulated from analytic models with
``shrmkit.brdf_io.merl.write_merl`` into a temporary folder). Every run is ``run_batch``, the
function behind ``shrm report``, on the whole library with the ``--quick`` (or full)
profile and the ``--preview`` renderer (default ``auto``: OpenGL when it works).

Prints

1. **stages**: per BRDF, the seconds of each stage of the serial (1-worker) run, timed from
   the report's progress events: load, fits (and the fit slices), orders (``choose_orders``
   at each tolerance), reference (angular reference on the pairs, lighting SHT), prefilter
   (every tolerance, reusing the orders; in brackets the part spent on the window against
   Gibbs ringing, ``window_seconds`` of ``report.json``), checks, preview
   (``preview_seconds`` of ``report.json``, and the live view) and
   writing (plots, HTML, Markdown, the folder); the batch's cost estimate
   (``batch.estimate_cost``) beside the measured total, and the rank correlation of the two;
2. **worker start-up**: one spawned worker process: start, imports and thread limits;
   the peak resident memory of the serial run's process and of the largest worker;
3. **scaling**: for each engine and worker count, the wall time of the whole batch (minimum
   over ``--repeats``), the speed-up over the serial run, the efficiency, the best speed-up
   possible with whole BRDFs as tasks (serial time / max(sum/N, longest BRDF)), the load
   average of the machine before the run (other users' work shows here), and whether every
   ``report.json`` equals the serial run's (timings aside).

Dask runs use a ``distributed.LocalCluster`` of N worker processes with one thread each
(``dask worker --nworkers N --nthreads 1`` on one machine), started before the clock starts.
Target: >= 1.8x with 2 workers on 2 cores (an otherwise idle machine).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from shrmkit.brdf_io.merl import write_merl
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.cli.report.batch import estimate_cost, report_names, run_batch
from shrmkit.cli.report.collect import strip_timings
from shrmkit.cli.report.options import profile
from shrmkit.cli.report.threads import usable_cores, worker_initializer, worker_start_seconds, worker_threads

console = Console(highlight=False, width=200)

ANALYTIC = [
    *(f"phong:s={s}" for s in (4, 16, 64, 256, 1024)),
    *(f"lambert:albedo={a}" for a in (0.3, 0.8)),
    *(f"lafortune:kd=0.2,n={n},ks=2" for n in (5, 10, 30, 100, 300)),
    "lafortune:kd=0.1,n=20,ks=1,cxy2=-0.6,cz2=0.9,n2=80,ks2=3",
    "lafortune:kd=0.3,cxy=-0.9,cz=0.6,n=15,ks=1",
    *(f"microfacet:sigma={s}" for s in (0.1, 0.15, 0.2, 0.3, 0.4, 0.5)),
    *(f"cook-torrance:kd=0.2,alpha={a}" for a in (0.1, 0.2, 0.3, 0.5)),
    *(f"cook-torrance:kd=0.2,alpha={a},dist=ggx" for a in (0.2, 0.4)),
]
#: Models of the MERL-size tables: reciprocal and finite at grazing, as a measurement is (RH02's
#: Phong and simplified microfacet define ρ̂ = ρ cos θ_i, so their ρ grows like 1/cos θ_i toward
#: the horizon: tabulated, a Phong s = 64 holds 2e15 sr⁻¹ at grazing and no order captures it).
TABLE_MODELS = [
    "lafortune:kd=0.2,n=30,ks=2",
    "cook-torrance:kd=0.2,alpha=0.3,dist=ggx",
    "cook-torrance:kd=0.3,alpha=0.25",
    "lafortune:kd=0.3,n=10,ks=1",
    "cook-torrance:kd=0.1,alpha=0.4",
    "lafortune:kd=0.1,n=80,ks=3",
]


def library(n: int, n_tables: int, folder: Path) -> list[str]:
    """``n`` sources: ``n_tables`` MERL tables spread among the analytic specs."""
    n_tables = min(n_tables, n)
    tables = []
    for k in range(n_tables):
        spec = TABLE_MODELS[k % len(TABLE_MODELS)]
        tables.append(str(write_merl(folder / f"merl{k}_{spec.split(':')[0]}.binary", load_brdf(spec))))
    out = [ANALYTIC[k % len(ANALYTIC)] for k in range(n - n_tables)]  # repeats (beyond 28) get "-2" folders
    for k, table in enumerate(tables):  # spread evenly, not all at the end
        out.insert(k * (len(out) + 1) // n_tables, table)
    return out


def load_reports(out: Path) -> dict[str, dict]:
    return {d.name: strip_timings(json.loads((d / "report.json").read_text())) for d in sorted(out.iterdir())
            if d.is_dir()}


def serial_run(sources: list[str], out: Path, options) -> tuple[float, dict[str, dict[str, float]]]:
    """The 1-worker run with per-stage times from the progress events."""
    marks: dict[str, list[tuple[str, float]]] = {}

    def progress(event: str, name: str, detail: str) -> None:
        now = time.perf_counter()
        if event == "start":
            marks[name] = [("start", now)]
        elif event == "stage":
            marks[name].append((detail, now))
        elif event == "done":
            marks[name].append(("done", now))

    t0 = time.perf_counter()
    result = run_batch(sources, out, options, workers=1, progress=progress)
    wall = time.perf_counter() - t0
    stages: dict[str, dict[str, float]] = {}
    for name, seq in marks.items():
        d: dict[str, float] = {}
        for (stage, t), (_, t_next) in zip(seq[1:-1], seq[2:], strict=True):
            key = stage.split(" ")[0]
            d[key] = d.get(key, 0.0) + t_next - t
        d["total"] = seq[-1][1] - seq[0][1]
        path = out / name / "report.json"
        doc = json.loads(path.read_text()) if path.is_file() else {}
        if doc.get("status") == "ok":
            d["preview_only"] = doc["preview"]["preview_seconds"]
            d["writing"] = d.get("preview", 0.0) - d["preview_only"]
            d["prefilter_window"] = sum(r["window_seconds"] for r in doc["speed_vs_error"])
        stages[name] = d
    if result.n_failed:
        console.print(f"[red]{result.n_failed} reports failed in the serial run[/red]")
    return wall, stages


def stage_table(sources: list[str], names: list[str], stages: dict[str, dict[str, float]]) -> np.ndarray:
    cols = ("load", "fits", "orders", "reference", "prefilter", "checks", "preview_only", "writing")
    table = Table(title="1. where the time of one report goes (serial run, seconds)", box=None)
    for c in ("BRDF", "load", "fits", "orders", "reference", "prefilter (window)", "checks", "preview",
              "writing", "total", "est. cost"):
        table.add_column(c, justify="left" if c == "BRDF" else "right")
    sums = dict.fromkeys((*cols, "prefilter_window", "total"), 0.0)
    totals, costs = [], []
    for source, name in zip(sources, names, strict=True):
        d = stages.get(name, {})
        for c in sums:
            sums[c] += d.get(c, 0.0)
        cost = estimate_cost(source)
        totals.append(d.get("total", 0.0))
        costs.append(cost)
        label = Path(source).name if source.endswith(".binary") else source
        table.add_row(label[:44], *(f"{d.get(c, 0.0):.2f}" for c in cols[:4]),
                      f"{d.get('prefilter', 0.0):.2f} ({d.get('prefilter_window', 0.0):.2f})",
                      *(f"{d.get(c, 0.0):.2f}" for c in cols[5:]), f"{d.get('total', 0.0):.2f}", f"{cost:.1f}")
    total = max(sums["total"], 1e-9)
    table.add_row("[bold]sum[/bold]", *(f"{sums[c]:.1f}" for c in cols[:4]),
                  f"{sums['prefilter']:.1f} ({sums['prefilter_window']:.1f})",
                  *(f"{sums[c]:.1f}" for c in cols[5:]), f"{sums['total']:.1f}", "")
    table.add_row("[bold]share[/bold]", *(f"{sums[c] / total:.0%}" for c in cols[:4]),
                  f"{sums['prefilter'] / total:.0%} ({sums['prefilter_window'] / total:.0%})",
                  *(f"{sums[c] / total:.0%}" for c in cols[5:]), "100%", "")
    console.print(table)
    ranks = [np.argsort(np.argsort(v)) for v in (np.array(totals), np.array(costs))]
    rho = float(np.corrcoef(*ranks)[0, 1]) if len(totals) > 2 else float("nan")
    console.print(f"rank correlation of the cost estimate with the measured time: {rho:.2f}; "
                  f"longest BRDF {max(totals):.1f} s of {sum(totals):.1f} s")
    return np.array(totals)


def _probe() -> tuple[float | None, int | None]:
    return worker_start_seconds(), worker_threads()


def worker_startup() -> None:
    t0 = time.perf_counter()
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=worker_initializer,
                             initargs=(1,)) as pool:
        configure, threads = pool.submit(_probe).result()
    console.print(f"2. worker start-up: {time.perf_counter() - t0:.2f} s to spawn one worker process (imports of this "
                  f"script's modules included) and get its first result; configure_worker (the imports not yet "
                  f"done, thread limits) {configure:.2f} s of it; {threads} thread(s)")


def machine_busy() -> float:
    """CPU seconds the whole machine has been busy (all cores, all users), from /proc/stat."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except OSError:  # pragma: no cover - not Linux
        return float("nan")
    user, nice, system, _idle, _iowait, irq, softirq, steal = v
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def own_cpu() -> float:
    """CPU seconds of this process and its reaped children (worker processes once they exit)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


class Meter:
    """Wall time, our CPU and the cores other users kept busy over a ``with`` block."""

    def __enter__(self) -> Meter:
        self.t0, self.cpu0, self.busy0 = time.perf_counter(), own_cpu(), machine_busy()
        return self

    def __exit__(self, *exc) -> None:
        self.wall = time.perf_counter() - self.t0
        self.cpu = own_cpu() - self.cpu0
        self.others = max(0.0, (machine_busy() - self.busy0 - self.cpu) / self.wall)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the quick report profile (what --quick of shrm report is)")
    ap.add_argument("--brdfs", type=int, default=32, help="BRDFs in the library (default 32)")
    ap.add_argument("--tables", type=int, default=4, help="of which MERL-size tables (default 4)")
    ap.add_argument("--max-workers", type=int, default=os.cpu_count() or 1,
                    help="largest worker count of the 1, 2, 4, ... series (default os.cpu_count())")
    ap.add_argument("--workers", default=None, help="explicit comma-separated worker counts instead of the series")
    ap.add_argument("--repeats", type=int, default=1, help="runs per point, the fastest is kept (default 1)")
    ap.add_argument("--preview", default="auto", choices=("auto", "gl", "cpu", "none"))
    ap.add_argument("--no-dask", action="store_true", help="skip the Dask runs")
    ap.add_argument("--no-processes", action="store_true", help="skip the worker-process runs")
    ap.add_argument("--keep", default=None, help="write the reports here (default: a temporary folder)")
    args = ap.parse_args()

    if args.workers:
        counts = sorted({int(w) for w in args.workers.split(",")})
    else:
        counts, n = [], 1
        while n < args.max_workers:
            counts.append(n)
            n *= 2
        counts.append(args.max_workers)
    options = profile("quick" if args.quick else "full", preview=args.preview)
    with tempfile.TemporaryDirectory(prefix="batch-scaling-") as tmp:
        root = Path(args.keep) if args.keep else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        tables = Path(tmp) / "tables"
        tables.mkdir()
        sources = library(args.brdfs, args.tables, tables)
        names = report_names(sources)
        console.print(f"{len(sources)} BRDFs ({min(args.tables, args.brdfs)} MERL tables), profile "
                      f"{options.profile}, preview {args.preview}; {usable_cores()} usable cores, "
                      f"os.cpu_count() {os.cpu_count()}")
        runs: dict[tuple[str, int], list[tuple[float, float, float, bool]]] = {}
        best_serial, stages = float("inf"), {}
        for _ in range(max(1, args.repeats)):
            with Meter() as m:
                wall, st = serial_run(sources, root / "serial", options)
            runs.setdefault(("serial", 1), []).append((m.wall, m.cpu, m.others, True))
            console.print(f"   serial: {m.wall:.1f} s, our CPU {m.cpu:.0f} s, other users {m.others:.2f} cores")
            if wall < best_serial:
                best_serial, stages = wall, st
        totals = stage_table(sources, names, stages)
        console.print(f"peak resident memory of the serial run's process: "
                      f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
        reference = load_reports(root / "serial")
        worker_startup()

        engines = ([] if args.no_processes else ["processes"]) + ([] if args.no_dask else ["dask"])
        for engine in engines:
            for n in counts:
                if engine == "processes" and n == 1:
                    continue  # workers=1 is the serial run
                for r in range(max(1, args.repeats)):
                    out = root / f"{engine}-{n}-{r}"
                    if engine == "processes":
                        with Meter() as m:
                            run_batch(sources, out, options, workers=n)
                        wall, cpu, others = m.wall, m.cpu, m.others
                    else:
                        wall, cpu, others = dask_run(sources, out, options, n)
                    same = load_reports(out) == reference
                    runs.setdefault((engine, n), []).append((wall, cpu, others, same))
                    console.print(f"   {engine} {n}: {wall:.1f} s, our CPU {cpu:.0f} s, other users {others:.2f} "
                                  f"cores, same reports {same}")

        table = Table(title="3. scaling (wall seconds of the whole batch; the fastest of the repeats)", box=None)
        for c in ("engine", "workers", "threads/worker", "wall s", "all runs", "speed-up", "efficiency",
                  "best possible", "our CPU s", "other users' cores", "same reports"):
            table.add_column(c, justify="left" if c == "engine" else "right")
        cores = usable_cores()
        serial_wall = min(r[0] for r in runs[("serial", 1)])
        for (engine, n), rs in runs.items():
            wall, cpu, others, _ = min(rs)
            same = all(r[3] for r in rs)
            bound = serial_wall / max(totals.sum() / n, totals.max()) if len(totals) else float("nan")
            table.add_row(engine, str(n), "all" if engine == "serial" else str(max(1, cores // n)), f"{wall:.1f}",
                          " / ".join(f"{r[0]:.0f}" for r in rs), f"{serial_wall / wall:.2f}x",
                          f"{serial_wall / wall / n:.0%}", f"{bound:.2f}x", f"{cpu:.0f}", f"{others:.2f}",
                          "yes" if same else "[red]NO[/red]")
        console.print(table)
        console.print(f"peak resident memory of the largest worker process (all runs): "
                      f"{resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024:.0f} MiB")
        console.print("best possible: the serial time over max(serial time / N, the longest BRDF): whole BRDFs are "
                      "the tasks, so no engine beats the longest report. Other users' cores: the machine's busy "
                      "CPU minus ours, over the run (the Dask runs: over the cluster's life).")


def dask_run(sources: list[str], out: Path, options, n: int) -> tuple[float, float, float]:
    """Wall time of the batch on a fresh LocalCluster of ``n`` processes × 1 thread; our CPU and
    the other users' cores over the cluster's life (its worker processes are reaped at close)."""
    from distributed import LocalCluster

    with Meter() as m:
        t0 = time.perf_counter()
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
            started = time.perf_counter() - t0
            t0 = time.perf_counter()
            run_batch(sources, out, options, scheduler=cluster.scheduler_address)
            wall = time.perf_counter() - t0
    console.print(f"   dask {n} worker(s): cluster start {started:.1f} s (not counted)")
    return wall, m.cpu, m.others


if __name__ == "__main__":
    main()
