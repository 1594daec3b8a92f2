"""Side-by-side image strip: reference, each representation, and difference images (RH02 Figs. 9–10).

Computed on the CPU (``render.cpu_reference``): an orthographic camera looks at a unit
sphere (or a small mesh), each hit pixel gets its R and V, the reference column is the
angular-domain integral (RH02 eq. 2) and every other column a representation's B(R, V).
The bottom row holds |B − B_ref| per channel, **not amplified**: it is tone mapped with the
same exposure as the images above it, so a difference is as visible as it would be on
screen. The exposure maps the reference's 99th percentile to 1 (sRGB curve, no filmic
shoulder, so differences are not compressed).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.reference import reference_radiance

__all__ = ["strip_images", "write_strip"]

STRIP_VIEW = (1.0, 0.0, 0.25)


def strip_images(
    reps: Sequence[Any], env: Any, brdf: Any, *, size: int = 64, mesh: Any = None, view: Sequence[float] = STRIP_VIEW
) -> tuple[np.ndarray, list[tuple[str, np.ndarray]], np.ndarray]:
    """(reference image, [(label, image)], hit mask): linear float64 (size, size, 3) images."""
    from .camera import Camera
    from .cpu_reference import mesh_geometry, shade, sphere_geometry

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


def _short(rep: Any) -> str:
    """A label that fits a 64-pixel panel."""
    p = rep.params
    if rep.key.startswith("gaussian"):
        return f"Green K={p['K']}"
    if rep.key == "kautz_mccool":
        return f"KM P={p['P']}"
    if rep.key.startswith("cabral"):
        return "Cabral" if p.get("source") == "shrm" else "Cabral ref"
    if "P" in p:
        return f"SHRM P={p['P']}"
    return rep.key[:10]


def _label(image8: np.ndarray, text: str) -> np.ndarray:
    from PIL import Image, ImageDraw

    pil = Image.fromarray(image8)
    ImageDraw.Draw(pil).text((2, 1), text, fill=(255, 255, 0))
    return np.asarray(pil)


def write_strip(
    path: str | Path, reps: Sequence[Any], env: Any, brdf: Any, *, size: int = 64, mesh: Any = None
) -> dict[str, Any]:
    """Write the strip PNG (atomically) and return its description with per-panel errors.

    Layout: top row reference, then one column per representation; bottom row the
    difference images |B − B_ref| (same exposure, not amplified).
    """
    from ..analysis.compare.table import relative_rms
    from ..brdf_io.errors import BadInputError
    from .output import to_8bit, write_png

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
        top.append(_label(eight(image), _short(rep)))
        bottom.append(_label(eight(np.abs(image - reference)), "|diff|"))
        panels.append({"label": label, "rel_rms": relative_rms(image[hit], reference[hit])})
    strip = np.concatenate([np.concatenate(top, axis=1), np.concatenate(bottom, axis=1)], axis=0)
    write_png(path, strip)
    return {"path": str(path), "size": size, "exposure": exposure, "panels": panels,
            "mesh": getattr(mesh, "name", "sphere") if mesh is not None else "sphere"}
