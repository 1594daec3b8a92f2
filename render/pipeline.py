"""Rendering of one mesh under a built model: cameras, frames, background, timings.

:func:`render_frames` is what :func:`shrmkit.render.api.render_scene` (and so ``shrm render``)
calls once the model is built: it builds the offscreen renderer, renders every camera (first
frame timed separately: it includes shader compilation and texture upload), measures frames
per second over repeated frames, and composites the environment behind the object.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .camera import Camera, orbit_camera
from .mesh import Mesh
from .modes import DEFAULT_MODE
from .output import composite, environment_background
from .vtk_renderer import SHRMRenderer

__all__ = ["Frame", "FrameTimings", "BACKGROUNDS", "turntable_cameras", "render_frames"]

BACKGROUNDS = ("env", "black", "transparent")


@dataclass(frozen=True, eq=False)
class Frame:
    """A finished frame: ``linear`` (H, W, 3) float32 composite radiance, ``alpha`` (H, W) coverage,
    ``transparent`` True when the background was left empty."""

    linear: np.ndarray
    alpha: np.ndarray
    transparent: bool


@dataclass(frozen=True)
class FrameTimings:
    """Seconds for the first frame (context, shaders, upload, draw, readback), frames per second
    over ``fps_frames`` repeated draws, and the OpenGL back end."""

    first_frame_s: float
    fps: float
    fps_frames: int
    backend: str


def turntable_cameras(base: Camera, n_frames: int, center: np.ndarray = (0.0, 0.0, 0.0)) -> list[Camera]:
    """``n_frames`` cameras orbiting about the world z axis, frame k at angle 2πk/n."""
    if n_frames < 1:
        raise ValueError(f"turntable needs at least 1 frame, got {n_frames}")
    c = np.asarray(center, dtype=np.float64)
    return [orbit_camera(base, c, 2.0 * np.pi * k / n_frames) for k in range(n_frames)]


def render_frames(
    mesh: Mesh,
    model: Any,
    cameras: Sequence[Camera],
    *,
    size: int,
    mode: str = DEFAULT_MODE,
    env_radiance: np.ndarray | None = None,
    background: str = "env",
    fps_frames: int = 10,
    visibility_sh: np.ndarray | None = None,
) -> tuple[list[Frame], FrameTimings]:
    """Render ``mesh`` shaded by ``model`` in render ``mode`` from each camera into size × size frames.

    Parameters
    ----------
    model
        What the mode draws (``SHRMRenderer.add_object``).
    background
        ``"env"``: the environment (``env_radiance``, lat-long z-up) seen along each ray;
        ``"black"``; ``"transparent"`` (alpha from coverage).
    fps_frames
        Repeated frames for the frames-per-second figure (0 skips it; fps is then NaN).
    visibility_sh
        Modes with self-shadowing only: per-vertex order-4 SH visibility
        (``analysis.baselines.selfshadow.vertex_visibility_sh``).
    """
    if background not in BACKGROUNDS:
        raise ValueError(f"background must be one of {BACKGROUNDS}, got {background!r}")
    if background == "env" and env_radiance is None:
        raise ValueError("background 'env' needs env_radiance")
    t0 = time.perf_counter()
    with SHRMRenderer(size, size) as renderer:
        renderer.add_object(mesh, model, mode=mode, visibility_sh=visibility_sh)
        results = [renderer.render(cameras[0])]
        first = time.perf_counter() - t0
        results += [renderer.render(cam) for cam in cameras[1:]]
        fps = renderer.frames_per_second(cameras[0], fps_frames) if fps_frames > 0 else float("nan")
        backend = renderer.backend
    frames = []
    for cam, res in zip(cameras, results, strict=True):
        if background == "env":
            bg = environment_background(env_radiance, cam, size, size)
            frames.append(Frame(composite(res.radiance, res.alpha, bg), res.alpha, False))
        elif background == "black":
            frames.append(Frame(composite(res.radiance, res.alpha, (0.0, 0.0, 0.0)), res.alpha, False))
        else:
            frames.append(Frame(res.radiance, res.alpha, True))
    return frames, FrameTimings(first, fps, fps_frames, backend)
