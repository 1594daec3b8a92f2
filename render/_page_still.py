"""The view page's camera (:func:`page_camera`, as ``view.js``) and its still image for browsers
without WebGL2: the CPU reference renderer on the sphere, or VTK offscreen on the mesh.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..analysis.shrm import SHRM
from ..brdf_io.env_rotation import env_rotation_matrix
from ..brdf_io.envmap import EnvironmentMap
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_lookup
from .camera import Camera, orthonormal_frame
from .cpu_reference import shade, sphere_geometry
from .mesh import Mesh
from .offscreen import probe_offscreen
from .output import composite, environment_background, to_8bit
from .pipeline import render_frames
from .preview import png_bytes

#: The camera: eye at this distance from the origin (the mesh is in the unit sphere) ...
CAMERA_DISTANCE = 3.0
#: ... and at zoom 1 the vertical field of view is tangent to a sphere of this radius.
CAMERA_MARGIN = 1.15
#: Elevations are clamped to ±this (the image up is +z).
MAX_ELEVATION = 89.0


def page_camera(
    azimuth: float, elevation: float, zoom: float = 1.0, width: int = 1, height: int = 1
) -> Camera:
    """The perspective camera of the page for a view (``view.js`` ``pageCamera``).

    The eye is at :data:`CAMERA_DISTANCE` along v = (cos e cos a, cos e sin a, sin e) (a =
    ``azimuth``, e = ``elevation`` in degrees, e clamped to ±89°), looking at the origin, image
    up from +z; tan(fov_y / 2) = tan(asin(:data:`CAMERA_MARGIN` / distance)) / ``zoom``, and ×
    height/width for a portrait canvas (so the sphere fits the narrower side).
    """
    if not (math.isfinite(azimuth) and math.isfinite(elevation) and math.isfinite(zoom) and zoom > 0):
        raise BadInputError(None, f"view must be finite with zoom > 0, got {azimuth}, {elevation}, {zoom}")
    a = math.radians(azimuth)
    e = math.radians(min(max(elevation, -MAX_ELEVATION), MAX_ELEVATION))
    view = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    forward, right, up = orthonormal_frame(view, np.array([0.0, 0.0, 1.0]))
    t = math.tan(math.asin(CAMERA_MARGIN / CAMERA_DISTANCE)) / zoom
    if width < height:
        t *= height / width
    return Camera(CAMERA_DISTANCE * view, forward, right, up, "perspective", fov_y=2.0 * math.atan(t))


def _chunked(radiance, chunk: int = 8192):
    def evaluate(R: np.ndarray, V: np.ndarray) -> np.ndarray:
        out = np.empty((len(R), 3))
        for s in range(0, len(R), chunk):
            out[s:s + chunk] = radiance(R[s:s + chunk], V[s:s + chunk])
        return out

    return evaluate


def _cpu_radiance(shrm: SHRM, mode: str, camera: Camera, env_rotation: np.ndarray | None = None):
    """B(R, V) of the page's ``mode`` for ``shade`` (which turns R and V by Qᵀ itself): per pixel, or
    the distant view map made for Qᵀ Ṽ, as the shaders."""
    if mode == "perpixel":
        return _chunked(shrm.radiance)
    view_map = shrm.view_map(camera.view_direction(np.zeros(3)), env_rotation=env_rotation)
    if shrm.has_lights:  # the map holds the SHRM part; the lights at each pixel's own V, as the shaders
        return _chunked(lambda R, V: bilinear_lookup(view_map, R) + shrm.light_radiance(R, V))
    return lambda R, V: bilinear_lookup(view_map, R)


def _still(
    shrm: SHRM, env: EnvironmentMap | None, mesh: Mesh, is_sphere: bool, view: dict[str, Any], size: int, how: str
) -> tuple[bytes, str, str | None, str]:
    """PNG of the initial view (the lighting turned by the view's ``env_*`` angles), its renderer, a
    note when it shows less than the page, its mode."""
    mode = view["mode"]
    rotation = env_rotation_matrix(view["env_azimuth"], view["env_elevation"], view["env_roll"])
    q = None if np.array_equal(rotation, np.eye(3)) else rotation
    if how == "none":
        return b"", "none", None, mode
    camera = page_camera(view["azimuth"], view["elevation"], view["zoom"], size, size)
    note = None
    use_gl = how == "gl" or (how == "auto" and not is_sphere)
    if use_gl:
        ok, message = probe_offscreen(timeout=60.0)
        if not ok and how == "gl":
            raise BadInputError(None, f"still image with OpenGL: no offscreen context ({message})")
        if not ok:
            use_gl = False
            note = f"the still image shows the sphere: no offscreen OpenGL to render the mesh ({message})"
    elif not is_sphere:
        note = "the still image shows the sphere (CPU reference renderer), not the mesh"
    if use_gl:
        background = "env" if env is not None and view["background"] else "black"
        try:
            frames, timings = render_frames(
                mesh, shrm, [camera], size=size, mode=mode,
                env_radiance=None if env is None else env.radiance, background=background, fps_frames=0,
                env_rotation=q,
            )
        except ValueError as err:  # a perpixel atlas over the GPU's texture limit (render.shader)
            mode = "distant"
            note = f"the still image is drawn in mode distant ({err})"
            frames, timings = render_frames(
                mesh, shrm, [camera], size=size, mode=mode,
                env_radiance=None if env is None else env.radiance, background=background, fps_frames=0,
                env_rotation=q,
            )
        linear, renderer = frames[0].linear, f"opengl ({timings.backend})"
    else:
        geometry = sphere_geometry(camera, size, size)
        radiance = shade(geometry, _cpu_radiance(shrm, mode, camera, q), env_rotation=q).astype(np.float32)
        if env is not None and view["background"]:
            bg = environment_background(env.radiance, camera, size, size, env_rotation=q)
        else:
            bg = np.zeros((size, size, 3), np.float32)
        linear = composite(radiance, geometry.hit.astype(np.float32), bg)
        renderer = "cpu-reference"
    image = to_8bit(linear, exposure=view["exposure"], curve=view["tone"])
    return png_bytes(image), renderer, note, mode
