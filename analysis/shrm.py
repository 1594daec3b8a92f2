"""The Spherical Harmonic Reflection Map (RH02 §4, eqs. 8, 12) and its prefiltering.

An :class:`SHRM` stores the *global* SHRM B̃_pq(α, β): for each reflection direction
(α, β) on a lat-long grid, the real-basis coefficients of the reflected radiance as a
function of the global view direction V,

    B(R, V) = Σ_{p≤P, |q|≤p} B̃_pq(R) Y^r_pq(V)                (RH02 eq. 8)

with the real basis of ``analysis.sh`` at flat index p² + p + q.

Reference: R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering",
SIGGRAPH 2002 (RH02), doi:10.1145/566654.566611.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import ducc0
import numpy as np

from .._version import __version__
from ..brdf_io.cubemap import cube_map_directions
from ..brdf_io.envmap import EnvironmentMap, load_env
from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import bilinear_lookup, pixel_angles, pixel_directions
from ..brdf_io.specs import load_brdf
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients, alm_index
from .orders import DEFAULT_MAX_F, DEFAULT_MAX_P, OrderChoice, choose_orders, orders_on_grid_for
from .scene import lanczos_sigma, lanczos_window, reflected_error_parts, residual_bound, scene_for
from .sh import Lambda, real_index, real_sph_harm
from .shrm_file import read_shrm_fields, save_shrm
from .tolerance import DEFAULT_EPS, check_eps
from .view_bands import DEFAULT_CRITERION, DEFAULT_MAX_VIEW_DEG, bands_inside, shrm_view_bands
from .wigner import rotation_D, wigner_d_tilde

__all__ = [
    "SHRM",
    "load_shrm",
    "prefilter",
    "local_shrm_fast",
    "local_shrm_at",
    "global_shrm_latlong",
    "local_shrm_direct",
    "global_from_local",
    "default_size",
    "cube_directions",
    "gibbs_negative",
    "WINDOWS",
    "DEFAULT_WINDOW",
    "WINDOW_THRESHOLD",
    "WINDOW_BUDGET_EPS",
    "UNDERSHOOT_MAX_VIEW_DEG",
    "check_window",
    "undershoot_views",
    "undershoot_samples",
    "undershoot",
]

#: The windows of :func:`prefilter` and of every verb that prefilters (``--window``);
#: :func:`check_window` is their one validator.
WINDOWS = ("none", "lanczos", "auto")
DEFAULT_WINDOW = "auto"
#: ``auto`` windows when the undershoot (most negative sampled radiance over the largest,
#: worst channel; :func:`undershoot`) exceeds this fraction. Chosen from renders of the Grace
#: probe with Phong s = 32: black blotches are visible (+4 stops) at 0.4 % of the peak, barely
#: at 0.15 %, not at 0.03 % (README, accuracy).
WINDOW_THRESHOLD = 1e-3
#: ``auto``'s window may add at most this many ε of error energy to ε_B (worst channel): with
#: the truncation's own ≲ ε, √ε_B stays inside the tested 2√ε + 1 % relative RMS.
WINDOW_BUDGET_EPS = 2.0
#: Largest view angle θ_v = angle(N, V) of the undershoot sample (:func:`undershoot_samples`).
UNDERSHOOT_MAX_VIEW_DEG = 85.0


def check_window(window: Any, name: str = "window") -> str:
    """The one validator of a window name (:data:`WINDOWS`); BadInputError otherwise."""
    if not isinstance(window, str) or window not in WINDOWS:
        raise BadInputError(None, f"{name}={window!r}: choose one of {', '.join(WINDOWS)}")
    return window


def _unit_rows(vectors: np.ndarray, name: str) -> np.ndarray:
    """(n, 3) float64 unit vectors; BadInputError for a wrong shape, zero or non-finite rows."""
    v = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    if v.ndim != 2 or v.shape[1] != 3:
        raise BadInputError(None, f"{name} must have shape (n, 3), got {np.shape(vectors)}")
    norm = np.linalg.norm(v, axis=1, keepdims=True)
    bad = ~np.isfinite(norm[:, 0]) | (norm[:, 0] == 0)
    if np.any(bad):
        raise BadInputError(None, f"{name} has {int(bad.sum())} zero or non-finite direction(s)")
    return v / norm


@dataclass(frozen=True, eq=False)
class SHRM:
    """A global SHRM on a lat-long grid.

    Attributes
    ----------
    F, P
        Orders in the reflection direction and in the view direction.
    cube
        Optional float32 ((P+1)², 6, S, S, 3): the same global SHRM on a cube map (faces
        +X, −X, +Y, −Y, +Z, −Z of the z-up frame, OpenGL texel axes: see
        :func:`cube_directions` and ``data_specs/shrm_file.md``).
    coeffs
        float32 array ((P+1)², H, W, 3): B̃_pq(α, β) at the pixel centres
        α = (i+½)π/H, β = 2π(j+½)/W (z-up frame), real basis index p² + p + q.
    tolerance
        The requested ε; ``eps`` holds the achieved error estimates.
    eps
        Dict of achieved error estimates (``"brdf"``, ``"lighting"``, ``"bound"``).
    meta
        Provenance: BRDF and environment names, timings, tool version.
    """

    F: int
    P: int
    coeffs: np.ndarray
    tolerance: float = float("nan")
    eps: dict[str, float] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    cube: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = (self.P + 1) ** 2
        if self.coeffs.ndim != 4 or self.coeffs.shape[0] != n or self.coeffs.shape[3] != 3:
            raise ValueError(f"coeffs must have shape ({n}, H, W, 3), got {self.coeffs.shape}")
        if self.cube is not None and (
            self.cube.ndim != 5 or self.cube.shape[:2] != (n, 6) or self.cube.shape[2] != self.cube.shape[3]
        ):
            raise ValueError(f"cube must have shape ({n}, 6, S, S, 3), got {self.cube.shape}")

    @property
    def height(self) -> int:
        return int(self.coeffs.shape[1])

    @property
    def width(self) -> int:
        return int(self.coeffs.shape[2])

    def radiance(self, R: np.ndarray, V: np.ndarray, *, clamp: bool = True) -> np.ndarray:
        """Predicted reflected radiance B(R, V), shape (n, 3) (RH02 eq. 8).

        Parameters
        ----------
        R, V
            Reflection and view directions (n, 3) in the global z-up frame, normalized
            here (zero or non-finite rows are refused); the surface normal is
            normalize(R + V).
        clamp
            Set negative values to 0 (default): the Gibbs undershoot the window left
            (``meta["negative_after"]`` of the peak on ``meta["negative_fraction_after"]`` of
            the sampled (R, V); ``data_specs/shrm_file.md``). False returns the truncated
            expansion itself.
        """
        R = _unit_rows(R, "R")
        V = _unit_rows(V, "V")
        if R.shape != V.shape:
            raise BadInputError(None, f"R and V must have the same shape (n, 3), got {R.shape} and {V.shape}")
        maps = np.moveaxis(self.coeffs, 0, 2)  # (H, W, n_coef, 3)
        at_r = bilinear_lookup(maps, R)  # (n, n_coef, 3)
        basis = real_sph_harm(self.P, V)  # (n, n_coef)
        out = np.einsum("nc,nck->nk", basis, at_r)
        return np.maximum(out, 0.0) if clamp else out

    def save(self, path: str | Path) -> Path:
        """Write the SHRM to a ``.shrm.npz`` file (atomic; see ``data_specs/shrm_file.md``)."""
        return save_shrm(path, self)

    def view_map(self, view: np.ndarray, *, clamp: bool = True) -> np.ndarray:
        """Distant-viewer map Σ B̃_pq(α, β) Y^r_pq(V) for one view direction (RH02 eq. 12).

        Returns float32 (H, W, 3); ``clamp`` as in :meth:`radiance`.
        """
        basis = real_sph_harm(self.P, np.asarray(view, dtype=np.float64).reshape(3)).astype(np.float32)
        out = np.tensordot(basis, self.coeffs, axes=(0, 0))
        return np.maximum(out, 0.0, out=out) if clamp else out


# ----------------------------------------------------------------------------------------
# Prefiltering: local SHRM by spin-weighted SHT, rotation to the global SHRM (DESIGN §5–6)
# ----------------------------------------------------------------------------------------


def load_shrm(path: str | Path) -> SHRM:
    """Read an SHRM written by :meth:`SHRM.save` (``data_specs/shrm_file.md``).

    Raises
    ------
    BadInputError
        Missing or unreadable file, wrong format or version, inconsistent shapes,
        non-finite coefficients.
    """
    return SHRM(**read_shrm_fields(path))


def _full_m_lighting(lighting: LightingCoefficients, l: int) -> np.ndarray:
    """L_lm for m = −l..l (complex (3, 2l+1)) from the m >= 0 layout."""
    m = np.arange(0, l + 1)
    pos = lighting.alm[:, alm_index(l, m, lighting.lmax)]
    neg = ((-1.0) ** m)[None, :] * np.conj(pos)
    return np.concatenate([neg[:, :0:-1], pos], axis=1)


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
    lmax = min(F, lighting.lmax, coefficients.F0)
    if P > coefficients.P0:
        raise ValueError(f"P={P} exceeds the computed P0={coefficients.P0}")
    l_of_index = np.concatenate([np.arange(m, lmax + 1) for m in range(lmax + 1)])
    m_of_index = np.concatenate([np.full(lmax + 1 - m, m) for m in range(lmax + 1)])
    alm_light = lighting.alm[:, alm_index(l_of_index, m_of_index, lighting.lmax)] * Lambda(l_of_index)[None, :]
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
    map (spin 0) or Q, U of a gradient-only spin field, shape (1 or 2, H, W)."""
    return ducc0.sht.experimental.synthesis_2d(
        alm=alm[None, :], spin=spin, lmax=lmax, geometry="F1", ntheta=height, nphi=width,
        phi0=np.pi / width, nthreads=nthreads, mode="STANDARD" if spin == 0 else "GRAD_ONLY",
    )


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
    terms = itertools.groupby(_spin_terms(lighting, coefficients, F, P), key=lambda term: term[0])
    for p, p_terms in terms:
        # real and imaginary parts of B_{p,−s}, s = 0..p, laid out (row, s, column, channel): each
        # row's (p+1) × (column·channel) block is one right-hand side of the rotation below. The
        # rotation runs in float32, the maps' storage type (relative rounding ~(p+1)·2⁻²⁴): it is
        # memory-bound, and float32 halves the traffic
        re = np.zeros((height, p + 1, width, 3), dtype=np.float32)
        im = np.zeros((height, p + 1, width, 3), dtype=np.float32)
        for _, s, c, alm, lmax in p_terms:
            if azimuth_free and s > 0:
                continue
            field = _synthesize_latlong(alm, s, lmax, height, width, nthreads)
            re[:, s, :, c] = field[0]
            if s:
                im[:, s, :, c] = field[1]
        if p == 0:
            out[0] = re[:, 0]
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
        t_re = fold_re @ re.reshape(height, p + 1, width * 3)  # (H, s, column·channel)
        t_im = fold_im @ im[:, 1:].reshape(height, p, width * 3)
        del re, im
        s_phi = np.arange(p + 1)[:, None] * phi[None, :]  # e^{−isβ}, per (s, column·channel)
        cos_sb = np.repeat(np.cos(s_phi), 3, axis=1).astype(np.float32)
        sin_sb = np.repeat(np.sin(s_phi), 3, axis=1).astype(np.float32)
        value_re = t_re * cos_sb
        value_re += t_im * sin_sb
        value_im = t_im * cos_sb
        value_im -= t_re * sin_sb
        del t_re, t_im
        out[real_index(p, 0)] = value_re[:, 0].reshape(height, width, 3)
        for s in range(1, p + 1):
            sign = -1.0 if s % 2 else 1.0
            out[real_index(p, s)] = (np.float32(root2 * sign) * value_re[:, s]).reshape(height, width, 3)
            out[real_index(p, -s)] = (np.float32(-root2 * sign) * value_im[:, s]).reshape(height, width, 3)
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


def _strength_for(before: np.ndarray, full: np.ndarray, threshold: float, t_max: float) -> float:
    """The window strength t in [0, t_max] for ``auto``: the smallest t (to t_max·2⁻¹³) with
    undershoot((1 − t)·before + t·full) <= threshold — the synthesis is linear in σ, so these are
    the samples of the map at strength t — or, when no t reaches the threshold, the t of a 33-point
    grid with the least undershoot (0 when the window does not reduce it: where the true radiance
    is 0 over large regions, any ringing is negative).

    Only two small subsets of the samples matter, per channel: those negative at some t
    (min(before, full) < 0), and those that can be the maximum at some t
    (max(before, full) >= max over samples of min(before, full))."""
    low_side = np.minimum(before, full)
    high_side = np.maximum(before, full)
    floor = low_side.max(axis=1, keepdims=True)  # <= the maximum at every t
    channels = []
    for c in range(before.shape[0]):
        keep = (low_side[c] < 0.0) | (high_side[c] >= floor[c])
        channels.append((before[c, keep].astype(np.float64), full[c, keep].astype(np.float64)))

    def under(t: float) -> float:
        worst = 0.0
        for b, f in channels:
            value = b + t * (f - b)
            peak = value.max(initial=0.0)
            if peak > 0.0:
                worst = max(worst, -value.min(initial=0.0) / peak)
        return worst

    grid = t_max * np.arange(33) / 32.0
    values = np.array([under(t) for t in grid])
    ok = np.flatnonzero(values <= threshold)
    if ok.size == 0:
        return float(grid[int(np.argmin(values))])
    if ok[0] == 0:
        return 0.0
    lo, hi = float(grid[ok[0] - 1]), float(grid[ok[0]])
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        if under(mid) <= threshold:
            hi = mid
        else:
            lo = mid
    return hi


def _order_for_window(
    orders: Any, base: BRDFCoefficients, band_energy: np.ndarray, F: int, P: int, eps: float, q_max: int | None,
    top: int,
) -> int | None:
    """The smallest F' in [F, top] whose field with the full Lanczos window σ_lp(F', P) is
    predicted to meet ``eps`` in every view band inside the limit, or None (then the window's
    cost is only budgeted, :func:`_band_window_budget`). Scans with a growing step, then back."""
    inside = bands_inside(orders.profile, orders.max_view_deg)
    top = min(top, orders.profile.F0, base.F0)

    def meets(f: int) -> bool:
        # the window in l (its cost falls as F grows); the view part's cost does not depend on F
        bands = shrm_view_bands(orders.profile, base, band_energy, f, P, sigma=lanczos_window(f), q_max=q_max).bands
        return max(bands[b]["predicted_rel_rms"] ** 2 for b in inside) <= eps

    prev, f, step = F, F, 1
    while f <= top:
        if meets(f):
            for g in range(prev + 1, f):
                if meets(g):
                    return g
            return f
        prev, f, step = f, f + step, step * 2
    return None


def _band_window_budget(
    orders: Any, base: BRDFCoefficients, band_energy: np.ndarray, F: int, P: int, eps: float, q_max: int | None
) -> float:
    """The largest Lanczos strength t whose window adds at most :data:`WINDOW_BUDGET_EPS`·ε to
    the predicted error energy ε_b of every view band inside the limit (bisection on t; the
    prediction of :func:`~shrmkit.analysis.view_bands.shrm_view_bands` without the map term)."""
    inside = bands_inside(orders.profile, orders.max_view_deg)

    def worst_excess(t: float) -> float:
        sigma = lanczos_sigma(F, P, t) if t > 0.0 else None
        bands = shrm_view_bands(orders.profile, base, band_energy, F, P, sigma=sigma, q_max=q_max).bands
        return max(bands[b]["predicted_rel_rms"] ** 2 for b in inside)

    limit = worst_excess(0.0) + WINDOW_BUDGET_EPS * eps
    if worst_excess(1.0) <= limit:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(10):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst_excess(mid) <= limit else (lo, mid)
    return lo


def _windowed(coefficients: BRDFCoefficients, sigma: np.ndarray | None, F: int, P: int) -> BRDFCoefficients:
    """ρ̂_lpq multiplied by σ_lp (l <= F, p <= P, every q); unchanged for None."""
    if sigma is None:
        return coefficients
    damped = coefficients.coeffs.copy()
    damped[: F + 1, : P + 1] *= sigma[:, :, None, None]
    return BRDFCoefficients(coeffs=damped, energy=coefficients.energy, name=coefficients.name)


def cube_directions(size: int) -> np.ndarray:
    """Unit texel-centre directions (6, S, S, 3) of the SHRM cube map, faces +x, −x, +y, −y,
    +z, −z of the z-up frame with OpenGL texel axes (the one table: ``brdf_io.cubemap``)."""
    return cube_map_directions(size)


DEFAULT_MAP_BUDGET_BYTES = 256 << 20


def default_size(F: int, P: int = 0, budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES) -> int:
    """S_B from the rule S ≈ 10F (RH02 §5.2), clamped to [32, 1024] and to a memory budget.

    The global SHRM holds (P+1)² float32 RGB maps of S × 2S: the default S is lowered
    until they fit in ``budget_bytes`` (256 MiB), which keeps high-P materials usable;
    pass ``size=`` to override.
    """
    rule = int(np.clip(10 * F, 32, 1024))
    per_row_squared = (P + 1) ** 2 * 2 * 3 * 4  # bytes per S² texels of all maps
    fits = int(np.sqrt(budget_bytes / per_row_squared))
    return max(8, min(rule, fits))


def _check_finite(coeffs: np.ndarray, env: Any) -> np.ndarray:
    """``coeffs`` when every value is finite, else :class:`BadInputError` naming the map."""
    if not np.all(np.isfinite(coeffs)):
        raise BadInputError(
            getattr(env, "source", None) or env.name,
            "the prefiltered radiance overflows float32 maps (radiance values near 1e38?): rescale the map",
        )
    return coeffs


def _check_given_orders(orders: OrderChoice, brdf: Any, eps: float, criterion: str, max_view_deg: float) -> None:
    """Refuse an :class:`OrderChoice` made for another tolerance, rule or view limit."""
    given = (orders.tolerance, orders.criterion, orders.max_view_deg)
    if given != (float(eps), criterion, float(max_view_deg)):
        raise BadInputError(
            getattr(brdf, "name", None),
            f"orders chosen at eps={given[0]:g}, criterion={given[1]}, max view {given[2]:g} deg do not match "
            f"eps={eps:g}, criterion={criterion}, max view {max_view_deg:g} deg",
        )


def prefilter(
    env: Any,
    brdf: Any,
    *,
    eps: float = DEFAULT_EPS,
    size: int | None = None,
    F: int | None = None,
    P: int | None = None,
    max_F: int = DEFAULT_MAX_F,
    max_P: int = DEFAULT_MAX_P,
    nthreads: int = 0,
    azimuth_free: bool = False,
    window: str = DEFAULT_WINDOW,
    cube: bool = False,
    cube_size: int | None = None,
    progress: Any = None,
    criterion: str = DEFAULT_CRITERION,
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG,
    orders: OrderChoice | None = None,
) -> SHRM:
    """Prefilter an environment into a global SHRM (RH02 §4–5, Appendix C).

    Parameters
    ----------
    env
        An :class:`~shrmkit.brdf_io.envmap.EnvironmentMap`, or a spec/path for ``load_env``.
    brdf
        A BRDF, or a spec/path for ``load_brdf``.
    eps
        Tolerance: orders come from :func:`~shrmkit.analysis.orders.choose_orders` and the
        scene's F_B, P_B = P_ρ from :func:`~shrmkit.analysis.scene.scene_orders`.
    criterion, max_view_deg
        The order rule (``"bands"``: every view band θ_v below ``max_view_deg`` meets ε, the
        default; ``"rh02"``: RH02's energy rule and F_B = min(F_ρ, F_L)); see
        :mod:`~shrmkit.analysis.view_bands`. ``meta["view_bands"]`` states the predicted and
        bounded relative RMS per band for either.
    size
        Rows S_B of the S_B × 2S_B output (default :func:`default_size`: 10 F_B, within
        [32, 1024] rows and a 256 MiB map budget; the meta says when the budget applied).
    F, P
        Force the orders instead of choosing them.
    orders
        The BRDF's :class:`~shrmkit.analysis.orders.OrderChoice` when the caller already has it
        (:func:`~shrmkit.analysis.orders.choose_orders` of this ``brdf`` with the same ``eps``,
        ``criterion`` and ``max_view_deg``; a report chooses them once for its tables): used
        instead of choosing again. Ignored when both ``F`` and ``P`` are given.
    azimuth_free
        Keep only the q = 0 terms of the local SHRM (Kautz & McCool 2000; RH02 Fig. 9):
        B(α, β, θ_o) = Σ_p B_p0(α, β) Y_p0(ω_o'). Exact for radially symmetric lobes.
    nthreads
        Threads for the SHTs (0: all available cores).
    window
        Damping of the negative lobes (Gibbs ringing) a sharp truncation creates (DESIGN §7),
        one of :data:`WINDOWS`; the orders (F, P) are chosen first and never change.
        ``"lanczos"``: multiply ρ̂_lpq by the Lanczos σ-factors
        σ_lp = sinc(l/(F+1)) sinc(p/(P+1)) (:func:`~shrmkit.analysis.scene.lanczos_sigma`).
        ``"auto"`` (default): synthesize without a window and measure the undershoot
        (:func:`undershoot` on :func:`undershoot_samples`: every pixel's normal view and, for
        P > 0, two oblique views per pixel up to θ_v = 85°); when it exceeds
        :data:`WINDOW_THRESHOLD` (0.1 % of the peak), synthesize again with the Lanczos
        σ-factors at the smallest strength t (σ(t) = 1 − t(1 − σ)) that brings it under the
        threshold, but at most the strength whose cost stays within
        :data:`WINDOW_BUDGET_EPS`·ε of added ε_B (when none reaches it: the strength of least
        undershoot, possibly 0; :func:`_strength_for`). With the ``"bands"`` rule, F_B is first
        raised to the smallest F whose field with the full Lanczos window in l is predicted to
        meet ε in every view band inside the limit, and the budget is WINDOW_BUDGET_EPS·ε of
        added predicted error energy in every such band (``data_specs/view_bands.md``).
        ``"none"``: no window. The window's cost is
        included in ``eps["reflected"]`` and ``eps["bound"]``; ``meta`` records the window
        used, its strength and why, and the undershoot before and after
        (``data_specs/shrm_file.md``). What undershoot is left, :meth:`SHRM.radiance`,
        :meth:`SHRM.view_map` and the renderer clamp to 0.
    cube, cube_size
        Also synthesize the SHRM on a 6 × S × S cube map (default S = rows // 2) through
        ducc0's general synthesis at the texel centres.
    progress
        Optional callable ``progress(stage: str)`` told when each stage starts.

    Returns
    -------
    SHRM
        float32 global SHRM with orders, achieved errors, timings in ``meta``.

    Raises
    ------
    BadInputError
        ε outside (0, 1), an unreadable map or BRDF, an all-zero BRDF, sizes out of range,
        radiance that overflows float32 maps, or ``orders`` chosen at another tolerance, rule
        or view limit.

    Examples
    --------
    A constant sky of radiance 1 over a Lambertian surface of albedo 0.5 reflects 0.5 in
    every direction (closed form), and needs only the l = 0 lighting band:

    >>> m = prefilter("builtin:constant,height=16", "lambert:albedo=0.5")
    >>> m.F, (m.height, m.width)
    (0, (32, 64))
    >>> R = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    >>> V = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    >>> m.radiance(R, V).round(4)
    array([[0.5, 0.5, 0.5],
           [0.5, 0.5, 0.5]])

    A file works the same way (a 4 × 8 Radiance ``.hdr``, z-up lat-long):

    >>> m = prefilter("tests/resources/tiny_4x8.hdr", "phong:s=8", eps=0.1)
    >>> m.P, m.F <= 3   # Phong needs no view dependence; the 4-row map resolves l <= 3
    (0, True)
    """
    eps = check_eps(eps)
    window = check_window(window)

    def stage(name: str) -> None:
        if progress is not None:
            progress(name)

    timings: dict[str, float] = {}
    t = time.perf_counter()
    if not isinstance(env, EnvironmentMap):
        env = load_env(env)
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    stage("orders")
    t0 = time.perf_counter()
    if F is not None and P is not None:
        orders = orders_on_grid_for(brdf, int(F), int(P), eps=eps, criterion=criterion, max_view_deg=max_view_deg)
    elif orders is not None:
        _check_given_orders(orders, brdf, eps, criterion, max_view_deg)
    else:
        orders = choose_orders(brdf, eps=eps, max_F=max_F, max_P=max_P, criterion=criterion,
                               max_view_deg=max_view_deg)
    timings["orders"] = time.perf_counter() - t0
    stage("lighting")
    t0 = time.perf_counter()
    lighting, scene = scene_for(env, orders, F=F, nthreads=nthreads)
    timings["lighting"] = time.perf_counter() - t0
    F_B = scene.F_B if F is None else int(min(F, lighting.lmax))
    P_B = scene.P_B if P is None else int(min(P, orders.P0))
    sigma = lanczos_sigma(F_B, P_B) if window == "lanczos" else None
    base = orders.coefficients_for(P_B)  # projected (rh02) or fitted to the views that matter (bands)
    band_energy = lighting.band_energy_all()
    coefficients = _windowed(base, sigma, F_B, P_B)
    S = default_size(F_B, P_B) if size is None else int(size)
    if S < 2 or S > 8192:
        raise BadInputError(None, f"SHRM size must be in [2, 8192] rows, got {S}")

    def synthesize(coefficients: BRDFCoefficients) -> np.ndarray:
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is checked (and reported) below
            coeffs = global_shrm_latlong(
                lighting, coefficients, F_B, P_B, S, 2 * S, nthreads=nthreads, azimuth_free=azimuth_free
            )
        return _check_finite(coeffs, env)

    q_max = 0 if azimuth_free else None
    stage("synthesis")
    t0 = time.perf_counter()
    coeffs = synthesize(coefficients)
    timings["synthesis"] = time.perf_counter() - t0
    stage("window")
    t0 = time.perf_counter()
    views = undershoot_views(S, 2 * S, P_B)
    values = undershoot_samples(coeffs, P_B, views)
    before = undershoot(values)
    strength = 1.0 if window == "lanczos" else 0.0
    raised = ""
    if window == "auto" and before > WINDOW_THRESHOLD and orders.criterion != "rh02" and F is None:
        # a window costs accuracy: find the F at which the fully windowed field still meets ε in
        # every band inside the view limit, and prefilter there instead (Lanczos costs ~F⁻⁴)
        # the F the full field needs with the window (an azimuth-free SHRM is judged by the
        # same F: its own q > 0 loss does not fall with F)
        F_W = _order_for_window(orders, base, band_energy, F_B, P_B, eps, None, lighting.lmax)
        if F_W is not None and F_W > F_B:
            raised = f"F_B raised from {F_B} to {F_W} so that the windowed field meets eps in every view band"
            F_B = F_W
            if size is None:
                S = default_size(F_B, P_B)
            del coeffs
            coeffs = synthesize(_windowed(base, None, F_B, P_B))
            views = undershoot_views(S, 2 * S, P_B)
            values = undershoot_samples(coeffs, P_B, views)
            before = undershoot(values)
    if window in ("none", "lanczos"):
        reason = "requested"
    elif before <= WINDOW_THRESHOLD:
        reason = f"auto: undershoot {before:.3%} of the peak <= threshold {WINDOW_THRESHOLD:.1%}"
    else:
        full = lanczos_sigma(F_B, P_B)
        if orders.criterion == "rh02":
            truncation, cost = reflected_error_parts(lighting, orders.coefficients, F_B, P_B, full, q_max=q_max)
            allowed = truncation.max() + WINDOW_BUDGET_EPS * eps  # ε_B may grow to this (worst channel)
            with np.errstate(divide="ignore", invalid="ignore"):
                t_budget = float(np.min(np.sqrt(np.clip(allowed - truncation, 0.0, None) / cost), initial=1.0))
        else:
            t_budget = _band_window_budget(orders, base, band_energy, F_B, P_B, eps, q_max)
        # the synthesis is linear in σ: the map at strength t is (1 − t)·unwindowed + t·full. Keep
        # the unwindowed map for that when two maps fit the map budget; else one map at a time
        # (the 256 MiB default budget holds while windowing too) and synthesize again
        unwindowed = coeffs if 2 * coeffs.nbytes <= DEFAULT_MAP_BUDGET_BYTES else None
        del coeffs
        coefficients = _windowed(base, full, F_B, P_B)
        coeffs = synthesize(coefficients)
        values_full = undershoot_samples(coeffs, P_B, views)
        strength = _strength_for(values, values_full, WINDOW_THRESHOLD, t_budget)
        if strength == 1.0:
            sigma, values = full, values_full
        else:
            sigma = lanczos_sigma(F_B, P_B, strength) if strength > 0.0 else None
            coefficients = _windowed(base, sigma, F_B, P_B)
            if unwindowed is not None and strength == 0.0:
                coeffs = unwindowed
            elif unwindowed is not None:  # t·full + (1 − t)·unwindowed, in place (float32 rounding)
                with np.errstate(over="ignore", invalid="ignore"):
                    coeffs -= unwindowed
                    coeffs *= np.float32(strength)
                    coeffs += unwindowed
                _check_finite(coeffs, env)
            else:
                del coeffs
                coeffs = synthesize(coefficients)
            # these are the new map's samples (up to float32 rounding)
            values += np.float32(strength) * (values_full - values)
        del unwindowed
        del values_full
        reason = f"auto: undershoot {before:.3%} of the peak > threshold {WINDOW_THRESHOLD:.1%}"
        if strength == 0.0:
            reason += ", not reduced by the Lanczos window"
        elif undershoot(values) > WINDOW_THRESHOLD:
            reason += (f", strength capped by the error budget ({WINDOW_BUDGET_EPS:g} eps of added error energy)"
                       if strength >= t_budget and t_budget < 1.0 else ", strength of the least undershoot")
    if raised:
        reason += f"; {raised}"
    after = undershoot(values)
    negative_fraction = float(np.mean(values.min(axis=0) < 0.0))
    if after > 0.0:
        reason += (f"; undershoot left {after:.3%} of the peak on {negative_fraction:.2%} of the samples, "
                   "clamped to 0 at the output")
    timings["window"] = time.perf_counter() - t0
    cube_coeffs = None
    if cube:
        stage("cube map")
        t0 = time.perf_counter()
        n_cube = max(2, S // 2) if cube_size is None else int(cube_size)
        if n_cube < 2 or n_cube > 4096:
            raise BadInputError(None, f"cube face size must be in [2, 4096], got {n_cube}")
        dirs = cube_directions(n_cube).reshape(-1, 3)
        alpha = np.arccos(np.clip(dirs[:, 2], -1.0, 1.0))
        beta = np.arctan2(dirs[:, 1], dirs[:, 0])
        local_cube = local_shrm_at(lighting, coefficients, F_B, P_B, alpha, beta, nthreads=nthreads)
        if azimuth_free:
            local_cube[:, np.arange(2 * P_B + 1) != P_B] = 0.0
        cube_coeffs = global_from_local(local_cube, alpha, beta).reshape(
            ((P_B + 1) ** 2, 6, n_cube, n_cube, 3)
        ).astype(np.float32)
        timings["cube"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    statement = shrm_view_bands(
        orders.profile, base, band_energy, F_B, P_B, sigma=sigma, q_max=q_max, map_rows=S,
        lighting_rows=(lighting.rows, lighting.source_rows), max_view_deg=orders.max_view_deg,
    )
    # on the coefficients the map was made of (the projection for rh02, the view fit for bands):
    # the window's cost, the energy of its change over all views, is exact for either
    truncation, cost = reflected_error_parts(lighting, base, F_B, P_B, sigma, q_max=q_max)
    if orders.criterion == "rh02":
        reflected = float((truncation + cost).max())
        unwindowed = float(truncation.max())
        bound = residual_bound(lighting, base, F_B, P_B, sigma, q_max=q_max)
    else:  # fitted coefficients: Parseval no longer splits the error; the view-band sums do
        reflected, bound = statement.eps_predicted, statement.eps_bound
        unwindowed = reflected if sigma is None else shrm_view_bands(
            orders.profile, base, band_energy, F_B, P_B, q_max=q_max, map_rows=S,
            lighting_rows=(lighting.rows, lighting.source_rows), max_view_deg=orders.max_view_deg,
        ).eps_predicted
    eps_info = {
        "brdf": orders.eps_at(min(F_B, orders.F0), P_B),
        "lighting": float(lighting.eps()[min(F_B, lighting.lmax)]),
        "reflected": reflected,
        "bound": bound,
        "gibbs_negative": undershoot(values[:, : S * 2 * S]),  # the normal views: gibbs_negative(coeffs, P_B)
    }
    timings["errors"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t
    size_note = "" if size is not None or S == default_size(F_B, 0) else (
        f"map rows lowered from {default_size(F_B, 0)} to {S} to fit the 256 MiB default budget (use size=)"
    )
    meta = {
        "brdf": brdf.name,
        "environment": env.name,
        "environment_source": getattr(env, "source", ""),
        "F_rho": orders.F,
        "P_rho": orders.P,
        "F_L": scene.F_L,
        "lighting_capped": bool(scene.lighting_capped),
        "orders_message": "; ".join(m for m in (orders.message, size_note) if m),
        "timings": timings,
        "shrmkit_version": __version__,
        "frame": "z-up; lat-long pixel centres theta=(i+1/2)pi/H, phi=2pi(j+1/2)/W",
        "azimuth_free": bool(azimuth_free),
        "window": "lanczos" if strength > 0.0 else "none",
        "window_requested": window,
        "window_strength": float(strength),
        "window_reason": reason,
        "window_threshold": WINDOW_THRESHOLD,
        "window_cost": float(cost.max()),
        "eps_reflected_unwindowed": unwindowed,
        "negative_before": None if window == "lanczos" else before,
        "negative_after": after,
        "negative_fraction_after": negative_fraction,
        "negative_max_view_deg": UNDERSHOOT_MAX_VIEW_DEG,
        "criterion": orders.criterion,
        "max_view_deg": orders.max_view_deg,
        "scene_capped": bool(scene.capped),
        "view_bands": statement.bands,
        "extrapolated_samples": int(orders.n_without_data),
    }
    return SHRM(F=F_B, P=P_B, coeffs=coeffs, tolerance=float(eps), eps=eps_info, meta=meta, cube=cube_coeffs)
