"""Numpy-free names, defaults and help of render, for what must start fast (``shrm VERB --help``
and usage errors: issue 26).

The one home of the backgrounds (:data:`~shrmkit.render.pipeline.BACKGROUNDS`) and of the live
view's defaults (:mod:`~shrmkit.render.webgl_page`). Mirrored from modules that import numpy,
scipy and VTK (``tests/cli/test_cli_startup.py`` checks that both agree): the render-mode table's
names, help, default, self-shadow and lobe-option modes (:data:`~shrmkit.render.modes.RENDER_MODES`;
a new mode adds its line here), and the error image's help
(:data:`~shrmkit.render.error_image.ERROR_IMAGE_HELP`). Internal module.
"""

from __future__ import annotations

__all__ = [
    "RENDER_MODE_HELP", "DEFAULT_MODE", "SELF_SHADOW_MODES", "LOBE_OPTION_MODES", "BACKGROUNDS",
    "ERROR_IMAGE_HELP", "VIEW_MODES", "DEFAULT_VIEW_MESH", "DEFAULT_VIEW", "STILL_RENDERERS", "DEFAULT_PAGE_BYTES",
]

#: Render mode -> its one-line help, in the table's order (``modes.RENDER_MODES``, ``RenderMode.help``).
RENDER_MODE_HELP = {
    "distant": "distant viewer (RH02 eq. 12): one SHRM map per frame, looked up by R",
    "perpixel": "per-pixel view direction (RH02 eq. 8): the SHRM summed in the fragment shader",
    "rsibr": "Cabral et al. 1999: 12 maps at the icosahedron's vertices, blended per frame",
    "kautz-mccool": "Kautz & McCool 2000: the azimuth-free (q = 0) SHRM on the SHRM's (F, P), per pixel",
    "gaussian-lobes": "Green et al. 2007: K Gaussian lobes per view elevation over an SG mip stack",
}
#: ``modes.DEFAULT_MODE``.
DEFAULT_MODE = "distant"
#: The modes with per-vertex self-shadowing (``modes.self_shadow_modes()``).
SELF_SHADOW_MODES = ("gaussian-lobes",)
#: The modes whose published method has the ``lobes`` and ``elevations`` settings (the Gaussian-lobe fit).
LOBE_OPTION_MODES = ("gaussian-lobes",)
#: What is seen behind the object (``pipeline.BACKGROUNDS``).
BACKGROUNDS = ("env", "black", "transparent")
#: The help of ``shrm render --error-image`` (``error_image.ERROR_IMAGE_HELP``).
ERROR_IMAGE_HELP = (
    "also write the SHRM's predicted relative error per pixel of the first frame to this EXR (float32, "
    "the value in R, G and B, NaN outside the object; from each pixel's R and V and the per-band "
    "statements, capped at 10; modes distant, perpixel, kautz-mccool; data_specs/render_outputs.md)"
)
#: The render modes the live view's page draws (``render.modes`` names; ``webgl_page.VIEW_MODES``).
VIEW_MODES = ("distant", "perpixel")
#: The live view's mesh when none is given: an icosphere of 5120 triangles (92 KB of vertex data;
#: ``webgl_page.DEFAULT_MESH``).
DEFAULT_VIEW_MESH = "builtin:sphere:subdivisions=4"
#: The live view's initial view: degrees about z from +x, degrees above the xy plane, zoom factor
#: (``webgl_page.DEFAULT_VIEW``).
DEFAULT_VIEW = {"azimuth": 30.0, "elevation": 20.0, "zoom": 1.0}
#: ``build_view(still=...)``: how the still image for browsers without WebGL2 is rendered
#: (``webgl_page.STILL_RENDERERS``).
STILL_RENDERERS = ("auto", "cpu", "gl", "none")
#: The live view page's size budget in bytes (``webgl_page.ViewBudget().page_bytes``).
DEFAULT_PAGE_BYTES = 8 << 20
