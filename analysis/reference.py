"""Angular-domain reference: brute-force integration of the reflected radiance.

    B(R, V) = ∫ L(ω) ρ̂(ω; V, N) dω,    N = normalize(R + V)             ([RH02] eq. 2)

summed over every pixel of the lat-long environment, each weighted by its exact solid
angle, with ρ̂ evaluated in the local frame of N (the BRDF's own ρ̂ for models that
define it, ρ max(N·ω, 0) otherwise). O(W S_L²) per output value ([RH02] Table 3): the
ground truth for tests and the baseline every speed ratio is measured against.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.latlong import pixel_directions, row_solid_angles

__all__ = ["reference_radiance", "reference_map", "local_frames"]


def local_frames(normals: np.ndarray) -> np.ndarray:
    """Orthonormal frames (n, 3, 3) with rows (tangent, bitangent, normal)."""
    n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    helper = np.where(np.abs(n[..., 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t = np.cross(helper, n)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    b = np.cross(n, t)
    return np.stack([t, b, n], axis=-2)


def reference_radiance(
    env: object, brdf: BRDF, R: np.ndarray, V: np.ndarray, *, chunk_bytes: int = 4 << 20
) -> np.ndarray:
    """B(R, V) by brute-force summation over all environment pixels.

    Parameters
    ----------
    env
        An EnvironmentMap (``radiance`` (H, W, 3)) or a bare (H, W, 3) array.
    brdf
        Any evaluable BRDF.
    R, V
        Unit reflection and view directions (n, 3), global z-up frame.

    Returns
    -------
    (n, 3) float64 radiance.
    """
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    height, width = radiance.shape[:2]
    dirs = pixel_directions(height, width).reshape(-1, 3)
    weight = np.repeat(row_solid_angles(height, width), width)
    lit = np.any(radiance.reshape(-1, 3) != 0, axis=1)  # skip black pixels: exact, and faster
    dirs, weight, emitted = dirs[lit], weight[lit], radiance.reshape(-1, 3)[lit] * weight[lit, None]
    R = np.atleast_2d(np.asarray(R, float))
    V = np.atleast_2d(np.asarray(V, float))
    frames = local_frames(R + V)
    out = np.zeros((R.shape[0], 3))
    per_pair = max(1, dirs.shape[0] * 3 * 8 * 6)
    step = max(1, chunk_bytes // per_pair)
    for start in range(0, R.shape[0], step):
        fr = frames[start : start + step]  # (k, 3, 3)
        L_loc = np.matmul(dirs, fr.transpose(0, 2, 1))  # (k, n, 3): each frame's rows dotted with every ω
        V_loc = np.einsum("kij,kj->ki", fr, V[start : start + step])[:, None, :]
        rho_hat = _rho_hat(brdf, L_loc, V_loc)
        out[start : start + step] = np.einsum("knc,nc->kc", rho_hat, emitted)
    return out


def _rho_hat(brdf: BRDF, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    if brdf.kind == "analytic":
        return brdf.rho_hat(L, V)
    rho, _ = brdf.eval_counted(L, np.broadcast_to(V, L.shape))
    return rho * np.maximum(L[..., 2], 0.0)[..., None]


def reference_map(env: object, brdf: BRDF, view: np.ndarray, height: int, width: int) -> np.ndarray:
    """Distant-viewer reference map: B(R, V) for every R pixel of an H × W grid, fixed V."""
    R = pixel_directions(height, width).reshape(-1, 3)
    V = np.broadcast_to(np.asarray(view, float) / np.linalg.norm(view), R.shape)
    return reference_radiance(env, brdf, R, V).reshape(height, width, 3)
