"""``shrm export``'s parser (numpy-free; the verb's work is in ``cmd_export.py``)."""

from __future__ import annotations

import argparse

from ..analysis.defaults import MAX_CUBE_FACE_SIZE
from ..brdf_io.names import DDS_FORMAT_NAMES, EXPORT_FORMAT_SUFFIXES
from .options import add_env_orientation, add_rgl_incident, brdf_help, number_in

__all__ = ["HELP", "add_arguments"]

HELP = ("export a BRDF as a Mitsuba 3 / pbrt-v4 / MaterialX material or a MERL table, or a prefiltered cube map "
        "(DDS or KTX2)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("brdf", help=brdf_help() + "; materials are fitted to scattered measurements directly, "
                        "a MERL table goes through their representation with the smallest held-out error")
    parser.add_argument("-o", "--output", required=True,
                        help="output file; its suffix picks the format unless --to names it ("
                        + ", ".join(f"{suffix} {name}" for name, suffix in EXPORT_FORMAT_SUFFIXES.items()) + ")")
    parser.add_argument("--to", choices=tuple(EXPORT_FORMAT_SUFFIXES), default=None,
                        help="format to write (default: from the output suffix)")
    parser.add_argument("--name", default=None,
                        help="material name in the snippet (default: the output file's stem)")
    parser.add_argument("--env", default=None,
                        help="dds, ktx2: the environment (builtin:sky, builtin:studio or a map file)")
    parser.add_argument("--face-size", type=number_in(1, MAX_CUBE_FACE_SIZE, integer=True), default=128,
                        help="dds, ktx2: texels along a face of mip level 0, a power of two (default 128)")
    parser.add_argument("--levels", type=number_in(1, 12, integer=True), default=None,
                        help="dds, ktx2: mip levels N (default log2(face size) + 1); level m holds roughness m/(N-1)")
    parser.add_argument("--dds-format", choices=DDS_FORMAT_NAMES, default="rgba16f",
                        help="dds, ktx2: texel format (default rgba16f, the engines' HDR format)")
    parser.add_argument("--json", action="store_true", help="print one JSON object describing what was written")
    add_env_orientation(parser)
    add_rgl_incident(parser)
