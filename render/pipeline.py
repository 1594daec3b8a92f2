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
from numpy.typing import ArrayLike

from ..brdf_io.env_rotation import check_env_rotation, rotation_about_z, to_map_frame
from .camera import Camera, orbit_camera
from .defaults import BACKGROUNDS  # numpy-free home, for the CLI's parsers
from .mesh import Mesh
from .modes import DEFAULT_MODE
from .output import composite, environment_background
from .vtk_renderer import SHRMRenderer

__all__ = ["Frame", "FrameTimings", "BACKGROUNDS", "turntable_cameras", "light_turntable_rotations", "view_cones",
           "render_frames"]


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
    over ``fps_frames`` repeated draws, the OpenGL back end, and ``frame_seconds``: each frame's
    own cost (per-frame map update, draw, readback and its background), the first one included."""

    first_frame_s: float
    fps: float
    fps_frames: int
    backend: str
    frame_seconds: tuple[float, ...] = ()

    @property
    def later_frame_s(self) -> float:
        """Mean seconds of the frames after the first (the first compiles shaders and uploads
        textures); the first frame's own cost when there is one frame only."""
        later = self.frame_seconds[1:] or self.frame_seconds
        return float(np.mean(later)) if later else float("nan")


def turntable_cameras(base: Camera, n_frames: int, center: ArrayLike = (0.0, 0.0, 0.0)) -> list[Camera]:
    """``n_frames`` cameras orbiting about the world z axis, frame k at angle 2πk/n."""
    if n_frames < 1:
        raise ValueError(f"turntable needs at least 1 frame, got {n_frames}")
    c = np.asarray(center, dtype=np.float64)
    return [orbit_camera(base, c, 2.0 * np.pi * k / n_frames) for k in range(n_frames)]


def light_turntable_rotations(n_frames: int, base: np.ndarray | None = None) -> list[np.ndarray]:
    """``n_frames`` rotations of the environment about the up axis (+z): frame k is
    R_z(360° k / n) · Q_base (``brdf_io.env_rotation``; the sense of ``--env-azimuth``), Q_base
    the identity for None. The lighting turns while the camera stays (``shrm render --light-turntable``)."""
    if n_frames < 1:
        raise ValueError(f"light turntable needs at least 1 frame, got {n_frames}")
    q = np.eye(3) if base is None else check_env_rotation(base)
    return [rotation_about_z(360.0 * k / n_frames) @ q for k in range(n_frames)]


def _rotations(env_rotation: Any, n: int) -> list[np.ndarray | None]:
    """One rotation (or None) per camera from ``render_frames``' ``env_rotation``."""
    if env_rotation is None:
        return [None] * n
    if np.ndim(env_rotation) != 3:  # one rotation for every frame
        return [check_env_rotation(env_rotation)] * n
    rotations = [check_env_rotation(r) for r in env_rotation]
    if len(rotations) != n:
        raise ValueError(f"env_rotation: {len(rotations)} rotations for {n} cameras (give one, or one per camera)")
    return rotations


def view_cones(mesh: Mesh, cameras: Sequence[Camera], env_rotation: Any = None) -> list[tuple[np.ndarray, float]]:
    """Every direction V toward the eye that frames of ``mesh`` from ``cameras`` shade, in the
    unrotated environment's frame (Qᵀ V, ``brdf_io.env_rotation``: where the lights are), as one
    cone (unit axis (3,), half-angle in radians) per camera: ``Camera.view_cone`` of the mesh's
    bounding sphere (the centre of its box, as the renderer's), its axis turned by that frame's
    rotation (``env_rotation`` as :func:`render_frames`'). What ``SHRMRenderer.add_object(views=)``
    takes.
    """
    centre, radius = mesh.bounding_sphere()  # the renderer's (SHRMRenderer.add_object)
    cones = []
    for cam, q in zip(cameras, _rotations(env_rotation, len(cameras)), strict=True):
        axis, half_angle = cam.view_cone(centre, radius)
        cones.append((to_map_frame(axis, q), half_angle))
    return cones


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
    env_rotation: Any = None,
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
    env_rotation
        The environment rotated at view time (``brdf_io.env_rotation``): None, one rotation for
        every frame (a (3, 3) matrix or Euler angles (AZ, EL[, ROLL]) in degrees), or a sequence of
        (3, 3) matrices, one per camera (:func:`light_turntable_rotations`). The object and the
        ``"env"`` background are drawn under it; the model is not built again.

    Raises
    ------
    ValueError
        A bad background, or as many rotations as cameras not given (BadInputError for a rotation
        that is not one).
    """
    if background not in BACKGROUNDS:
        raise ValueError(f"background must be one of {BACKGROUNDS}, got {background!r}")
    if background == "env" and env_radiance is None:
        raise ValueError("background 'env' needs env_radiance")
    rotations = _rotations(env_rotation, len(cameras))
    t0 = time.perf_counter()
    with SHRMRenderer(size, size) as renderer:
        # only these cameras are drawn: a measured BRDF's table holds only the rows their views read
        renderer.add_object(mesh, model, mode=mode, visibility_sh=visibility_sh,
                            views=view_cones(mesh, cameras, env_rotation))
        results = [renderer.render(cameras[0], env_rotation=rotations[0])]
        first = time.perf_counter() - t0
        results += [renderer.render(cam, env_rotation=q) for cam, q in zip(cameras[1:], rotations[1:], strict=True)]
        fps = renderer.frames_per_second(cameras[0], fps_frames) if fps_frames > 0 else float("nan")
        backend = renderer.backend
    frames, seconds = [], []
    for cam, q, res in zip(cameras, rotations, results, strict=True):
        t = time.perf_counter()
        if background == "env":
            assert env_radiance is not None  # refused above
            bg = environment_background(env_radiance, cam, size, size, env_rotation=q)
            frames.append(Frame(composite(res.radiance, res.alpha, bg), res.alpha, False))
        elif background == "black":
            frames.append(Frame(composite(res.radiance, res.alpha, (0.0, 0.0, 0.0)), res.alpha, False))
        else:
            frames.append(Frame(res.radiance, res.alpha, True))
        seconds.append(res.seconds + time.perf_counter() - t)
    return frames, FrameTimings(first, fps, fps_frames, backend, tuple(seconds))
