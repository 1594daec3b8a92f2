"""The command line's shared options and argument types, numpy-free: every verb's parser is built
from this module and ``options_<verb>.py`` (issue 26: ``shrm VERB --help`` and usage errors start
without the numerical stack; the verbs' work is in ``cmd_<verb>.py``).

The defaults, choices and limits shown come from the light modules beside the registries:
:mod:`shrmkit.brdf_io.names`, :mod:`shrmkit.analysis.defaults`, :mod:`shrmkit.render.defaults`.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from ..analysis.defaults import (
    CRITERIA,
    DEFAULT_CRITERION,
    DEFAULT_LIGHTS,
    DEFAULT_MAX_VIEW_DEG,
    DEFAULT_WINDOW,
    LIGHT_CONTRAST,
    MAX_LIGHT_RADIUS_DEG,
    MAX_LIGHTS,
    WINDOW_BUDGET_EPS,
    WINDOW_THRESHOLD,
    WINDOWS,
    check_lights,
)
from ..analysis.tolerance import check_eps
from ..brdf_io.errors import BadInputError
from ..brdf_io.names import BRDF_FILE_SUFFIXES, BRDF_MEMBER_SUFFIXES, BRDF_SELECTOR_SUFFIXES, RGL_INCIDENT_NAMES

__all__ = [
    "number_in",
    "positive_float",
    "tolerance",
    "brdf_help",
    "add_env_orientation",
    "add_window_option",
    "add_pixel_rule_option",
    "add_lights_option",
    "add_order_rule",
    "add_rgl_incident",
]


def number_in(
    lo: float, hi: float, *, integer: bool = False, lo_open: bool = False, hi_open: bool = False, unit: str = ""
) -> Callable[[str], float]:
    """argparse type factory: a finite number (or integer) in [lo, hi]; ``lo_open``/``hi_open``
    exclude the ends; ``unit`` follows the range in the message of a value outside it."""
    kind = "an integer" if integer else "a number"

    def parse(text: str) -> float:
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {kind}: {text!r}") from None
        if not math.isfinite(value) or value > hi or value < lo or (lo_open and value == lo) or (
                hi_open and value == hi):
            left, right = "(" if lo_open else "[", ")" if hi_open else "]"
            raise argparse.ArgumentTypeError(f"must be in {left}{lo:g}, {hi:g}{right}{unit}, got {text}")
        return value

    return parse


def tolerance(text: str) -> float:
    """argparse type for ε: the number checked by the one validator,
    :func:`shrmkit.analysis.tolerance.check_eps` (a number in (0, 1))."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    try:
        return check_eps(value)
    except BadInputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


positive_float = number_in(0.0, math.inf, lo_open=True)
"""argparse type: a finite number > 0."""


def brdf_help(*, many: bool = False) -> str:
    """Help text of a BRDF argument, its file suffixes those of the file-type registry
    (``brdf_io.specs.BRDF_FILE_TYPES``, through :mod:`shrmkit.brdf_io.names`); ``many``: the
    argument takes several BRDFs and a whole multi-BRDF file expands to every member."""
    suffixes = ", ".join(BRDF_FILE_SUFFIXES)
    picks = "/".join(BRDF_SELECTOR_SUFFIXES)
    if many:
        whole = "/".join(BRDF_MEMBER_SUFFIXES)
        return (f"BRDF files ({suffixes}; a whole {whole} file is every member; FILE#... picks one part of a "
                f"{picks} file) or specs (e.g. microfacet:sigma=0.2)")
    return f"BRDF spec (e.g. microfacet:sigma=0.2) or file ({suffixes}; FILE#... picks one part of a {picks} file)"


def add_env_orientation(parser: argparse.ArgumentParser) -> None:
    """``--env-up``, ``--env-flip``, ``--env-azimuth``: how a lat-long *file* is oriented
    (data_specs/environment_maps.md; ``load_env`` reads lat-long files y-up by default);
    ``--env-layer``, ``--env-part``: which layer/part of an OpenEXR file holds the map (§2.1)."""
    group = parser.add_argument_group(
        "environment orientation (--env-up/--env-flip: map files only, refused for builtin: maps; "
        "--env-azimuth: any map)")
    group.add_argument("--env-up", choices=("z", "y"), default=None,
                       help="lat-long file convention: y (default: y-up, as Blender, three.js and Mitsuba 3 place "
                       "panoramas) or z (top row = zenith, the file read as stored)")
    group.add_argument("--env-flip", action="store_true", help="reverse the rows of a lat-long file first")
    group.add_argument("--env-azimuth", type=float, default=0.0, metavar="DEG",
                       help="rotate the map about the up axis by this many degrees")
    group.add_argument("--env-layer", default=None, metavar="NAME",
                       help="OpenEXR files: the layer (channel prefix, e.g. 'diffuse' for diffuse.R/G/B) to read; "
                       "default: the plain R, G, B, else the only layer with colour")
    group.add_argument("--env-part", default=None, metavar="NAME|INDEX",
                       help="multi-part OpenEXR files: the part to read, by name or index; default: the only part "
                       "with colour channels")


def add_window_option(parser: argparse.ArgumentParser) -> None:
    """``--window none|lanczos|auto``: the prefilter's window against Gibbs ringing, for every
    verb that prefilters (the names are ``analysis.window.WINDOWS``; argparse exits 2 on others)."""
    parser.add_argument(
        "--window", choices=WINDOWS, default=DEFAULT_WINDOW,
        help=f"damping of the SHRM's Gibbs ringing (negative lobes): auto (default) applies Lanczos sigma-factors "
        f"just strong enough when the undershoot passes {100 * WINDOW_THRESHOLD:g}%% of the peak, raising F_B "
        "until the windowed field meets eps in every view band (the rh02 rule: within "
        f"{WINDOW_BUDGET_EPS:g} eps of added error); lanczos: full Lanczos; none: the bare truncation. What is left "
        "is clamped to 0 at the output",
    )


def add_pixel_rule_option(parser: argparse.ArgumentParser) -> None:
    """``--pixel-rule on|off``: the bands rule's per-direction check (``analysis.pixels``), for the verbs
    that prefilter one SHRM (``prefilter``, ``render``, ``view``)."""
    parser.add_argument(
        "--pixel-rule", choices=("on", "off"), default="on",
        help="on (default): raise F_B until 90%% of the sampled directions have a relative error within sqrt(eps) "
        "(the band statements bound an average that dark regions of a high dynamic range map miss); off: the "
        "energy rule's F_B only (faster, rings in dark regions)",
    )


def _lights_arg(text: str) -> str | int:
    """argparse type of ``--lights`` (``check_lights``)."""
    try:
        return check_lights(text)
    except BadInputError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def add_lights_option(parser: argparse.ArgumentParser) -> None:
    """``--lights auto|none|N``: bright compact regions taken out of the map as exact lights, for
    every verb that prefilters (``analysis.lights``; data_specs/lights.md)."""
    parser.add_argument(
        "--lights", type=_lights_arg, default=DEFAULT_LIGHTS, metavar="auto|none|N",
        help=f"take the sun, lamps and windows out of the map as lights shaded exactly (auto, default: regions "
        f"{LIGHT_CONTRAST:g}x brighter than the map's median within a {MAX_LIGHT_RADIUS_DEG:g} degree cap, at most "
        f"{MAX_LIGHTS}); N: at most N; none: keep them in the map (they ring)",
    )


def add_rgl_incident(parser: argparse.ArgumentParser) -> None:
    """``--rgl-incident camera|light``: which direction plays an RGL ``.bsdf`` file's incident
    direction ω_i, for every verb that loads BRDFs (data_specs/rgl_bsdf.md; applied by
    ``cli.common.rgl_brdf_arg``)."""
    parser.add_argument(
        "--rgl-incident", choices=RGL_INCIDENT_NAMES, default="camera",
        help="RGL .bsdf files: the direction that plays the file's incident direction; camera (default) renders "
        "as Mitsuba 3 does, light takes the direction the sample was lit from (the data are not reciprocal, "
        "so the two differ). A file written FILE.bsdf#camera or FILE.bsdf#light keeps its own choice")


def add_order_rule(parser: argparse.ArgumentParser) -> None:
    """``--criterion bands|rh02`` and ``--max-view-angle DEG``: the order rule of every verb that
    chooses orders (``analysis.view_bands``; README, accuracy)."""
    parser.add_argument(
        "--criterion", choices=CRITERIA, default=DEFAULT_CRITERION,
        help="order rule: bands (default) meets eps in every view band up to --max-view-angle; rh02 is "
        "RH02's energy over all views with F_B = min(F_rho, F_L) (reproduces RH02 Table 5)")
    parser.add_argument(
        "--max-view-angle", type=number_in(0.0, 90.0, lo_open=True, unit=" degrees"), default=DEFAULT_MAX_VIEW_DEG,
        metavar="DEG", dest="max_view_deg",
        help=f"view limit of the bands rule, degrees between view and normal (default {DEFAULT_MAX_VIEW_DEG:g}); "
        "beyond it errors are stated, not promised")
