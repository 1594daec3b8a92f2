"""``shrm census``'s parser (numpy-free; the verb's work is in ``cmd_census.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import (
    CENSUS_F,
    CENSUS_MAX_F_LIMIT,
    CENSUS_MAX_P_LIMIT,
    CENSUS_MAX_WORKERS,
    CENSUS_P,
    CENSUS_THRESHOLD,
    DEFAULT_FOLDS,
    DEFAULT_MAX_F,
    DEFAULT_MAX_P,
)
from ..analysis.defaults import REPRESENTATION_CANDIDATES as CANDIDATES
from ..analysis.tolerance import DEFAULT_EPS
from .options import add_order_rule, add_rgl_incident, brdf_help, number_in, tolerance

__all__ = ["HELP", "CSV_NAME", "JSON_NAME", "PLOT_NAME", "add_arguments"]

HELP = "census of a BRDF library: accuracy at (F, P) per material (RH02 Fig. 8), orders needed, fit error, reasons"


#: Files written into ``--out``.
CSV_NAME, JSON_NAME, PLOT_NAME = "census.csv", "census.json", "census.png"


def _candidates(text: str) -> tuple[str, ...]:
    items = tuple(t.strip() for t in text.split(",") if t.strip())
    unknown = [t for t in items if t not in CANDIDATES]
    if not items or unknown:
        raise argparse.ArgumentTypeError(f"expected a comma-separated list of {', '.join(CANDIDATES)}, got {text!r}")
    return items


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("brdfs", nargs="+", metavar="BRDF",
                        help=brdf_help(many=True) + "; a folder is every BRDF file in it")
    parser.add_argument("--out", default="shrm-census", help="output folder (default ./shrm-census)")
    parser.add_argument("--F", type=number_in(0, DEFAULT_MAX_F, integer=True), default=CENSUS_F, dest="F",
                        help=f"lighting order of the accuracy table (default {CENSUS_F}, RH02 Fig. 8)")
    parser.add_argument("--P", type=number_in(0, DEFAULT_MAX_P, integer=True), default=CENSUS_P, dest="P",
                        help=f"largest view order of the accuracy table, P = 0..this (default {CENSUS_P})")
    parser.add_argument("--threshold", type=number_in(0.0, 1.0, lo_open=True, hi_open=True),
                        default=CENSUS_THRESHOLD,
                        help=f"accuracy mark counted and explained (default {CENSUS_THRESHOLD:g}, RH02's 90 %%)")
    parser.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                        help=f"tolerance of the orders each material needs (default {DEFAULT_EPS:g})")
    parser.add_argument("--max-F", type=number_in(1, CENSUS_MAX_F_LIMIT, integer=True), default=DEFAULT_MAX_F,
                        help=f"cap on F needed (default {DEFAULT_MAX_F})")
    parser.add_argument("--max-P", type=number_in(0, CENSUS_MAX_P_LIMIT, integer=True), default=DEFAULT_MAX_P,
                        help=f"cap on P needed (default {DEFAULT_MAX_P})")
    add_order_rule(parser)
    parser.add_argument("--candidates", type=_candidates, default=CANDIDATES,
                        help=f"representations tried for scattered data (default {','.join(CANDIDATES)})")
    parser.add_argument("--folds", type=number_in(2, 100, integer=True), default=DEFAULT_FOLDS,
                        help=f"cross-validation folds of the representation choice (default {DEFAULT_FOLDS})")
    parser.add_argument("--seed", type=int, default=0, help="seed of the folds and the fits (default 0)")
    parser.add_argument("--max-theta", type=number_in(0.0, 90.0, lo_open=True, unit=" degrees"), default=80.0,
                        help="measurements with θ_i or θ_o above this are not fitted (default 80)")
    parser.add_argument("--workers", type=number_in(1, CENSUS_MAX_WORKERS, integer=True), default=1,
                        help="processes computing the rows (default 1; the numbers do not depend on it)")
    parser.add_argument("--no-plot", action="store_true", help=f"do not draw {PLOT_NAME}")
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object (census.json's, with the files written) instead of the table")
    add_rgl_incident(parser)
