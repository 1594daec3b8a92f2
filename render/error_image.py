"""The error image of a render: the SHRM's predicted relative error at every pixel (``--error-image``).

For each pixel the object covers we take the pixel's reflection direction R as the fragment
shaders compute it (read back from the renderer: :meth:`SHRMRenderer.reflection_directions`,
exact for any mesh, aligned with the PNG) and its view direction V (the camera ray through the
pixel centre, reversed: ``Camera.rays``, as the shaders' V), and evaluate
:func:`shrmkit.analysis.error_image.predicted_error` there: the SHRM's per-band statement turned
into a relative error at that (R, V), e(θ_v)/|B(R, V)|, capped at
:data:`~shrmkit.analysis.error_image.ERROR_CAP` (``data_specs/render_outputs.md``).

The image is that of the first frame, float32 (H, W), **NaN where no object covers the pixel
centre** (no statement there; 0 would read as "exact"). :func:`write_error_image` stores it as
an OpenEXR file whose R, G and B channels all hold it (``brdf_io.exr.write_exr``, ZIP, float32);
:func:`false_colour` makes a display image with a logarithmic colour scale.

Only the SHRM modes have a statement (:func:`error_image_modes`: ``distant``, ``perpixel``,
``kautz-mccool``). In ``distant`` mode with a perspective camera the SHRM part of a pixel is the
frame's map at the view Ṽ toward the object ([RH02] eq. 12); the image states the error of the
SHRM at the pixel's own V and does not count that distant-viewer approximation (with an ortho
camera V = Ṽ at every pixel, and the image describes the render exactly).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.error_image import BOUND_LEVEL, ERROR_CAP, predicted_error
from ..analysis.shrm import SHRM
from ..brdf_io.errors import BadInputError
from ..brdf_io.exr import write_exr
from .api import SceneRender
from .camera import Camera
from .mesh import Mesh
from .modes import RENDER_MODES
from .vtk_renderer import SHRMRenderer

__all__ = [
    "ErrorImage",
    "error_image_modes",
    "check_error_image_request",
    "pixel_directions",
    "error_image",
    "write_error_image",
    "false_colour",
    "FALSE_COLOUR_RANGE",
    "ERROR_IMAGE_HELP",
    "write_error_image_line",
]

#: The default range of :func:`false_colour`: relative errors from 0.1 % to 100 % (log scale).
FALSE_COLOUR_RANGE = (1e-3, 1.0)


@dataclass(frozen=True, eq=False)
class ErrorImage:
    """A frame's predicted relative error per pixel (:func:`error_image`).

    Attributes
    ----------
    error
        float32 (H, W): the predicted relative error, NaN where no object covers the pixel centre.
    covered
        bool (H, W): pixels the object covers.
    bound
        Whether ``error`` is the bound version (exceeded on at most a share ``level`` of a band's pairs).
    level
        The bound version's share.
    distant_approximation
        True when the render's SHRM part is a distant-viewer map at one view Ṽ for a perspective
        camera (``distant`` mode): the image does not count that approximation.
    """

    error: np.ndarray
    covered: np.ndarray
    bound: bool = False
    level: float = BOUND_LEVEL
    distant_approximation: bool = False

    def summary(self) -> dict[str, float]:
        """Median, 90th percentile and largest value over the covered pixels, and how many reach the cap."""
        values = self.error[self.covered].astype(np.float64)
        if values.size == 0:
            return {"pixels": 0, "median": float("nan"), "p90": float("nan"), "max": float("nan"), "capped": 0}
        return {"pixels": int(values.size), "median": float(np.median(values)),
                "p90": float(np.percentile(values, 90)), "max": float(values.max()),
                "capped": int(np.count_nonzero(values >= ERROR_CAP))}


def error_image_modes() -> tuple[str, ...]:
    """The render modes whose model is an SHRM with per-band statements (``distant``, ``perpixel``,
    ``kautz-mccool``): those an error image can be made for."""
    return tuple(m.name for m in RENDER_MODES.values() if m.models == (SHRM,))


def check_error_image_request(path: str | Path, mode: str) -> Path:
    """Refuse an error-image request before any computation: not a ``.exr`` name, or a mode
    without an SHRM. (Whether the path is writable: ``brdf_io.atomic.check_writable``.)

    Raises
    ------
    BadInputError
        One line naming the problem in the API's terms (``path``, ``mode=``); the CLI says it with
        its options (``cli.common.in_cli_terms``: ``--error-image``, ``--mode``).
    """
    path = Path(path)
    if path.suffix.lower() != ".exr":
        raise BadInputError(path, "the error image path must name a .exr file")
    modes = error_image_modes()
    if mode not in modes:
        raise BadInputError(None, f"an error image needs an SHRM mode ({', '.join(modes)}), not mode={mode}: "
                            "the error statement is the SHRM's")
    return path


def pixel_directions(mesh: Mesh, model: SHRM, camera: Camera, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each pixel's R (from the shaders, :meth:`SHRMRenderer.reflection_directions`) and V (the
    camera ray reversed) for ``mesh`` seen by ``camera`` in a size × size frame.

    Returns
    -------
    R, V
        float64 (H, W, 3) unit vectors, z-up frame; R is 0 where nothing is covered.
    covered
        bool (H, W).
    """
    with SHRMRenderer(size, size, deferred=False) as renderer:
        # any SHRM mode's object gives the same R; distant's shading is the cheapest to set up
        renderer.add_object(mesh, model, mode="distant")
        R, alpha = renderer.reflection_directions(camera)
    covered = alpha > 0.5
    R = R.astype(np.float64)
    norm = np.linalg.norm(R, axis=-1, keepdims=True)
    R = np.where(covered[..., None], R / np.where(norm > 0.0, norm, 1.0), 0.0)
    covered &= norm[..., 0] > 0.0
    _, dirs = camera.rays(size, size)
    return R, -dirs, covered


def error_image(result: SceneRender, *, frame: int = 0, bound: bool = False, level: float = BOUND_LEVEL
                ) -> ErrorImage:
    """The predicted relative error per pixel of frame ``frame`` of a render (module docstring).

    Parameters
    ----------
    result
        What :func:`~shrmkit.render.api.render_scene` made, in an SHRM mode (:func:`error_image_modes`).
    frame
        Which camera's frame (default the first).
    bound, level
        The bound version instead of the prediction (:func:`~shrmkit.analysis.error_image.predicted_error`).

    Raises
    ------
    BadInputError
        A render in a mode without an SHRM, or a frame index out of range.
    """
    if result.mode not in error_image_modes() or not isinstance(result.model, SHRM):
        raise BadInputError(None, f"an error image needs an SHRM mode ({', '.join(error_image_modes())}), "
                            f"not {result.mode}")
    if not 0 <= frame < len(result.cameras):
        raise BadInputError(None, f"frame must be in [0, {len(result.cameras) - 1}], got {frame}")
    camera = result.cameras[frame]
    shrm = result.model
    R, V, covered = pixel_directions(result.mesh, shrm, camera, result.size)
    error = np.full(covered.shape, np.nan, dtype=np.float32)
    if covered.any():
        error[covered] = predicted_error(shrm, R[covered], V[covered], bound=bound, level=level)
    distant = result.mode == "distant" and camera.projection != "ortho" and shrm.P > 0
    return ErrorImage(error, covered, bool(bound), float(level), distant)


def write_error_image(path: str | Path, image: ErrorImage | np.ndarray) -> Path:
    """Write an error image (H, W) as float32 OpenEXR, the value in R, G and B (NaN outside the
    object), atomically (``brdf_io.exr.write_exr``)."""
    error = image.error if isinstance(image, ErrorImage) else np.asarray(image)
    if error.ndim != 2:
        raise ValueError(f"an error image is (H, W), got {error.shape}")
    rgb = np.repeat(error.astype(np.float32)[..., None], 3, axis=-1)
    write_exr(path, rgb)
    return Path(path)


def _colour_map(t: np.ndarray) -> np.ndarray:
    """A perceptually ordered dark-blue → teal → yellow map (anchors of matplotlib's viridis) at
    t in [0, 1]: (..., 3) floats in [0, 1]."""
    anchors = np.array([
        [0.267, 0.005, 0.329], [0.283, 0.141, 0.458], [0.254, 0.265, 0.530], [0.207, 0.372, 0.553],
        [0.164, 0.471, 0.558], [0.128, 0.567, 0.551], [0.135, 0.659, 0.518], [0.267, 0.749, 0.441],
        [0.478, 0.821, 0.318], [0.741, 0.873, 0.150], [0.993, 0.906, 0.144],
    ])
    x = np.clip(t, 0.0, 1.0) * (len(anchors) - 1)
    i = np.minimum(np.floor(x).astype(int), len(anchors) - 2)
    f = (x - i)[..., None]
    return anchors[i] * (1.0 - f) + anchors[i + 1] * f


def false_colour(error: np.ndarray, *, vmin: float = FALSE_COLOUR_RANGE[0], vmax: float = FALSE_COLOUR_RANGE[1],
                 background: tuple[int, int, int] = (255, 255, 255)) -> np.ndarray:
    """uint8 (H, W, 3) display image of an error image: log10 of the error from ``vmin`` (dark
    blue) to ``vmax`` (yellow), clamped at both ends; NaN (no object) in ``background``."""
    if not 0.0 < vmin < vmax:
        raise ValueError(f"need 0 < vmin < vmax, got {vmin}, {vmax}")
    error = np.asarray(error, dtype=np.float64)
    t = (np.log10(np.maximum(np.nan_to_num(error, nan=vmin), 1e-300)) - np.log10(vmin)) / np.log10(vmax / vmin)
    rgb = np.round(_colour_map(t) * 255.0).astype(np.uint8)
    rgb[np.isnan(error)] = background
    return rgb


#: The help of ``shrm render --error-image``.
ERROR_IMAGE_HELP = (
    "also write the SHRM's predicted relative error per pixel of the first frame to this EXR (float32, "
    "the value in R, G and B, NaN outside the object; from each pixel's R and V and the per-band "
    f"statements, capped at {ERROR_CAP:g}; modes {', '.join(error_image_modes())}; data_specs/render_outputs.md)"
)


def write_error_image_line(path: str | Path, image: ErrorImage) -> str:
    """Write ``image`` (:func:`write_error_image`) and return the line ``shrm render`` prints about it."""
    write_error_image(path, image)
    s = image.summary()
    what = f"bound (level {image.level:g})" if image.bound else "predicted relative error"
    line = (f"wrote {path} ({what} per pixel: median {s['median']:.3g}, 90th percentile {s['p90']:.3g}, "
            f"max {s['max']:.3g} over {s['pixels']} pixels")
    if s["capped"]:
        line += f", {s['capped']} at the cap {ERROR_CAP:g}"
    line += ")"
    if image.distant_approximation:
        line += "; distant mode, perspective: the distant-viewer approximation is not counted"
    return line
