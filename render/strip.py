"""Side-by-side image strip: reference, each representation, and difference images ([RH02] Figs. 9–10).

Computed on the CPU (``render.cpu_reference``): an orthographic camera looks at a unit
sphere (or a small mesh), each hit pixel gets its R and V, the reference column is the
angular-domain integral ([RH02] eq. 2) and every other column a representation's B(R, V).
The bottom row holds |B − B_ref| per channel, **not amplified**: it is tone mapped with the
same exposure as the images above it, so a difference is as visible as it would be on
screen. The exposure maps the reference's 99th percentile to 1 (sRGB curve, no filmic
shoulder, so differences are not compressed).

The representations are those :func:`shrmkit.analysis.compare.compare_representations`
built (any :class:`~shrmkit.analysis.compare.Representation`: its ``short_label`` names the
panel); :func:`write_comparison_strip` draws them and returns the table with the strip's
description as its ``strip`` entry (what ``shrm compare --strip`` prints).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

from ..analysis.compare import Comparison, Representation, relative_rms
from ..analysis.reference import reference_radiance
from ..brdf_io.errors import BadInputError
from .camera import Camera
from .cpu_reference import mesh_geometry, shade, sphere_geometry
from .mesh import Mesh
from .output import to_8bit, write_png

__all__ = ["strip_images", "write_strip", "write_comparison_strip", "STRIP_VIEW"]

#: View direction of the strip's orthographic camera (z-up frame).
STRIP_VIEW = (1.0, 0.0, 0.25)


def strip_images(
    reps: Sequence[Representation], env: Any, brdf: Any, *, size: int = 64, mesh: Mesh | None = None,
    view: Sequence[float] = STRIP_VIEW,
) -> tuple[np.ndarray, list[tuple[str, np.ndarray]], np.ndarray]:
    """(reference image, [(label, image)], hit mask): linear float64 (size, size, 3) images."""
    if mesh is None:
        cam = Camera.looking_at(view=np.asarray(view, float), projection="ortho", margin=1.05)
        geom = sphere_geometry(cam, size, size)
    else:
        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        center = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(mesh.vertices - center, axis=1)))
        cam = Camera.looking_at(center=center, radius=radius, view=np.asarray(view, float), projection="ortho",
                                margin=1.05)
        geom = mesh_geometry(cam, size, size, mesh)
    reference = shade(geom, lambda R, V: reference_radiance(env, brdf, R, V))
    images = [(rep.label, shade(geom, rep.radiance)) for rep in reps]
    return reference, images, geom.hit


def _label(image8: np.ndarray, text: str) -> np.ndarray:
    pil = Image.fromarray(image8)
    ImageDraw.Draw(pil).text((2, 1), text, fill=(255, 255, 0))
    return np.asarray(pil)


def write_strip(
    path: str | Path, reps: Sequence[Representation], env: Any, brdf: Any, *, size: int = 64,
    mesh: Mesh | None = None,
) -> dict[str, Any]:
    """Write the strip PNG (atomically) and return its description with per-panel errors.

    Layout: top row reference, then one column per representation (labelled with its
    ``short_label``); bottom row the difference images |B − B_ref| (same exposure, not
    amplified). Pass the ``env`` and ``brdf`` the table was computed with
    (``Comparison.env``, ``Comparison.brdf``).

    Returns
    -------
    dict
        ``path``, ``size`` (panel pixels), ``exposure`` (stops), ``panels`` (``label``,
        ``rel_rms`` over the covered pixels, :func:`~shrmkit.analysis.compare.relative_rms`),
        ``mesh`` (its name, or ``"sphere"``): the ``strip`` entry of ``data_specs/compare_json.md``.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise BadInputError(path, "the image strip must be a .png file")
    if not 16 <= size <= 1024:
        raise BadInputError(None, f"strip panel size must be in [16, 1024], got {size}")
    reference, images, hit = strip_images(reps, env, brdf, size=size, mesh=mesh)
    p99 = float(np.percentile(reference[hit].max(axis=-1), 99.0)) if hit.any() else 1.0
    exposure = -np.log2(p99) if p99 > 0 else 0.0

    def eight(x: np.ndarray) -> np.ndarray:
        return to_8bit(x, exposure=exposure, curve="srgb")

    top = [_label(eight(reference), "reference")]
    bottom = [np.zeros_like(top[0])]
    panels = []
    for rep, (label, image) in zip(reps, images, strict=True):
        top.append(_label(eight(image), rep.short_label))
        bottom.append(_label(eight(np.abs(image - reference)), "|diff|"))
        panels.append({"label": label, "rel_rms": relative_rms(image[hit], reference[hit])})
    strip = np.concatenate([np.concatenate(top, axis=1), np.concatenate(bottom, axis=1)], axis=0)
    write_png(path, strip)
    return {"path": str(path), "size": size, "exposure": exposure, "panels": panels,
            "mesh": getattr(mesh, "name", "sphere") if mesh is not None else "sphere"}


def write_comparison_strip(
    comparison: Comparison, path: str | Path, *, size: int = 64, mesh: Mesh | None = None
) -> dict[str, Any]:
    """Draw the strip of a :class:`~shrmkit.analysis.compare.Comparison` (its representations,
    environment and BRDF, no second build) and return a copy of its table with the
    :func:`write_strip` description inserted as ``strip`` just before ``markdown`` (the layout
    of ``data_specs/compare_json.md``)."""
    strip = write_strip(path, comparison.representations, comparison.env, comparison.brdf, size=size, mesh=mesh)
    result = {key: value for key, value in comparison.result.items() if key != "markdown"}
    result["strip"] = strip
    result["markdown"] = comparison.result["markdown"]
    return result
