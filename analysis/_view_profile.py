"""The view profile of a BRDF (:class:`ViewProfile`): its energy per view node and per band, the
input of the bands rule (built by :func:`shrmkit.analysis.view_bands.view_profile`, public there).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .sh import legendre_f

__all__ = ["ViewProfile", "mult_q"]


def mult_q(n: int) -> np.ndarray:
    """Multiplicity of the azimuthal orders q = 0..n−1 of a real field: 1 for q = 0, else 2 (n,)."""
    return np.where(np.arange(n) == 0, 1.0, 2.0)


@dataclass(frozen=True, eq=False)
class ViewProfile:
    """ρ̂ resolved by view elevation: T_lq(θ_o') at Gauss–Legendre nodes of each θ_v band.

    **The identity.** Let T_lq(θ_o') = 2π ∫∫ ρ̂(θ_i', θ_o', φ') f_lq(θ_i') cos(qφ') sin θ_i' dθ_i' dφ'
    (the first and last passes of [RH02] Appendix C, without the θ_o' pass), so that
    T_lq(θ_o') = 2π Σ_p ρ̂_lpq f_pq(θ_o'). For the reflected field B = Σ L_lm ρ̂_lpq 𝒟^l_mq Y_pq
    (DESIGN §5), orthogonality of 𝒟^l_mq over R (∫|𝒟^l_mq|² dΩ = Λ_l²) and of e^{iqφ_o'}
    gives, at a fixed θ_o', the mean square over all reflection directions R and view azimuths

        D(θ_o') = Σ_{l,q} mult_q Λ_l² a_l T_lq(θ_o')² / (2π) / (8π²),    a_l = Σ_m |L_lm|²,

    (mult_q = 1 for q = 0, 2 otherwise; the constant 8π² cancels in every ratio below). The
    error of a truncated, windowed SHRM is the same sum with T_lq − T̂_lq, where
    T̂_lq = 2π Σ_{p<=P} σ_lp ρ̂_lpq f_pq for l <= F and 0 beyond. The relative RMS in a band
    [θ_a, θ_b] of θ_v is sqrt(∫ D_err dθ_v / ∫ D dθ_v), with θ_v uniform in angle and R
    uniform on the sphere — exactly the distribution of
    :func:`~shrmkit.analysis.compare.sample_pairs`, so the stated number and the measured
    relative RMS of ``shrm compare`` are the same quantity. Each band is integrated by
    Gauss–Legendre nodes in θ_v, where ρ̂ is sampled afresh (the orders' grid in θ_i' and φ').

    Attributes
    ----------
    edges_deg
        Band edges of θ_v in degrees, (n_bands + 1,), from 0 to 90.
    theta_v, weight, band
        Nodes θ_v (radians), their dθ_v quadrature weights and band index, each (K,).
    T
        float64 (F0+1, K, P0+1, 3): T_lq at each node (above), q <= P0 (:func:`view_profile`
        makes it a view of :attr:`Tq`, the layout the sums over q and l read fastest).
    beyond
        (K, 3): the energy density 𝓔(θ_o') − Σ_{l<=F0, q<=P0} mult T²/(2π) the table does
        not resolve (l > F0 or q > P0), >= 0.
    missing
        (n_bands,) int: samples per band where a measured table had no data (extrapolated).
    q_energy
        (K, n_phi//2 + 1, 3) or None: the energy density of each azimuthal order q of ρ̂ at
        the node, all l together (mult_q Σ_i w_i g_q(θ_i')², g_q the cosine transform in φ'),
        up to the grid's φ' Nyquist order — what the grid resolves beyond P0, for the
        resolution check of the order choice (:func:`resolution_tail`).
    """

    edges_deg: np.ndarray
    theta_v: np.ndarray
    weight: np.ndarray
    band: np.ndarray
    T: np.ndarray
    beyond: np.ndarray
    missing: np.ndarray
    name: str = ""
    q_energy: np.ndarray | None = None

    @property
    def n_bands(self) -> int:
        return len(self.edges_deg) - 1

    @property
    def F0(self) -> int:
        return self.T.shape[0] - 1

    @property
    def P0(self) -> int:
        return self.T.shape[2] - 1

    @cached_property
    def Tq(self) -> np.ndarray:
        """T_lq as (P0+1, K, 3, F0+1) [q, node, channel, l], C-contiguous (read-only; no copy when
        :attr:`T` is a view of it, as :func:`view_profile` makes it)."""
        out = np.ascontiguousarray(self.T.transpose(2, 1, 3, 0))
        out.setflags(write=False)
        return out

    @cached_property
    def _full(self) -> np.ndarray:
        out = _q_sum_of_squares(self.Tq).transpose(2, 0, 1).copy()
        out.setflags(write=False)
        return out

    def full(self) -> np.ndarray:
        """Σ_q mult T²/(2π) per (l, node, channel): (F0+1, K, 3) (read-only, computed once)."""
        return self._full

    @cached_property
    def band_matrix(self) -> np.ndarray:
        """(n_bands, K): each node's dθ_v weight in its band's row, 0 elsewhere (:meth:`band_sum`)."""
        m = np.zeros((self.n_bands, self.theta_v.size))
        m[self.band, np.arange(self.theta_v.size)] = self.weight
        return m

    def band_sum(self, per_node: np.ndarray) -> np.ndarray:
        """Σ over each band's nodes of weight × value; ``per_node`` has the nodes on axis 0."""
        return np.tensordot(self.band_matrix, per_node, axes=(1, 0))

    def view_legendre(self, P: int) -> np.ndarray:
        """f_pq(cos 2θ_v) at the nodes for p, q <= P: (P+1, P+1, K) (computed once at P0)."""
        return self._view_legendre[: P + 1, : P + 1]

    @cached_property
    def _view_legendre(self) -> np.ndarray:
        return legendre_f(self.P0, self.P0, np.cos(2.0 * self.theta_v))

    @cached_property
    def fit_cache(self) -> dict:
        """Working data of the view fits of this profile, by the F0 they keep
        (:mod:`shrmkit.analysis._view_fit`: what every view order P shares; filled on first use)."""
        return {}

    @cached_property
    def band_full(self) -> np.ndarray:
        """Band sums of :meth:`full`: (n_bands, F0+1, 3)."""
        return self.band_sum(np.moveaxis(self.full(), 1, 0))

    @cached_property
    def band_beyond(self) -> np.ndarray:
        """Band sums of ``beyond``: (n_bands, 3)."""
        return self.band_sum(self.beyond)

    def energy(self) -> np.ndarray:
        """∫∫ ρ̂² dω_i dω_o per channel (3,) by the profile's own quadrature (sin θ_o' dθ_o' =
        2 sin 2θ_v dθ_v over the band nodes): the energy of :meth:`ReparamBRDF.energy
        <shrmkit.brdf_io.reparam.ReparamBRDF.energy>` without the θ_o' grid."""
        density = self.full().sum(axis=0) + self.beyond  # (K, 3)
        return (self.weight * 2.0 * np.sin(2.0 * self.theta_v)) @ density


def _q_sum_of_squares(Tq: np.ndarray) -> np.ndarray:
    """Σ_q mult_q T_lq²/(2π) per (node, channel, l), (K, 3, F0+1), from T_lq as [q, node, channel, l]."""
    squares = Tq * Tq
    return np.tensordot(mult_q(Tq.shape[0]) / (2.0 * np.pi), squares, axes=(0, 0))
