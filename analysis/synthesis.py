"""Synthesis of the local and global SHRM from lighting and BRDF coefficients ([RH02] §4–5,
eqs. 5–8; DESIGN §5–6): one spin-weighted spherical-harmonic synthesis (ducc0) per view order p,
azimuthal order |q| and channel, the rotation of the local SHRM into the global one, a slow
direct path (explicit Wigner-d sums) as the reference, and the reflected field at fixed local
views on a coarse grid (the undershoot sample of :mod:`~shrmkit.analysis.window`).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import itertools

import ducc0
import numpy as np

from ..brdf_io.cubemap import cube_map_directions
from ..brdf_io.latlong import pixel_angles
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients, alm_index
from .sh import Lambda, legendre_f, real_index
from .wigner import rotation_D, wigner_d_tilde

__all__ = [
    "local_shrm_fast",
    "local_shrm_at",
    "global_shrm_latlong",
    "local_shrm_direct",
    "global_from_local",
    "global_shrm_cube",
    "local_view_field",
    "LOCAL_VIEWS_DEG",
    "sample_rows",
    "fast_rows",
    "windowed",
]


def fast_rows(rows: int, multiple: int = 1) -> int:
    """The smallest S >= ``rows``, a multiple of ``multiple``, whose 2S-column rings ducc0
    transforms fast: 2S 11-smooth (``ducc0.fft.good_size``). A lat-long synthesis costs its FFTs
    along the rings: at S = 89 (2S = 2·89, a prime factor: Bluestein's algorithm) one
    ``synthesis_2d`` at degree 32 took 1.38 ms against 0.21 ms at S = 90 (ducc0, one thread, this
    project's 2-core machine), and the maps of a high-P SHRM are hundreds of them. A larger S only
    samples the same band-limited field more densely (the lookup error falls as S⁻⁴)."""
    S = max(int(rows), 1)
    S += -S % multiple
    while ducc0.fft.good_size(2 * S) != 2 * S:
        S += multiple
    return S


def _full_m_lighting(lighting: LightingCoefficients, l: int) -> np.ndarray:
    """L_lm for m = −l..l (complex (3, 2l+1)) from the m >= 0 layout."""
    m = np.arange(0, l + 1)
    pos = lighting.alm[:, alm_index(l, m, lighting.lmax)]
    neg = ((-1.0) ** m)[None, :] * np.conj(pos)
    return np.concatenate([neg[:, :0:-1], pos], axis=1)


def _scaled_lighting(
    lighting: LightingCoefficients, coefficients: BRDFCoefficients, F: int, P: int
) -> tuple[int, np.ndarray, np.ndarray]:
    """(lmax, l of each index, Λ_l L_lm as (3, n_alm)) in ducc0's m-major order up to
    lmax = min(F, the lighting's, the coefficients'): what every synthesis of (F, P) multiplies by ρ̂.

    Raises
    ------
    ValueError
        P above the coefficients' P0.
    """
    lmax = min(F, lighting.lmax, coefficients.F0)
    if P > coefficients.P0:
        raise ValueError(f"P={P} exceeds the computed P0={coefficients.P0}")
    l_of_index = np.concatenate([np.arange(m, lmax + 1) for m in range(lmax + 1)])
    m_of_index = np.concatenate([np.full(lmax + 1 - m, m) for m in range(lmax + 1)])
    alm_light = lighting.alm[:, alm_index(l_of_index, m_of_index, lighting.lmax)] * Lambda(l_of_index)[None, :]
    return lmax, l_of_index, alm_light


def _spin_terms(
    lighting: LightingCoefficients, coefficients: BRDFCoefficients, F: int, P: int, only_p: int | None = None
):
    """Yield (p, s, channel, E_lm, lmax): the ducc0 input of each spin-s synthesis.

    With 𝒟^l_{m,−s}(α, β) = (−1)^s Λ_l ₛY_lm(α, β) for ducc0's spin-s harmonics (fed
    E_lm = −a_lm, B_lm = 0 for a real-symmetric set; checked against the explicit sum),
    B_{p,−s} = Σ_lm (−1)^s Λ_l L_lm ρ̂_lps ₛY_lm is one spin-s synthesis (GRAD_ONLY) of
    E_lm = −(−1)^s Λ_l L_lm ρ̂_lps, and B_{p,s} = (−1)^s conj(B_{p,−s}). For s = 0 the
    input is the plain spin-0 set Λ_l L_lm ρ̂_lp0.
    """
    lmax, l_of_index, alm_light = _scaled_lighting(lighting, coefficients, F, P)
    for p in range(P + 1) if only_p is None else (only_p,):
        for s in range(min(p, lmax) + 1):  # spin s needs l >= s: B_{p,±s} = 0 when s > lmax
            rho = np.where(l_of_index[None, :] >= s, coefficients.coeffs[l_of_index, p, s, :].T, 0.0)
            for c in range(3):
                alm = alm_light[c] * rho[c]
                yield p, s, c, (alm if s == 0 else -((-1.0) ** s) * alm), lmax


def _store_spin_field(out: np.ndarray, p: int, s: int, c: int, P: int, field: np.ndarray) -> None:
    """Place a synthesized B_{p,−s} (and its conjugate partner B_{p,s}) into ``out``."""
    if s == 0:
        out[p, P, ..., c] = field[0]
    else:
        neg = field[0] + 1j * field[1]
        out[p, P - s, ..., c] = neg
        out[p, P + s, ..., c] = ((-1.0) ** s) * np.conj(neg)


def _synthesize_latlong(alm: np.ndarray, spin: int, lmax: int, height: int, width: int, nthreads: int) -> np.ndarray:
    """One ducc0 synthesis on the pixel-centred lat-long grid (F1 rings, phi0 = π/W): the real
    map (spin 0) or Q, U of a gradient-only spin field, shape (1 or 2, H, W). Maps of fewer than
    :data:`THREADED_ROWS` rows are synthesized on one thread, whatever ``nthreads`` says."""
    return ducc0.sht.experimental.synthesis_2d(
        alm=alm[None, :], spin=spin, lmax=lmax, geometry="F1", ntheta=height, nphi=width,
        phi0=np.pi / width, nthreads=nthreads if height >= THREADED_ROWS else 1,
        mode="STANDARD" if spin == 0 else "GRAD_ONLY",
    )


#: Below this many rows a synthesis runs on one thread: a second thread of ducc0 cost more CPU than it
#: saved wall time (88 rows, degree 15: 195 µs CPU on one thread, 204–322 µs on two, the same wall time;
#: 125 rows, degree 31: even; 256 rows, degree 64: two threads 9 % faster; this project's 2-core machine)
THREADED_ROWS = 192


def local_shrm_fast(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    height: int,
    width: int,
    *,
    nthreads: int = 1,
) -> np.ndarray:
    """Local SHRM B_pq(α, β) on a lat-long grid by spin-weighted SHT (DESIGN §6).

    One ducc0 ``synthesis_2d`` per (p, |q|, channel); see :func:`_spin_terms`.

    Returns
    -------
    complex128 (P+1, 2P+1, H, W, 3), indexed [p, q+P]; zero where |q| > p.
    """
    out = np.zeros((P + 1, 2 * P + 1, height, width, 3), dtype=np.complex128)
    for p, s, c, alm, lmax in _spin_terms(lighting, coefficients, F, P):
        _store_spin_field(out, p, s, c, P, _synthesize_latlong(alm, s, lmax, height, width, nthreads))
    return out


def global_shrm_latlong(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    height: int,
    width: int,
    *,
    nthreads: int = 1,
    azimuth_free: bool = False,
) -> np.ndarray:
    """Global SHRM on a lat-long grid, one view order p at a time (memory-lean path).

    Same result as :func:`global_from_local` of :func:`local_shrm_fast`, but only the
    q <= 0 half of one p-block of the local SHRM is held at a time (B_{p,q} =
    (−1)^q conj(B_{p,−q})), in real arithmetic, and the rotation
    B̃_ps = e^{−isβ} Σ_q B_pq d̃^p_sq(α) is done one output order s at a time.
    ``azimuth_free`` keeps only q = 0 (Kautz & McCool 2000).

    Returns float32 ((P+1)², H, W, 3), real basis.
    """
    theta, phi = pixel_angles(height, width)
    out = np.zeros(((P + 1) ** 2, height, width, 3), dtype=np.float32)
    root2 = np.sqrt(2.0)
    # work buffers sized for p = P, reused by every p (views of their first elements): fresh
    # temporaries per p cost as much in first-touch page faults as the arithmetic itself
    n_max = height * (P + 1) * width * 3
    buffers = {name: np.empty(n_max, np.float32) for name in ("re", "im", "t_re", "t_im")}
    row = np.empty((height, width * 3), np.float32)  # scratch of one s's (row, column·channel) products

    def view(name: str, rows: int) -> np.ndarray:
        return buffers[name][: height * rows * width * 3].reshape(height, rows, width * 3)

    terms = itertools.groupby(_spin_terms(lighting, coefficients, F, P), key=lambda term: term[0])
    for p, p_terms in terms:
        # real and imaginary parts of B_{p,−s}, s = 0..p, laid out (row, s, column, channel): each
        # row's (p+1) × (column·channel) block is one right-hand side of the rotation below. The
        # rotation runs in float32, the maps' storage type (relative rounding ~(p+1)·2⁻²⁴): it is
        # memory-bound, and float32 halves the traffic
        re, im = view("re", p + 1), view("im", p + 1)
        re.fill(0.0)
        im.fill(0.0)
        re4, im4 = re.reshape(height, p + 1, width, 3), im.reshape(height, p + 1, width, 3)
        for _, s, c, alm, lmax in p_terms:
            if azimuth_free and s > 0:
                continue
            field = _synthesize_latlong(alm, s, lmax, height, width, nthreads)
            re4[:, s, :, c] = field[0]
            if s:
                im4[:, s, :, c] = field[1]
        if p == 0:
            out[0] = re4[:, 0]
            continue
        # Σ_q B_pq d̃_sq with B_{p,q>0} = (−1)^q conj(B_{p,−q}): the q > 0 columns fold onto the
        # q < 0 ones, + for the real part and − for the imaginary part
        d = wigner_d_tilde(p, theta)[:, p:, :]  # (H, s = 0..p, q = −p..p)
        d_neg = d[:, :, p::-1]  # q = 0, −1, ..., −p
        d_pos = d[:, :, p + 1 :] * np.where(np.arange(1, p + 1) % 2, -1.0, 1.0)  # q = 1..p
        fold_re = d_neg.copy()
        fold_re[:, :, 1:] += d_pos
        fold_re = fold_re.astype(np.float32)
        fold_im = (d_neg[:, :, 1:] - d_pos).astype(np.float32)  # the q = 0 imaginary part is 0
        # one (p+1) × (p+1) matrix per row times that row's fields: a batched product (BLAS)
        t_re, t_im = view("t_re", p + 1), view("t_im", p + 1)
        np.matmul(fold_re, re, out=t_re)  # (H, s, column·channel)
        np.matmul(fold_im, im[:, 1:], out=t_im)
        s_phi = np.arange(p + 1)[:, None] * phi[None, :]  # e^{−isβ}, per (s, column·channel)
        cos_sb = np.repeat(np.cos(s_phi), 3, axis=1).astype(np.float32)
        sin_sb = np.repeat(np.sin(s_phi), 3, axis=1).astype(np.float32)
        # B̃_ps = e^{−isβ} (t_re + i t_im), written into the output maps one s at a time (the row blocks
        # stay in cache; the maps' first touch is this write)
        out[real_index(p, 0)] = t_re[:, 0].reshape(height, width, 3) * cos_sb[0].reshape(width, 3) + \
            t_im[:, 0].reshape(height, width, 3) * sin_sb[0].reshape(width, 3)
        for s in range(1, p + 1):
            scale = np.float32(root2 * (-1.0 if s % 2 else 1.0))
            target = out[real_index(p, s)].reshape(height, -1)
            np.multiply(t_re[:, s], cos_sb[s], out=target)
            target += np.multiply(t_im[:, s], sin_sb[s], out=row)
            target *= scale
            target = out[real_index(p, -s)].reshape(height, -1)
            np.multiply(t_im[:, s], cos_sb[s], out=target)
            target -= np.multiply(t_re[:, s], sin_sb[s], out=row)
            target *= -scale
    return out


def local_shrm_at(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    theta: np.ndarray,
    phi: np.ndarray,
    *,
    nthreads: int = 1,
    epsilon: float = 1e-10,
) -> np.ndarray:
    """Local SHRM at arbitrary directions (θ, φ) by ducc0's general (NUFFT) synthesis.

    Used for cube-map output. Returns complex128 (P+1, 2P+1, n, 3) for n directions.
    """
    loc = np.stack([np.ravel(theta), np.mod(np.ravel(phi), 2.0 * np.pi)], axis=-1).astype(np.float64)
    out = np.zeros((P + 1, 2 * P + 1, loc.shape[0], 3), dtype=np.complex128)
    for p, s, c, alm, lmax in _spin_terms(lighting, coefficients, F, P):
        field = ducc0.sht.experimental.synthesis_general(
            alm=alm[None, :], spin=s, lmax=lmax, loc=loc, epsilon=epsilon, nthreads=nthreads,
            mode="STANDARD" if s == 0 else "GRAD_ONLY",
        )
        _store_spin_field(out, p, s, c, P, field)
    return out


def local_shrm_direct(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    alpha: np.ndarray,
    beta: np.ndarray,
) -> np.ndarray:
    """Local SHRM B_pq(α, β) = Σ_lm L_lm ρ̂_lpq 𝒟^l_mq(α, β) by explicit Wigner-d sums.

    Slow reference path (RH02 eqs. 5–7); returns complex (n, P+1, 2P+1, 3).
    """
    alpha = np.atleast_1d(np.asarray(alpha, float))
    beta = np.atleast_1d(np.asarray(beta, float))
    lmax = min(F, lighting.lmax, coefficients.F0)
    out = np.zeros((alpha.size, P + 1, 2 * P + 1, 3), dtype=np.complex128)
    for l in range(lmax + 1):
        D = rotation_D(l, alpha, beta)  # (n, 2l+1, 2l+1) [m+l, q+l]
        Lm = _full_m_lighting(lighting, l)  # (3, 2l+1)
        for p in range(P + 1):
            for q in range(-min(l, p), min(l, p) + 1):
                rho = coefficients.coeffs[l, p, abs(q), :]  # (3,)
                out[:, p, q + P, :] += np.einsum("nm,cm->nc", D[:, :, q + l], Lm) * rho
    return out


def global_from_local(local: np.ndarray, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Global SHRM from the local one (RH02 eq. 8, DESIGN §5).

    B̃_ps(α, β) = Σ_q B_pq(α, β) conj(𝒟^p_sq(α, β)) = e^{−isβ} Σ_q B_pq d̃^p_sq(α), from
    Y_pq(R⁻¹V) = Σ_s conj(𝒟^p_sq) Y_ps(V) (unitarity of 𝒟). Returned in the real basis.

    Parameters
    ----------
    local
        complex (P+1, 2P+1, *grid, 3) with ``alpha``/``beta`` broadcastable to ``grid``.
    """
    P = local.shape[0] - 1
    grid_shape = local.shape[2:-1]
    # d̃ depends on α only: keep α's own (broadcastable) shape, e.g. one value per row
    a = np.asarray(alpha, dtype=np.float64)
    b = np.asarray(beta, dtype=np.float64)
    real = np.zeros(((P + 1) ** 2,) + grid_shape + (3,))
    root2 = np.sqrt(2.0)
    rows_only = a.ndim == len(grid_shape) and all(n == 1 for n in a.shape[1:])  # α constant along rows
    for p in range(P + 1):
        blk = local[p, P - p : P + p + 1]  # (2p+1 over q, *grid, 3)
        if rows_only:
            # one small d̃^p(α) per row and a batched matrix product over the rest of the row
            d = wigner_d_tilde(p, a.reshape(-1))[:, p:, :]  # (H, s = 0..p, q)
            rows = blk.reshape(2 * p + 1, grid_shape[0], -1).transpose(1, 0, 2)  # (H, q, rest)
            tilde = np.matmul(d, rows).transpose(1, 0, 2).reshape((p + 1,) + grid_shape + (3,))
        else:
            d = wigner_d_tilde(p, a)[..., p:, :]  # (*grid, s = 0..p, q)
            tilde = np.einsum("...sq,q...c->s...c", d, blk, optimize=True)
        for s in range(0, p + 1):
            value = np.exp(-1j * s * b)[..., None] * tilde[s]
            if s == 0:
                real[real_index(p, 0)] = value.real
            else:
                sign = -1.0 if s % 2 else 1.0
                real[real_index(p, s)] = root2 * sign * value.real
                real[real_index(p, -s)] = -root2 * sign * value.imag
    return real


def windowed(coefficients: BRDFCoefficients, sigma: np.ndarray | None, F: int, P: int) -> BRDFCoefficients:
    """ρ̂_lpq multiplied by σ_lp (l <= F, p <= P, every q); unchanged for None."""
    if sigma is None:
        return coefficients
    damped = coefficients.coeffs.copy()
    damped[: F + 1, : P + 1] *= sigma[:, :, None, None]
    return BRDFCoefficients(coeffs=damped, energy=coefficients.energy, name=coefficients.name)


#: The fixed local views (θ_v = angle(N, V) in degrees, azimuth ψ of V' in the local frame of R) of
#: :func:`local_view_field` besides the normal view V = R: oblique views ring from the truncation
#: in the view order p, worst toward grazing (the sample reaches θ_v = 80°, the default view limit).
#: Since the local frame of R_{α,β} turns with β, every azimuth relative to a light is sampled
#: somewhere on the map.
LOCAL_VIEWS_DEG = ((35.0, 0.0), (60.0, 120.0), (80.0, 240.0))


def sample_rows(F: int, P: int) -> int:
    """Rows of the coarse undershoot sample for orders (F, P): ≈ 2.5 (F + P), five samples per
    period of the highest degree (measured: the sampled undershoot is within 10 % of a sample
    2.4× as dense for sun, sky, studio and Grace maps under Phong, microfacet and Lafortune lobes),
    a multiple of 4 (the sample turns with the map under rotations by multiples of 1/8 turn), at
    least 16, with 11-smooth rings (:func:`fast_rows`)."""
    return fast_rows(max(16, 4 * int(np.ceil((2.5 * (F + P) + 2) / 4.0))), 4)


def local_view_field(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    rows: int,
    *,
    views_deg: tuple[tuple[float, float], ...] = LOCAL_VIEWS_DEG,
    q_max: int | None = None,
    nthreads: int = 1,
    channel_weights: np.ndarray | None = None,
) -> np.ndarray:
    """The reflected radiance B(R, V) on a rows × 2·rows lat-long grid of R (pixel centres, F1) at
    the normal view V = R and at fixed local views V' = (2θ_v, ψ) in the frame R_{α,β} of each R
    (``views_deg``; none when P = 0: B does not depend on V): float32 (3, n_views·rows·2·rows),
    channel-major, normal views first.

    B(R, V) = Σ_{p,q} B_pq(α, β) Y_pq(V') (DESIGN §5), and for a fixed V' the sum over p is taken
    in the coefficients: with Y_{p,−s}(θ', ψ) = (−1)^s f_ps(θ') e^{−isψ} and B_{p,s} =
    (−1)^s conj(B_{p,−s}), Σ_q B_pq Y_pq = Σ_s w_s [Re B_{·,−s} cos sψ + Im B_{·,−s} sin sψ] with
    w_0 = 1, w_s = 2, where B_{·,−s} is one spin-s synthesis of Σ_p (−1)^s f_ps(θ') E^{p,s}
    (:func:`_spin_terms`): (P+1) syntheses per view and channel instead of (P+1)(P+2)/2, and no
    rotation to the global SHRM. ``q_max=0`` keeps the azimuth-free terms only. With
    ``channel_weights`` (3,), the weighted sum of the channels (luminance) as (1, n_views·rows·2·rows):
    the coefficients are summed before the synthesis, a third of the transforms.
    """
    height, width = int(rows), 2 * int(rows)
    views = [(0.0, 0.0)] + (list(views_deg) if P > 0 else [])
    theta_o = np.array([2.0 * np.radians(v[0]) for v in views])
    psi = np.array([np.radians(v[1]) for v in views])
    f = legendre_f(P, P, np.cos(theta_o))  # (P+1, P+1, n_views)
    s_top = P if q_max is None else min(P, q_max)
    # combined alm per (view, s, channel): for each spin s, Σ_p (−1)^s f_ps(θ'_v) E^{p,s}_lm, all p, views
    # and channels at once (the same sums as _spin_terms' per (p, s, channel) inputs)
    lmax, l_of_index, alm_light = _scaled_lighting(lighting, coefficients, F, P)
    combined: dict[tuple[int, int, int], np.ndarray] = {}
    lmaxes: dict[int, int] = {}
    for s_ in range(min(s_top, lmax) + 1):
        p = np.arange(s_, P + 1)
        rho = coefficients.coeffs[l_of_index[:, None], p[None, :], s_, :]  # (nalm, p, c)
        rho = np.where((l_of_index >= s_)[:, None, None], rho, 0.0)
        sign = 1.0 if s_ == 0 else -((-1.0) ** s_)
        weights = ((-1.0) ** s_) * f[p, s_, :] * sign  # (p, views)
        terms = rho * alm_light.T[:, None, :]  # E^{p,s}_lm per channel: (nalm, p, c)
        if channel_weights is not None:  # Σ_c w_c E^{p,s}_lm: (nalm, p)
            terms = terms @ np.asarray(channel_weights, dtype=terms.real.dtype)
            mixed = (weights.T @ terms.T)[:, None, :]  # (views, 1, nalm)
        else:
            mixed = np.tensordot(weights.T, terms, axes=(1, 1)).transpose(0, 2, 1)  # (views, c, nalm)
        lmaxes[s_] = lmax
        for v in range(len(views)):
            if not np.any(weights[:, v]):
                continue
            for c in range(mixed.shape[1]):
                combined[(v, s_, c)] = mixed[v, c]
    n_out = 3 if channel_weights is None else 1
    out = np.zeros((n_out, len(views), height, width), dtype=np.float32)
    for (v, s, c), alm in combined.items():
        field = _synthesize_latlong(alm, s, lmaxes[s], height, width, nthreads)
        if s == 0:
            out[c, v] += field[0]
        else:
            out[c, v] += 2.0 * (field[0] * np.cos(s * psi[v]) + field[1] * np.sin(s * psi[v]))
    return out.reshape(n_out, -1)


def global_shrm_cube(
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    size: int,
    *,
    nthreads: int = 1,
    azimuth_free: bool = False,
) -> np.ndarray:
    """The global SHRM on a 6 × S × S cube map (faces of ``brdf_io.cubemap``, texel centres) by
    ducc0's general synthesis of the local SHRM (:func:`local_shrm_at`) rotated to the global
    frame (:func:`global_from_local`); ``azimuth_free`` keeps q = 0 as :func:`global_shrm_latlong`.

    Returns float32 ((P+1)², 6, S, S, 3), real basis.
    """
    dirs = cube_map_directions(size).reshape(-1, 3)
    alpha = np.arccos(np.clip(dirs[:, 2], -1.0, 1.0))
    beta = np.arctan2(dirs[:, 1], dirs[:, 0])
    local = local_shrm_at(lighting, coefficients, F, P, alpha, beta, nthreads=nthreads)
    if azimuth_free:
        local[:, np.arange(2 * P + 1) != P] = 0.0
    return global_from_local(local, alpha, beta).reshape(((P + 1) ** 2, 6, size, size, 3)).astype(np.float32)
