"""Offscreen VTK renderer shading meshes in a GLSL fragment shader, one render mode per object.

One :class:`SHRMRenderer` holds a float-framebuffer offscreen window (see ``offscreen``)
and any number of objects, each a mesh with its own model (its material under its lighting:
an SHRM, RSIBR maps, Gaussian lobes …) drawn in a render mode of the table in ``modes``. The
mode's record makes the object's texture, shader replacements and vertex attributes
(``glsl.Shading``) and its per-frame texture update; this module only sets up the VTK actor,
once for every mode, and dispatches through the record. Rendering returns linear radiance
read back as float32, never clamped or quantized.

:class:`SHRMRenderer` documents the frame, what a frame does, and the deferred shading of the
per-pixel modes on CPU rasterizers (each covered pixel shaded once).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..brdf_io.env_rotation import check_env_rotation, to_map_frame
from ._closed_mesh import closed_outward
from ._vtk_deferred import (
    MAX_DEFERRED_OBJECTS,
    _Deferred,
    _deferred_actors,
    _gbuffer_texture,
    _quad_corners,
    _restore_depth,
    _screen_pass_depth,
)
from ._vtk_upload import _attribute_array, _float_texture, _new_actor, _polydata, _set_view_uniforms, _shader
from .camera import Camera, orbit_camera
from .glsl import Shading, gbuffer_fragment_replacements, vertex_replacements
from .mesh import Mesh
from .modes import DEFAULT_MODE, RenderMode, get_mode
from .offscreen import is_software_rasterizer, make_render_window, read_rgba_float

__all__ = ["SHRMRenderer", "RenderResult", "closed_outward"]


@dataclass(frozen=True, eq=False)
class RenderResult:
    """A rendered frame.

    Attributes
    ----------
    radiance
        float32 (H, W, 3) linear reflected radiance, 0 where no object covers the pixel.
    alpha
        float32 (H, W): 1 where an object covers the pixel centre, else 0.
    seconds
        Wall time of the frame (per-frame texture updates, draw, readback).
    """

    radiance: np.ndarray
    alpha: np.ndarray
    seconds: float


@dataclass(eq=False)
class _Object:
    mesh: Mesh
    model: Any
    mode: RenderMode
    actor: Any
    texture: Any
    image: Any  # vtkImageData sharing ``buffer``
    buffer: np.ndarray  # float32 (h·w, 3) texels, rewritten by the mode's per-frame update
    state: Any  # what the mode's update reads
    center: np.ndarray
    radius: float
    closed: bool  # closed, consistently and outward oriented: back faces never visible from outside
    deferred: _Deferred | None = None  # the deferred passes' actors, when the mode has them
    geometry: Any = None  # vtkActor writing R (the geometry pass's shader, tag 1), made by reflection_directions


class SHRMRenderer:
    """Render meshes shaded by SHRMs (or another mode's model), offscreen, with float readback.

    Frame: VTK world coordinates are the z-up math frame (``camera`` module docstring); meshes
    are uploaded in world coordinates with an identity actor matrix. The environment may be rotated
    per frame (``draw``/``render``'s ``env_rotation`` Q, ``brdf_io.env_rotation``): the shaders look
    up at Qᵀ R, Qᵀ V (``glsl.TO_MAP_UNIFORM``) and the per-frame maps are made for Qᵀ Ṽ; no texture
    changes.

    Per frame, ``draw`` only sets the camera, four uniforms and each object's back-face culling,
    runs the modes' texture updates and calls VTK's Render; shader replacements, textures and
    geometry are set up once in ``add_object``. Back faces are culled for an object whose mesh is
    closed and outward oriented (:func:`closed_outward`) while its bounding sphere lies wholly
    beyond the near plane: then they are all hidden, and culling them saves their rasterization
    and shading (on a CPU rasterizer, most of a frame) without changing a pixel.

    Deferred shading (``perpixel``, ``kautz-mccool``, and ``distant`` with explicit lights: the shadings
    whose ``Shading.deferred`` is set):
    when every object of the scene has it, a frame is two VTK renders. (1) The geometry pass draws
    each object k with a trivial shader writing its R (the prelude's reflected direction, unit, z-up
    world frame) times the tag 2^(k+1) (exact in float32) to the float colour buffer, with depth.
    (2) The screen pass keeps that depth buffer (``PreserveDepthBuffer``) and draws, per object, one
    quad filling the view just inside the far plane with depth test GL_GREATER and depth writes
    off: only covered pixels pass the depth test, before their shader runs (background blocks are
    skipped whole), and each is shaded once. Its fragment shader reads R back from the geometry
    pass's colour texture (the display framebuffer's GL_RGBA32F attachment, which VTK's blit at
    the end of pass 1 filled; no readback to the CPU), discards the pixels of other objects' tags,
    computes V from the quad's point (on the same pixel ray as the surface point) and evaluates
    the mode's sum ([RH02] eq. 8) once. The forward path shades each fragment of each small
    triangle: a CPU rasterizer (llvmpipe) shades whole 2×2 quads / 4×4 blocks of every one- or
    two-pixel triangle, plus overdraw. Images equal the forward path's to float rounding (R is
    passed exactly; V differs by the rounding of the interpolated point); coverage is identical.
    Scenes with an object of another mode, or built with ``deferred=False``, use the forward path;
    by default (``deferred=None``) the deferred path is used on CPU rasterizers only.


    Parameters
    ----------
    width, height
        Image size in pixels.
    deferred
        Shade per-pixel objects once per covered pixel (above) when every object of
        the scene can be; False always draws forward (the reference for the deferred path).
        None (default): deferred where the OpenGL renderer is a CPU rasterizer
        (:func:`~shrmkit.render.offscreen.is_software_rasterizer`: llvmpipe, SwiftShader, …),
        whose fragment shading of small triangles it cuts 2–3× (``benchmarks/render_speed.py``);
        forward on a GPU, where quads of small triangles cost little and the second render's
        fixed cost would not pay (the deferred path is not measured on a GPU).

    Examples
    --------
    >>> r = SHRMRenderer(256, 256)                                   # doctest: +SKIP
    >>> r.add_object(load_mesh("builtin:sphere"), shrm, mode="perpixel")  # doctest: +SKIP
    >>> frame = r.render(Camera.looking_at(view=(1, 0, 0)))        # doctest: +SKIP
    """

    def __init__(self, width: int, height: int, *, deferred: bool | None = None) -> None:
        self.width, self.height = int(width), int(height)
        self._window = make_render_window(self.width, self.height)
        self._renderer = self._window.GetRenderers().GetFirstRenderer()
        self._renderer.SetBackground(0.0, 0.0, 0.0)
        self._renderer.SetBackgroundAlpha(0.0)
        self._renderer.AutomaticLightCreationOff()
        self._objects: list[_Object] = []
        self._textures: dict[int, tuple[Shading, dict[str, Any]]] = {}  # Shading.textures, kept alive
        if deferred is None:
            deferred = is_software_rasterizer(self._window)
        self._gbuffer = _gbuffer_texture(self._window, self.width, self.height) if deferred else None
        self._deferred_frame = False
        if self._gbuffer is not None:
            # VTK resets the depth function only when it clears; the screen pass sets GL_GREATER
            self._renderer.AddObserver("EndEvent", self._restore_depth_state)

    def _restore_depth_state(self, *_: object) -> None:
        _restore_depth(self._window)

    def _screen_pass_state(self, *_: object) -> None:
        # the quad mapper's StartEvent, before it draws: pass only where pass 1 left a surface
        _screen_pass_depth(self._window)

    @property
    def deferred(self) -> bool:
        """Whether the next frame is drawn deferred (every object has a deferred pass)."""
        return (self._gbuffer is not None and 0 < len(self._objects) <= MAX_DEFERRED_OBJECTS
                and all(o.deferred is not None for o in self._objects))

    @property
    def render_window(self):  # -> vtkRenderWindow
        """The offscreen vtkRenderWindow (for timing with its Start/End events; do not resize it)."""
        return self._window

    @property
    def backend(self) -> str:
        """The VTK window class in use (e.g. vtkEGLRenderWindow)."""
        return str(self._window.GetClassName())

    def add_object(
        self,
        mesh: Mesh,
        model: Any,
        *,
        mode: str = DEFAULT_MODE,
        visibility_sh: np.ndarray | None = None,
        normalized_visibility: bool = True,
        views: Any = None,
    ) -> int:
        """Add a mesh shaded by ``model`` in render ``mode``; returns the object's index.

        ``model`` is what the mode's record accepts (``modes.RENDER_MODES[mode].models``): an
        SHRM for ``distant``, ``perpixel`` and ``kautz-mccool`` (an azimuth-free SHRM), RSIBR
        maps or an SHRM for ``rsibr``, a ``GaussianLobeModel`` for ``gaussian-lobes``. In the
        modes with self-shadowing, ``visibility_sh`` (n_vertices, 25), the order-4 SH visibility
        of each vertex (``analysis.baselines.selfshadow.vertex_visibility_sh``), turns it on
        (Green et al. 2007 eq. 7), ``normalized_visibility`` as in ``selfshadow.visibility_at``.
        ``views``: only these views will be drawn (``RenderMode.prepare``; ``pipeline.view_cones``).
        Raises ValueError for an unknown mode or a model or visibility the mode does not take.
        """
        record = get_mode(mode)
        shading = record.prepare(model, mesh, visibility_sh, normalized_visibility, views=views)
        actor, tex, data, buf = self._actor(mesh, shading)
        self._renderer.AddActor(actor)
        center, radius = mesh.bounding_sphere()
        obj = _Object(mesh, model, record, actor, tex, data, buf, shading.state, center, radius, closed_outward(mesh))
        if self._gbuffer is not None and shading.deferred is not None:
            obj.deferred = _deferred_actors(self._renderer, self._gbuffer, actor, tex, shading, len(self._objects),
                                        self._extra_textures(shading), self._screen_pass_state)
        self._objects.append(obj)
        return len(self._objects) - 1

    def _extra_textures(self, shading: Shading) -> dict[str, Any]:
        """The shading's further textures (``Shading.textures``), made once per Shading and kept
        alive with their buffers for the renderer's lifetime."""
        key = id(shading)
        if key not in self._textures:
            made = {name: _float_texture(image) for name, image in shading.textures.items()}
            self._textures[key] = (shading, made)
        return {name: parts[0] for name, parts in self._textures[key][1].items()}

    def _actor(self, mesh: Mesh, shading: Shading):  # -> (vtkActor, vtkTexture, vtkImageData, buffer)
        """The one VTK set-up of every mode: mapper, actor, texture, shader replacements, uniforms."""
        from vtkmodules.vtkCommonDataModel import vtkDataObject  # lazy: VTK is loaded only when rendering

        tex, data, buf = _float_texture(shading.texture)
        actor = _new_actor(_polydata(mesh, shading.attributes))
        for name in shading.attributes:
            actor.GetMapper().MapDataArrayToVertexAttribute(
                name, _attribute_array(name), vtkDataObject.FIELD_ASSOCIATION_POINTS, -1
            )
        actor.GetProperty().SetTexture("shrmTex", tex)
        for name, extra in self._extra_textures(shading).items():
            actor.GetProperty().SetTexture(name, extra)
        _shader(actor, shading.vertex, shading.fragment, uniforms=shading.uniforms)
        return actor, tex, data, buf

    def update_view_maps(self, camera: Camera, env_rotation: np.ndarray | None = None) -> None:
        """Run each object's per-frame texture update (its mode's ``update``) and mark the texture for upload.

        The update gets Ṽ, the direction from the object's bounding-sphere centre toward the
        camera (distant: the map Σ B̃_pq Y^r_pq(Ṽ) of RH02 eq. 12; rsibr: the blended view map),
        in the unrotated environment's frame (Qᵀ Ṽ for ``env_rotation`` Q, a (3, 3) rotation).
        """
        for obj in self._objects:
            if obj.mode.update is None:
                continue
            view = to_map_frame(camera.view_direction(obj.center), env_rotation)
            # obj.buffer is shared with the vtkImageData (no copy); Modified() re-uploads it
            obj.mode.update(obj.state, view, obj.buffer)
            obj.image.Modified()

    def _clipping(self, camera: Camera) -> tuple[float, float]:
        """Near and far planes about every object's bounding sphere."""
        if not self._objects:
            raise ValueError("nothing to render: add an object first")
        centers = np.array([o.center for o in self._objects])
        radii = np.array([o.radius for o in self._objects])
        dist = np.linalg.norm(centers - camera.eye, axis=1)
        near = max(float(np.min(dist - radii)) * 0.99, 1e-3 * float(np.max(dist + radii)))
        return near, float(np.max(dist + radii)) * 1.01

    @staticmethod
    def _cull(obj: _Object, camera: Camera, near: float) -> bool:
        """Whether ``obj``'s back faces can be culled from ``camera`` without changing a pixel.

        Back faces of a closed, outward-oriented surface are hidden behind its front faces
        whenever the view rays start outside the solid; with its bounding sphere wholly
        beyond the near plane they do (and the near plane cuts nothing open), so culling
        them skips their rasterization and shading and changes no pixel.
        """
        depth = float(np.dot(obj.center - camera.eye, camera.forward))
        return bool(obj.closed and depth - obj.radius >= near)

    def _setup(self, camera: Camera, update_maps: bool = True, env_rotation: np.ndarray | None = None) -> None:
        near, far = self._clipping(camera)
        camera.apply_to(self._renderer.GetActiveCamera(), (near, far))
        self._deferred_frame = self.deferred
        corners = _quad_corners(camera, far, self.width, self.height) if self._deferred_frame else None
        for obj in self._objects:
            cull = self._cull(obj, camera, near)
            actors: tuple[Any, ...]
            if self._deferred_frame:  # the mesh drawn in pass 1, the quad (never culled) in pass 2
                deferred = obj.deferred
                assert deferred is not None  # a deferred frame: every object has its passes (self.deferred)
                deferred.gbuffer.GetProperty().SetBackfaceCulling(cull)
                deferred.quad_points[...] = corners
                deferred.screen.GetMapper().GetInput().GetPoints().Modified()
                actors = (deferred.gbuffer, deferred.screen)
            else:
                obj.actor.GetProperty().SetBackfaceCulling(cull)
                actors = (obj.actor,)
            for actor in actors:
                _set_view_uniforms(actor, camera, env_rotation)
        if update_maps:
            self.update_view_maps(camera, env_rotation)

    def draw(self, camera: Camera, *, update_maps: bool = True, env_rotation: Any = None) -> None:
        """Render one frame into the offscreen framebuffer (no readback; for timing).

        ``env_rotation``: the environment rotated by Q for this frame (a (3, 3) rotation, Euler
        angles (AZ, EL[, ROLL]) in degrees, or None; ``brdf_io.env_rotation``, BadInputError for
        anything else): every object is shaded at Qᵀ R, Qᵀ V, its lights moved with the map.

        A deferred frame (:attr:`deferred`) is two VTK renders: the geometry pass, then the
        screen pass (class docstring).

        ``update_maps=False`` keeps the distant-mode maps of the previous frame (only for
        measuring the cost of the per-frame map update).
        """
        self._setup(camera, update_maps, check_env_rotation(env_rotation))
        if not self._deferred_frame:
            self._show(forward=True, gbuffer=False, screen=False)
            self._window.Render()
            return
        self._show(forward=False, gbuffer=True, screen=False)
        self._window.Render()  # pass 1: R · tag and depth; VTK's blit leaves it in the G-buffer texture
        self._show(forward=False, gbuffer=False, screen=True)
        self._renderer.PreserveDepthBufferOn()
        try:
            self._window.Render()  # pass 2: each covered pixel shaded once
        finally:
            self._renderer.PreserveDepthBufferOff()

    def _show(self, *, forward: bool, gbuffer: bool, screen: bool) -> None:
        for obj in self._objects:
            obj.actor.SetVisibility(forward)
            if obj.deferred is not None:
                obj.deferred.gbuffer.SetVisibility(gbuffer)
                obj.deferred.screen.SetVisibility(screen)

    def finish(self) -> None:
        """Block until the OpenGL commands issued so far have completed (glFinish)."""
        self._window.WaitForCompletion()

    def frames_per_second(self, camera: Camera, n_frames: int = 10, center: ArrayLike = (0.0, 0.0, 0.0)) -> float:
        """Frames per second over ``n_frames`` draws while orbiting ``camera`` about z (no readback).

        Each frame changes the view, so distant-mode maps are recomputed and re-uploaded.
        """
        if n_frames < 1:
            raise ValueError(f"n_frames must be >= 1, got {n_frames}")
        self.draw(camera)
        self.finish()
        t0 = time.perf_counter()
        for k in range(n_frames):
            self.draw(orbit_camera(camera, np.asarray(center, float), 2.0 * np.pi * (k + 1) / (n_frames + 1)))
        self.finish()
        return n_frames / (time.perf_counter() - t0)

    def render(self, camera: Camera, *, env_rotation: Any = None) -> RenderResult:
        """Render one frame and read back linear radiance and coverage (``env_rotation`` as in :meth:`draw`)."""
        t0 = time.perf_counter()
        self.draw(camera, env_rotation=env_rotation)
        rgba = read_rgba_float(self._window)
        return RenderResult(rgba[..., :3].copy(), rgba[..., 3].copy(), time.perf_counter() - t0)

    def reflection_directions(self, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
        """The reflection direction R at each pixel centre, as the fragment shaders compute it.

        Draws the objects once more with the deferred geometry pass's shader (the shared prelude's
        R, unit, z-up world frame; tag 1) — forward, with the frame's camera, clipping planes and
        back-face culling — and reads the float colour buffer back: the R every mode shades each
        pixel with (the view direction there is the pixel's camera ray reversed,
        ``Camera.rays``). For per-pixel statements on any mesh (``render.error_image``).

        Returns
        -------
        R
            float32 (H, W, 3), row 0 at the top; 0 where no object covers the pixel centre.
        coverage
            float32 (H, W): 1 where an object covers the pixel centre, else 0.
        """
        near, far = self._clipping(camera)
        camera.apply_to(self._renderer.GetActiveCamera(), (near, far))
        for obj in self._objects:
            if obj.geometry is None:
                obj.geometry = _new_actor(obj.actor.GetMapper().GetInput())
                _shader(obj.geometry, vertex_replacements(), gbuffer_fragment_replacements(), 1.0)
                self._renderer.AddActor(obj.geometry)
            obj.geometry.GetProperty().SetBackfaceCulling(self._cull(obj, camera, near))
            _set_view_uniforms(obj.geometry, camera)
        self._show(forward=False, gbuffer=False, screen=False)
        try:
            for obj in self._objects:
                obj.geometry.SetVisibility(True)
            self._window.Render()
            rgba = read_rgba_float(self._window)
        finally:
            for obj in self._objects:
                obj.geometry.SetVisibility(False)
        return rgba[..., :3].copy(), rgba[..., 3].copy()

    def close(self) -> None:
        """Release the OpenGL context."""
        self._window.Finalize()

    def __enter__(self) -> SHRMRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
