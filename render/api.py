"""One call from a scene to rendered frames: :func:`render_scene`.

Loads what is given as a spec or path (mesh, environment, BRDF), builds the model of the
render mode through its record in the mode table (``render.modes``: an SHRM, RSIBR maps,
Gaussian lobes …), renders it offscreen from each camera (``render.pipeline.render_frames``)
and returns a :class:`SceneRender` with the frames, the timings and what was built.
``shrm render`` is this call plus argument parsing and file writing.

:func:`render_sequence` renders one frame per environment of a sequence (a time-lapse of HDR
captures, ``shrm render --env A.exr B.exr ...``): the BRDF's orders are chosen once
(``analysis.orders.choose_orders``; they depend on the BRDF only) and each map is prefiltered
with them (``prefilter(orders=)``), so a frame is exactly what :func:`render_scene` makes of its map.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from numbers import Integral
from pathlib import Path
from typing import Any

from ..analysis.orders import OrderChoice, choose_orders
from ..analysis.tolerance import DEFAULT_EPS, check_eps
from ..brdf_io.brdf import BRDF
from ..brdf_io.envmap import EnvironmentMap, load_env
from ..brdf_io.errors import BadInputError
from ..brdf_io.specs import load_brdf
from .camera import Camera
from .mesh import Mesh, load_mesh
from .modes import DEFAULT_MODE, BuiltModel, RenderOptions, get_mode, self_shadow_modes
from .notebook import scene_render_html, scene_render_png, sequence_render_html
from .pipeline import BACKGROUNDS, Frame, FrameTimings, render_frames

__all__ = ["render_scene", "SceneRender", "render_sequence", "SequenceRender", "SIZE_RANGE"]

#: Image sizes (width = height, pixels) :func:`render_scene` accepts.
SIZE_RANGE = (16, 8192)


@dataclass(frozen=True, eq=False)
class SceneRender:
    """What :func:`render_scene` made.

    Attributes
    ----------
    mesh
        The mesh rendered (loaded and normalized).
    mode
        The render mode's name.
    built
        The mode's model with its numbers (``built.info``: orders, ε, seconds of the prefilter,
        fit and mip stack, fit residual …) and description lines (``built.description``).
    cameras
        One per frame.
    frames
        ``pipeline.Frame`` per camera: linear composite radiance and coverage.
    timings
        First frame, frames per second, OpenGL back end (``pipeline.FrameTimings``).
    size
        Width and height of every frame in pixels.
    """

    mesh: Mesh
    mode: str
    built: BuiltModel
    cameras: tuple[Camera, ...]
    frames: list[Frame]
    timings: FrameTimings
    size: int

    _repr_html_ = scene_render_html  # notebook card and picture (render.notebook)
    _repr_png_ = scene_render_png

    @property
    def model(self) -> Any:
        """The model drawn (an SHRM, RSIBR maps, a Gaussian-lobe model …)."""
        return self.built.model


def _cameras(camera: Camera | Sequence[Camera] | None) -> tuple[Camera, ...]:
    if camera is None:
        return (Camera.looking_at(),)
    if isinstance(camera, Camera):
        return (camera,)
    cameras = tuple(camera)
    if not cameras or not all(isinstance(c, Camera) for c in cameras):
        raise BadInputError(None, "camera must be a Camera or a non-empty sequence of Cameras")
    return cameras


def render_scene(
    mesh: Mesh | str | Path,
    env: EnvironmentMap | str | Path,
    brdf: BRDF | str | Path,
    *,
    mode: str = DEFAULT_MODE,
    eps: float = DEFAULT_EPS,
    camera: Camera | Sequence[Camera] | None = None,
    size: int = 512,
    background: str = "env",
    fps_frames: int = 10,
    options: RenderOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> SceneRender:
    """Render ``mesh`` made of ``brdf`` under ``env`` in render ``mode``, offscreen.

    Parameters
    ----------
    mesh, env, brdf
        Loaded objects, or specs/paths for ``load_mesh``, ``load_env`` (no orientation options:
        load oriented files yourself) and ``load_brdf``.
    mode
        A name of the mode table (``render.modes.mode_names()``).
    eps
        Tolerance of the SHRM orders (``analysis.tolerance``); modes without an SHRM ignore it.
    camera
        A camera, a sequence of cameras (one frame each), or None for
        ``Camera.looking_at()`` (perspective, from +x, z up).
    size
        Frame width and height in pixels, within :data:`SIZE_RANGE`.
    background
        ``"env"`` (the environment seen along each ray), ``"black"`` or ``"transparent"``.
    fps_frames
        Repeated frames for the frames-per-second figure (0 skips it).
    options
        The builders' options (Gaussian lobes, elevations, self-shadowing, the SHRM modes' window
        against Gibbs ringing: ``RenderOptions(window="auto" | "lanczos" | "none")``); default
        ``RenderOptions()`` (window ``"auto"``). The SHRM modes clamp the radiance at 0 in the
        shader; ``built.info`` has the window used and the undershoot before and after it.
        ``RenderOptions(env_rotation=...)`` rotates the environment at view time, one rotation for
        every frame or one per camera (built once; the lights and background turn with it).
    progress
        Optional callable told the stage as each starts: ``"load"``, ``"build"``, ``"render"``.

    Raises
    ------
    BadInputError
        Unknown mode, ε outside (0, 1), size, background or frame count out of range,
        self-shadowing in a mode without it, several environment rotations but not one per camera,
        and anything the loaders and builders refuse.
    OffscreenError
        No offscreen OpenGL context.

    Examples
    --------
    >>> r = render_scene("builtin:sphere", "builtin:sky", "microfacet:sigma=0.2",
    ...                  mode="perpixel", size=256)                        # doctest: +SKIP
    >>> r.built.info["F"], r.built.info["P"], r.timings.fps                 # doctest: +SKIP
    >>> write_exr("sphere.exr", r.frames[0].linear, r.frames[0].alpha)      # doctest: +SKIP
    """
    record = get_mode(mode)
    eps = check_eps(eps)
    options = RenderOptions() if options is None else options
    if not isinstance(options, RenderOptions):
        raise BadInputError(None, f"options must be a RenderOptions, got {type(options).__name__}")
    if options.self_shadow and not record.self_shadow:
        raise BadInputError(None, f"self_shadow needs mode {' or '.join(self_shadow_modes())}, not {mode!r}")
    if isinstance(size, bool) or not isinstance(size, Integral) or not SIZE_RANGE[0] <= size <= SIZE_RANGE[1]:
        raise BadInputError(None, f"size must be an integer in [{SIZE_RANGE[0]}, {SIZE_RANGE[1]}], got {size!r}")
    if background not in BACKGROUNDS:
        raise BadInputError(None, f"background must be one of {', '.join(BACKGROUNDS)}, got {background!r}")
    if isinstance(fps_frames, bool) or not isinstance(fps_frames, Integral) or fps_frames < 0:
        raise BadInputError(None, f"fps_frames must be an integer >= 0, got {fps_frames!r}")
    size, fps_frames = int(size), int(fps_frames)
    cameras = _cameras(camera)
    rotations = options.rotations()
    if isinstance(rotations, list) and len(rotations) != len(cameras):
        raise BadInputError(None, f"options.env_rotation holds {len(rotations)} rotations for {len(cameras)} "
                            "camera(s): give one, or one per camera")

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    stage("load")
    mesh = mesh if isinstance(mesh, Mesh) else load_mesh(mesh)
    env = env if isinstance(env, EnvironmentMap) else load_env(env)
    brdf = brdf if isinstance(brdf, BRDF) else load_brdf(brdf)
    stage("build")
    built = record.build(env, brdf, mesh, eps=eps, options=options)
    stage("render")
    frames, timings = render_frames(
        mesh, built.model, cameras, size=size, mode=record.name, env_radiance=env.radiance,
        background=background, fps_frames=fps_frames, visibility_sh=built.visibility_sh, env_rotation=rotations,
    )
    return SceneRender(mesh, record.name, built, cameras, frames, timings, size)


@dataclass(frozen=True, eq=False)
class SequenceRender:
    """What :func:`render_sequence` made: one :class:`SceneRender` per environment.

    Attributes
    ----------
    renders
        One per environment, in the order given (each with its one frame, its model and timings).
    environments
        The environments' names (``EnvironmentMap.name``), in the same order.
    orders
        The BRDF's order choice shared by every frame, or None for a mode without SHRM orders
        (``RenderMode.uses_orders``) or when ``options.orders`` was given.
    orders_seconds
        Seconds the order choice took (once for the whole sequence; 0 when none was made).
    frame_seconds
        Per environment: seconds to build its model (the prefilter) and render its frame.
    """

    renders: tuple[SceneRender, ...]
    environments: tuple[str, ...]
    orders: OrderChoice | None
    orders_seconds: float
    frame_seconds: tuple[float, ...]

    _repr_html_ = sequence_render_html  # notebook card (render.notebook)

    @property
    def frames(self) -> list[Frame]:
        """The frames, one per environment."""
        return [r.frames[0] for r in self.renders]


def render_sequence(
    mesh: Mesh | str | Path,
    envs: Sequence[EnvironmentMap | str | Path],
    brdf: BRDF | str | Path,
    *,
    mode: str = DEFAULT_MODE,
    eps: float = DEFAULT_EPS,
    camera: Camera | None = None,
    size: int = 512,
    background: str = "env",
    fps_frames: int = 0,
    options: RenderOptions | None = None,
    progress: Callable[[str], None] | None = None,
) -> SequenceRender:
    """Render ``mesh`` made of ``brdf`` under each environment of ``envs``: one frame per map.

    The BRDF's orders (F, P) depend on the BRDF and the order rule only, so the SHRM modes choose
    them once (:func:`~shrmkit.analysis.orders.choose_orders` under ``options.rule_at(eps)``: ``eps``,
    ``options.criterion`` and ``options.max_view_deg``) and prefilter every map with them
    (``RenderOptions(orders=)``); each map's lights, F_B, window and stated errors are its own. Frame k equals
    ``render_scene(mesh, envs[k], brdf, ...)`` with the same arguments.

    Parameters
    ----------
    mesh, brdf
        As :func:`render_scene`; loaded once.
    envs
        A non-empty sequence of loaded maps or specs/paths for ``load_env``. Specs are all loaded
        before anything is prefiltered, so an unreadable member fails first, naming its file.
    mode, eps, size, background, options
        As :func:`render_scene`; ``options.env_rotation`` (one rotation) applies to every frame.
    camera
        One camera for every frame (None: ``Camera.looking_at()``).
    fps_frames
        Repeated frames for each frame's frames-per-second figure (default 0: none).
    progress
        Optional callable told ``"orders"`` and then ``"frame K/N"`` as each frame starts.

    Returns
    -------
    SequenceRender

    Raises
    ------
    BadInputError
        An empty sequence, a member that cannot be loaded (one line naming it), a camera that is
        not one :class:`Camera`, several environment rotations, and what :func:`render_scene` refuses.
    OffscreenError
        No offscreen OpenGL context.
    """
    record = get_mode(mode)
    eps = check_eps(eps)
    options = RenderOptions() if options is None else options
    if not isinstance(options, RenderOptions):
        raise BadInputError(None, f"options must be a RenderOptions, got {type(options).__name__}")
    if isinstance(envs, str | Path | EnvironmentMap) or not len(envs):
        raise BadInputError(None, "envs must be a non-empty sequence of environment maps or specs")
    if camera is not None and not isinstance(camera, Camera):
        raise BadInputError(None, "render_sequence takes one camera for every frame")
    if isinstance(options.rotations(), list):
        raise BadInputError(None, "render_sequence takes one environment rotation for every frame, not one per frame")

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    maps = [env if isinstance(env, EnvironmentMap) else load_env(env) for env in envs]  # every member first
    mesh = mesh if isinstance(mesh, Mesh) else load_mesh(mesh)
    brdf = brdf if isinstance(brdf, BRDF) else load_brdf(brdf)
    choice, orders_seconds = None, 0.0
    if record.uses_orders and options.orders is None:
        stage("orders")
        t0 = time.perf_counter()
        choice = choose_orders(brdf, rule=options.rule_at(eps))
        orders_seconds = time.perf_counter() - t0
        options = dataclasses.replace(options, orders=choice)
    renders, seconds = [], []
    for k, env in enumerate(maps):
        stage(f"frame {k + 1}/{len(maps)}")
        t0 = time.perf_counter()
        renders.append(render_scene(mesh, env, brdf, mode=record.name, eps=eps, camera=camera, size=size,
                                    background=background, fps_frames=fps_frames, options=options))
        seconds.append(time.perf_counter() - t0)
    return SequenceRender(tuple(renders), tuple(m.name for m in maps), choice, orders_seconds, tuple(seconds))
