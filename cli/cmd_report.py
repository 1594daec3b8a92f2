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

from ..analysis.order_rule import resolve_rule
from ..brdf_io.errors import BadInputError
from ..brdf_io.specs import brdf_sources
from ..render.mesh import load_mesh
from .common import (
    orientation_notes,
    print_json,
    progress_shown,
    rgl_brdf_arg,
    stderr,
    stdout,
)
from .report.batch import BRDF_SUFFIXES, BatchInterrupted, run_batch
from .report.options import load_report_env, profile


def options_from_args(args: argparse.Namespace):
    """ReportOptions from the parsed arguments (the quick profile when ``--quick``)."""

    changes = {"lobes": args.lobes, "preview": args.preview, "seed": args.seed, "mesh": args.mesh,
               "env_up": args.env_up, "env_flip": args.env_flip, "env_azimuth": args.env_azimuth,
               "env_layer": args.env_layer, "env_part": args.env_part,
               "window": args.window, "lights": args.lights, "plots": not args.no_plots}
    for key, value in (("tolerances", args.tolerances), ("envs", tuple(args.env) if args.env else None),
                       ("env_height", args.env_height), ("models", args.models), ("n_pairs", args.pairs),
                       ("fit_samples", args.fit_samples), ("explorer_plots", args.explorer_plots)):
        if value is not None:
            changes[key] = value
    options = profile("quick" if args.quick else "full", **changes)
    # one order rule: the profile's (quick caps F at 96) with the rule options given
    rule = resolve_rule(options.rule, override=True, eps=args.eps, max_F=args.max_F, criterion=args.criterion,
                        max_view_deg=args.max_view_deg)
    return options.with_changes(**rule.to_json())


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
    _check_shared_inputs(options, show=not args.json)
    _check_brdf_files(args.brdfs)
    # a whole multi-BRDF file (the 61 CURET samples, a CSV's wavelengths) is one report per member
    sources = [rgl_brdf_arg(member, args) for source in args.brdfs for member in brdf_sources(source)]
    t0 = time.perf_counter()
    try:
        with _signals_stop_the_batch():
            result = run_with_progress(sources, args.out, options, workers=args.workers,
                                       scheduler=args.dask_scheduler, show=progress_shown(args))
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


def _check_shared_inputs(options, show: bool = True) -> None:
    """Inputs every BRDF of the batch uses (environments, mesh) are checked once, up front:
    a bad one is a usage error (exit 2), not one failure per BRDF. A lat-long map file read with
    the default orientation says so (``orientation_notes``: one line), as every other verb does."""
    orientation = argparse.Namespace(env_up=options.env_up, env_flip=options.env_flip, env_azimuth=options.env_azimuth)
    read = [(env.name, env.source) for env in map(lambda spec: load_report_env(spec, options), options.envs)]
    note = orientation_notes([argparse.Namespace(name=name, source=source) for name, source in read], orientation)
    if note and show:
        say(note)  # one line for every map file read y-up
    if options.mesh:
        load_mesh(options.mesh)
