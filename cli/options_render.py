"""``shrm render``'s parser (numpy-free; the verb's work is in ``cmd_render.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import GAUSSIAN_ELEVATIONS_LIMITS, GAUSSIAN_LOBES_LIMITS
from ..analysis.tolerance import DEFAULT_EPS
from ..render.defaults import (
    BACKGROUNDS,
    DEFAULT_MODE,
    ERROR_IMAGE_HELP,
    LOBE_OPTION_MODES,
    RENDER_MODE_HELP,
    SELF_SHADOW_MODES,
)
from .options import (
    add_env_orientation,
    add_lights_option,
    add_order_rule,
    add_pixel_rule_option,
    add_rgl_incident,
    add_window_option,
)

__all__ = ["HELP", "LOBE_OPTION_MODES", "add_arguments"]

HELP = "render a mesh shaded by the SHRM of ENV and BRDF to PNG (and linear EXR), offscreen"


class _StoreGiven(argparse.Action):
    """Store the value and record that the option was given (``args.<dest>_given``), so that
    an option that does not apply to the chosen mode is refused rather than ignored."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        setattr(namespace, self.dest, values)
        setattr(namespace, f"{self.dest}_given", True)


def _mode_help() -> str:
    listed = "; ".join(f"{name}: {text}" for name, text in RENDER_MODE_HELP.items())
    return f"{listed} (default {DEFAULT_MODE})"


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``shrm render``."""
    p.add_argument(
        "mesh", metavar="MESH", help="mesh file (obj, ply, stl, off, glb, gltf) or builtin:sphere|torus|torus-knot"
    )
    p.add_argument("--env", nargs="+", default=["builtin:sky"], metavar="ENV",
                   help="environment map spec or file (default builtin:sky); several maps, a folder of maps or a "
                   "glob pattern render one frame per map to OUT_0000.png ... and OUT.gif (the BRDF's orders chosen "
                   "once, each map prefiltered, its cost and stated error printed)")
    p.add_argument("--brdf", default="microfacet:sigma=0.2", help="BRDF spec or file (default microfacet:sigma=0.2)")
    p.add_argument("--eps", type=float, default=DEFAULT_EPS, help=f"SHRM tolerance epsilon (default {DEFAULT_EPS:g})")
    p.add_argument("--mode", choices=tuple(RENDER_MODE_HELP), default=DEFAULT_MODE, help=_mode_help())
    (lobes, *lobes_range), (elevations, *elevations_range) = GAUSSIAN_LOBES_LIMITS, GAUSSIAN_ELEVATIONS_LIMITS
    shadow = " or ".join(SELF_SHADOW_MODES)
    lobe_modes = " or ".join(LOBE_OPTION_MODES)
    # _StoreGiven: given with another mode they are refused, not silently ignored
    p.add_argument("--lobes", type=int, default=lobes, action=_StoreGiven,
                   help=f"{lobe_modes} only: lobes per elevation K, {lobes_range[0]}..{lobes_range[1]} "
                   f"(default {lobes})")
    p.add_argument("--elevations", type=int, default=elevations, action=_StoreGiven,
                   help=f"{lobe_modes} only: fitted view elevations, {elevations_range[0]}..{elevations_range[1]} "
                   f"(default {elevations})")
    p.add_argument("--self-shadow", action="store_true",
                   help=f"{shadow}: per-vertex self-shadowing by ray casting (Green et al. 2007 eq. 7)")
    add_window_option(p)
    add_pixel_rule_option(p)
    add_lights_option(p)
    add_order_rule(p)
    p.add_argument("--size", type=int, default=512, help="image width and height in pixels (default 512)")
    p.add_argument("--camera", choices=("perspective", "ortho"), default="perspective")
    p.add_argument("--view", default="1,0,0", help="direction from the object toward the camera, z-up frame")
    p.add_argument("--up", default="0,0,1", help="image up direction, z-up frame (default 0,0,1)")
    p.add_argument("--exposure", type=float, default=None,
                   help="exposure in stops for the PNG (default: the environment's mean luminance brought to "
                   "middle grey, as shrm view does; printed)")
    p.add_argument("--tone", choices=("filmic", "srgb"), default="filmic", help="PNG tone mapping (default filmic)")
    p.add_argument("--background", choices=BACKGROUNDS, default="env",
                   help="environment seen behind the object, black, or transparent PNG (default env)")
    p.add_argument("--turntable", type=int, default=0, metavar="N",
                   help="render N frames around the z axis to OUT_0000.png ... and OUT.gif")
    p.add_argument("--env-rotation", default=None, metavar="AZ,EL[,ROLL]",
                   help="rotate the environment at view time, degrees: AZ about the up axis (the sense of "
                   "--env-azimuth), then EL raises the horizon point at azimuth 0, ROLL about it first; "
                   "nothing is prefiltered again (README, 'Lighting that moves')")
    p.add_argument("--light-turntable", type=int, default=0, metavar="N",
                   help="render N frames with the environment turning about the up axis (360/N degrees a frame, "
                   "after --env-rotation) and the camera still, to OUT_0000.png ... and OUT.gif; built once, "
                   "per-frame cost printed")
    p.add_argument("--fps-frames", type=int, default=10,
                   help="repeated frames for the fps figure (default 10; not measured for a sequence of maps)")
    p.add_argument("-o", "--output", required=True, help="output PNG")
    add_env_orientation(p)
    add_rgl_incident(p)
    p.add_argument("--exr", help="also write linear radiance (before tone mapping) to this EXR")
    p.add_argument("--error-image", metavar="PATH", help=ERROR_IMAGE_HELP)
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (orders, stated errors, timings, files written; "
                   "data_specs/render_outputs.md) instead of the text lines")
