"""Rendered-image output: EXR (linear radiance), PNG (exposure + tone mapping), turntable GIF.

Pipeline (data_specs/render_outputs.md):

1. ``composite``: linear radiance of the objects over a background — the environment seen
   directly along each camera ray (HDR background), a constant, or nothing (alpha 0);
2. EXR: the linear composite as float32 channels R, G, B plus coverage A — before any
   exposure or tone mapping;
3. PNG: scale by 2^exposure, tone map (``srgb``: clip to [0, 1]; ``filmic``: the ACES
   fitted curve of [Narkowicz15], x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)), encode with
   the sRGB transfer function [sRGB], quantize to 8 bits; RGBA when the
   background is transparent (alpha = coverage). Step 3 lives in ``brdf_io.display`` (re-exported here).

All writers are atomic (temporary file in the target folder, then ``os.replace``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

from ..brdf_io.atomic import atomic_path
from ..brdf_io.display import TONE_MAPS, srgb_encode, to_8bit, tone_map  # the one tone mapping, re-exported
from ..brdf_io.env_rotation import to_map_frame
from ..brdf_io.latlong import bilinear_lookup
from .camera import Camera

__all__ = [
    "TONE_MAPS",
    "environment_background",
    "composite",
    "tone_map",
    "srgb_encode",
    "to_8bit",
    "write_exr",
    "write_png",
    "write_gif",
    "turntable_paths",
]


def environment_background(
    env_radiance: np.ndarray, camera: Camera, width: int, height: int, *, env_rotation: np.ndarray | None = None
) -> np.ndarray:
    """The environment seen along each camera ray: bilinear lat-long lookup, float32 (H, W, 3).

    ``env_radiance`` is an (h, w, 3) lat-long map in the z-up frame (DESIGN §2); ``env_rotation``
    a (3, 3) rotation Q of the map (``brdf_io.env_rotation``): the ray d sees L(Qᵀ d).
    """
    _, dirs = camera.rays(width, height)
    dirs = to_map_frame(dirs, env_rotation)
    return bilinear_lookup(np.asarray(env_radiance, dtype=np.float64), dirs).astype(np.float32)


def composite(radiance: np.ndarray, alpha: np.ndarray, background: np.ndarray | Sequence[float] | None) -> np.ndarray:
    """radiance·α + background·(1 − α); ``None`` keeps the radiance (transparent background)."""
    if background is None:
        return np.asarray(radiance, dtype=np.float32)
    a = np.asarray(alpha, dtype=np.float32)[..., None]
    bg = np.broadcast_to(np.asarray(background, dtype=np.float32), radiance.shape)
    return (radiance * a + bg * (1.0 - a)).astype(np.float32)


def write_exr(path: str | Path, radiance: np.ndarray, alpha: np.ndarray | None = None, *,
              atomic: bool = True) -> None:
    """Write linear float32 radiance (H, W, 3) [and coverage A] to OpenEXR, atomically (``atomic=False``:
    straight to ``path``, for a caller's :func:`~shrmkit.brdf_io.atomic.atomic_paths` group).

    Channels R, G, B (and A), 32-bit float, ZIP compression (lossless).
    """
    rgb = np.asarray(radiance, dtype=np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"radiance must be (H, W, 3), got {rgb.shape}")
    channels = {name: np.ascontiguousarray(rgb[..., k]) for k, name in enumerate("RGB")}
    if alpha is not None:
        channels["A"] = np.ascontiguousarray(np.asarray(alpha, dtype=np.float32))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with _target(path, atomic) as tmp, OpenEXR.File(header, channels) as exr:
        exr.write(str(tmp))


def write_png(path: str | Path, image8: np.ndarray, *, atomic: bool = True) -> None:
    """Write a uint8 RGB or RGBA image to PNG, atomically (``atomic=False``: as :func:`write_exr`)."""
    with _target(path, atomic) as tmp:
        Image.fromarray(np.asarray(image8, dtype=np.uint8)).save(tmp, format="PNG")


def _target(path: str | Path, atomic: bool) -> contextlib.AbstractContextManager[Path]:
    return atomic_path(path) if atomic else contextlib.nullcontext(Path(path))


def write_gif(path: str | Path, frames: Sequence[np.ndarray], *, fps: float = 20.0, atomic: bool = True) -> None:
    """Write uint8 RGB frames as a looping animated GIF (Pillow), atomically (``atomic=False``: as
    :func:`write_exr`)."""
    if not frames:
        raise ValueError("no frames")
    images = [Image.fromarray(np.asarray(f, dtype=np.uint8)[..., :3]) for f in frames]
    with _target(path, atomic) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=max(int(round(1000.0 / fps)), 10),
            loop=0,
        )


def turntable_paths(output: str | Path, n_frames: int) -> tuple[list[Path], Path]:
    """Frame paths ``<stem>_0000<suffix>`` … and the GIF path ``<stem>.gif`` for ``output``."""
    out = Path(output)
    digits = max(4, len(str(n_frames - 1)))
    frames = [out.with_name(f"{out.stem}_{k:0{digits}d}{out.suffix}") for k in range(n_frames)]
    return frames, out.with_suffix(".gif")
