"""``shrm report``'s parser (numpy-free; the verb's work is in ``cmd_report.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import DEFAULT_MAX_F
from ..analysis.tolerance import DEFAULT_EPS
from .options import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_rgl_incident,
    add_window_option,
    brdf_help,
    tolerance,
)

__all__ = ["HELP", "MAX_LOBES", "MAX_FIT_SAMPLES", "MAX_PAIRS", "MAX_WORKERS", "add_arguments"]

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
