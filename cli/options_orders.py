"""``shrm orders``'s parser (numpy-free; the verb's work is in ``cmd_orders.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import DEFAULT_MAX_F, DEFAULT_MAX_P
from ..analysis.tolerance import DEFAULT_EPS
from .options import add_env_orientation, add_lights_option, add_order_rule, add_rgl_incident, brdf_help, tolerance

__all__ = ["HELP", "add_arguments"]

HELP = "choose the SH orders (F, P) a BRDF needs at a tolerance eps (RH02 §5.1)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``shrm orders``."""
    parser.add_argument("brdf", help=brdf_help())
    parser.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                        help=f"tolerance on uncaptured energy (default {DEFAULT_EPS:g})")
    parser.add_argument("--max-F", type=int, default=DEFAULT_MAX_F, help=f"cap on F (default {DEFAULT_MAX_F})")
    parser.add_argument("--max-P", type=int, default=DEFAULT_MAX_P, help=f"cap on P (default {DEFAULT_MAX_P})")
    parser.add_argument("--env", help="environment (builtin:sky or a map file): also report F_L, F_B and the bound")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of tables")
    add_order_rule(parser)
    add_lights_option(parser)
    add_env_orientation(parser)
    add_rgl_incident(parser)
