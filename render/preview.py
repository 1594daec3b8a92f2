"""Preview thumbnails for a report: a sphere (and optionally a mesh) shaded by an SHRM.

Two renderers give the same image up to rasterization: the VTK/OpenGL shader of
``render.pipeline`` (needs an offscreen context, ``render.offscreen.probe_offscreen``) and
the numpy CPU reference of ``render.cpu_reference`` (ray–sphere intersection, then
:meth:`SHRM.radiance` per pixel — no OpenGL). Meshes need OpenGL. The environment is
composited behind the object and the result tone mapped (filmic) to 8-bit sRGB.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass

import numpy as np
from PIL import Image

from ..analysis.shrm import SHRM
from ..brdf_io.envmap import EnvironmentMap
from .camera import Camera
from .cpu_reference import shade, sphere_geometry
from .mesh import Mesh, load_mesh
from .offscreen import probe_offscreen
from .output import composite, environment_background, to_8bit
from .pipeline import render_frames

__all__ = [
    "PREVIEW_DISABLED", "PREVIEW_VIEW", "PreviewImage", "png_bytes", "render_previews", "resolve_preview_mode",
    "preview_camera", "cpu_sphere_image", "preview_exposure", "unit_mesh",
]

#: the note of a report made with ``preview="none"`` (not a warning)
PREVIEW_DISABLED = "preview disabled"
#: direction from the object toward the camera (z-up frame): slightly above the horizon
PREVIEW_VIEW = (1.0, 0.35, 0.45)


@dataclass(frozen=True)
class PreviewImage:
    """One preview: ``key`` (``sphere`` or ``mesh``), the PNG bytes and the renderer used."""

    key: str
    png: bytes
    renderer: str
    first_frame_seconds: float


def png_bytes(image8: np.ndarray) -> bytes:
    """Encode a uint8 (H, W, 3|4) image as PNG."""
    buf = io.BytesIO()
    Image.fromarray(np.asarray(image8, dtype=np.uint8)).save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def resolve_preview_mode(mode: str) -> tuple[str, str]:
    """Turn ``auto`` into ``gl`` or ``cpu`` by probing for an offscreen context (in a subprocess).

    Returns ``(mode, note)``; other modes are returned unchanged with an empty note.
    """
    if mode != "auto":
        return mode, ""
    ok, message = probe_offscreen(timeout=60.0)
    if ok:
        return "gl", ""
    return "cpu", f"no offscreen OpenGL ({message}): CPU reference renderer used, mesh previews skipped"


def preview_camera() -> Camera:
    """The preview camera: frames the unit sphere from :data:`PREVIEW_VIEW`."""
    return Camera.looking_at(view=np.array(PREVIEW_VIEW), up=(0.0, 0.0, 1.0), margin=1.15)


def cpu_sphere_image(shrm: SHRM, env: EnvironmentMap, size: int) -> np.ndarray:
    """Linear (size, size, 3) image of the unit sphere shaded by ``shrm`` over ``env`` (numpy only)."""
    camera = preview_camera()
    geometry = sphere_geometry(camera, size, size)
    radiance = shade(geometry, shrm.radiance).astype(np.float32)
    alpha = geometry.hit.astype(np.float32)
    return composite(radiance, alpha, environment_background(env.radiance, camera, size, size))


def render_previews(
    shrm: SHRM, env: EnvironmentMap, *, mode: str, size: int, mesh: str | None = None
) -> tuple[list[PreviewImage], list[str]]:
    """Render the sphere (and ``mesh``) previews.

    Parameters
    ----------
    mode
        ``gl``, ``cpu`` or ``none`` (resolve ``auto`` first with :func:`resolve_preview_mode`).

    Returns
    -------
    (images, notes)
        The previews made and notes about those that were not.
    """
    if mode == "none":
        return [], [PREVIEW_DISABLED]
    images: list[PreviewImage] = []
    notes: list[str] = []
    exposure = preview_exposure(env)
    if mode == "cpu":
        t0 = time.perf_counter()
        linear = cpu_sphere_image(shrm, env, size)
        images.append(PreviewImage("sphere", png_bytes(to_8bit(linear, exposure=exposure)), "cpu-reference",
                                   time.perf_counter() - t0))
        if mesh:
            notes.append(f"mesh preview of {mesh} needs OpenGL (CPU preview renders the sphere only)")
        return images, notes
    targets = [("sphere", "builtin:sphere")] + ([("mesh", mesh)] if mesh else [])
    camera = preview_camera()
    for key, source in targets:
        frames, timings = render_frames(
            unit_mesh(load_mesh(source)), shrm, [camera], size=size, mode="distant", env_radiance=env.radiance,
            background="env", fps_frames=0,
        )
        images.append(PreviewImage(key, png_bytes(to_8bit(frames[0].linear, exposure=exposure)),
                                   f"opengl ({timings.backend})", timings.first_frame_s))
    return images, notes


def unit_mesh(mesh: Mesh) -> Mesh:
    """The mesh moved and scaled into the unit sphere about the origin (what the camera frames)."""
    centre, radius = mesh.bounding_sphere()
    return mesh.transformed(scale=1.0 / radius, translate=-centre / radius) if radius > 0 else mesh


def preview_exposure(env: EnvironmentMap) -> float:
    """Stops that bring the environment's mean luminance to 0.18 (a middle grey)."""
    mean = float(np.average(env.radiance.mean(axis=(1, 2)), weights=env.solid_angles()))
    if not mean > 0:
        return 0.0
    return float(np.clip(np.log2(0.18 / mean), -20.0, 20.0))
