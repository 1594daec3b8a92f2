"""The one (R, V) sampler of the project's error measurements, grazing views well represented.

Used by ``shrm compare`` and meant for ``shrm report``, so that their errors are measured
on the same distribution of reflection and view directions.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..brdf_io.latlong import pixel_directions, row_solid_angles

__all__ = ["sample_pairs", "sample_pairs_focused", "brightest_pixels", "band_pairs"]


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


def sample_pairs_focused(
    per_band: int, edges_deg: Sequence[float] | np.ndarray, *, centre: np.ndarray | None = None,
    centre_weights: np.ndarray | None = None, caps_deg: Sequence[float] = (2.0, 6.0, 20.0), seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(R, V) pairs for per-band error measurements, with importance weights, for lighting
    whose reflection is concentrated (a one-pixel sun, the bright windows of a light probe):
    ``per_band`` pairs in each θ_v band.

    In band [a, b): θ_v uniform in angle on [a, b) (as :func:`sample_pairs`); R from a mixture:
    with probability ¼ uniform on the sphere, else uniform in one of the caps of half-angle
    ``caps_deg`` (equally likely) about one of the ``centre`` directions ((3,) or (k, 3) unit
    vectors; picked with probability ∝ ``centre_weights``, default equal); None: uniform only.
    V is at angle 2θ_v from R with uniform azimuth (so N = normalize(R + V) is at θ_v from V).
    The weight of a pair is (1/4π) / mixture pdf of its R, so weighted sums estimate the
    uniform-R averages of :func:`sample_pairs` (pass them to
    :func:`~.metrics.band_relative_rms`).

    Returns
    -------
    R, V
        (n, 3) unit vectors, n = per_band × number of bands.
    theta_v
        (n,) radians.
    weights
        (n,) importance weights (all 1 when ``centre`` is None).
    """
    rng = np.random.default_rng(seed)
    edges = np.radians(np.asarray(edges_deg, dtype=np.float64))
    theta_v = np.concatenate([lo + (hi - lo) * (np.arange(per_band) + rng.random(per_band)) / per_band
                              for lo, hi in zip(edges[:-1], edges[1:], strict=True)])
    n = theta_v.size
    R = rng.normal(size=(n, 3))
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    weights = np.ones(n)
    if centre is not None:
        centres = np.atleast_2d(np.asarray(centre, dtype=np.float64))
        centres = centres / np.linalg.norm(centres, axis=1, keepdims=True)
        cw = np.ones(len(centres)) if centre_weights is None else np.asarray(centre_weights, dtype=np.float64)
        cw = cw / cw.sum()
        cos_caps = np.cos(np.radians(np.asarray(caps_deg, dtype=np.float64)))
        # component probabilities: uniform ¼, cap (c, k) ¾·cw_c/len(caps)
        prob = 0.75 * cw[:, None] / cos_caps.size * np.ones((1, cos_caps.size))
        pick = rng.random(n)
        flat = np.concatenate([[0.25], prob.ravel()])
        component = np.searchsorted(np.cumsum(flat), pick, side="right")  # 0: uniform
        component = np.minimum(component, flat.size - 1)
        for index in range(1, flat.size):
            sel = component == index
            m = int(sel.sum())
            if m == 0:
                continue
            c = centres[(index - 1) // cos_caps.size]
            cos_cap = cos_caps[(index - 1) % cos_caps.size]
            cos_t = 1.0 - rng.random(m) * (1.0 - cos_cap)
            phi = rng.random(m) * 2.0 * np.pi
            t, b = _perpendicular_pair(np.broadcast_to(c, (m, 3)))
            sin_t = np.sqrt(1.0 - cos_t**2)[:, None]
            R[sel] = cos_t[:, None] * c + sin_t * (np.cos(phi)[:, None] * t + np.sin(phi)[:, None] * b)
        pdf = np.full(n, 0.25 / (4.0 * np.pi))
        cos_r = R @ centres.T  # (n, k)
        for k, cos_cap in enumerate(cos_caps):
            pdf += ((cos_r >= cos_cap) * prob[:, k]).sum(axis=1) / (2.0 * np.pi * (1.0 - cos_cap))
        weights = (1.0 / (4.0 * np.pi)) / pdf
    t, b = _perpendicular_pair(R)
    psi = rng.random(n) * 2.0 * np.pi
    two = 2.0 * theta_v[:, None]
    V = np.cos(two) * R + np.sin(two) * (np.cos(psi)[:, None] * t + np.sin(psi)[:, None] * b)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    return R, V, theta_v, weights


def brightest_pixels(radiance: np.ndarray, k: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` pixels of a lat-long map (H, W, 3) with the largest flux (radiance summed over
    channels × solid angle): their unit directions (k, 3) and √flux as sampling weights — the
    ``centre``/``centre_weights`` of :func:`sample_pairs_focused`."""
    radiance = np.asarray(radiance, dtype=np.float64)
    h, w = radiance.shape[:2]
    flux = (radiance.sum(axis=-1) * row_solid_angles(h, w)[:, None]).ravel()
    top = np.argsort(flux)[::-1][:k]
    return pixel_directions(h, w).reshape(-1, 3)[top], np.sqrt(np.clip(flux[top], 0.0, None))


def band_pairs(radiance: np.ndarray, per_band: int, edges_deg: Sequence[float], *, seed: int = 0
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`sample_pairs_focused` on the 16 brightest pixels of ``radiance`` (the per-band
    measurement of ``shrm report``, the tests and ``benchmarks/view_bands.py``)."""
    centres, weights = brightest_pixels(radiance)
    return sample_pairs_focused(per_band, edges_deg, centre=centres, centre_weights=weights, seed=seed)


def _perpendicular_pair(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (t, b) perpendicular to each unit row of ``d`` and to each other."""
    helper = np.where(np.abs(d[:, 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t = np.cross(d, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return t, np.cross(d, t)
