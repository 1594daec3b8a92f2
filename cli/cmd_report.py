"""``shrm report``: per-BRDF accuracy reports and a sortable summary over a BRDF library.

Exit status: 0 when every report was made, 1 when some BRDFs failed (each failure is in
``summary.csv`` / ``index.html`` with its error, and has a ``report.json`` with
``status: failed``), 2 for bad usage (unknown options, bad values, unreachable Dask
scheduler), 128 + the signal when stopped by one: 130 for SIGINT (Ctrl-C), 143 for SIGTERM
(the worker processes are stopped, the summary lists the reports written so far, and one
line says how many).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..analysis.orders import DEFAULT_MAX_F
from ..analysis.tolerance import DEFAULT_EPS
from ..brdf_io.errors import BadInputError
from ..brdf_io.specs import brdf_sources
from ..render.mesh import load_mesh
from .common import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_rgl_incident,
    add_window_option,
    brdf_help,
    print_json,
    rgl_brdf_arg,
    stderr,
    stdout,
    tolerance,
)
from .report.batch import BRDF_SUFFIXES, BatchInterrupted, run_batch
from .report.options import load_report_env, profile

HELP = "accuracy reports (orders, scene errors, fits, speed vs error, preview) for BRDFs, with a summary"


def _csv_list(text: str) -> tuple[str, ...]:
    items = tuple(t.strip() for t in text.split(",") if t.strip())
    if not items:
        raise argparse.ArgumentTypeError("expected a comma-separated list")
    return items


def _tolerances(text: str) -> tuple[float, ...]:
    return tuple(tolerance(t) for t in _csv_list(text))


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text}")
    return value


def _int_in(low: int, high: int, why: str):
    """An argparse type: an integer in [low, high]; ``why`` says what the upper bound protects."""
    def parse(text: str) -> int:
        value = _positive_int(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in {low}..{high:,} ({why}), got {text}")
        return value

    return parse


#: Upper bounds of the report's size options (issue 30: ``--fit-samples 1e9`` asked for 22-24 GiB per
#: BRDF, ``--lobes 1000`` silently dropped the fit): the fits support 1-4 Lafortune lobes; 2^22 fit
#: samples (~0.4 GiB) exceed a MERL table's 1.46 million cells; 10^6 measured-error pairs are hours of
#: brute force per environment.
MAX_LOBES, MAX_FIT_SAMPLES, MAX_PAIRS, MAX_WORKERS = 4, 2**22, 10**6, 256


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("brdfs", nargs="+", metavar="BRDF",
                   help=brdf_help(many=True))
    p.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                   help=f"main tolerance (scene orders, preview; default {DEFAULT_EPS:g})")
    p.add_argument("--tolerances", type=_tolerances, default=None,
                   help="tolerances of the order table and speed rows (default 0.1,0.03,0.01)")
    p.add_argument("--env", nargs="+", default=None, metavar="ENV",
                   help="environment specs or files (default builtin:sky)")
    p.add_argument("--env-height", type=_positive_int, default=None,
                   help="environment rows used by the report (default 64, quick 32)")
    p.add_argument("--models", type=_csv_list, default=None,
                   help="models to fit, comma-separated (default lafortune,cook-torrance)")
    p.add_argument("--lobes", type=_int_in(1, MAX_LOBES, "the Lafortune fits support 1-4 lobes"), default=1,
                   help="Lafortune lobes, 1-4 (default 1)")
    p.add_argument("--mesh", default=None, help="also preview this mesh (file or builtin:torus-knot ...)")
    p.add_argument("--preview", choices=("auto", "gl", "cpu", "none"), default="auto",
                   help="preview renderer: OpenGL if available else CPU (auto), or force one (default auto)")
    p.add_argument("--pairs", type=_int_in(1, MAX_PAIRS, "each pair is a brute-force sum over the map"),
                   default=None, help="(R, V) pairs for the measured error (at most 1,000,000)")
    p.add_argument("--seed", type=int, default=0, help="seed of every random choice (default 0)")
    p.add_argument("--quick", action="store_true",
                   help="quick profile: 32-row environments, fewer pairs, small fits (what tests and demo use)")
    p.add_argument("--out", default="shrm-report", help="output folder (default ./shrm-report)")
    p.add_argument("--workers", type=_int_in(1, MAX_WORKERS, "each worker is a process with its own copy of the "
                                             "analysis"), default=1,
                   help="parallel worker processes, each with its share of the cores (default 1, at most 256)")
    p.add_argument("--dask-scheduler", default=None, metavar="ADDRESS",
                   help="run the per-BRDF tasks on this Dask distributed scheduler (tcp://host:8786); "
                        "start workers with --nthreads 1 --nworkers N (see README)")
    p.add_argument("--max-F", type=_positive_int, default=None,
                   help=f"cap on F (default {DEFAULT_MAX_F}, as shrm orders: the same orders for the same file and "
                   "eps; quick 96)")
    p.add_argument("--fit-samples", type=_int_in(1, MAX_FIT_SAMPLES, "about 0.4 GiB of samples"), default=None,
                   help="fit samples (default 16384, quick 4096; at most 4,194,304)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (the summary rows, as summary.csv holds them; "
                   "data_specs/report_json.md)"
                   " instead of the text lines; no progress bar")
    p.add_argument("--no-plots", action="store_true",
                   help="leave out the matplotlib plots (every number stays in report.json and the tables): "
                   "about 3x faster quick reports, for a census of a large library")
    p.add_argument("--explorer-plots", action=argparse.BooleanOptionalAction, default=None,
                   help="draw the BRDF views' plots (fit slices, BRDF Explorer's slice, polar and albedo plots; "
                   "~1 s CPU a report): on by default, off with --quick")
    add_window_option(p)
    add_lights_option(p)
    add_order_rule(p)
    add_env_orientation(p)
    add_rgl_incident(p)
    p.epilog = ("exit status: 0 all reports made, 1 some BRDFs failed (see summary), 2 bad usage, 130/143 stopped by "
                "SIGINT/SIGTERM (the reports written so far are kept and listed; rerun to make the rest). A worker "
                "process that dies is replaced and its BRDF retried once.")


def options_from_args(args: argparse.Namespace):
    """ReportOptions from the parsed arguments (the quick profile when ``--quick``)."""

    changes = {"eps": args.eps, "lobes": args.lobes, "preview": args.preview, "seed": args.seed, "mesh": args.mesh,
               "env_up": args.env_up, "env_flip": args.env_flip, "env_azimuth": args.env_azimuth,
               "env_layer": args.env_layer, "env_part": args.env_part,
               "window": args.window, "lights": args.lights, "criterion": args.criterion,
               "max_view_deg": args.max_view_deg, "plots": not args.no_plots}
    for key, value in (("tolerances", args.tolerances), ("envs", tuple(args.env) if args.env else None),
                       ("env_height", args.env_height), ("models", args.models), ("n_pairs", args.pairs),
                       ("max_F", args.max_F), ("fit_samples", args.fit_samples),
                       ("explorer_plots", args.explorer_plots)):
        if value is not None:
            changes[key] = value
    return profile("quick" if args.quick else "full", **changes)


def run_with_progress(sources: list[str], out: str, options, *, workers: int = 1, scheduler: str | None = None,
                      show: bool = True):
    """Run the batch with a rich progress bar on stderr; returns the BatchResult."""

    columns = (TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("{task.fields[stage]}"))
    with Progress(*columns, console=stderr, transient=False, disable=not show) as bar:
        task = bar.add_task("BRDFs", total=len(sources), stage="")

        def progress(event: str, name: str, detail: str) -> None:
            if event == "stage":
                bar.update(task, stage=f"{name}: {detail}")
            elif event == "done":
                bar.advance(task)
                bar.update(task, stage=f"{name}: {detail}")
                if detail != "ok":
                    bar.console.print(f"failed: {name}", markup=False, soft_wrap=True)
            elif event == "retry":
                bar.console.print(f"worker died on {name} ({detail}); retried", markup=False, soft_wrap=True,
                                  highlight=False)

        return run_batch(sources, out, options, workers=workers, scheduler=scheduler, progress=progress)


def say(text: str) -> None:
    """One plain line on stdout (no wrapping, no markup)."""
    stdout.print(text, soft_wrap=True, markup=False, highlight=False)


def run(args: argparse.Namespace) -> int:
    options = options_from_args(args)
    _check_shared_inputs(options)
    _check_brdf_files(args.brdfs)
    # a whole multi-BRDF file (the 61 CURET samples, a CSV's wavelengths) is one report per member
    sources = [rgl_brdf_arg(member, args) for source in args.brdfs for member in brdf_sources(source)]
    t0 = time.perf_counter()
    try:
        with _signals_stop_the_batch():
            result = run_with_progress(sources, args.out, options, workers=args.workers,
                                       scheduler=args.dask_scheduler, show=not (args.no_progress or args.json))
    except BatchInterrupted as stop:
        stderr.print(f"shrm report: interrupted ({stop.signal_name}): {stop.written} of {stop.total} reports written "
                     f"to {stop.out_dir or args.out}; rerun to make the rest", soft_wrap=True, markup=False,
                     highlight=False)
        return stop.exit_status
    if args.json:
        print_json({"out_dir": str(result.out_dir), "summary_csv": str(result.out_dir / "summary.csv"),
                    "index_html": str(result.out_dir / "index.html"), "engine": result.engine,
                    "n_reports": len(result.rows), "n_failed": result.n_failed,
                    "seconds": time.perf_counter() - t0, "rows": result.rows})
        return 0 if result.ok else 1
    for row in result.rows:
        where = result.out_dir / row["name"] / "report.html"
        if row["status"] == "ok":
            say(f"{row['name']}: {where}")
        else:
            say(f"{row['name']}: FAILED: {row.get('error')}")
    say(f"summary: {result.out_dir / 'index.html'} and {result.out_dir / 'summary.csv'}")
    say(f"{len(result.rows) - result.n_failed} of {len(result.rows)} reports made in "
                 f"{time.perf_counter() - t0:.1f} s ({result.engine})")
    return 0 if result.ok else 1


@contextlib.contextmanager
def _signals_stop_the_batch() -> Iterator[None]:
    """While the batch runs, SIGINT and SIGTERM raise :class:`BatchInterrupted` (the batch then
    stops its workers and keeps what it wrote); a second signal is ignored while it does so.
    The handlers before are restored afterwards. Only in the main thread (where Python runs
    signal handlers)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    signals = (signal.SIGINT, signal.SIGTERM)

    def stop(signum: int, frame: object) -> None:
        for s in signals:
            signal.signal(s, signal.SIG_IGN)
        raise BatchInterrupted(signum)

    before = {s: signal.signal(s, stop) for s in signals}
    try:
        yield
    finally:
        for s, handler in before.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)


def _check_brdf_files(sources: list[str]) -> None:
    """A BRDF named by a file path that does not exist is a usage error (exit 2, nothing
    written); a file that exists but cannot be read is one failed report in the batch."""
    for source in sources:
        base, sep, _ = source.rpartition("#")
        path = Path(base if sep and Path(base).suffix.lower() in BRDF_SUFFIXES else source)
        if path.suffix.lower() in BRDF_SUFFIXES and not path.exists():
            raise BadInputError(path, "no such BRDF file")


def _check_shared_inputs(options) -> None:
    """Inputs every BRDF of the batch uses (environments, mesh) are checked once, up front:
    a bad one is a usage error (exit 2), not one failure per BRDF."""

    for spec in options.envs:
        load_report_env(spec, options)
    if options.mesh:
        load_mesh(options.mesh)
