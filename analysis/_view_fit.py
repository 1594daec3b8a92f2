"""The view fit: ρ̂_lpq fitted to the views that matter, and the ``"bands"`` rule's ε column from it.

:func:`fit_view_coefficients` fits the view dependence of a :class:`~shrmkit.analysis.view_bands.ViewProfile`
(weighted least squares per (l, q) over the band nodes, reweighted toward the worst band inside the
view limit); :func:`band_eps_column` gives one column ε(F, P), F = 0..F0, of the order rule's table
from that fit. Both are public from :mod:`shrmkit.analysis.view_bands`, which documents the
identity they rest on; this module holds the work, and what one profile's fits share whatever
the view order P (:class:`_FitParts`, computed once per profile and F0, kept on the profile: an
order search fits several P on the same profile).

Reference: [RH02] §3.1, §5.1 and Appendices B–C (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ._band_eps import bands_inside, eps_from_band_residual, profile_totals
from ._view_profile import mult_q
from .brdf_coeffs import BRDFCoefficients

if TYPE_CHECKING:
    from ._view_profile import ViewProfile

__all__ = ["OUTSIDE_WEIGHT", "FIT_PASSES", "fit_view_coefficients", "band_eps_column", "profile_shaped"]

#: Weight of the bands beyond the view limit in the view fit (relative to those inside):
#: small, so that the grazing singularity of physically based lobes (ρ̂ ∝ 1/cos θ_v) does not
#: spoil the views inside, but not zero, so that the fit stays tame beyond the limit.
OUTSIDE_WEIGHT = 0.02
#: Reweighting passes of the view fit toward the worst band inside the limit (Lawson-style,
#: square-root damped), stopped early when a pass gains < 0.5 %: the least-squares fit alone
#: leaves the band next to the limit worst (Cook–Torrance α = 0.1, f0 = 0.04: ε 0.031 after
#: 4 passes, 0.030 after 8).
FIT_PASSES = 8
#: The weighted least squares of a pass are solved by their normal equations (B^T W B) x = B^T W y,
#: and the pass's residual taken from the Gram matrices in O(P K²), when the bound on their
#: condition number κ₁ is below this (measured: <= 1.3·10³ for the model families and RGL tables at
#: P <= 20 on the default bands' 44 nodes, so both carry <= ~10⁻¹³ relative rounding); else by QR
#: of the weighted basis and the residual operator in full (P close to the node count: the fit
#: nearly interpolates the nodes, κ₁ 4·10⁸ at P = 38 of 44, and rounding relative to the signal
#: would swamp the small residual).
NORMAL_EQUATIONS_COND = 1e6


def fit_view_coefficients(
    profile: ViewProfile, coefficients: BRDFCoefficients | None, P: int, max_view_deg: float,
    F0: int | None = None,
) -> BRDFCoefficients:
    """ρ̂_lpq (p <= P) fitted to T_lq over the views that matter, instead of projected.

    RH02's coefficients are the orthogonal projection over *all* views θ_o' ∈ [0, π]; for a
    physically based lobe ρ̂ grows like 1/cos θ_v toward grazing (Smith G and Fresnel keep
    it large), so the projection spends its P orders on the last few degrees and converges
    slowly everywhere (measured, Cook–Torrance α = 0.092: ε_b 0.03–0.09 in *every* band at
    P = 16). Here, for each (l, q), the coefficients minimize Σ_k W_k (T_lq(θ_k) − T̂_lq(θ_k))²
    over the profile's nodes, with W_k = dθ_v weight / the band's signal (each band's relative
    error counts alike), bands beyond ``max_view_deg`` down-weighted by
    :data:`OUTSIDE_WEIGHT`, then :data:`FIT_PASSES` passes that raise the weight of the bands
    inside with the largest error. The l-expansion is still the projection (exact in l).

    Parameters
    ----------
    profile
        The BRDF's :class:`~shrmkit.analysis.view_bands.ViewProfile`.
    coefficients
        ρ̂_lpq whose shape and energy the result takes (entries p > P zero); None: the shape
        (F0+1, P0+1, P0+1, 3) of the profile and the energy its ``energy()``.
    P
        View order of the fit, <= the profile's P0.
    max_view_deg
        View limit θ_v in degrees: the bands starting below it are fitted in full.
    F0
        With ``coefficients`` None, the highest l kept (default the profile's): the fit of
        :func:`band_eps_column` with that F0.

    Returns
    -------
    BRDFCoefficients
        float64 coefficients [l, p, q, channel].

    Raises
    ------
    numpy.linalg.LinAlgError
        P >= the number of band nodes (44 for the default bands): the fit is singular.
    """
    if coefficients is None:
        coefficients = profile_shaped(profile, F0)
    F0 = min(profile.F0, coefficients.F0)
    fit = _FitParts.of(profile, F0).solve(P, max_view_deg).coefficients()
    out = np.zeros_like(coefficients.coeffs)
    out[: F0 + 1, : P + 1, : P + 1] = fit
    return BRDFCoefficients(coeffs=out, energy=coefficients.energy, name=coefficients.name)


def band_eps_column(profile: ViewProfile, P: int, max_view_deg: float, F0: int | None = None) -> np.ndarray:
    """One column of :func:`~shrmkit.analysis.view_bands.band_eps_table` from the profile alone:
    ε(F, P) for F = 0..F0 of the worst band inside ``max_view_deg`` (worst channel), with the view
    fit at order ``P`` (equal to ``_band_eps_all`` of :func:`fit_view_coefficients`; the fit's own
    residual is used). ``F0`` (default the profile's): the highest order kept; the profile's orders
    above it count as error, and the view fit is made for l <= F0 (the column of a profile cut at F0).

    Returns
    -------
    numpy.ndarray
        (F0+1,) energy fractions.

    Raises
    ------
    numpy.linalg.LinAlgError
        As :func:`fit_view_coefficients`.
    """
    F0 = profile.F0 if F0 is None else min(int(F0), profile.F0)
    parts = _FitParts.of(profile, F0)
    # the fit's residual at q <= P, and all of the energy at P < q <= P0 (no term of the fit holds it)
    residual = parts.solve(P, max_view_deg).band_residual() + parts.band_tail(P)
    return eps_from_band_residual(profile, F0, residual)[bands_inside(profile, max_view_deg)].max(axis=0)


def profile_shaped(profile: ViewProfile, F0: int | None = None) -> BRDFCoefficients:
    """Zero ρ̂_lpq of the profile's orders (F0+1, P0+1, P0+1, 3) (``F0`` default the profile's)
    carrying its energy: the shape a view fit fills when no projected coefficients are at hand."""
    F0 = profile.F0 if F0 is None else min(int(F0), profile.F0)
    shape = (F0 + 1, profile.P0 + 1, profile.P0 + 1, 3)
    return BRDFCoefficients(coeffs=np.zeros(shape), energy=profile.energy(), name=profile.name)


class _FitParts:
    """What every view fit of one profile at one F0 shares, whatever P: the right-hand sides
    T_lq (l <= F0) by q, their Gram matrices per (q, channel) over the nodes, the energy per
    azimuthal order q (per node summed over l, and per band and l) and the band totals of
    ε_b(F0) — each computed once (the Gram matrices for the q asked so far)."""

    def __init__(self, profile: ViewProfile, F0: int) -> None:
        self.profile, self.F0 = profile, F0
        self.K = profile.theta_v.size
        self.n_cols = (F0 + 1) * 3
        # T_lq as [q, node, (channel, l)] (a view of the profile's Tq when F0 is the profile's)
        self.Y = np.ascontiguousarray(profile.Tq[..., : F0 + 1]).reshape(profile.P0 + 1, self.K, self.n_cols)
        self._gram = np.empty((0, self.K, 3 * self.K))
        totals = profile_totals(profile, F0)
        self.total, self.after = totals.total, totals.beyond  # (nb, 3): all energy, energy at l > F0
        self.live = totals.live & (self.total > 0)
        self.safe_total = np.where(self.total > 0, self.total, 1.0)

    @staticmethod
    def of(profile: ViewProfile, F0: int) -> _FitParts:
        """The parts of ``profile`` at ``F0``, made on first use and kept on the profile."""
        cache = profile.fit_cache
        if F0 not in cache:
            cache[F0] = _FitParts(profile, F0)
        return cache[F0]

    def rhs(self, P: int) -> np.ndarray:
        """T_lq for q <= P as (P+1, K, 3·(F0+1)) [q, node, (channel, l)]: the right-hand sides of the fit."""
        return self.Y[: P + 1]

    def gram(self, P: int) -> np.ndarray:
        """G_qc = Σ_l T_lq T_lq^T over the nodes for q <= P, the channels side by side:
        (P+1, K, 3·K) [q, node, channel·node] (computed once per q; every array kept is a whole
        prefix in q, so callers in other threads read a correct one whichever they find)."""
        gram = self._gram
        done = gram.shape[0]
        if P + 1 > done:
            by_channel = self.rhs(P)[done:].reshape(P + 1 - done, self.K, 3, self.F0 + 1).transpose(0, 2, 1, 3)
            more = (by_channel @ by_channel.transpose(0, 1, 3, 2)).transpose(0, 2, 1, 3)  # [q, k, c, j]
            gram = self._gram = np.concatenate([gram, more.reshape(P + 1 - done, self.K, 3 * self.K)])
        return gram[: P + 1]

    def gram_diagonal(self, P: int) -> np.ndarray:
        """The diagonals of :meth:`gram`, (P+1, 3, K): Σ_l T_lq² per (q, channel, node)."""
        gram = self.gram(P).reshape(P + 1, self.K, 3, self.K)
        return np.diagonal(gram, axis1=1, axis2=3)

    @cached_property
    def _q_energy(self) -> tuple[np.ndarray, np.ndarray]:
        """mult_q T_lq²/(2π) per q: summed over l per node (P0+1, K, 3), and per band (P0+1, nb, F0+1, 3)."""
        profile = self.profile
        Q, nb = profile.P0 + 1, profile.n_bands
        T2 = self.Y * self.Y  # (P0+1, K, 3·(F0+1))
        T2 *= (mult_q(Q) / (2.0 * np.pi))[:, None, None]
        per_node = T2.reshape(Q, self.K, 3, self.F0 + 1).sum(axis=3)
        per_band = np.matmul(profile.band_matrix, T2).reshape(Q, nb, 3, self.F0 + 1).transpose(0, 1, 3, 2)
        return per_node, per_band

    @cached_property
    def band_normals(self) -> np.ndarray:
        """Σ_{k in b} dθ_v weight_k B_k^T B_k per (q, band) of the basis at the profile's P0,
        (P0+1, P0+1, P0+1, n_bands) [q, p − q, p' − q, band] (zero where p or p' > P0)."""
        profile = self.profile
        basis = _basis(profile, profile.P0)  # [q, node, p − q]
        weighted = basis * profile.weight[None, :, None]
        out = np.empty(basis.shape[:1] + basis.shape[2:] * 2 + (profile.n_bands,))
        for b in range(profile.n_bands):
            nodes = profile.band == b
            out[..., b] = weighted[:, nodes].transpose(0, 2, 1) @ basis[:, nodes]
        return out

    def node_tail(self, P: int) -> np.ndarray:
        """Σ_{l<=F0, P<q<=P0} mult T²/(2π) per (node, channel), (K, 3): what no fit at order P holds."""
        return self._q_energy[0][P + 1 :].sum(axis=0)

    def band_tail(self, P: int) -> np.ndarray:
        """The band sums of the energy at P < q <= P0 per (band, l, channel), (nb, F0+1, 3)."""
        return self._q_energy[1][P + 1 :].sum(axis=0)

    def band_eps_at_F0(self, residual: np.ndarray) -> np.ndarray:
        """ε_b(F0) per band (n_bands,), worst live channel, from a per-node error density (K, 3)
        summed over l <= F0 (the energy at l > F0 added): the reweighting passes' measure."""
        err = self.profile.band_matrix @ residual + self.after
        eps = np.where(self.live, err / self.safe_total, 0.0)
        return np.maximum(eps, 0.0).max(axis=-1)

    def solve(self, P: int, max_view_deg: float) -> _Fit:
        """The reweighted fit at view order ``P`` (:func:`fit_view_coefficients`)."""
        return _Fit(self, P, max_view_deg)


class _Fit:
    """One view fit at order P: the basis, the reweighting passes and the final least-squares
    operator M (ρ̂ = M T per q), and what is read from it (coefficients, band residual).

    The basis of each q, 2π f_pq(cos 2θ_v) for p = q..P, is padded with zero columns to P+1 so
    that all q are solved at once; in the normal equations each padding column gets a unit
    diagonal entry (in the QR fallback a unit row), so the system has full rank and its
    solution there is zero: the padding changes nothing."""

    def __init__(self, parts: _FitParts, P: int, max_view_deg: float) -> None:
        self.parts, self.P = parts, P
        self.basis = _basis(parts.profile, P)
        # 1 on the padding columns of each q: p − q > P − q
        self.pad = (np.arange(P + 1)[None, :] > P - np.arange(P + 1)[:, None]).astype(np.float64)
        self.mult = mult_q(P + 1) / (2.0 * np.pi)
        self.pad_eye = self.pad[:, :, None] * np.eye(P + 1)  # a unit diagonal entry per padding column
        self.M = self._reweighted(max_view_deg)

    def _band_normals(self) -> np.ndarray:
        """Σ_{k in b} dθ_v weight_k B_k^T B_k per (q, band) at this P: ((P+1)³, n_bands)
        [(q, p − q, p' − q), band] (the profile's at P0, the columns above P zeroed)."""
        keep = 1.0 - self.pad
        normals = self.parts.band_normals[: self.P + 1, : self.P + 1, : self.P + 1] * (
            keep[:, :, None, None] * keep[:, None, :, None])
        return normals.reshape(-1, normals.shape[-1])  # [(q, p − q, p' − q), band]: one product per pass

    def _operator(self, node_w: np.ndarray, band_w: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, bool]:
        """M = (B^T W B)^{-1} B^T W per q, (P+1, P+1, K), W = diag(``node_w``) = the node weights ×
        ``band_w`` of each node's band, and whether it came from the normal equations (``normals``:
        :meth:`_band_normals`), used when well conditioned (:data:`NORMAL_EQUATIONS_COND`), or from
        QR of the weighted basis."""
        A = (normals @ band_w).reshape(self.pad_eye.shape) + self.pad_eye
        try:
            inverse = np.linalg.inv(A)
            # max_q ‖A‖₁ × max_q ‖A⁻¹‖₁ >= the largest condition number κ₁ of the q
            if np.abs(A).sum(axis=1).max() * np.abs(inverse).sum(axis=1).max() < NORMAL_EQUATIONS_COND:
                return inverse @ (self.basis.transpose(0, 2, 1) * node_w), True
        except np.linalg.LinAlgError:
            pass
        sw = np.sqrt(node_w)
        Q, Rq = np.linalg.qr(np.concatenate([self.basis * sw[None, :, None], self.pad_eye], axis=1))
        return np.linalg.solve(Rq, Q.transpose(0, 2, 1))[:, :, : self.parts.K] * sw[None, None, :], False

    def _pass_residual(self, M: np.ndarray, gram: np.ndarray, gram_diag: np.ndarray, low_rank: bool) -> np.ndarray:
        """Σ_q mult Σ_l (R T)²/(2π) per (node, channel), (K, 3), R = I − B M the residual operator:
        the diagonal of R G R^T per (q, channel) from the Gram matrices G (``gram``:
        :meth:`_FitParts.gram`, one matrix product per q serves the three channels; never a pass
        over every (l, channel) column). ``low_rank``: as G − 2 B (M G) + B (M G M^T) B^T, O(P K²)
        per (q, channel); else as (R G) R^T, O(K³), whose rounding stays relative to R where the
        fit nearly interpolates the nodes (P close to K, when the normal equations are not used)."""
        P1, K = self.P + 1, self.parts.K
        if low_rank:
            Bt = self.basis.transpose(0, 2, 1)  # (P+1, P+1, K)
            per_q = np.empty((P1, 3, K))
            half = (P1 + 1) // 2
            # the q >= P+1 − half have at most ``half`` basis columns: their products skip the padding
            for qs, n in ((slice(0, P1 - half), P1), (slice(P1 - half, P1), half)):
                Mq, Bq = M[qs, :n], Bt[qs, :n]
                H = (Mq @ gram[qs]).reshape(-1, n * 3, K)  # M G: [q, (p, c), k]
                Z = (H @ Mq.transpose(0, 2, 1)) @ Bq  # M G M^T B^T
                Z -= 2.0 * H
                per_q[qs] = gram_diag[qs] + np.einsum("qpk,qpck->qck", Bq, Z.reshape(-1, n, 3, K))
        else:
            R = np.eye(K) - self.basis @ M  # (P+1, K, K)
            per_q = np.einsum("qkcj,qkj->qck", (R @ gram).reshape(P1, K, 3, K), R)
        return (self.mult @ per_q.reshape(P1, 3 * K)).reshape(3, K).T

    def _reweighted(self, max_view_deg: float) -> np.ndarray:
        """The operator M after the reweighting passes toward the worst band inside the limit."""
        parts, P = self.parts, self.P
        profile = parts.profile
        inside = np.zeros(profile.n_bands, dtype=bool)
        inside[bands_inside(profile, max_view_deg)] = True
        signal = (profile.band_full.sum(axis=1) + profile.band_beyond).sum(axis=1)
        band_w = np.where(inside, 1.0, OUTSIDE_WEIGHT) / np.where(signal > 0, signal, 1.0)
        normals = self._band_normals()
        prev_worst = np.inf
        for npass in range(FIT_PASSES + 1):
            M, low_rank = self._operator(profile.weight * band_w[profile.band], band_w, normals)
            if npass == FIT_PASSES or not inside.any():
                return M
            if npass == 0:
                gram, gram_diag, fixed = parts.gram(P), parts.gram_diagonal(P), parts.node_tail(P)
            eps = parts.band_eps_at_F0(fixed + self._pass_residual(M, gram, gram_diag, low_rank))
            worst = eps[inside].max()
            if worst <= 0.0 or worst > 0.995 * prev_worst:  # nothing to gain (a view-independent lobe)
                return M
            prev_worst = worst
            band_w = band_w * np.where(inside, np.sqrt(np.minimum(np.maximum(eps / worst, 1e-3), 1.0)), 1.0)
        return M

    def coefficients(self) -> np.ndarray:
        """ρ̂_lpq of the fit for l <= F0: (F0+1, P+1, P+1, 3) [l, p, q, channel]."""
        P, F0 = self.P, self.parts.F0
        sol = (self.M @ self.parts.rhs(P)).reshape(P + 1, P + 1, 3, F0 + 1)  # [q, p − q, c, l]
        fit = np.zeros((F0 + 1, P + 1, P + 1, 3))
        for q in range(P + 1):
            fit[:, q:, q, :] = sol[q, : P + 1 - q].transpose(2, 0, 1)
        return fit

    def band_residual(self) -> np.ndarray:
        """Band sums of Σ_{q<=P} mult (T_lq − T̂_lq)²/(2π) per (band, l, channel), (nb, F0+1, 3)."""
        parts, P = self.parts, self.P
        rhs = parts.rhs(P)
        mult = mult_q(P + 1) / (2.0 * np.pi)
        acc = np.zeros((parts.K, parts.n_cols))
        for q in range(P + 1):
            n = P + 1 - q  # the basis columns of this q (the rest is padding)
            diff = rhs[q] - self.basis[q, :, :n] @ (self.M[q, :n] @ rhs[q])
            diff *= diff
            acc += mult[q] * diff
        return (parts.profile.band_matrix @ acc).reshape(-1, 3, parts.F0 + 1).transpose(0, 2, 1)


def _basis(profile: ViewProfile, P: int) -> np.ndarray:
    """The fit's basis 2π f_pq(cos 2θ_v) of each q for p = q..P, padded with zero columns to P+1:
    (P+1, K, P+1) [q, node, p − q]."""
    fo = profile.view_legendre(P)  # (P+1, P+1, K)
    basis = np.zeros((P + 1, profile.theta_v.size, P + 1))
    for q in range(P + 1):
        basis[q, :, : P + 1 - q] = 2.0 * np.pi * fo[q : P + 1, q, :].T
    return basis
