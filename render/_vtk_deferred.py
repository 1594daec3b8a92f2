"""The deferred passes of the VTK renderer (:class:`~shrmkit.render.vtk_renderer.SHRMRenderer`'s
docstring): the G-buffer texture, each object's geometry-pass actor and screen quad, the quad's
corners per frame and the depth state of the screen pass.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._vtk_upload import _new_actor, _polydata, _shader
from .camera import Camera
from .glsl import Shading, gbuffer_fragment_replacements, vertex_replacements
from .mesh import make_mesh

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


def _gbuffer_texture(window, width: int, height: int):  # -> vtkOpenGLTexture or None
    """The display framebuffer's colour texture (what pass 1 leaves), wrapped for a sampler."""
    from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLTexture  # lazy: VTK

    fbo = window.GetDisplayFramebuffer()
    colour = None if fbo is None else fbo.GetColorAttachmentAsTextureObject(0)
    if colour is None or (colour.GetWidth(), colour.GetHeight()) != (width, height):
        return None
    tex = vtkOpenGLTexture()
    tex.SetTextureObject(colour)
    return tex


def _restore_depth(window) -> None:
    """VTK's depth state (GL_LEQUAL, writes on), which it resets only when it clears."""
    state = window.GetState()
    state.vtkglDepthFunc(GL_LEQUAL)
    state.vtkglDepthMask(True)


def _screen_pass_depth(window) -> None:
    """The screen pass's depth state (GL_GREATER, writes off): pass only where pass 1 left a surface."""
    state = window.GetState()
    state.vtkglDepthFunc(GL_GREATER)
    state.vtkglDepthMask(False)


def _deferred_actors(renderer, gbuffer_tex, actor, tex, shading: Shading, index: int,
                     extra_textures: dict[str, Any], on_screen_start: Any) -> _Deferred:
    """The geometry-pass actor (same polydata as ``actor``) and the screen quad of object ``index``
    (``on_screen_start``: the quad mapper's StartEvent observer, :func:`_screen_pass_depth`)."""
    from vtkmodules.util.numpy_support import numpy_to_vtk  # lazy: VTK

    scale = float(2.0 ** (index + 1))
    # its own mapper (its own shader program) on the same polydata
    gbuffer = _new_actor(actor.GetMapper().GetInput())
    _shader(gbuffer, vertex_replacements(), gbuffer_fragment_replacements(), scale)
    renderer.AddActor(gbuffer)

    # a unit square for the mesh checks; its corners are rewritten every frame (_quad_corners)
    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    quad = make_mesh(square, np.array([[0, 1, 2], [0, 2, 3]]), np.tile([0.0, 0.0, 1.0], (4, 1)),
                     normalize=False)
    poly = _polydata(quad, {})
    points = np.zeros((4, 3), dtype=np.float32)
    poly.GetPoints().SetData(numpy_to_vtk(points, deep=0))  # shares ``points``
    screen = _new_actor(poly)
    screen.GetMapper().AddObserver("StartEvent", on_screen_start)
    screen.GetProperty().SetTexture("shrmTex", tex)
    screen.GetProperty().SetTexture("shrmGbuf", gbuffer_tex)
    for name, extra in extra_textures.items():
        screen.GetProperty().SetTexture(name, extra)
    assert shading.deferred is not None  # add_object calls this for modes with a deferred pass only
    _shader(screen, shading.vertex, shading.deferred, scale, shading.uniforms)
    renderer.AddActor(screen)
    gbuffer.SetVisibility(False)
    screen.SetVisibility(False)
    return _Deferred(gbuffer, screen, points)


def _quad_corners(camera: Camera, far: float, width: int, height: int) -> np.ndarray:
    """(4, 3) world corners of a quad filling the view (with a margin) at depth far / 1.004."""
    d = far / 1.004  # beyond every surface (all within far / 1.01), inside the far plane
    half_h = camera.parallel_scale if camera.projection == "ortho" else d * np.tan(0.5 * camera.fov_y)
    half_w = half_h * width / height
    c = camera.eye + d * camera.forward
    x, y = 1.25 * half_w * camera.right, 1.25 * half_h * camera.up
    return np.array([c - x - y, c + x - y, c + x + y, c - x + y])
