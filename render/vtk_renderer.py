"""Offscreen VTK renderer shading meshes from global SHRMs in a GLSL fragment shader.

One :class:`SHRMRenderer` holds a float-framebuffer offscreen window (see ``offscreen``)
and any number of objects, each a mesh with its own SHRM (its material under its lighting)
and mode (``distant`` or ``perpixel``, see ``shader``), or, in mode ``gaussian-lobes``, a
``GaussianLobeModel`` (Green et al. 2007 lobes + SG mip stack, see ``gaussian_shader``).
Rendering returns linear radiance read back as float32, never clamped or quantized.

Frame: VTK world coordinates are the z-up math frame (``camera`` module docstring); meshes
are uploaded in world coordinates with an identity actor matrix.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..analysis.baselines.gaussian_lobes import GaussianLobeModel
from ..analysis.sh import real_sph_harm
from ..analysis.shrm import SHRM
from .camera import Camera, orbit_camera
from .gaussian_shader import (
    N_VIS_ATTRIBUTES,
    gaussian_fragment_replacements,
    gaussian_vertex_replacements,
    sg_atlas,
)
from .mesh import Mesh
from .offscreen import make_render_window, read_rgba_float
from .shader import MODES, atlas_layout, fragment_replacements, vertex_replacements

__all__ = ["SHRMRenderer", "RenderResult", "coefficient_atlas", "RENDER_MODES"]

#: Shader modes plus ``rsibr`` (Cabral et al. 1999: the distant-mode shader fed, per frame, the
#: spherical-barycentric blend of twelve maps made from the SHRM at the icosahedron's
#: vertices, ``analysis.baselines.rsibr``). Kautz–McCool is the SHRM shader fed an
#: azimuth-free SHRM (``prefilter(..., azimuth_free=True)``), so it needs no mode here.
#: ``gaussian-lobes``: Green, Kautz & Durand 2007 (``analysis.baselines.gaussian_lobes``), fed a
#: ``GaussianLobeModel`` in place of the SHRM.
RENDER_MODES = MODES + ("rsibr", "gaussian-lobes")

#: Largest texture edge we rely on (llvmpipe and current GPUs allow at least 16384).
MAX_TEXTURE_SIZE = 16384


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
        Wall time of the frame (dynamic-map update, draw, readback).
    """

    radiance: np.ndarray
    alpha: np.ndarray
    seconds: float


def coefficient_atlas(coeffs: np.ndarray) -> np.ndarray:
    """Tile the (n, H, W, 3) coefficient maps into one float32 (rows·H, cols·W, 3) image.

    Tile c sits at rows [r·H, (r+1)·H), columns [k·W, (k+1)·W) with k = c mod cols,
    r = c div cols (``shader.atlas_layout``); texture row 0 is the first array row.
    """
    n, h, w, _ = coeffs.shape
    cols, rows = atlas_layout(n)
    out = np.zeros((rows * h, cols * w, 3), dtype=np.float32)
    for c in range(n):
        r, k = divmod(c, cols)
        out[r * h:(r + 1) * h, k * w:(k + 1) * w] = coeffs[c]
    return out


def _float_texture(image: np.ndarray):  # -> (vtkTexture, vtkImageData, numpy buffer)
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkRenderingCore import vtkTexture

    h, w, _ = image.shape
    buf = np.ascontiguousarray(image, dtype=np.float32).reshape(h * w, 3)
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


def _polydata(mesh: Mesh, visibility_sh: np.ndarray | None = None):
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

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
    if visibility_sh is not None:  # 25 SH-4 coefficients per vertex as 7 vec4 arrays (last padded)
        padded = np.zeros((mesh.vertices.shape[0], 4 * N_VIS_ATTRIBUTES), dtype=np.float32)
        padded[:, :visibility_sh.shape[1]] = visibility_sh
        for i in range(N_VIS_ATTRIBUTES):
            arr = numpy_to_vtk(np.ascontiguousarray(padded[:, 4 * i:4 * i + 4]), deep=1)
            arr.SetName(f"glVisArray{i}")
            poly.GetPointData().AddArray(arr)
    return poly


@dataclass(eq=False)
class _Object:
    mesh: Mesh
    shrm: SHRM | GaussianLobeModel
    mode: str
    actor: object
    texture: object
    image: object
    buffer: np.ndarray
    center: np.ndarray
    radius: float
    flat_coeffs: np.ndarray | None  # (n, H·W·3) for the distant-mode update
    rsibr: object = None  # RSIBRMaps for mode "rsibr"


class SHRMRenderer:
    """Render meshes shaded by global SHRMs, offscreen, with float readback.

    Parameters
    ----------
    width, height
        Image size in pixels.

    Examples
    --------
    >>> r = SHRMRenderer(256, 256)                                   # doctest: +SKIP
    >>> r.add_object(load_mesh("builtin:sphere"), shrm, mode="perpixel")  # doctest: +SKIP
    >>> frame = r.render(Camera.looking_at(view=(1, 0, 0)))        # doctest: +SKIP
    """

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = int(width), int(height)
        self._window = make_render_window(self.width, self.height)
        self._renderer = self._window.GetRenderers().GetFirstRenderer()
        self._renderer.SetBackground(0.0, 0.0, 0.0)
        self._renderer.SetBackgroundAlpha(0.0)
        self._renderer.AutomaticLightCreationOff()
        self._objects: list[_Object] = []

    @property
    def backend(self) -> str:
        """The VTK window class in use (e.g. vtkEGLRenderWindow)."""
        return str(self._window.GetClassName())

    def add_object(
        self,
        mesh: Mesh,
        shrm: SHRM | GaussianLobeModel,
        *,
        mode: str = "distant",
        visibility_sh: np.ndarray | None = None,
        normalized_visibility: bool = True,
    ) -> int:
        """Add a mesh shaded by ``shrm`` in ``mode``; returns the object's index.

        For ``mode="gaussian-lobes"`` pass a ``GaussianLobeModel`` as ``shrm``; then
        ``visibility_sh`` (n_vertices, 25), the order-4 SH visibility of each vertex
        (``analysis.baselines.selfshadow.vertex_visibility_sh``), turns on self-shadowing
        (Green et al. 2007 eq. 7), ``normalized_visibility`` as in ``selfshadow.visibility_at``.
        """
        from vtkmodules.vtkRenderingCore import vtkActor
        from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLPolyDataMapper

        if mode not in RENDER_MODES:
            raise ValueError(f"mode must be one of {RENDER_MODES}, got {mode!r}")
        if (mode == "gaussian-lobes") != isinstance(shrm, GaussianLobeModel):
            raise ValueError("mode 'gaussian-lobes' takes a GaussianLobeModel, the other modes an SHRM")
        if visibility_sh is not None:
            if mode != "gaussian-lobes":
                raise ValueError("visibility_sh (self-shadowing) is only supported in mode 'gaussian-lobes'")
            visibility_sh = np.asarray(visibility_sh, dtype=np.float64)
            if visibility_sh.shape != (mesh.vertices.shape[0], 25) or not np.all(np.isfinite(visibility_sh)):
                raise ValueError(f"visibility_sh must be finite (n_vertices={mesh.vertices.shape[0]}, 25), "
                                 f"got shape {visibility_sh.shape}")
        if mode == "gaussian-lobes":
            if visibility_sh is not None and normalized_visibility:
                from ..analysis.baselines.selfshadow import hemisphere_step_sh

                # the shader gets occlusion coefficients: unoccluded vertex step − visibility
                visibility_sh = hemisphere_step_sh(mesh.normals, 4) - visibility_sh
            return self._add_gaussian(mesh, shrm, visibility_sh, normalized_visibility)
        rsibr = None
        if mode == "rsibr":
            from ..analysis.baselines.rsibr import rsibr_from_shrm

            rsibr = rsibr_from_shrm(shrm)
        n, h, w, _ = shrm.coeffs.shape
        if mode == "perpixel":
            cols, rows = atlas_layout(n)
            if max(cols * w, rows * h) > MAX_TEXTURE_SIZE:
                raise ValueError(
                    f"SHRM with P={shrm.P} on {h}x{w} needs a {rows * h}x{cols * w} texture "
                    f"(limit {MAX_TEXTURE_SIZE}); use mode='distant' or a coarser SHRM"
                )
            image = coefficient_atlas(shrm.coeffs)
            flat = None
        else:
            flat = np.ascontiguousarray(shrm.coeffs.reshape(n, -1), dtype=np.float32)
            image = np.zeros((h, w, 3), dtype=np.float32)
        tex, data, buf = _float_texture(image)
        mapper = vtkOpenGLPolyDataMapper()
        mapper.SetInputData(_polydata(mesh))
        mapper.SetVBOShiftScaleMethod(0)  # DISABLE_SHIFT_SCALE: vertexMC must be world coordinates
        mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetTexture("shrmTex", tex)
        sp = actor.GetShaderProperty()
        for tag, text in vertex_replacements():
            sp.AddVertexShaderReplacement(tag, True, text, False)
        for tag, text in fragment_replacements("distant" if mode == "rsibr" else mode, shrm.P, h, w):
            sp.AddFragmentShaderReplacement(tag, True, text, False)
        return self._finish_object(mesh, shrm, mode, actor, tex, data, buf, flat, rsibr)

    def _finish_object(self, mesh, shrm, mode, actor, tex, data, buf, flat, rsibr) -> int:
        uni = actor.GetShaderProperty().GetFragmentCustomUniforms()
        uni.SetUniform3f("shrmEye", [0.0, 0.0, 0.0])
        uni.SetUniform3f("shrmViewDir", [1.0, 0.0, 0.0])
        uni.SetUniformi("shrmOrtho", 0)
        self._renderer.AddActor(actor)
        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        center = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(mesh.vertices - center, axis=1)))
        self._objects.append(_Object(mesh, shrm, mode, actor, tex, data, buf, center, radius, flat, rsibr))
        return len(self._objects) - 1

    def _add_gaussian(
        self, mesh: Mesh, glr: GaussianLobeModel, visibility_sh: np.ndarray | None, normalized: bool
    ) -> int:
        """Green et al. 2007: mip atlas texture + lobe table compiled into the fragment shader."""
        from vtkmodules.vtkCommonDataModel import vtkDataObject
        from vtkmodules.vtkRenderingCore import vtkActor
        from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLPolyDataMapper

        image, rows, heights = sg_atlas(glr.stack.levels)
        if max(image.shape[:2]) > MAX_TEXTURE_SIZE:
            raise ValueError(f"SG mip atlas {image.shape[0]}x{image.shape[1]} exceeds {MAX_TEXTURE_SIZE}")
        tex, data, buf = _float_texture(image)
        shadow = visibility_sh is not None
        mapper = vtkOpenGLPolyDataMapper()
        mapper.SetInputData(_polydata(mesh, visibility_sh))
        mapper.SetVBOShiftScaleMethod(0)  # DISABLE_SHIFT_SCALE: vertexMC must be world coordinates
        mapper.ScalarVisibilityOff()
        if shadow:
            for i in range(N_VIS_ATTRIBUTES):
                mapper.MapDataArrayToVertexAttribute(
                    f"glVis{i}", f"glVisArray{i}", vtkDataObject.FIELD_ASSOCIATION_POINTS, -1
                )
        actor = vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetTexture("shrmTex", tex)
        sp = actor.GetShaderProperty()
        for tag, text in gaussian_vertex_replacements(shadow):
            sp.AddVertexShaderReplacement(tag, True, text, False)
        frag = gaussian_fragment_replacements(
            glr.lobes, glr.stack.sigmas, rows, heights, shadow=shadow, normalized=normalized
        )
        for tag, text in frag:
            sp.AddFragmentShaderReplacement(tag, True, text, False)
        return self._finish_object(mesh, glr, "gaussian-lobes", actor, tex, data, buf, None, None)

    def update_view_maps(self, camera: Camera) -> None:
        """Recompute each distant-mode object's map Σ B̃_pq Y^r_pq(Ṽ) (RH02 eq. 12) and mark it for upload.

        Ṽ is the direction from the object's bounding-sphere centre toward the camera.
        """
        for obj in self._objects:
            if obj.mode == "rsibr":  # Cabral et al. 1999: blend of the face's three maps
                blended = obj.rsibr.view_map(camera.view_direction(obj.center))
                obj.buffer.reshape(blended.shape)[...] = blended
                obj.image.Modified()
                continue
            if obj.mode != "distant":
                continue
            view = camera.view_direction(obj.center)
            basis = real_sph_harm(obj.shrm.P, view).astype(np.float32)
            # obj.buffer is shared with the vtkImageData (no copy); Modified() re-uploads it
            np.matmul(basis, obj.flat_coeffs, out=obj.buffer.reshape(-1))
            obj.image.Modified()

    def _setup(self, camera: Camera, update_maps: bool = True) -> None:
        if not self._objects:
            raise ValueError("nothing to render: add an object first")
        centers = np.array([o.center for o in self._objects])
        radii = np.array([o.radius for o in self._objects])
        dist = np.linalg.norm(centers - camera.eye, axis=1)
        near = max(float(np.min(dist - radii)) * 0.99, 1e-3 * float(np.max(dist + radii)))
        far = float(np.max(dist + radii)) * 1.01
        camera.apply_to(self._renderer.GetActiveCamera(), (near, far))
        ortho = 1 if camera.projection == "ortho" else 0
        for obj in self._objects:
            uni = obj.actor.GetShaderProperty().GetFragmentCustomUniforms()
            uni.SetUniform3f("shrmEye", camera.eye.tolist())
            uni.SetUniform3f("shrmViewDir", (-camera.forward).tolist())
            uni.SetUniformi("shrmOrtho", ortho)
        if update_maps:
            self.update_view_maps(camera)

    def draw(self, camera: Camera, *, update_maps: bool = True) -> None:
        """Render one frame into the offscreen framebuffer (no readback; for timing).

        ``update_maps=False`` keeps the distant-mode maps of the previous frame (only for
        measuring the cost of the per-frame map update).
        """
        self._setup(camera, update_maps)
        self._window.Render()

    def finish(self) -> None:
        """Block until the OpenGL commands issued so far have completed (glFinish)."""
        self._window.WaitForCompletion()

    def frames_per_second(self, camera: Camera, n_frames: int = 10, center: np.ndarray = (0.0, 0.0, 0.0)) -> float:
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

    def render(self, camera: Camera) -> RenderResult:
        """Render one frame and read back linear radiance and coverage."""
        t0 = time.perf_counter()
        self.draw(camera)
        rgba = read_rgba_float(self._window)
        return RenderResult(rgba[..., :3].copy(), rgba[..., 3].copy(), time.perf_counter() - t0)

    def close(self) -> None:
        """Release the OpenGL context."""
        self._window.Finalize()

    def __enter__(self) -> SHRMRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
