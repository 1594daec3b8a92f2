"""Data checks of a BRDF for its report: missing data, clamped values, reciprocity, energy.

- *Missing measurements*: table samples marked missing (MERL negative values), and the
  reparameterized / fit samples that had no data to interpolate.
- *Clamped values*: components clipped on input (Cornell spectral → sRGB gives negative
  out-of-gamut components, clipped to 0 by ``brdf_io.cornell``).
- *Reciprocity*: ρ(L, V) = ρ(V, L) (Helmholtz). Evaluable BRDFs are compared at seeded
  random pairs; scattered measurements at pairs whose swapped configuration (θ_i ↔ θ_o,
  same |φ_o − φ_i|) was also measured, within 0.5°. Stated relative to max ρ and, per
  pair, relative to the pair's mean (median, 90th percentile): for a non-reciprocal
  measured file (RGL) the choice of incident direction changes renders by about that much.
- *Energy*: the directional albedo a(V) = ∫_{H²} ρ(L, V) cos θ_i dω_i must not exceed 1;
  it is integrated by Gauss–Legendre quadrature in cos θ_i times the midpoint rule in φ_i
  (exact for the piecewise-smooth part, under-resolving lobes much narrower than the
  node spacing, which the report says).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ...brdf_io.brdf import BRDF
from ...brdf_io.halfdiff import halfdiff_to_directions
from ...brdf_io.merl import merl_sample_angles

__all__ = ["directional_albedo", "reciprocity_check", "pair_asymmetry", "scattered_reciprocity", "data_checks",
           "merl_missing_above_surface", "ALBEDO_VIEWS_DEG"]

ALBEDO_VIEWS_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0)
#: relative asymmetry |ρ(L,V) − ρ(V,L)| / max(ρ) above which a BRDF is called non-reciprocal
RECIPROCITY_TOLERANCE = 1e-3


def directional_albedo(brdf: BRDF, views_deg: tuple[float, ...] = ALBEDO_VIEWS_DEG, nodes: int = 64) -> np.ndarray:
    """a(θ_o) = ∫ ρ(L, V) cos θ_i dω_i per channel, shape (len(views_deg), 3).

    Quadrature: ``nodes`` Gauss–Legendre nodes in cos θ_i ∈ (0, 1) and 2·``nodes`` midpoint
    nodes in φ_i; V = (sin θ_o, 0, cos θ_o). The cosine-weighted ρ̂ of the BRDF is used
    (``BRDF.rho_hat``; Phong and the simplified microfacet define it directly).
    """
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    mu = 0.5 * (x + 1.0)
    w_mu = 0.5 * w
    n_phi = 2 * int(nodes)
    phi = (np.arange(n_phi) + 0.5) * 2.0 * np.pi / n_phi
    sin = np.sqrt(1.0 - mu**2)
    L = np.stack(
        [
            sin[:, None] * np.cos(phi)[None, :],
            sin[:, None] * np.sin(phi)[None, :],
            np.broadcast_to(mu[:, None], (mu.size, n_phi)),
        ],
        axis=-1,
    )
    weight = w_mu[:, None] * (2.0 * np.pi / n_phi)
    out = np.zeros((len(views_deg), 3))
    for k, deg in enumerate(views_deg):
        t = np.radians(deg)
        V = np.broadcast_to(np.array([np.sin(t), 0.0, np.cos(t)]), L.shape)
        rho_hat = brdf.rho_hat(L, V)
        out[k] = np.einsum("ijc,ij->c", rho_hat, weight)
    return out


def _random_hemisphere(n: int, rng: np.random.Generator, max_theta_deg: float = 85.0) -> np.ndarray:
    mu = rng.uniform(np.cos(np.radians(max_theta_deg)), 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - mu**2)
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)


def pair_asymmetry(a: np.ndarray, b: np.ndarray) -> tuple[float | None, float | None]:
    """Median and 90th percentile over pairs of |ρ(L,V) − ρ(V,L)| / ((ρ(L,V) + ρ(V,L))/2), ρ summed
    over the channels; ``a``, ``b`` (n, 3) are ρ(L,V) and ρ(V,L). Pairs whose mean is 0 (or below
    10⁻⁹ of the largest) are left out; ``(None, None)`` if none is left. A per-pair relative figure:
    the few pairs in a glossy peak do not dominate it (an RMS over 2000 random pairs varied 2–5x
    between seeds for the RGL vinyls; this median by at most 6 %)."""
    a, b = np.asarray(a, float).sum(axis=-1), np.asarray(b, float).sum(axis=-1)
    mean = 0.5 * (a + b)
    ok = mean > 1e-9 * max(float(mean.max(initial=0.0)), 1e-300)
    if not np.any(ok):
        return None, None
    rel = np.abs(a - b)[ok] / mean[ok]
    return float(np.median(rel)), float(np.quantile(rel, 0.9))


def reciprocity_check(brdf: BRDF, n: int = 2000, seed: int = 0) -> dict[str, Any]:
    """Reciprocity ρ(L,V) = ρ(V,L) at ``n`` seeded random pairs (L, V each uniform in solid angle on
    the cap θ ≤ 85°): max and RMS of |ρ(L,V) − ρ(V,L)| relative to max ρ (``max_rel``, ``rms_rel``)
    and the median and 90th percentile of the per-pair relative difference (``median_pair_rel``,
    ``p90_pair_rel``: :func:`pair_asymmetry`), the figures to quote for a measured file (the RGL
    files: median 0.022 paper, 0.040 paint, 0.18–0.32 vinyls; data_specs/rgl_bsdf.md)."""
    rng = np.random.default_rng(seed)
    L = _random_hemisphere(n, rng)
    V = _random_hemisphere(n, rng)
    a = brdf.eval(L, V)
    b = brdf.eval(V, L)
    scale = float(max(np.max(np.abs(a)), np.max(np.abs(b)), 1e-300))
    diff = np.abs(a - b) / scale
    return {
        "method": "random pairs",
        "n_pairs": int(n),
        "max_rel": float(diff.max()),
        "rms_rel": float(np.sqrt(np.mean(diff**2))),
        **dict(zip(("median_pair_rel", "p90_pair_rel"), pair_asymmetry(a, b), strict=True)),
    }


def _angles(L: np.ndarray, V: np.ndarray) -> np.ndarray:
    th_i = np.arccos(np.clip(L[:, 2], -1, 1))
    th_o = np.arccos(np.clip(V[:, 2], -1, 1))
    dphi = np.abs(np.angle(np.exp(1j * (np.arctan2(V[:, 1], V[:, 0]) - np.arctan2(L[:, 1], L[:, 0])))))
    return np.stack([th_i, th_o, dphi], axis=-1)


def scattered_reciprocity(L: np.ndarray, V: np.ndarray, rgb: np.ndarray, tol_deg: float = 0.5) -> dict[str, Any]:
    """Compare measurements at swapped configurations (θ_i, θ_o, Δφ) ↔ (θ_o, θ_i, Δφ)."""

    a = _angles(np.asarray(L, float), np.asarray(V, float))
    swapped = a[:, [1, 0, 2]]
    tree = cKDTree(a)
    dist, idx = tree.query(swapped, distance_upper_bound=np.radians(tol_deg))
    ok = np.isfinite(dist) & (a[:, 0] != a[:, 1])
    if not np.any(ok):
        return {"method": "swapped measurements", "n_pairs": 0, "max_rel": None, "rms_rel": None,
                "median_pair_rel": None, "p90_pair_rel": None}
    rgb = np.asarray(rgb, float)
    scale = np.maximum(np.maximum(np.abs(rgb[ok]), np.abs(rgb[idx[ok]])).max(axis=1, keepdims=True), 1e-300)
    diff = np.abs(rgb[ok] - rgb[idx[ok]]) / scale
    return {
        "method": "swapped measurements",
        "n_pairs": int(ok.sum() // 2),
        "max_rel": float(diff.max()),
        "rms_rel": float(np.sqrt(np.mean(diff**2))),
        **dict(zip(("median_pair_rel", "p90_pair_rel"), pair_asymmetry(rgb[ok], rgb[idx[ok]]), strict=True)),
    }


def merl_missing_above_surface(brdf: BRDF) -> int | None:
    """Missing MERL table samples whose (L, V) are both above the surface (``None`` if not MERL).

    Samples with tan θ_h tan θ_d |cos φ_d| >= 1 put L or V below the surface; they are
    missing in every MERL file (and in tabulated models) and are not a data problem.
    """
    values = getattr(brdf, "values", None)
    if values is None or getattr(values, "shape", None) != (3, 90, 90, 180):
        return None

    th, td, pd = merl_sample_angles()
    L, V = halfdiff_to_directions(th[:, None, None], td[None, :, None], pd[None, None, :])
    above = (L[..., 2] > 0) & (V[..., 2] > 0)
    missing = np.any(np.isnan(values), axis=0)
    return int(np.count_nonzero(missing & above))


def data_checks(brdf: BRDF, analysis_brdf: BRDF, *, seed: int = 0, albedo_nodes: int = 64) -> dict[str, Any]:
    """The ``data_checks`` block of a report (``data_specs/report_json.md``).

    ``analysis_brdf`` is the BRDF the frequency analysis uses (the BRDF itself, or for
    scattered data the fitted model); its albedo is reported.
    """
    scattered = brdf.kind == "scattered"
    if scattered:
        reciprocity = scattered_reciprocity(brdf.L, brdf.V, brdf.rgb)
    else:
        reciprocity = reciprocity_check(brdf, seed=seed)
    albedo = directional_albedo(analysis_brdf, nodes=albedo_nodes)
    k = int(np.argmax(albedo.max(axis=1)))
    return {
        "n_measurements": int(len(brdf)) if scattered else None,
        "n_missing": int(getattr(brdf, "n_missing", 0)),
        "n_missing_above_surface": merl_missing_above_surface(brdf),
        "n_clamped": int(getattr(brdf, "n_clipped", 0)),
        "reciprocity": reciprocity,
        "albedo": {
            "of": "fitted model" if scattered else "brdf",
            "views_deg": list(ALBEDO_VIEWS_DEG),
            "rgb": albedo.tolist(),
            "max": float(albedo.max()),
            "max_view_deg": float(ALBEDO_VIEWS_DEG[k]),
            "nodes": int(albedo_nodes),
        },
    }
