"""``shrm compare``'s parser (numpy-free; the verb's work is in ``cmd_compare.py``)."""

from __future__ import annotations

import argparse
import types

from ..analysis.defaults import COMPARE_DEFAULTS, GAUSSIAN_ELEVATIONS_LIMITS, RSIBR_REFERENCE_HEIGHT_LIMITS
from ..analysis.tolerance import DEFAULT_EPS
from .options import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_rgl_incident,
    add_window_option,
    brdf_help,
    number_in,
    tolerance,
)

__all__ = ["HELP", "CLI_RSIBR_REFERENCE_HEIGHT", "add_arguments"]

HELP = "compare the SHRM with Kautz-McCool, RSIBR (12 maps) and Gaussian-lobe representations"


#: ``CompareOptions()``'s defaults (``analysis.defaults.COMPARE_DEFAULTS``)
_DEFAULTS = types.SimpleNamespace(**COMPARE_DEFAULTS)


#: The CLI's RSIBR reference maps are smaller than the library's (it is the slowest row).
CLI_RSIBR_REFERENCE_HEIGHT = 16


CLI_CABRAL_REFERENCE_HEIGHT = CLI_RSIBR_REFERENCE_HEIGHT  # earlier name


class _DeprecatedOption(argparse.Action):
    """An earlier option name: store the value under the new ``dest`` and remember a one-line note."""

    def __init__(self, *args, new: str, **kwargs) -> None:
        self.new = new
        super().__init__(*args, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        setattr(namespace, self.dest, values)
        notes = getattr(namespace, "deprecation_notes", None) or []
        notes.append(f"{option_string} is deprecated: use {self.new}")
        namespace.deprecation_notes = notes


def add_arguments(parser: argparse.ArgumentParser) -> None:
    d = _DEFAULTS
    parser.add_argument("brdf", metavar="BRDF", help=brdf_help())
    parser.add_argument("--env", required=True, help="environment map spec or file")
    add_env_orientation(parser)
    add_rgl_incident(parser)
    parser.add_argument("--env-height", type=number_in(8, 512, integer=True), default=d.env_height,
                        help=f"resample the environment to this many rows (default {d.env_height}; the reference "
                        "is O(W S_L^2))")
    parser.add_argument("--mesh", help="mesh for the image strip (default: a sphere); brute-force ray casting, "
                        "keep it small")
    parser.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                        help=f"SHRM tolerance (default {DEFAULT_EPS:g})")
    add_window_option(parser)
    add_lights_option(parser)
    add_order_rule(parser)
    parser.add_argument("--pairs", type=number_in(10, 10**6, integer=True), default=d.n_pairs,
                        help=f"sampled (R, V) pairs (default {d.n_pairs})")
    parser.add_argument("--max-view", type=number_in(1.0, 90.0, hi_open=True), default=d.sample_max_view_deg,
                        help=f"largest view angle from the normal, degrees (default {d.sample_max_view_deg:g})")
    parser.add_argument("--lower-p", type=number_in(0, 64, integer=True), help="P of the lower-order SHRM "
                        "(default P-2)")
    parser.add_argument("--lobes", default=",".join(map(str, d.lobes)),
                        help=f"Gaussian-lobe counts K, comma separated (default {','.join(map(str, d.lobes))}; "
                        "'none' skips)")
    elev, ref = (types.SimpleNamespace(default=default, lo=lo, hi=hi) for default, lo, hi in
                 (GAUSSIAN_ELEVATIONS_LIMITS, RSIBR_REFERENCE_HEIGHT_LIMITS))
    parser.add_argument("--elevations", type=number_in(elev.lo, elev.hi, integer=True), default=d.elevations,
                        help=f"view elevations of the Gaussian-lobe fits, {elev.lo}..{elev.hi} "
                        f"(default {d.elevations})")
    parser.add_argument("--rsibr-reference-height", type=number_in(0, ref.hi, integer=True),
                        default=CLI_RSIBR_REFERENCE_HEIGHT,
                        help=f"rows of the RSIBR maps by the angular reference, {ref.lo}..{ref.hi} "
                        f"(default {CLI_RSIBR_REFERENCE_HEIGHT}; 0 skips)")
    parser.add_argument("--cabral-reference-height", dest="rsibr_reference_height", action=_DeprecatedOption,
                        new="--rsibr-reference-height", type=number_in(0, ref.hi, integer=True),
                        help=argparse.SUPPRESS)
    parser.add_argument("--seed", type=int, default=d.seed)
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    parser.add_argument("--strip", help="write the image strip to this PNG")
    parser.add_argument("--strip-size", type=number_in(16, 1024, integer=True), default=64,
                        help="strip panel size in pixels (default 64)")
    parser.add_argument("--markdown", help="write the table as Markdown to this file")
