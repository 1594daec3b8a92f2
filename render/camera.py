"""Pinhole and orthographic cameras in the z-up math frame, shared by the VTK and CPU renderers.

Frame convention (DESIGN §2): **the VTK world frame is the z-up math frame**. Meshes are
stored, the camera is placed and the shader computes N, V, R directly in these coordinates,
so no conversion happens anywhere; this module is the one documented place that says so.

Image convention: an image is (height, width, ...) with row 0 at the top and column 0 at
the left. Pixel (i, j) has its centre at normalized device coordinates
x = (2j + 1)/W − 1, y = 1 − (2i + 1)/H, and the ray through it is

- ortho: origin = eye + s·(x·a·right + y·up), direction = forward, with s the parallel
  scale (half the image height in world units) and a = W/H;
- perspective: origin = eye, direction = normalize(forward + t·(x·a·right + y·up)),
  t = tan(fov_y / 2).

This is the projection VTK's vtkCamera builds (symmetric frustum, view angle = fov_y,
parallel scale = s), so the CPU reference and the shader see the same rays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Camera", "orbit_camera", "orthonormal_frame"]


def orthonormal_frame(view: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(forward, right, up') for a camera looking along −view with image up close to ``up``.

    ``view`` points from the object toward the camera. Raises ValueError when ``up`` is
    parallel to ``view`` or either is zero / non-finite.
    """
    v = np.asarray(view, dtype=np.float64).reshape(3)
    u = np.asarray(up, dtype=np.float64).reshape(3)
    if not (np.all(np.isfinite(v)) and np.all(np.isfinite(u))):
        raise ValueError(f"view {v} and up {u} must be finite")
    nv = np.linalg.norm(v)
    if nv == 0.0:
        raise ValueError("view direction is zero")
    forward = -v / nv
    u_perp = u - np.dot(u, forward) * forward
    nu = np.linalg.norm(u_perp)
    if nu < 1e-9 * max(float(np.linalg.norm(u)), 1e-300):
        raise ValueError(f"up {u.tolist()} is parallel to the view direction {v.tolist()}")
    up_o = u_perp / nu
    right = np.cross(forward, up_o)
    return forward, right, up_o


@dataclass(frozen=True)
class Camera:
    """A camera in the z-up world frame.

    Attributes
    ----------
    eye
        Camera position (3,).
    forward, right, up
        Orthonormal frame: viewing direction, image right, image up.
    projection
        ``"perspective"`` or ``"ortho"``.
    fov_y
        Vertical field of view in radians (perspective).
    parallel_scale
        Half the image height in world units (ortho).
    """

    eye: np.ndarray
    forward: np.ndarray
    right: np.ndarray
    up: np.ndarray
    projection: str = "perspective"
    fov_y: float = np.deg2rad(30.0)
    parallel_scale: float = 1.0

    @classmethod
    def looking_at(
        cls,
        *,
        center: ArrayLike = (0.0, 0.0, 0.0),
        view: ArrayLike = (1.0, 0.0, 0.0),
        up: ArrayLike = (0.0, 0.0, 1.0),
        radius: float = 1.0,
        projection: str = "perspective",
        distance: float | None = None,
        margin: float = 1.0,
    ) -> Camera:
        """A camera that frames the sphere (``center``, ``radius``) seen from direction ``view``.

        ortho: parallel scale = ``margin`` · radius, so with margin 1 the square image spans
        the sphere exactly. perspective: eye at distance ``distance`` (default 3·radius) and
        fov_y = 2 asin(margin · radius / distance), the cone tangent to the (scaled) sphere.
        """
        if projection not in ("perspective", "ortho"):
            raise ValueError(f"projection must be 'perspective' or 'ortho', got {projection!r}")
        if not radius > 0:
            raise ValueError(f"radius must be positive, got {radius}")
        forward, right, up_o = orthonormal_frame(np.asarray(view, float), np.asarray(up, float))
        c = np.asarray(center, dtype=np.float64).reshape(3)
        if projection == "ortho":
            d = 4.0 * radius if distance is None else float(distance)
            return cls(c - d * forward, forward, right, up_o, "ortho", parallel_scale=margin * radius)
        d = 3.0 * radius if distance is None else float(distance)
        if not d > margin * radius:
            raise ValueError(f"camera distance {d} must exceed the framed radius {margin * radius}")
        fov = 2.0 * np.arcsin(margin * radius / d)
        return cls(c - d * forward, forward, right, up_o, "perspective", fov_y=float(fov))

    def rays(self, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Ray origins and unit directions through the pixel centres, each (H, W, 3)."""
        aspect = width / height
        x = (2.0 * np.arange(width) + 1.0) / width - 1.0
        y = 1.0 - (2.0 * np.arange(height) + 1.0) / height
        xx, yy = np.meshgrid(x * aspect, y)
        offs = xx[..., None] * self.right + yy[..., None] * self.up
        if self.projection == "ortho":
            origins = self.eye + self.parallel_scale * offs
            dirs = np.broadcast_to(self.forward, origins.shape).copy()
            return origins, dirs
        t = np.tan(0.5 * self.fov_y)
        dirs = self.forward + t * offs
        dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
        return np.broadcast_to(self.eye, dirs.shape).copy(), dirs

    def view_direction(self, point: np.ndarray) -> np.ndarray:
        """Unit direction from ``point`` toward the camera (the distant-viewer Ṽ for ortho)."""
        if self.projection == "ortho":
            return -self.forward
        d = self.eye - np.asarray(point, dtype=np.float64).reshape(3)
        return d / np.linalg.norm(d)

    def view_cone(self, center: ArrayLike, radius: float) -> tuple[np.ndarray, float]:
        """The cone of the directions toward the camera from the points within ``radius`` of
        ``center``: (unit axis (3,), half-angle in radians).

        ortho: (−forward, 0), every ray parallel. perspective: the axis toward the eye from
        ``center`` and asin(radius / d), d the eye's distance (the ball seen from the eye fills the
        cone of that half-angle, so eye − P of a point P in it is within it); π when the eye is
        within the ball.
        """
        if self.projection == "ortho":
            return -self.forward, 0.0
        d = self.eye - np.asarray(center, dtype=np.float64).reshape(3)
        dist = float(np.linalg.norm(d))
        if not dist > radius:
            return (d / dist if dist > 0 else -self.forward), float(np.pi)
        return d / dist, float(np.arcsin(radius / dist))

    def apply_to(self, vtk_camera, near_far: tuple[float, float]) -> None:
        """Set a vtkCamera to this camera (world frame = z-up frame, no conversion)."""
        vtk_camera.SetPosition(*self.eye)
        vtk_camera.SetFocalPoint(*(self.eye + self.forward))
        vtk_camera.SetViewUp(*self.up)
        if self.projection == "ortho":
            vtk_camera.ParallelProjectionOn()
            vtk_camera.SetParallelScale(self.parallel_scale)
        else:
            vtk_camera.ParallelProjectionOff()
            vtk_camera.SetViewAngle(float(np.rad2deg(self.fov_y)))
        vtk_camera.SetClippingRange(*near_far)


def orbit_camera(base: Camera, center: np.ndarray, angle: float) -> Camera:
    """``base`` rotated by ``angle`` radians about the world z axis through ``center`` (turntable)."""
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    center = np.asarray(center, dtype=np.float64).reshape(3)
    return Camera(
        center + rot @ (base.eye - center),
        rot @ base.forward,
        rot @ base.right,
        rot @ base.up,
        base.projection,
        base.fov_y,
        base.parallel_scale,
    )
