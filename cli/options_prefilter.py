"""``shrm prefilter``'s parser (numpy-free; the verb's work is in ``cmd_prefilter.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import DEFAULT_MAX_F, DEFAULT_MAX_P
from ..analysis.tolerance import DEFAULT_EPS
from .options import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_pixel_rule_option,
    add_rgl_incident,
    add_window_option,
    brdf_help,
    tolerance,
)

__all__ = ["HELP", "add_arguments"]

HELP = "prefilter an environment map with a BRDF into a global SHRM file (.shrm.npz)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--env", required=True, help="environment: builtin:sky, builtin:studio, or a map file")
    parser.add_argument("--brdf", required=True, help=brdf_help() + "; scattered measurements go through the "
                        "representation with the smallest held-out error")
    parser.add_argument("--eps", type=tolerance, default=DEFAULT_EPS, help=f"tolerance (default {DEFAULT_EPS:g})")
    parser.add_argument("--size", type=int, help="SHRM rows S (S x 2S lat-long); default: the smallest whose "
                        "bilinear lookup adds at most 1%% of eps to any view band's error (bands rule; 10 F for rh02)")
    parser.add_argument("--max-F", type=int, default=DEFAULT_MAX_F)
    parser.add_argument("--max-P", type=int, default=DEFAULT_MAX_P)
    parser.add_argument("--cube", action="store_true", help="also store the SHRM on a 6 x S x S cube map")
    parser.add_argument("--cube-size", type=int, help="cube face size S (default: rows // 2)")
    add_window_option(parser)
    add_pixel_rule_option(parser)
    add_lights_option(parser)
    add_order_rule(parser)
    parser.add_argument("--json", action="store_true",
                        help="print one JSON object (orders, errors, view bands, meta) instead of tables")
    parser.add_argument("-o", "--output", required=True, help="output path, e.g. sky.shrm.npz")
    add_env_orientation(parser)
    add_rgl_incident(parser)
