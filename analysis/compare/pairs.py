"""The one (R, V) sampler of the project's error measurements, grazing views well represented.

Used by ``shrm compare`` and meant for ``shrm report``, so that their errors are measured
on the same distribution of reflection and view directions.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sample_pairs"]


def sample_pairs(n: int, *, seed: int = 0, max_view_deg: float = 88.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` seeded (R, V) pairs whose view elevations are spread uniformly *in angle*.

    The distribution, exactly (z-up frame, DESIGN §2; RH02 reparameterization, DESIGN §3):

    1. **V** is uniform on the whole sphere (a normalized isotropic Gaussian 3-vector).
    2. **θ_v** = angle(N, V), the view elevation from the surface normal N, is *stratified
       uniform in angle* on [0, max_view_deg): θ_v,i = (i + u_i)/n · max_view_deg for
       i = 0 … n−1 with u_i uniform on [0, 1), then randomly permuted. So each of n equal
       angular strata holds exactly one sample and the fraction of pairs with θ_v > t is
       (max_view_deg − t)/max_view_deg (for max 88°: 18/88 ≈ 20 % beyond 70°) — *not*
       uniform in cos θ_v or in solid angle, which would make grazing views rare.
    3. **N** is at angle θ_v from V with its azimuth about V uniform on [0, 2π):
       N = cos θ_v V + sin θ_v (cos ψ t + sin ψ b), (t, b) an orthonormal pair ⟂ V.
    4. **R** = 2(N·V)N − V, the mirror of V about N (renormalized): angle(R, V) = 2θ_v,
       N = normalize(R + V) is the bisector, and R is uniform on the cone of half-angle
       2θ_v about V. The pair law is invariant under rotations (V isotropic), so R is
       uniform on the sphere too, and equivalently V is uniform on the cone of half-angle
       2θ_v about R: only the θ_v law above distinguishes this sampler from "R uniform,
       V at 2θ_v from R with uniform azimuth".

    Random numbers come from ``numpy.random.default_rng(seed)`` in the order V, u, the
    permutation, ψ: the same (n, seed, max_view_deg) give bit-identical pairs.

    Parameters
    ----------
    n
        Number of pairs, at least 1.
    seed
        Seed of the generator.
    max_view_deg
        Largest view elevation θ_v in degrees, in (0, 90) (θ_v = 90° is the grazing
        singularity θ_o' = π of the reparameterization).

    Returns
    -------
    R, V
        float64 unit vectors (n, 3), z-up frame.
    theta_v
        (n,) view elevations θ_v in radians, in [0, max_view_deg).

    Raises
    ------
    ValueError
        ``n < 1`` or ``max_view_deg`` outside (0, 90).
    """
    if n < 1 or not 0.0 < max_view_deg < 90.0:
        raise ValueError(f"need n >= 1 and max_view_deg in (0, 90), got {n}, {max_view_deg}")
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(n, 3))
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    theta_v = (np.arange(n) + rng.random(n)) / n * np.radians(max_view_deg)
    rng.shuffle(theta_v)
    az = rng.random(n) * 2.0 * np.pi
    helper = np.where(np.abs(V[:, 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t = np.cross(V, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(V, t)
    N = np.cos(theta_v)[:, None] * V + np.sin(theta_v)[:, None] * (np.cos(az)[:, None] * t + np.sin(az)[:, None] * b)
    R = 2.0 * np.sum(N * V, axis=1, keepdims=True) * N - V
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    return R, V, theta_v
