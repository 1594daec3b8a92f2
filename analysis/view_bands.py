"""Error by view band: how accurate a truncated BRDF or SHRM is at each view elevation θ_v.

[RH02]'s ε is one number, an energy average over all views, and hides where the error lives:
physically based lobes put most of their ρ̂ energy at grazing views and are poorly
represented exactly there (DESIGN §4). This module states the error per band of the view
elevation θ_v = θ_o'/2 (the angle between the view and the normal N = normalize(R + V'),
[RH02] §3.1), from the coefficients alone — no brute force.

:func:`view_profile` resolves ρ̂ by view elevation (:class:`ViewProfile`: the identity that turns
coefficients into a band's mean square error), :func:`band_eps_table` and :func:`brdf_view_bands`
state a truncated BRDF's error per band under a point light, and :func:`shrm_view_bands` states an
SHRM's (lighting weights, the map's lookup and storage, the unresolved energy; a prediction and a
bound, :class:`BandStatement`). The bands and what a band states: ``data_specs/view_bands.md``.

Reference: [RH02] §3.1, §5.1 and Appendices B–C (``data_specs/bibliography.md``).

"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import ducc0
import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.errors import BadInputError
from ..brdf_io.quadrature import gauss_legendre
from ..brdf_io.reparam import ReparamGrid, sample_rho_hat_half
from ._band_eps import (
    CHANNEL_FLOOR,
    bands_inside,
    eps_from_band_residual,
    live_channels,
)
from ._view_fit import FIT_PASSES, OUTSIDE_WEIGHT, band_eps_column, fit_view_coefficients, profile_shaped
from ._view_profile import ViewProfile, _q_sum_of_squares, mult_q
from .brdf_coeffs import BRDFCoefficients, weighted_legendre
from .defaults import CRITERIA, DEFAULT_CRITERION, DEFAULT_MAX_VIEW_DEG  # numpy-free home, for the CLI's parsers
from .sh import Lambda, legendre_f

__all__ = [
    "DEFAULT_BAND_EDGES_DEG", "DEFAULT_MAX_VIEW_DEG", "CRITERIA", "DEFAULT_CRITERION", "ViewProfile",
    "view_profile", "fit_view_coefficients", "band_eps_table", "brdf_view_bands", "scene_error_curve",
    "shrm_view_bands", "check_max_view", "check_criterion", "bands_inside", "worst_inside", "BandStatement",
    "window_matrix", "band_eps_column", "resolution_tail", "CHANNEL_FLOOR", "OUTSIDE_WEIGHT", "FIT_PASSES",
]

#: Band edges of θ_v in degrees: 15° wide up to 60°, then 10° and 5° toward grazing.
DEFAULT_BAND_EDGES_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 85.0, 90.0)

_FLOAT32_REL = 2.0**-24
#: Relative margin of every bound over its computed value: covers the Gauss–Legendre
#: quadrature of each band (doubling the nodes changes the per-band errors by < 0.6 %,
#: Cook–Torrance, microfacet σ = 0.05 and 0.3) and the rounding of a float64 reference.
BOUND_MARGIN = 1.05


def check_max_view(value: float) -> float:
    """The view limit as a float in (0, 90] degrees, else :class:`BadInputError`."""
    try:
        deg = float(value)
    except (TypeError, ValueError):
        raise BadInputError(None, f"max view angle must be a number of degrees, got {value!r}") from None
    if not 0.0 < deg <= 90.0:
        raise BadInputError(None, f"max view angle must be in (0, 90] degrees, got {value!r}")
    return deg


def check_criterion(value: str) -> str:
    """``value`` if it names an order rule of :data:`CRITERIA`, else :class:`BadInputError`."""
    if value not in CRITERIA:
        raise BadInputError(None, f"criterion must be one of {', '.join(CRITERIA)}, got {value!r}")
    return value


def _band_nodes(edges_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes in θ_v per band: (θ_v rad (K,), dθ_v weights (K,), band index (K,))."""
    theta, weight, band = [], [], []
    for b, (lo, hi) in enumerate(zip(edges_deg[:-1], edges_deg[1:], strict=True)):
        n = max(4, int(np.ceil((hi - lo) / 2.5)))
        x, w = gauss_legendre(n)
        half = np.radians(hi - lo) / 2.0
        theta.append(np.radians(lo) + half * (x + 1.0))
        weight.append(half * w)
        band.append(np.full(n, b))
    return np.concatenate(theta), np.concatenate(weight), np.concatenate(band)


def _cosine_transform(half: np.ndarray, n_phi: int) -> np.ndarray:
    """Σ_j x_j cos(2π q j / n_phi) over the whole period for q = 0 .. n_phi // 2, from the half
    period x_0 .. x_{n_phi // 2} of an even sequence on axis 3: the real part of its rfft. For
    even n_phi a DCT-I of the half (half the points), for odd n_phi the rfft of the mirrored whole."""
    if n_phi % 2 == 0 and half.shape[3] > 1:
        return ducc0.fft.dct(half, type=1, axes=(3,))
    inner = np.arange(1, (n_phi + 1) // 2)
    whole = np.concatenate([half, half[:, :, :, inner[::-1]]], axis=3)
    return np.fft.rfft(whole, axis=3).real


def view_profile(
    brdf: BRDF, grid: ReparamGrid, F0: int, P0: int, edges_deg: tuple[float, ...] = DEFAULT_BAND_EDGES_DEG
) -> ViewProfile:
    """Sample ρ̂ at Gauss–Legendre nodes of every θ_v band (the θ_i' and φ' nodes of ``grid``)
    and transform it in φ' and θ_i' to T_lq (:class:`ViewProfile`), l <= F0, q <= P0.

    Cost: n_theta_i × K × n_phi BRDF evaluations (K ≈ 57 nodes for the default bands).

    Raises
    ------
    BadInputError
        Non-finite BRDF values; band edges not increasing from 0 to 90.
    """
    edges = np.asarray(edges_deg, dtype=np.float64)
    if edges.ndim != 1 or edges.size < 2 or edges[0] != 0.0 or edges[-1] != 90.0 or np.any(np.diff(edges) <= 0):
        raise BadInputError(None, f"view band edges must increase from 0 to 90 degrees, got {edges_deg!r}")
    if grid.n_theta_i <= F0 or grid.n_phi <= 2 * P0:
        raise ValueError(f"grid {grid} too coarse for orders F0={F0}, P0={P0}")
    theta_v, weight, band = _band_nodes(edges)
    xi, wi = grid.theta_i()
    K, n_i = theta_v.size, grid.n_theta_i
    n_q = grid.n_phi // 2 + 1
    h = (n_i + 1) // 2
    folded = np.empty((2, P0 + 1, K, 3, h))  # Σ_j ρ̂ cos qφ'_j folded by parity in cos θ_i': [parity, q, node, c, i]
    energy = np.empty((K, 3))
    q_energy = np.empty((K, n_q, 3))
    # the half period φ' ∈ [0, π] stands for the whole (ρ̂ is even in φ'): every node but 0 (and π)
    # counts twice, as every cosine order q but 0 (and n_phi/2) does in Parseval's sum
    q_mult = np.where((np.arange(n_q) == 0) | (2 * np.arange(n_q) == grid.n_phi), 1.0, 2.0)
    # Σ_i w_i g_i² = Σ_{i < n_i/2} w_i (e_i² + o_i²)/2 for (e_i, o_i) = g_i ± g_mirror (symmetric
    # weights; the middle node of an odd n_i is e alone, at its own weight)
    w_folded = wi[:h] / 2.0
    if n_i % 2:
        w_folded[-1] = wi[h - 1]
    missing = np.zeros(len(edges) - 1, dtype=np.int64)
    dphi = 2.0 * np.pi / grid.n_phi
    for b in range(len(edges) - 1):
        idx = np.nonzero(band == b)[0]
        nodes = slice(idx[0], idx[-1] + 1)  # a band's nodes are consecutive
        # (n_i, k, n_phi // 2 + 1, 3): φ' ∈ [0, π] (ρ̂ is even in φ')
        values, missing[b] = sample_rho_hat_half(brdf, xi, np.cos(2.0 * theta_v[idx]), grid.n_phi)
        g = _cosine_transform(_fold_theta_i(values), grid.n_phi)  # [parity, i, node, q, c] (fold and DCT: linear)
        np.copyto(folded[:, :, nodes], g[:, :, :, : P0 + 1].transpose(0, 3, 2, 4, 1))
        # per q, all l (Bessel's equality in θ_i'): mult_q ∫ g_q² d cos θ_i'; Σ_q of it is 𝓔 (Parseval)
        per_q = np.matmul(w_folded, np.square(g, out=g).reshape(2, h, -1)).sum(axis=0)
        q_energy[nodes] = per_q.reshape(-1, n_q, 3) * (q_mult * dphi**2)[None, :, None]
        # 𝓔(θ_o') = 2π ∫ dω_i ρ̂²: the density whose sin θ_o' dθ_o' integral is ∫∫ ρ̂² (ReparamBRDF.energy)
        energy[nodes] = 2.0 * np.pi * dphi * np.einsum("kjc,j->kc", np.tensordot(wi, np.square(values, out=values),
                                                                                axes=(0, 0)), q_mult)
    Tq = _theta_i_transform(folded, F0, n_i, 2.0 * np.pi * dphi)  # [q, node, c, l]
    resolved = _q_sum_of_squares(Tq).sum(axis=2)  # (K, 3)
    return ViewProfile(
        edges_deg=edges, theta_v=theta_v, weight=weight, band=band, T=Tq.transpose(3, 1, 0, 2),
        beyond=np.clip(energy - resolved, 0.0, None), missing=missing, name=brdf.name, q_energy=q_energy,
    )


def _fold_theta_i(values: np.ndarray) -> np.ndarray:
    """The even and odd parts in cos θ_i' of ``values`` (n_i, ...) on the symmetric Gauss–Legendre
    nodes (node i and n_i − 1 − i mirror each other): v_i ± v_mirror for i < n_i/2, and the middle
    node of an odd n_i once in the even part: (2, ⌈n_i/2⌉, ...) [parity, i, ...]."""
    n_i = values.shape[0]
    h = n_i // 2
    out = np.empty((2, (n_i + 1) // 2) + values.shape[1:])
    top, bottom = values[:h], values[::-1][:h]
    np.add(top, bottom, out=out[0, :h])
    np.subtract(top, bottom, out=out[1, :h])
    if n_i % 2:
        out[0, h] = values[h]
        out[1, h] = 0.0
    return out


@lru_cache(maxsize=8)
def _parity_legendre(F0: int, P0: int, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """The weighted f_lq(θ_i') w_i of :func:`weighted_legendre` on the first ⌈n/2⌉ nodes, for even
    and for odd l: ((P0+1, ⌈n/2⌉, ⌈(F0+1)/2⌉), (P0+1, ⌈n/2⌉, ⌊(F0+1)/2⌋)) [q, i, l], read-only
    (computed once per size and kept; the whole table it is cut from is not kept beside it: it is
    ``weighted_legendre``'s, uncached, as only the 3-D projection of ``rho_lpq`` reads it whole)."""
    fi = weighted_legendre.__wrapped__(F0, P0, n_nodes)[:, :, : (n_nodes + 1) // 2]
    out = tuple(np.ascontiguousarray(fi[parity::2].transpose(1, 2, 0)) for parity in (0, 1))
    for a in out:
        a.setflags(write=False)
    return out[0], out[1]


def _theta_i_transform(folded: np.ndarray, F0: int, n_nodes: int, scale: float) -> np.ndarray:
    """T_lq = ``scale`` Σ_i f_lq(θ_i') w_i g_q(θ_i') for l <= F0, q <= P0, as (P0+1, K, 3, F0+1)
    [q, node, c, l], from the folded g [parity, q, node, c, i] (:func:`_fold_theta_i`):
    f_lq(−x) = (−1)^{l+q} f_lq(x), so the sum over the nodes is one over half of them, of the even
    part of g where l + q is even and of the odd part where it is odd — one matrix product per
    (q, parity of l), batched over the q of each parity (half the work of the whole sum)."""
    _, Q, K, _, h = folded.shape
    Tq = np.empty((Q, K, 3, F0 + 1))
    for parity_l, f in enumerate(_parity_legendre(F0, Q - 1, n_nodes)):  # f: [q, i, l of that parity]
        for parity_q in (0, 1):
            rhs = folded[(parity_q + parity_l) % 2, parity_q::2].reshape(-1, K * 3, h)
            Tq[parity_q::2, ..., parity_l::2] = (rhs @ f[parity_q::2]).reshape(-1, K, 3, f.shape[2])
    Tq *= scale
    return Tq


def window_matrix(window: np.ndarray, F: int, P: int) -> np.ndarray:
    """A window as (F+1, P+1): a 1-D σ_l (l = 0..F) applies to every p.

    Raises
    ------
    ValueError
        Any other shape.
    """
    w = np.asarray(window, dtype=np.float64)
    if w.ndim == 1:
        w = np.repeat(w[: F + 1, None], P + 1, axis=1)
    if w.shape != (F + 1, P + 1):
        raise ValueError(f"window must have shape ({F + 1},) or ({F + 1}, {P + 1}), got {w.shape}")
    return w


def _approximation(
    profile: ViewProfile, coefficients: BRDFCoefficients, F: int, P: int,
    sigma: np.ndarray | None = None, q_max: int | None = None,
) -> np.ndarray:
    """T̂_lq at the nodes, l <= F, q <= P: 2π Σ_{p<=P} σ_lp ρ̂_lpq f_pq(θ_o'), (F+1, K, P+1, 3)."""
    c = coefficients.coeffs[: F + 1, : P + 1, : P + 1, :].copy()
    if sigma is not None:
        c *= window_matrix(sigma, F, P)[:, :, None, None]
    if q_max is not None:
        c[:, :, q_max + 1 :, :] = 0.0
    fo = legendre_f(P, P, np.cos(2.0 * profile.theta_v))  # (P+1, P+1, K)
    out = np.empty((F + 1, profile.theta_v.size, P + 1, 3))
    for q in range(P + 1):
        # Σ_p c[l, p, q, ch] fo[p, q, k] -> (l, ch, k)
        out[:, :, q, :] = np.tensordot(c[:, q:, q, :], fo[q:, q, :], axes=(1, 0)).transpose(0, 2, 1)
    return 2.0 * np.pi * out


def _residual(profile: ViewProfile, approx: np.ndarray) -> np.ndarray:
    """Σ_q mult (T − T̂)²/(2π) per (l, node, channel) for l <= F (= approx.shape[0] − 1)."""
    F1, _, Q1, _ = approx.shape
    diff = profile.T[:F1].copy()
    diff[:, :, :Q1, :] -= approx
    return np.tensordot(diff**2, mult_q(profile.P0 + 1), axes=(2, 0)) / (2.0 * np.pi)


def resolution_tail(profile: ViewProfile, F: int, P: int, max_view_deg: float, n_phi: int) -> float:
    """Largest share, over the bands inside ``max_view_deg`` (and their live channels), of the band's
    energy the quadrature grid only just resolves: l above the midpoint of F and the grid's F0,
    azimuthal orders q above the midpoint of P and the φ' Nyquist order n_phi/2, and what the
    table leaves unresolved. Gauss–Legendre nodes in cos θ_i' alias a degree l' into l <= F only
    from l' >= 2·n_theta_i − F (= 3F + 48 for the grids of ``ReparamGrid.for_orders``), and the
    uniform φ' nodes alias q' into q <= P only from q' >= n_phi − P; when the energy a step above
    the chosen orders is already this small, the rest — and with it the aliasing into the
    chosen orders — is smaller still for a decaying spectrum, and a finer grid changes the
    table by about that much (the resolution check of :func:`~shrmkit.analysis.orders.choose_orders`).
    """
    full = profile.band_full  # (nb, F0+1, 3), q <= P0
    total = full.sum(axis=1) + profile.band_beyond  # (nb, 3)
    l_cut = F + max(1, (profile.F0 - F) // 2)
    tail = full[:, l_cut + 1 :].sum(axis=1)
    if profile.q_energy is not None:
        per_q = profile.band_sum(profile.q_energy)  # (nb, n_q, 3), all l
        q_cut = P + max(1, (n_phi // 2 - P) // 2)
        high_q = per_q[:, q_cut + 1 :].sum(axis=1)
        # the table's unresolved energy at l > F0 with q <= P0 (beyond holds both kinds)
        low_q_beyond = np.clip(profile.band_beyond - per_q[:, profile.P0 + 1 :].sum(axis=1), 0.0, None)
        tail = tail + high_q + low_q_beyond
    else:
        tail = tail + profile.band_beyond
    inside = bands_inside(profile, max_view_deg)
    live = live_channels(total.sum(axis=0))[None, :] & (total >= CHANNEL_FLOOR * total.max(axis=1, keepdims=True))
    share = np.where(live & (total > 0), tail / np.where(total > 0, total, 1.0), 0.0)
    return float(share[inside].max(initial=0.0))


def projected_eps(profile: ViewProfile, F: int, P: int) -> float:
    """RH02's ε(F, P) (§5.1: 1 − Σ_{l<=F, p<=P, q} mult ρ̂²_lpq / ∫∫ ρ̂², worst live channel) with
    the projected ρ̂_lpq of eq. 13 taken from the profile: ρ̂_lpq = ∫ T_lq(θ_o') f_pq(θ_o')
    sin θ_o' dθ_o' by the band nodes (sin θ_o' dθ_o' = 2 sin 2θ_v dθ_v), the energy by
    :meth:`ViewProfile.energy`. Needs F <= F0 and P <= P0 of the profile.

    Raises
    ------
    ValueError
        (F, P) beyond the profile's orders.
    """
    F, P = int(F), int(P)
    if F > profile.F0 or P > profile.P0 or F < 0 or P < 0:
        raise ValueError(f"orders ({F}, {P}) outside the profile's (F0, P0) = ({profile.F0}, {profile.P0})")
    fo = profile.view_legendre(P)  # (P+1, P+1, K) [p, q, node]
    w = profile.weight * 2.0 * np.sin(2.0 * profile.theta_v)
    T = profile.T[: F + 1, :, : P + 1, :]  # (F+1, K, P+1, 3) [l, node, q, c]
    captured = np.zeros(3)
    for q in range(P + 1):
        c = np.tensordot(fo[q:, q, :] * w, T[:, :, q, :], axes=(1, 1))  # (p, l, channel), p = q..P
        captured += (1.0 if q == 0 else 2.0) * (c * c).sum(axis=(0, 1))
    energy = profile.energy()
    live = energy > 1e-12 * max(float(energy.max()), 1e-300)
    if not live.any():
        return 0.0
    return float((1.0 - captured[live] / energy[live]).max())


def view_order_floor(profile: ViewProfile, tolerance: float, max_view_deg: float) -> int:
    """The smallest view order P that can meet ``tolerance``: below it, the energy at azimuthal
    orders q > P alone exceeds it in some band inside ``max_view_deg`` (worst live channel).

    A lower bound on the ``"bands"`` rule's P, from the profile's ``q_energy`` without a fit:
    ε_b(F, P) counts all energy at q > P as error (the fit has no term there, and what the table
    leaves unresolved counts as error), so ε_b(F, P) >= Σ_{q>P} energy / total for every F. A
    margin of 10⁻⁶ ε keeps rounding from raising the bound. 0 when the profile has no
    ``q_energy``; P0 when no P <= P0 can meet the tolerance."""
    if profile.q_energy is None:
        return 0
    full = profile.band_full
    total = full.sum(axis=1) + profile.band_beyond  # (nb, 3)
    live = live_channels(total.sum(axis=0))[None, :] & (total >= CHANNEL_FLOOR * total.max(axis=1, keepdims=True))
    per_q = profile.band_sum(profile.q_energy)  # (nb, n_q, 3)
    above = per_q[:, ::-1].cumsum(axis=1)[:, ::-1]  # [:, q] = energy at q' >= q
    above = np.concatenate([above[:, 1:], np.zeros_like(above[:, :1])], axis=1)  # [:, P] = energy at q > P
    share = np.where((live & (total > 0))[:, None, :], above / np.where(total > 0, total, 1.0)[:, None, :], 0.0)
    worst = share.max(axis=-1)[bands_inside(profile, max_view_deg)].max(axis=0, initial=0.0)
    ok = np.nonzero(worst[: profile.P0 + 1] <= tolerance * (1.0 + 1e-6))[0]
    return int(ok[0]) if ok.size else profile.P0


def band_eps_table(
    profile: ViewProfile, coefficients: BRDFCoefficients | None, max_view_deg: float, *, fit: bool = True,
    stop_at: float | None = None,
) -> np.ndarray:
    """ε(F, P) of the worst band inside ``max_view_deg`` and the worst channel, (F0+1, P0+1).

    ε_b(F, P) = ∫_b D_err dθ_v / ∫_b D dθ_v with unit lighting weights (a point light, module
    docs): the energy fraction the truncation to (F, P) misses in band b, the unresolved
    energy (l > F0, q > P0) counted as missed. The per-band analogue of RH02's ε (§5.1).
    With ``fit`` (default) the coefficients at each P are :func:`fit_view_coefficients`,
    else the projection ``coefficients``. With ``stop_at`` (a tolerance), the columns after the
    first one whose minimum meets it are left NaN (the order rule needs no more: a search saves
    the fits of higher P on its intermediate grids).
    """
    inside = bands_inside(profile, max_view_deg)
    if coefficients is None:
        coefficients = profile_shaped(profile)
    if not fit:
        return _band_eps_all(profile, coefficients)[inside].max(axis=0)
    P0 = min(profile.P0, coefficients.P0)
    table = np.full((min(profile.F0, coefficients.F0) + 1, P0 + 1), np.nan)
    for p in range(P0 + 1):
        fitted = fit_view_coefficients(profile, coefficients, p, max_view_deg)
        table[:, p] = _band_eps_all(profile, fitted, p_list=[p])[inside, :, 0].max(axis=0)
        if stop_at is not None and table[:, p].min() <= stop_at:
            break
    return table


def _band_eps_all(
    profile: ViewProfile, coefficients: BRDFCoefficients, p_list: list[int] | None = None
) -> np.ndarray:
    """ε_b(F, p) for every band, worst live channel: (n_bands, F0+1, len(p_list)) (all p <= P0
    by default)."""
    F0, P0 = min(profile.F0, coefficients.F0), min(profile.P0, coefficients.P0)
    p_list = list(range(P0 + 1)) if p_list is None else p_list
    out = np.empty((profile.n_bands, F0 + 1, len(p_list)))
    for j, p in enumerate(p_list):
        residual = np.moveaxis(_residual(profile, _approximation(profile, coefficients, F0, p)), 1, 0)
        out[:, :, j] = eps_from_band_residual(profile, F0, profile.band_sum(residual))
    return out


def brdf_view_bands(
    profile: ViewProfile, coefficients: BRDFCoefficients, F: int, P: int, max_view_deg: float
) -> list[dict]:
    """Per band at (F, P) with unit lighting weights: ``eps`` (energy) and
    ``rel_rms_point_light`` = √ε, the relative RMS a single point light would show, plus
    ``inside`` (the band starts below the view limit) and ``extrapolated`` samples."""
    eps = _band_eps_all(profile, coefficients, p_list=[P])[:, F, 0]
    inside = set(bands_inside(profile, max_view_deg).tolist())
    return [
        {
            "theta_v_deg": [float(lo), float(hi)],
            "eps": float(e),
            "rel_rms_point_light": float(np.sqrt(e)),
            "inside": b in inside,
            "extrapolated_samples": int(profile.missing[b]),
        }
        for b, (lo, hi, e) in enumerate(zip(profile.edges_deg[:-1], profile.edges_deg[1:], eps, strict=True))
    ]


def _lighting_weights(band_energy: np.ndarray, F0: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Λ_l² a_l for l <= F0 as (predicted, bound) (F0+1, 3) and the ceiling Λ_0² a_0 (3,):
    known where the lighting holds l, else the mean of the last 8 known (predicted) or the
    ceiling (bound)."""
    n = band_energy.shape[0]
    w = Lambda(np.arange(n))[:, None] ** 2 * band_energy
    ceiling = w.max(axis=0)  # = Λ_0² a_0 = (∫L)² for non-negative lighting
    pred = np.empty((F0 + 1, 3))
    bound = np.empty((F0 + 1, 3))
    k = min(n, F0 + 1)
    pred[:k] = bound[:k] = w[:k]
    pred[k:] = w[max(0, n - 8) :].mean(axis=0)
    bound[k:] = ceiling
    return pred, bound, ceiling


def scene_error_curve(
    profile: ViewProfile, coefficients: BRDFCoefficients, band_energy: np.ndarray, P: int,
    *, q_max: int | None = None,
) -> np.ndarray:
    """Predicted ε_b(F) of the reflected field for F = 0..F0 at view order P, no window:
    (n_bands, F0+1), pooled over channels (the relative RMS² of the band).

    ``band_energy`` is a_l = Σ_m |L_lm|² per channel, (lmax+1, 3)
    (:meth:`~shrmkit.analysis.lighting.LightingCoefficients.band_energy`).
    """
    F0 = min(profile.F0, coefficients.F0)
    w, _, _ = _lighting_weights(band_energy, profile.F0)
    full = np.moveaxis(profile.full(), 1, 0) * w[None]  # (K, F0p+1, 3)
    tail = w[-1] * profile.beyond + full[:, F0 + 1 :].sum(axis=1)
    full = full[:, : F0 + 1]
    approx = _approximation(profile, coefficients, F0, P, q_max=q_max)
    res = np.moveaxis(_residual(profile, approx), 1, 0) * w[None, : F0 + 1]
    res_b = profile.band_sum(res.sum(axis=-1))  # (nb, F0+1)
    full_b = profile.band_sum(full.sum(axis=-1))
    total = full_b.sum(axis=1) + profile.band_sum(tail.sum(axis=-1))
    err = np.cumsum(res_b, axis=1) + (total[:, None] - np.cumsum(full_b, axis=1))
    return np.where(total[:, None] > 0, err / np.where(total > 0, total, 1.0)[:, None], 0.0)


def _map_factor(l: np.ndarray, rows: int, scale: float) -> np.ndarray:
    """Mean square relative error of bilinear lookup of a degree-l field on ``rows`` rows."""
    h = np.pi / rows
    return np.minimum(1.0, (l * (l + 1.0)) ** 2 * h**4 / scale)


def shrm_view_bands(
    profile: ViewProfile,
    coefficients: BRDFCoefficients,
    band_energy: np.ndarray,
    F: int,
    P: int,
    *,
    sigma: np.ndarray | None = None,
    q_max: int | None = None,
    map_rows: int | None = None,
    lighting_rows: tuple[int, int] | None = None,
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG,
    signal_band_energy: np.ndarray | None = None,
) -> BandStatement:
    """Predicted and bounded relative RMS error of an SHRM per θ_v band (the identity of
    :class:`ViewProfile`, with the terms below).

    **Lighting weights.** Λ_l² a_l = ∫∫ L(ω) L(ω') P_l(ω·ω') dω dω' <= (∫ L dω)² = Λ_0² a_0 for
    non-negative lighting (addition theorem, |P_l| <= 1). A single distant point light (a
    one-pixel sun) has Λ_l² a_l = Λ_0² a_0 for every l, so unit weights — the BRDF-only tables
    (:func:`band_eps_table`, :func:`brdf_view_bands`) — state the error under a point light, the
    hardest lighting. Where the lighting
    coefficients are not known (l beyond what the map or the computed lighting holds) the
    bound takes the ceiling Λ_0² a_0; the prediction takes the mean of the last known weights.

    **What else is counted**:

    - the energy the profile does not resolve (l > F0 or q > P0: the node's energy by direct
      quadrature minus the resolved part — discrete Bessel, non-negative) is error;
    - bilinear lookup in an S × 2S map: the mean square error of a degree-l field is
      κ_l ≈ (l(l+1))² h⁴/160, h = π/S (measured: 0.0035–0.0095 × (l(l+1))² h⁴ for
      S = 32–128, l = 1..S−1), at degree l + p for view order p's share of the degree-l energy (the
      global map of order p has degree up to l + p); the bound takes h⁴/100;
    - the area-averaging of large maps before the SHT (lighting amplitude error
      δ_l ≈ l(l+1)h_L²/24 of a block h_L; the bound doubles it);
    - float32 storage ((P+1)² terms, each rounded to 2⁻²⁴ relative).

    The bound adds the map terms to the truncation in amplitude, (√a + √b)², divides by the
    resolved signal only and takes a :data:`BOUND_MARGIN` of 5 % for the band quadrature; the
    prediction adds energies and includes the estimated tail. Measured against brute force
    (``tests/analysis/test_view_bands.py``, ``benchmarks/view_bands.py``) the prediction agrees
    with the measured relative RMS to its Monte Carlo error.

    Parameters
    ----------
    profile, coefficients
        The BRDF's :class:`ViewProfile` and ρ̂_lpq (the orders' grid).
    band_energy
        a_l = Σ_m |L_lm|² per channel, (lmax+1, 3).
    F, P, sigma, q_max
        Orders kept, the window σ_l (F+1,) or σ_lp (F+1, P+1), and ``q_max=0`` for the
        azimuth-free SHRM.
    map_rows
        Rows S of the stored S × 2S maps (bilinear lookup; None: exact evaluation).
    lighting_rows
        (rows the SHT ran on, rows of the source map): area averaging before the SHT.
    signal_band_energy
        a_l of the lighting the errors are relative to, when it is not the one the map was made
        of (``band_energy``): the whole map when the SHRM holds the map without its explicit
        lights (the lights add signal, not error).

    Returns
    -------
    BandStatement
        ``bands``: one dict per band: ``theta_v_deg`` [lo, hi], ``predicted_rel_rms``,
        ``bound_rel_rms`` (same units as a measured relative RMS), ``inside`` (starts below
        ``max_view_deg``), ``extrapolated_samples`` (measured data missing: the bound is then
        not a bound there, ``bound_holds`` False), and the parts ``truncation_rel_rms`` and
        ``map_rel_rms`` of the prediction. ``eps_predicted``/``eps_bound``: the energy
        fractions over all views (RH02's measure).
    """
    F0 = profile.F0
    if F > min(F0, coefficients.F0) or P > min(profile.P0, coefficients.P0):
        raise ValueError(f"orders (F={F}, P={P}) beyond the profile (F0={F0}, P0={profile.P0})")
    w_pred, w_bound, ceiling = _lighting_weights(band_energy, F0)
    approx = _approximation(profile, coefficients, F, P, sigma, q_max)
    trunc_pred, trunc_bound = _truncation_error(profile, approx, w_pred, w_bound, ceiling)
    # the map's lookup and storage error of the field kept, (K, 3) each
    kept = np.moveaxis(np.tensordot(approx**2, mult_q(P + 1), axes=(2, 0)), 1, 0) / (2.0 * np.pi)
    kept_w = kept * w_pred[None, : F + 1]
    map_pred, map_bound = _map_error_factors(coefficients, F, P, sigma, map_rows, lighting_rows)
    map_p = (kept_w * map_pred[None, :, None]).sum(axis=1)
    map_b = (kept_w * map_bound[None, :, None]).sum(axis=1)
    if signal_band_energy is None:
        signal_pred, signal_low = _signal(profile, band_energy, w_pred, w_bound)
    else:
        s_pred, s_bound, _ = _lighting_weights(signal_band_energy, F0)
        signal_pred, signal_low = _signal(profile, signal_band_energy, s_pred, s_bound)
    per_node = (trunc_pred, trunc_bound, map_p, map_b, signal_pred, signal_low)
    bands = _band_statements(profile, [profile.band_sum(x) for x in per_node], max_view_deg)
    # all views with RH02's measure (sin θ_o' dθ_o' = 2 sin 2θ_v dθ_v): the energy fractions ε_B
    solid = 2.0 * np.sin(2.0 * profile.theta_v)[:, None]
    pred, _, _, bound = _ratios(*[(x * solid).T @ profile.weight for x in per_node])
    return BandStatement(bands=bands, eps_predicted=pred**2, eps_bound=min(1.0, bound**2))


def _truncation_error(profile: ViewProfile, approx: np.ndarray, w_pred: np.ndarray, w_bound: np.ndarray,
                      ceiling: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The truncation error density per (node, channel), (K, 3) each, predicted and bounded, of the
    field T̂ = ``approx`` (F+1, K, P+1, 3) under the lighting weights of :func:`_lighting_weights`:
    the residual at l <= F, everything at F < l <= F0 and the energy the profile does not resolve."""
    F = approx.shape[0] - 1
    res = np.moveaxis(_residual(profile, approx), 1, 0)  # (K, F+1, 3)
    above = np.moveaxis(profile.full(), 1, 0)[:, F + 1 :]

    def trunc(w: np.ndarray, w_beyond: np.ndarray) -> np.ndarray:
        return (res * w[None, : F + 1]).sum(axis=1) + (above * w[None, F + 1 :]).sum(axis=1) + w_beyond * profile.beyond

    return trunc(w_pred, w_pred[-1]), trunc(w_bound, ceiling)


def _map_error_factors(coefficients: BRDFCoefficients, F: int, P: int, sigma: np.ndarray | None,
                       map_rows: int | None, lighting_rows: tuple[int, int] | None) -> tuple[np.ndarray, np.ndarray]:
    """Mean square relative error per l of the kept field's storage, map lookup and lighting
    averaging (:func:`shrm_view_bands`): (predicted, bound), (F+1,) each."""
    l = np.arange(F + 1, dtype=np.float64)
    map_pred = np.full(F + 1, _FLOAT32_REL**2 * (P + 1) ** 2)
    map_bound = 4.0 * map_pred
    if map_rows is not None:
        # the global map of view order p has degree up to l + p in R (the rotation to the global
        # frame, RH02 eq. 8): each p's share of the degree-l energy at degree l + p
        c = coefficients.coeffs[: F + 1, : P + 1, : P + 1, :]
        if sigma is not None:
            c = c * window_matrix(sigma, F, P)[:, :, None, None]
        e_lp = np.tensordot(c**2, mult_q(P + 1), axes=(2, 0)).sum(axis=-1)  # (F+1, P+1)
        total = e_lp.sum(axis=1, keepdims=True)
        share = np.where(total > 0, e_lp / np.where(total > 0, total, 1.0), 0.0)
        share[total[:, 0] <= 0, P] = 1.0  # nothing known: the largest degree
        degree = l[:, None] + np.arange(P + 1)[None, :]
        map_pred += (share * _map_factor(degree, map_rows, 160.0)).sum(axis=1)
        map_bound += (share * _map_factor(degree, map_rows, 100.0)).sum(axis=1)
    if lighting_rows is not None and lighting_rows[0] < lighting_rows[1]:
        delta = l * (l + 1.0) * (np.pi / lighting_rows[0]) ** 2 / 24.0
        map_pred += np.minimum(delta, 1.0) ** 2
        map_bound += np.minimum(2.0 * delta, 1.0) ** 2
    return map_pred, map_bound


def _signal(profile: ViewProfile, signal_energy: np.ndarray, s_pred: np.ndarray,
            s_bound: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The signal density per (node, channel), (K, 3) each: predicted (all l, the tail included)
    and low (the resolved signal at the l the lighting holds: a lower bound on the band's signal)."""
    full = np.moveaxis(profile.full(), 1, 0)  # (K, F0+1, 3)
    known = min(signal_energy.shape[0], profile.F0 + 1)
    signal_low = (full[:, :known] * s_bound[None, :known]).sum(axis=1)
    signal_pred = (full * s_pred[None]).sum(axis=1) + s_pred[-1] * profile.beyond
    return signal_pred, signal_low


def _band_statements(profile: ViewProfile, band_parts: list[np.ndarray], max_view_deg: float) -> list[dict]:
    """One dict per band (:func:`shrm_view_bands`) from the band sums (nb, 3) of the truncation
    (predicted, bound), map (predicted, bound) and signal (predicted, low) densities."""
    inside = set(bands_inside(profile, max_view_deg).tolist())
    bands = []
    for b in range(profile.n_bands):
        pred, tp, mp, bound = _ratios(*[x[b] for x in band_parts])
        bands.append({
            "theta_v_deg": [float(profile.edges_deg[b]), float(profile.edges_deg[b + 1])],
            "predicted_rel_rms": pred,
            "bound_rel_rms": bound,
            "truncation_rel_rms": tp,
            "map_rel_rms": mp,
            "inside": b in inside,
            "extrapolated_samples": int(profile.missing[b]),
            "bound_holds": bool(profile.missing[b] == 0),
        })
    return bands


@dataclass(frozen=True)
class BandStatement:
    """What :func:`shrm_view_bands` states: per-band dicts, and over all views (RH02's energy
    measure) the predicted and bounded energy fractions ε_B."""

    bands: list
    eps_predicted: float
    eps_bound: float


def _ratios(tp_e: np.ndarray, tb_e: np.ndarray, mp_e: np.ndarray, mb_e: np.ndarray, sp: np.ndarray,
            sl: np.ndarray) -> tuple[float, float, float, float]:
    """(predicted, truncation part, map part, bound) relative RMS from per-channel energies,
    pooled over channels; the bound adds truncation and map in amplitude over the resolved
    signal, and is never below the prediction."""
    den_p, den_l = float(sp.sum()), float(sl.sum())
    if den_p <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    tp = float(np.sqrt(tp_e.sum() / den_p))
    mp = float(np.sqrt(mp_e.sum() / den_p))
    pred = float(np.sqrt((tp_e.sum() + mp_e.sum()) / den_p))
    num_b = float(((np.sqrt(tb_e) + np.sqrt(mb_e)) ** 2).sum())
    bound = BOUND_MARGIN * float(np.sqrt(num_b / den_l)) if den_l > 0.0 else float("inf")
    return pred, tp, mp, max(bound, pred)


def worst_inside(bands: list[dict], key: str) -> float:
    """The largest ``key`` over the bands inside the view limit (NaN when there are none)."""
    values = [b[key] for b in bands if b["inside"]]
    return float(max(values)) if values else float("nan")
