"""``shrm bench``'s parser (numpy-free; the verb's work is in ``cmd_bench.py``)."""

from __future__ import annotations

import argparse

__all__ = ["HELP", "BENCHMARKS", "add_arguments"]

HELP = ("run the speed-against-error benchmarks (prefilter vs the best angular methods, with targets; fits; "
        "render fps) and print tables")


BENCHMARKS = {
    "prefilter": ("prefilter_speed.py", "prefiltering vs lobe-truncated sum and split sum, errors beside times, "
                  "targets"),
    "fit": ("fit_speed.py", "fit times and errors"),
    "render": ("render_speed.py", "SHRM shader frames per second"),
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true", help="the benchmarks' quick variants (about a minute each)")
    p.add_argument("--only", choices=tuple(BENCHMARKS), nargs="+", default=None, help="run only these benchmarks")
    p.add_argument("--benchmarks", default=None, metavar="DIR",
                   help="folder of the benchmark scripts (default: benchmarks/ of the source checkout)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (each benchmark's status, seconds, tables and text; "
                   "data_specs/benchmarks_json.md) on stdout; the benchmarks' own output goes to stderr")
