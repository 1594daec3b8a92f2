"""BRDF coefficients ρ̂_lpq ([RH02] eq. 13, Appendix C three-pass algorithm).

    ρ̂_lpq = 2π ∫₀^π ∫₀^π ∫₀^{2π} ρ̂(θ_i', θ_o', φ') f_lq(θ_i') f_pq(θ_o') cos(qφ')
             sin θ_i' sin θ_o' dφ' dθ_o' dθ_i',        0 <= q <= min(l, p),

computed as three separable passes over a :class:`~shrmkit.brdf_io.reparam.ReparamGrid`:
a cosine transform in φ' (FFT), a Gauss–Legendre sum over θ_o', then one over θ_i'.
ρ̂_{l,−q,p,−q} = ρ̂_lpq, and Parseval reads
∫∫ ρ̂² dω_i dω_o = Σ_{l,p} (ρ̂_lp0² + 2 Σ_{q>=1} ρ̂_lpq²).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..brdf_io.reparam import ReparamBRDF, ReparamGrid
from .sh import legendre_f

__all__ = ["BRDFCoefficients", "rho_lpq", "rho_lpq_direct", "weighted_legendre"]


@lru_cache(maxsize=16)
def weighted_legendre(lmax: int, mmax: int, n_nodes: int) -> np.ndarray:
    """f_lm(θ_j) w_j at the ``n_nodes`` Gauss–Legendre nodes of a :class:`ReparamGrid` axis
    (θ ascending, weights folded in): (lmax+1, mmax+1, n_nodes), read-only, computed once per
    size (the θ_i' pass of eq. 13 and of the view profile reuse it on every grid of a search)."""
    x, w = ReparamGrid(n_nodes, 1, 1).theta_i()
    out = legendre_f(lmax, mmax, x) * w
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class BRDFCoefficients:
    """ρ̂_lpq for l <= F0, p <= P0, 0 <= q <= min(l, p).

    Attributes
    ----------
    coeffs
        float64 (F0+1, P0+1, P0+1, 3) indexed [l, p, q, channel]; zero where q > min(l, p).
    energy
        ∫∫ ρ̂² per channel by independent quadrature of the samples (shape (3,)).
    """

    coeffs: np.ndarray
    energy: np.ndarray
    name: str

    @property
    def F0(self) -> int:
        return self.coeffs.shape[0] - 1

    @property
    def P0(self) -> int:
        return self.coeffs.shape[1] - 1

    def parseval_terms(self) -> np.ndarray:
        """ρ̂_lpq² with multiplicity (1 for q = 0, 2 for q >= 1): (F0+1, P0+1, P0+1, 3)."""
        mult = np.where(np.arange(self.P0 + 1) == 0, 1.0, 2.0)
        return self.coeffs**2 * mult[None, None, :, None]


def rho_lpq(reparam: ReparamBRDF, F0: int, P0: int) -> BRDFCoefficients:
    """Fast three-pass ρ̂_lpq (RH02 eq. 13, Appendix C).

    Parameters
    ----------
    reparam
        ρ̂ on a quadrature grid with ``n_theta_i > F0``, ``n_theta_o > P0`` and
        ``n_phi > 2 P0`` (so the discrete transform is orthonormal).
    F0, P0
        Largest orders computed.
    """
    grid = reparam.grid
    if grid.n_theta_i <= F0 or grid.n_theta_o <= P0 or grid.n_phi <= 2 * P0:
        raise ValueError(f"grid {grid} too coarse for orders F0={F0}, P0={P0}")
    # pass 1: Σ_φ ρ̂ cos(qφ_k) Δφ = Re FFT (φ_k = 2πk/n), in blocks of θ_i' rows (the complex
    # transform of a whole fine grid would double its memory)
    values = reparam.values
    g = np.empty((values.shape[0], values.shape[1], P0 + 1, 3))
    rows = max(1, (1 << 20) // max(values.shape[1] * values.shape[2], 1))
    for r0 in range(0, values.shape[0], rows):
        block = np.fft.rfft(values[r0 : r0 + rows], axis=2).real[:, :, : P0 + 1]
        g[r0 : r0 + rows] = block * (2.0 * np.pi / grid.n_phi)
    # pass 2: θ_o' sum with f_pq(θ_o') → h[i, p, q, c]; pass 3: θ_i' sum with f_lq(θ_i')
    # and the 2π of eq. 13 — one matrix product per q
    fo = weighted_legendre(P0, P0, grid.n_theta_o)  # (P0+1, P0+1, n_o), weights folded in
    fi = weighted_legendre(F0, P0, grid.n_theta_i)  # (F0+1, P0+1, n_i)
    n_i = g.shape[0]
    coeffs = np.zeros((F0 + 1, P0 + 1, P0 + 1, 3))
    for q in range(P0 + 1):
        h = np.tensordot(fo[:, q, :], g[:, :, q, :], axes=(1, 1))  # (p, i, c)
        coeffs[:, :, q, :] = 2.0 * np.pi * (fi[:, q, :] @ h.transpose(1, 0, 2).reshape(n_i, -1)).reshape(
            F0 + 1, P0 + 1, 3
        )
    l_idx = np.arange(F0 + 1)[:, None, None]
    p_idx = np.arange(P0 + 1)[None, :, None]
    q_idx = np.arange(P0 + 1)[None, None, :]
    coeffs[(q_idx > l_idx) | (q_idx > p_idx)] = 0.0
    return BRDFCoefficients(coeffs=coeffs, energy=reparam.energy(), name=reparam.name)


def rho_lpq_direct(reparam: ReparamBRDF, l: int, p: int, q: int) -> np.ndarray:
    """One ρ̂_lpq by a direct triple sum over the grid (slow reference for tests)."""
    grid = reparam.grid
    xi, wi = grid.theta_i()
    xo, wo = grid.theta_o()
    phi = grid.phi()
    fi = legendre_f(l, q, xi)[l, q]
    fo = legendre_f(p, q, xo)[p, q]
    total = np.zeros(3)
    dphi = 2.0 * np.pi / grid.n_phi
    for a in range(grid.n_theta_i):
        for b in range(grid.n_theta_o):
            for k in range(grid.n_phi):
                weight = wi[a] * wo[b] * dphi * fi[a] * fo[b] * np.cos(q * phi[k])
                total += weight * reparam.values[a, b, k]
    return 2.0 * np.pi * total
