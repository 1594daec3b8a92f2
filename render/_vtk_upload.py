"""What the VTK renderer uploads: float textures, the mesh as polydata with the modes' vertex
attributes, actors drawing in world coordinates, shader replacements and uniforms (constant ones
on each bind, the per-frame view uniforms). Used by :mod:`shrmkit.render.vtk_renderer`; VTK is
imported lazily, inside the functions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .camera import Camera
from .glsl import TO_MAP_UNIFORM
from .mesh import Mesh


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


def _to_map_values(env_rotation: np.ndarray | None) -> list[float]:
    """The 9 floats of the uniform :data:`~shrmkit.render.glsl.TO_MAP_UNIFORM` (the GLSL matrix Qᵀ):
    OpenGL reads them column by column (glUniformMatrix3fv, no transpose), and the columns of Qᵀ
    are the rows of Q."""
    q = np.eye(3) if env_rotation is None else np.asarray(env_rotation, dtype=np.float64)
    return [float(x) for x in q.reshape(-1)]


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


def _set_view_uniforms(actor, camera: Camera, env_rotation: np.ndarray | None = None) -> None:
    """The uniforms each frame sets on ``actor``: eye, view direction, projection and Qᵀ."""
    uni = actor.GetShaderProperty().GetFragmentCustomUniforms()
    uni.SetUniform3f("shrmEye", camera.eye.tolist())
    uni.SetUniform3f("shrmViewDir", (-camera.forward).tolist())
    uni.SetUniformi("shrmOrtho", 1 if camera.projection == "ortho" else 0)
    uni.SetUniformMatrix3x3(TO_MAP_UNIFORM, _to_map_values(env_rotation))
