"""``shrm view``'s parser (numpy-free; the verb's work is in ``cmd_view.py``)."""

from __future__ import annotations

import argparse

from ..analysis.tolerance import DEFAULT_EPS
from ..brdf_io.names import TONE_MAP_NAMES as TONE_MAPS
from ..render.defaults import DEFAULT_PAGE_BYTES, DEFAULT_VIEW, STILL_RENDERERS, VIEW_MODES
from ..render.defaults import DEFAULT_VIEW_MESH as DEFAULT_MESH
from .options import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_pixel_rule_option,
    add_rgl_incident,
    add_window_option,
    number_in,
    tolerance,
)

__all__ = ["HELP", "add_arguments"]

HELP = "write a self-contained HTML page that renders the SHRM of ENV and BRDF live in the browser (WebGL2)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("brdf", metavar="BRDF", help="BRDF spec or file")
    p.add_argument("--env", nargs="+", default=["builtin:sky"], metavar="ENV",
                   help="environment map spec or file (default builtin:sky); several maps, a folder of maps or a "
                   "glob pattern: the page switches between them without reloading (an environment menu, "
                   "#env_index=K), the BRDF's orders chosen once")
    p.add_argument("--env-rotation", default=None, metavar="AZ,EL[,ROLL]",
                   help="the lighting's starting rotation, degrees, as shrm render --env-rotation (the page's "
                   "#env_azimuth=&env_elevation=&env_roll=; the still image shows it too)")
    p.add_argument("--mesh", default=None,
                   help=f"mesh file or builtin: spec (default {DEFAULT_MESH}); decimated to the page's mesh budget")
    p.add_argument("--eps", type=tolerance, default=DEFAULT_EPS,
                   help=f"SHRM tolerance epsilon (default {DEFAULT_EPS:g})")
    p.add_argument("--size", type=number_in(8, 1024, integer=True), default=None, metavar="S",
                   help="SHRM rows S (S x 2S lat-long) for the prefilter; default: what the error needs "
                   "(shrm prefilter), then lowered to fit the page")
    add_window_option(p)
    add_pixel_rule_option(p)
    add_lights_option(p)
    add_order_rule(p)
    p.add_argument("--mode", choices=VIEW_MODES, default="distant", help="initial render mode (default distant)")
    p.add_argument("--exposure", type=number_in(-30.0, 30.0, unit=" stops"), default=None,
                   help="initial exposure in stops (default: the environment's mean brought to middle grey)")
    p.add_argument("--tone", choices=TONE_MAPS, default="filmic", help="tone mapping (default filmic)")
    p.add_argument("--azimuth", type=number_in(-360.0, 360.0, unit=" degrees"), default=DEFAULT_VIEW["azimuth"],
                   help=f"initial camera azimuth about z from +x, degrees (default {DEFAULT_VIEW['azimuth']:g})")
    p.add_argument("--elevation", type=number_in(-89.0, 89.0, unit=" degrees"), default=DEFAULT_VIEW["elevation"],
                   help=f"initial camera elevation, degrees (default {DEFAULT_VIEW['elevation']:g})")
    p.add_argument("--zoom", type=number_in(0.25, 10.0), default=DEFAULT_VIEW["zoom"], help="initial zoom (default 1)")
    p.add_argument("--no-background", action="store_true", help="start with a black background (the page toggles it)")
    default_mb = DEFAULT_PAGE_BYTES / 2**20
    p.add_argument("--budget-mb", type=number_in(0.25, 1024.0, unit=" MiB"), default=default_mb,
                   help=f"size budget of the page in MiB (default {default_mb:g}); the SHRM maps are reduced to fit")
    p.add_argument("--still", choices=STILL_RENDERERS, default="auto",
                   help="renderer of the still image shown without WebGL2: cpu (CPU reference, sphere), gl (VTK "
                   "offscreen, the mesh), auto (cpu for the sphere, gl for a mesh when available), none")
    p.add_argument("-o", "--output", required=True, help="output .html page")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (each map's SHRM and stated error, the page, the file written; "
                   "data_specs/view_html.md) instead of the text lines")
    add_env_orientation(p)
    add_rgl_incident(p)
