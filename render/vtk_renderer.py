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

from ..analysis.components import connected_labels
from ..brdf_io.env_rotation import check_env_rotation, to_map_frame
from .camera import Camera, orbit_camera
from .glsl import TO_MAP_UNIFORM, Shading, gbuffer_fragment_replacements, vertex_replacements
from .mesh import Mesh, make_mesh
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


def _float_texture(image: np.ndarray):  # -> (vtkTexture, vtkImageData, numpy buffer)
    """A float texture of the (h, w, 3) or (h, w, 4) image: GL_RGB32F or GL_RGBA32F, texels exact."""
    from vtkmodules.util.numpy_support import numpy_to_vtk  # lazy: VTK is loaded only when rendering
    from vtkmodules.vtkCommonDataModel import vtkImageData  # lazy: VTK
    from vtkmodules.vtkRenderingCore import vtkTexture  # lazy: VTK

    h, w, channels = image.shape
    buf = np.ascontiguousarray(image, dtype=np.float32).reshape(h * w, channels)
    data = vtkImageData()
    data.SetDimensions(w, h, 1)  # x (columns) fastest, then rows: texel (x, y) = image[y, x]
    arr = numpy_to_vtk(buf, deep=0)
    arr.SetName("shrm")
    data.GetPointData().SetScalars(arr)
    tex = vtkTexture()
    tex.SetInputData(data)
    tex.SetColorModeToDirectScalars()  # float32 texels as they are (GL_RGB32F), no colour mapping
    tex.InterpolateOff()
    tex.MipmapOff()
    tex.SetUseSRGBColorSpace(False)
    return tex, data, buf


def _set_uniforms(actor, uniforms: dict[str, tuple[str, list[float]]]) -> None:
    """Set constant uniforms (``Shading.uniforms``: float, int, vec3, vec3[]) on the mapper's shader
    program each time it is bound (its UpdateShaderEvent). The GLSL declares them (the shared
    ``render/webgl`` files), so they are not VTK custom uniforms (VTK would declare those again),
    and vtkUniforms cannot hold a vec3 array from Python."""
    if not uniforms:
        return
    from vtkmodules.util.misc import calldata_type  # lazy: VTK
    from vtkmodules.util.vtkConstants import VTK_OBJECT  # lazy: VTK
    from vtkmodules.vtkCommonCore import vtkCommand  # lazy: VTK

    calls: list[tuple[str, tuple[Any, ...]]] = []
    for name, (kind, values) in uniforms.items():
        values = [float(v) for v in values]
        if kind == "float":
            calls.append(("SetUniformf", (name, values[0])))
        elif kind == "int":
            calls.append(("SetUniformi", (name, int(values[0]))))
        elif kind == "vec3":
            calls.append(("SetUniform3f", (name, values)))
        elif kind == "vec3[]":
            calls.append(("SetUniform3fv", (name, len(values) // 3, values)))
        else:
            raise ValueError(f"uniform {name}: unknown type {kind!r}")

    @calldata_type(VTK_OBJECT)
    def upload(_caller, _event, program) -> None:  # the vtkShaderProgram the mapper has bound
        for method, args in calls:
            getattr(program, method)(*args)

    actor.GetMapper().AddObserver(vtkCommand.UpdateShaderEvent, upload)


def _attribute_array(name: str) -> str:
    """Name of the point-data array that feeds the vertex attribute ``name``."""
    return f"{name}_data"


def _polydata(mesh: Mesh, attributes: dict[str, np.ndarray]):
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray  # lazy: VTK
    from vtkmodules.vtkCommonCore import vtkPoints  # lazy: VTK
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData  # lazy: VTK

    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(mesh.vertices, dtype=np.float32), deep=1))
    cells = vtkCellArray()
    offsets = np.arange(0, 3 * mesh.n_triangles + 1, 3, dtype=np.int64)
    cells.SetData(
        numpy_to_vtkIdTypeArray(offsets, deep=1),
        numpy_to_vtkIdTypeArray(np.ascontiguousarray(mesh.faces.reshape(-1), dtype=np.int64), deep=1),
    )
    poly = vtkPolyData()
    poly.SetPoints(pts)
    poly.SetPolys(cells)
    normals = numpy_to_vtk(np.ascontiguousarray(mesh.normals, dtype=np.float32), deep=1)
    normals.SetName("Normals")
    poly.GetPointData().SetNormals(normals)
    for name, values in attributes.items():  # per-vertex vec4 attributes of the mode
        arr = numpy_to_vtk(np.ascontiguousarray(values, dtype=np.float32), deep=1)
        arr.SetName(_attribute_array(name))
        poly.GetPointData().AddArray(arr)
    return poly


def closed_outward(mesh: Mesh) -> bool:
    """Whether ``mesh`` is a closed surface whose faces all wind counter-clockwise seen from outside.

    True when every directed edge (a → b) of the faces occurs exactly once and its reverse
    (b → a) exactly once (closed and consistently oriented: each edge is shared by two faces
    that traverse it in opposite directions), and every connected piece encloses a positive
    signed volume Σ a·(b × c)/6 (outward orientation). For such a mesh, seen from outside its
    bounding sphere, every back face lies behind a front face of the same piece, so culling
    back faces changes no pixel. Meshes with open borders, non-manifold or inconsistently
    wound edges, split seam vertices, or a cavity (a piece with inward orientation) give False.
    """
    faces = np.asarray(mesh.faces, dtype=np.int64)
    n = len(mesh.vertices)
    a = faces.reshape(-1)
    b = faces[:, [1, 2, 0]].reshape(-1)
    directed = np.sort(a * n + b)
    if np.any(directed[1:] == directed[:-1]) or not np.array_equal(directed, np.sort(b * n + a)):
        return False
    label = connected_labels(a, b, n)
    v = mesh.vertices
    volume6 = np.einsum("ij,ij->i", v[faces[:, 0]], np.cross(v[faces[:, 1]], v[faces[:, 2]]))
    return bool(np.all(np.bincount(label[faces[:, 0]], weights=volume6) > 0.0))


#: GL_LEQUAL (VTK's depth function), GL_GREATER (the deferred screen pass's)
GL_LEQUAL, GL_GREATER = 0x0203, 0x0204
#: Most objects tagged in one deferred frame: tags 2^1 … 2^64 times a unit R stay finite in
#: float32, and the screen pass divides by the tag before it measures |R|
MAX_DEFERRED_OBJECTS = 64


@dataclass(eq=False)
class _Deferred:
    """The two extra actors of a deferred object and the quad's vertex buffer."""

    gbuffer: Any  # vtkActor: the mesh writing R · 2^(k+1)
    screen: Any  # vtkActor: the quad filling the view, shading each covered pixel once
    quad_points: np.ndarray  # float32 (4, 3), shared with the quad's vtkPoints


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


def _to_map_values(env_rotation: np.ndarray | None) -> list[float]:
    """The 9 floats of the uniform :data:`~shrmkit.render.glsl.TO_MAP_UNIFORM` (the GLSL matrix Qᵀ):
    OpenGL reads them column by column (glUniformMatrix3fv, no transpose), and the columns of Qᵀ
    are the rows of Q."""
    q = np.eye(3) if env_rotation is None else np.asarray(env_rotation, dtype=np.float64)
    return [float(x) for x in q.reshape(-1)]


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
        self._gbuffer = self._gbuffer_texture() if deferred else None
        self._deferred_frame = False
        if self._gbuffer is not None:
            # VTK resets the depth function only when it clears; the screen pass sets GL_GREATER
            self._renderer.AddObserver("EndEvent", self._restore_depth_state)

    def _gbuffer_texture(self):  # -> vtkOpenGLTexture or None
        """The display framebuffer's colour texture (what pass 1 leaves), wrapped for a sampler."""
        from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLTexture  # lazy: VTK

        fbo = self._window.GetDisplayFramebuffer()
        colour = None if fbo is None else fbo.GetColorAttachmentAsTextureObject(0)
        if colour is None or (colour.GetWidth(), colour.GetHeight()) != (self.width, self.height):
            return None
        tex = vtkOpenGLTexture()
        tex.SetTextureObject(colour)
        return tex

    def _restore_depth_state(self, *_: object) -> None:
        state = self._window.GetState()
        state.vtkglDepthFunc(GL_LEQUAL)
        state.vtkglDepthMask(True)

    def _screen_pass_state(self, *_: object) -> None:
        # the quad mapper's StartEvent, before it draws: pass only where pass 1 left a surface
        state = self._window.GetState()
        state.vtkglDepthFunc(GL_GREATER)
        state.vtkglDepthMask(False)

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
    ) -> int:
        """Add a mesh shaded by ``model`` in render ``mode``; returns the object's index.

        ``model`` is what the mode's record accepts (``modes.RENDER_MODES[mode].models``): an
        SHRM for ``distant``, ``perpixel`` and ``kautz-mccool`` (an azimuth-free SHRM), RSIBR
        maps or an SHRM for ``rsibr``, a ``GaussianLobeModel`` for ``gaussian-lobes``. In the
        modes with self-shadowing, ``visibility_sh`` (n_vertices, 25), the order-4 SH visibility
        of each vertex (``analysis.baselines.selfshadow.vertex_visibility_sh``), turns it on
        (Green et al. 2007 eq. 7), ``normalized_visibility`` as in ``selfshadow.visibility_at``.
        Raises ValueError for an unknown mode or a model or visibility the mode does not take.
        """
        record = get_mode(mode)
        shading = record.prepare(model, mesh, visibility_sh, normalized_visibility)
        actor, tex, data, buf = self._actor(mesh, shading)
        self._renderer.AddActor(actor)
        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        center = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(mesh.vertices - center, axis=1)))
        obj = _Object(mesh, model, record, actor, tex, data, buf, shading.state, center, radius, closed_outward(mesh))
        if self._gbuffer is not None and shading.deferred is not None:
            obj.deferred = self._deferred_actors(actor, tex, shading, len(self._objects))
        self._objects.append(obj)
        return len(self._objects) - 1

    def _deferred_actors(self, actor, tex, shading: Shading, index: int) -> _Deferred:
        """The geometry-pass actor (same polydata as ``actor``) and the screen quad of object ``index``."""
        from vtkmodules.util.numpy_support import numpy_to_vtk  # lazy: VTK

        scale = float(2.0 ** (index + 1))
        # its own mapper (its own shader program) on the same polydata
        gbuffer = self._new_actor(actor.GetMapper().GetInput())
        self._shader(gbuffer, vertex_replacements(), gbuffer_fragment_replacements(), scale)
        self._renderer.AddActor(gbuffer)

        # a unit square for the mesh checks; its corners are rewritten every frame (_quad_corners)
        square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
        quad = make_mesh(square, np.array([[0, 1, 2], [0, 2, 3]]), np.tile([0.0, 0.0, 1.0], (4, 1)),
                         normalize=False)
        poly = _polydata(quad, {})
        points = np.zeros((4, 3), dtype=np.float32)
        poly.GetPoints().SetData(numpy_to_vtk(points, deep=0))  # shares ``points``
        screen = self._new_actor(poly)
        screen.GetMapper().AddObserver("StartEvent", self._screen_pass_state)
        screen.GetProperty().SetTexture("shrmTex", tex)
        screen.GetProperty().SetTexture("shrmGbuf", self._gbuffer)
        for name, extra in self._extra_textures(shading).items():
            screen.GetProperty().SetTexture(name, extra)
        assert shading.deferred is not None  # add_object calls this for modes with a deferred pass only
        self._shader(screen, shading.vertex, shading.deferred, scale, shading.uniforms)
        self._renderer.AddActor(screen)
        gbuffer.SetVisibility(False)
        screen.SetVisibility(False)
        return _Deferred(gbuffer, screen, points)

    @staticmethod
    def _new_actor(polydata):  # -> vtkActor
        """An actor drawing ``polydata`` through its own mapper, world coordinates as given."""
        from vtkmodules.vtkRenderingCore import vtkActor  # lazy: VTK
        from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLPolyDataMapper  # lazy: VTK

        mapper = vtkOpenGLPolyDataMapper()
        mapper.SetInputData(polydata)
        mapper.SetVBOShiftScaleMethod(0)  # DISABLE_SHIFT_SCALE: vertexMC must be world coordinates
        mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        return actor

    @staticmethod
    def _shader(actor, vertex: list[tuple[str, str]], fragment: list[tuple[str, str]],
                scale: float | None = None, uniforms: dict[str, tuple[str, list[float]]] | None = None) -> None:
        """Shader replacements, the uniforms every frame sets (``shrmGScale``: a deferred pass's tag)
        and the shading's constant ``uniforms`` (``Shading.uniforms``: the lights and the BRDF)."""
        sp = actor.GetShaderProperty()
        for tag, text in vertex:
            sp.AddVertexShaderReplacement(tag, True, text, False)
        for tag, text in fragment:
            sp.AddFragmentShaderReplacement(tag, True, text, False)
        uni = sp.GetFragmentCustomUniforms()
        uni.SetUniform3f("shrmEye", [0.0, 0.0, 0.0])
        uni.SetUniform3f("shrmViewDir", [1.0, 0.0, 0.0])
        uni.SetUniformi("shrmOrtho", 0)
        uni.SetUniformMatrix3x3(TO_MAP_UNIFORM, _to_map_values(None))
        if scale is not None:
            uni.SetUniformf("shrmGScale", scale)
        _set_uniforms(actor, uniforms or {})

    def _quad_corners(self, camera: Camera, far: float) -> np.ndarray:
        """(4, 3) world corners of a quad filling the view (with a margin) at depth far / 1.004."""
        d = far / 1.004  # beyond every surface (all within far / 1.01), inside the far plane
        half_h = camera.parallel_scale if camera.projection == "ortho" else d * np.tan(0.5 * camera.fov_y)
        half_w = half_h * self.width / self.height
        c = camera.eye + d * camera.forward
        x, y = 1.25 * half_w * camera.right, 1.25 * half_h * camera.up
        return np.array([c - x - y, c + x - y, c + x + y, c - x + y])

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
        actor = SHRMRenderer._new_actor(_polydata(mesh, shading.attributes))
        for name in shading.attributes:
            actor.GetMapper().MapDataArrayToVertexAttribute(
                name, _attribute_array(name), vtkDataObject.FIELD_ASSOCIATION_POINTS, -1
            )
        actor.GetProperty().SetTexture("shrmTex", tex)
        for name, extra in self._extra_textures(shading).items():
            actor.GetProperty().SetTexture(name, extra)
        SHRMRenderer._shader(actor, shading.vertex, shading.fragment, uniforms=shading.uniforms)
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

    @staticmethod
    def _set_view_uniforms(actor, camera: Camera, env_rotation: np.ndarray | None = None) -> None:
        uni = actor.GetShaderProperty().GetFragmentCustomUniforms()
        uni.SetUniform3f("shrmEye", camera.eye.tolist())
        uni.SetUniform3f("shrmViewDir", (-camera.forward).tolist())
        uni.SetUniformi("shrmOrtho", 1 if camera.projection == "ortho" else 0)
        uni.SetUniformMatrix3x3(TO_MAP_UNIFORM, _to_map_values(env_rotation))

    def _setup(self, camera: Camera, update_maps: bool = True, env_rotation: np.ndarray | None = None) -> None:
        near, far = self._clipping(camera)
        camera.apply_to(self._renderer.GetActiveCamera(), (near, far))
        self._deferred_frame = self.deferred
        corners = self._quad_corners(camera, far) if self._deferred_frame else None
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
                self._set_view_uniforms(actor, camera, env_rotation)
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
                obj.geometry = self._new_actor(obj.actor.GetMapper().GetInput())
                self._shader(obj.geometry, vertex_replacements(), gbuffer_fragment_replacements(), 1.0)
                self._renderer.AddActor(obj.geometry)
            obj.geometry.GetProperty().SetBackfaceCulling(self._cull(obj, camera, near))
            self._set_view_uniforms(obj.geometry, camera)
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
