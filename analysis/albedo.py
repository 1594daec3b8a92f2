"""Directional albedo of a BRDF: a(θ_v) = ∫_{H²} ρ(L, V) cos θ_i dω_i (energy conservation: a ≤ 1).

Integrated by Gauss–Legendre quadrature in cos θ_i times the midpoint rule in φ_i: exact for the
piecewise-smooth part, under-resolving lobes much narrower than the node spacing.
"""

from __future__ import annotations

import numpy as np

from ..brdf_io.brdf import BRDF

__all__ = ["ALBEDO_CHECK_VIEWS_DEG", "directional_albedo"]

#: θ_v at which the report's energy check evaluates the albedo (``data_checks.albedo``).
ALBEDO_CHECK_VIEWS_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0)


def directional_albedo(brdf: BRDF, views_deg: tuple[float, ...] = ALBEDO_CHECK_VIEWS_DEG, nodes: int = 64
                       ) -> np.ndarray:
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
