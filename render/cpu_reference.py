"""CPU reference renderer (numpy): the same camera rays as the shader, shading from any B(R, V).

Per pixel centre (``camera.Camera.rays``) we find the surface point, the unit normal N, the
view direction V = −ray direction and R = 2(N·V)N − V, then evaluate a radiance function
``radiance(R, V) -> (n, 3)``: :meth:`SHRM.radiance` to check the shader, or the
angular-domain reference of ``analysis.reference`` to check the whole pipeline.

Intersections: analytic ray–sphere for a sphere (:func:`sphere_geometry`), or brute-force
Möller–Trumbore over all triangles with barycentric interpolation of vertex normals
(:func:`mesh_geometry`; O(pixels × triangles), meant for small test images and meshes).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..brdf_io.env_rotation import check_env_rotation, to_map_frame
from .camera import Camera
from .mesh import Mesh

__all__ = ["HitGeometry", "sphere_geometry", "mesh_geometry", "shade", "interpolate_vertex_data"]


@dataclass(frozen=True, eq=False)
class HitGeometry:
    """Where each camera ray hits the surface, arrays (H, W, ...); N, V, R are zero where ``hit`` is False.

    ``face`` (H, W) triangle index (−1 on misses) and ``bary`` (H, W, 3) barycentric weights of
    its three vertices are set by :func:`mesh_geometry` only (None for the analytic sphere).
    """

    hit: np.ndarray
    position: np.ndarray
    N: np.ndarray
    V: np.ndarray
    R: np.ndarray
    face: np.ndarray | None = None
    bary: np.ndarray | None = None


def _finish(hit: np.ndarray, pos: np.ndarray, normal: np.ndarray, dirs: np.ndarray) -> HitGeometry:
    V = -dirs
    N = normal / np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-300)
    R = 2.0 * np.sum(N * V, axis=-1, keepdims=True) * N - V
    R /= np.maximum(np.linalg.norm(R, axis=-1, keepdims=True), 1e-300)
    z = ~hit[..., None]
    return HitGeometry(hit, np.where(z, 0.0, pos), np.where(z, 0.0, N), np.where(z, 0.0, V), np.where(z, 0.0, R))


def sphere_geometry(
    camera: Camera, width: int, height: int, center: ArrayLike = (0.0, 0.0, 0.0), radius: float = 1.0
) -> HitGeometry:
    """Analytic ray–sphere intersection (nearest root), N = (P − c)/r."""
    origins, dirs = camera.rays(width, height)
    oc = origins - np.asarray(center, dtype=np.float64)
    b = np.sum(oc * dirs, axis=-1)
    c = np.sum(oc * oc, axis=-1) - radius * radius
    disc = b * b - c
    hit = disc > 0.0
    t = -b - np.sqrt(np.maximum(disc, 0.0))
    hit &= t > 0.0
    pos = origins + t[..., None] * dirs
    return _finish(hit, pos, pos - np.asarray(center, dtype=np.float64), dirs)


def mesh_geometry(camera: Camera, width: int, height: int, mesh: Mesh, *, chunk: int = 2048) -> HitGeometry:
    """Brute-force Möller–Trumbore ray casting with barycentric vertex-normal interpolation.

    The normal is flipped toward the viewer on back faces, as the shader does (gl_FrontFacing).
    """
    origins, dirs = camera.rays(width, height)
    o = origins.reshape(-1, 3)
    d = dirs.reshape(-1, 3)
    v0 = mesh.vertices[mesh.faces[:, 0]]
    e1 = mesh.vertices[mesh.faces[:, 1]] - v0
    e2 = mesh.vertices[mesh.faces[:, 2]] - v0
    n_rays = len(o)
    best_t = np.full(n_rays, np.inf)
    best_f = np.full(n_rays, -1, dtype=np.int64)
    best_uv = np.zeros((n_rays, 2))
    for s in range(0, n_rays, chunk):
        oo, dd = o[s:s + chunk], d[s:s + chunk]
        pvec = np.cross(dd[:, None, :], e2[None, :, :])
        det = np.einsum("fk,rfk->rf", e1, pvec)
        ok = np.abs(det) > 1e-14
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tvec = oo[:, None, :] - v0[None, :, :]
        u = np.einsum("rfk,rfk->rf", tvec, pvec) * inv
        qvec = np.cross(tvec, e1[None, :, :])
        v = np.einsum("rk,rfk->rf", dd, qvec) * inv
        t = np.einsum("fk,rfk->rf", e2, qvec) * inv
        valid = ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > 0.0)
        t = np.where(valid, t, np.inf)
        idx = np.argmin(t, axis=1)
        rows = np.arange(len(oo))
        best_t[s:s + chunk] = t[rows, idx]
        best_f[s:s + chunk] = np.where(np.isfinite(t[rows, idx]), idx, -1)
        best_uv[s:s + chunk, 0] = u[rows, idx]
        best_uv[s:s + chunk, 1] = v[rows, idx]
    hit = best_f >= 0
    f = mesh.faces[np.where(hit, best_f, 0)]
    w1, w2 = best_uv[:, 0:1], best_uv[:, 1:2]
    normal = (1.0 - w1 - w2) * mesh.normals[f[:, 0]] + w1 * mesh.normals[f[:, 1]] + w2 * mesh.normals[f[:, 2]]
    face_n = np.cross(e1, e2)[np.where(hit, best_f, 0)]
    back = np.sum(face_n * d, axis=-1) > 0.0
    normal[back] *= -1.0
    pos = o + np.where(hit, best_t, 0.0)[:, None] * d
    shape = (height, width)
    geom = _finish(hit.reshape(shape), pos.reshape(shape + (3,)), normal.reshape(shape + (3,)), dirs)
    bary = np.where(hit[:, None], np.concatenate([1.0 - w1 - w2, w1, w2], axis=1), 0.0)
    return HitGeometry(
        geom.hit, geom.position, geom.N, geom.V, geom.R, best_f.reshape(shape), bary.reshape(shape + (3,))
    )


def interpolate_vertex_data(geometry: HitGeometry, mesh: Mesh, values: np.ndarray) -> np.ndarray:
    """Per-vertex ``values`` (n_vertices, C) interpolated barycentrically at the hit pixels: (n_hit, C).

    Rows follow ``geometry.hit`` in C order (as in :func:`shade`); this is what the rasterizer
    does to a vertex attribute (perspective-correct interpolation = barycentric on the surface).
    """
    if geometry.face is None or geometry.bary is None:
        raise ValueError("interpolate_vertex_data needs the geometry of mesh_geometry (faces and barycentrics)")
    m = geometry.hit
    f = mesh.faces[geometry.face[m]]
    b = geometry.bary[m]
    values = np.asarray(values, dtype=np.float64)
    return b[:, 0:1] * values[f[:, 0]] + b[:, 1:2] * values[f[:, 1]] + b[:, 2:3] * values[f[:, 2]]


def shade(
    geometry: HitGeometry, radiance: Callable[[np.ndarray, np.ndarray], np.ndarray], *, env_rotation: Any = None
) -> np.ndarray:
    """Radiance image (H, W, 3) float64: ``radiance(R, V)`` at hit pixels, 0 elsewhere.

    ``env_rotation``: the environment rotated by Q (a (3, 3) rotation, Euler angles (AZ, EL[, ROLL])
    in degrees, or None; ``brdf_io.env_rotation``): ``radiance`` of the unrotated scene is called at
    (Qᵀ R, Qᵀ V), which is the radiance under the rotated map for any B (an SHRM, the angular
    reference, a baseline), as the shaders do. BadInputError for a bad rotation.
    """
    rotation = check_env_rotation(env_rotation)
    out = np.zeros(geometry.hit.shape + (3,))
    m = geometry.hit
    if m.any():
        out[m] = radiance(to_map_frame(geometry.R[m], rotation), to_map_frame(geometry.V[m], rotation))
    return out
