"""The undershoot of a windowed SHRM: the sample of (R, V) pairs it is measured on (the normal
view and oblique views per pixel, :func:`undershoot_views`), the field there
(:func:`undershoot_samples`), and the measure itself, −min/max (:func:`undershoot`,
:func:`gibbs_negative`). Public through :mod:`shrmkit.analysis.window`.
"""

from __future__ import annotations

import numpy as np

from ..brdf_io.latlong import pixel_angles, pixel_directions
from .sh import real_sph_harm

#: Largest view angle θ_v = angle(N, V) of the full-map undershoot sample (:func:`undershoot_samples`).
UNDERSHOOT_MAX_VIEW_DEG = 85.0


def gibbs_negative(coeffs: np.ndarray, P: int) -> float:
    """Ringing measure: −min / max of the normal-view radiance B(R, V = R) over the map
    (worst channel; 0 when nothing is negative). Truncating a sharp lobe creates
    negative lobes (Gibbs); a window reduces them."""
    height, width = coeffs.shape[1:3]
    dirs = pixel_directions(height, width)
    peak = np.full(3, -np.inf)
    low = np.full(3, np.inf)
    for r0 in range(0, height, 32):  # row blocks keep the basis array small at high P
        basis = real_sph_harm(P, dirs[r0 : r0 + 32]).astype(np.float32)  # (h, W, n_coef)
        normal_view = np.einsum("hwk,khwc->hwc", basis, coeffs[:, r0 : r0 + 32])
        peak = np.maximum(peak, normal_view.max(axis=(0, 1)))
        low = np.minimum(low, normal_view.min(axis=(0, 1)))
    return undershoot(np.stack([low, peak], axis=1))


_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
#: Oblique views per pixel of the undershoot sample when P > 0 (:func:`undershoot_views`).
OBLIQUE_VIEWS = 2


def undershoot_views(
    height: int, width: int, P: int, *, max_view_deg: float = UNDERSHOOT_MAX_VIEW_DEG
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The view directions of the undershoot sample of an H × W map, one (θ_V, Δφ_V) pair of
    (H,) arrays per view: at pixel (i, j) (reflection direction R_ij) the view V_ij has polar
    angle θ_V[i] and azimuth φ_j + Δφ_V[i], φ_j the pixel column's azimuth.

    The first is the normal view V = R (what :func:`gibbs_negative` measures). When P > 0,
    :data:`OBLIQUE_VIEWS` more give each pixel a view at θ_v = angle(N, V) in
    (0, ``max_view_deg``], N = normalize(R + V), since the view-order (P) truncation rings at
    oblique views too: for row i and extra view e, k = i·OBLIQUE_VIEWS + e, θ_v at
    1 − frac((k + ½)·0.618…) of the range, and V = cos 2θ_v R + sin 2θ_v (cos ψ t + sin ψ b)
    with ψ = 2π frac(k·√2), t = z × R / |z × R| and b = R × t. The choice depends on the row
    only, so rotating the environment about z by whole columns shifts the sample with it (and
    ``prefilter``'s ``auto`` decision does not change). For P = 0, B does not depend on V.
    """
    theta, _ = pixel_angles(height, width)
    views = [(theta, np.zeros(height))]
    if P > 0:
        # R in the x-z plane (φ = 0): t = (0, 1, 0), b = R × t; then rotate by each column's φ
        R0 = np.stack([np.sin(theta), np.zeros(height), np.cos(theta)], axis=-1)
        t_axis = np.array([0.0, 1.0, 0.0])
        b_axis = np.cross(R0, t_axis)
        for extra in range(OBLIQUE_VIEWS):
            k = np.arange(height, dtype=np.float64) * OBLIQUE_VIEWS + extra
            two_theta = (2.0 * np.radians(max_view_deg) * (1.0 - ((k + 0.5) * _GOLDEN) % 1.0))[:, None]
            psi = (2.0 * np.pi * ((k * np.sqrt(2.0)) % 1.0))[:, None]
            V0 = np.cos(two_theta) * R0 + np.sin(two_theta) * (np.cos(psi) * t_axis + np.sin(psi) * b_axis)
            views.append((np.arccos(np.clip(V0[:, 2], -1.0, 1.0)), np.arctan2(V0[:, 1], V0[:, 0])))
    return views


def _row_basis(P: int, theta: np.ndarray, offset: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Real SH Y^r_k (k < (P+1)²) at the directions (θ[i], offset[i] + φ[j]): float32 (h, W, n_coef).

    Y^r_lm = A_l|m|(θ) cos(mφ) for m >= 0 and A_l|m|(θ) sin(|m|φ) for m < 0 (the real basis of
    ``analysis.sh``), so the θ part is evaluated once per row, at φ = 0."""
    n = (P + 1) ** 2
    l_of = np.floor(np.sqrt(np.arange(n))).astype(int)
    m_of = np.arange(n) - l_of * l_of - l_of
    at_zero = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    amplitude = real_sph_harm(P, at_zero)[:, l_of * l_of + l_of + np.abs(m_of)].astype(np.float32)  # (h, n)
    angle = (offset[:, None, None] + phi[None, :, None]) * np.arange(P + 1)  # (h, W, P+1): mφ
    trig = np.concatenate([np.cos(angle), np.sin(angle)], axis=-1).astype(np.float32)
    pick = np.where(m_of < 0, P + 1 - m_of, m_of)  # cos(mφ) for m >= 0, sin(|m|φ) for m < 0
    basis = trig[..., pick]
    basis *= amplitude[:, None, :]
    return basis


def undershoot_samples(coeffs: np.ndarray, P: int, views: list | None = None) -> np.ndarray:
    """B(R, V) of a global SHRM (unclamped) on its undershoot sample, channel-major float32
    (3, n): R at every pixel centre (the renderer interpolates bilinearly between them, which
    creates no new minimum at a fixed V), V from :func:`undershoot_views` (computed here when
    not given); the first H·W columns are the normal views."""
    height, width = coeffs.shape[1:3]
    views = undershoot_views(height, width, P) if views is None else views
    _, phi = pixel_angles(height, width)
    out = np.empty((3, len(views) * height * width), dtype=np.float32)
    for i, (theta_v, offset) in enumerate(views):
        block = out[:, i * height * width : (i + 1) * height * width].reshape(3, height, width)
        for r0 in range(0, height, 32):  # row blocks keep the basis array small at high P
            rows = slice(r0, r0 + 32)
            basis = _row_basis(P, theta_v[rows], offset[rows], phi)  # (h, W, n_coef)
            # per pixel (1, n_coef) @ (n_coef, 3): a batched product over (h, W)
            per_pixel = np.matmul(basis[:, :, None, :], coeffs[:, rows].transpose(1, 2, 0, 3))  # (h, W, 1, 3)
            block[:, rows] = per_pixel[:, :, 0, :].transpose(2, 0, 1)
    return out


def undershoot(values: np.ndarray) -> float:
    """−min / max of sampled radiance, channel-major (3, n); worst channel, 0 when nothing is
    negative (the measure of ``eps["gibbs_negative"]`` and ``meta["negative_after"]``)."""
    peak = values.max(axis=1)
    low = values.min(axis=1)
    live = peak > 0
    return float(np.max(np.clip(-low[live] / peak[live], 0.0, None), initial=0.0))
