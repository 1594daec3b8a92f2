"""[Green07]: BRDFs as sums of isotropic Gaussian lobes over a spherical-Gaussian mip stack.

Fits K lobes to the BRDF's transfer function per view elevation, convolves the environment
with Gaussians of doubling width, and evaluates B(R, V) from both (the ``gaussian_lobes`` method
of :mod:`.methods` builds its model here):

1. **Fit** ([Green07] §3, :func:`fit_gaussian_lobes` → :class:`GaussianLobes`): at N view
   elevations θ_v, the transfer function in the reflection frame by K spherical Gaussians
   G_σ(t) = exp((t − 1)/σ²) / N(σ) (:func:`sg_eval`, :func:`sg_norm`);
2. **Mip stack** ([Green07] §4, :func:`sg_mip_stack` → :class:`SGMipStack`): the environment
   convolved with G_σ for doubling σ, as an SH product (:func:`sg_zonal_factors`);
3. **Render** (:class:`GaussianLobeModel`): B(R, V) = Σ_k w_k (G_σk * L)(d_k), interpolated in θ_v.

Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import ducc0
import nlopt
import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.latlong import bilinear_lookup
from ...brdf_io.reparam import reparam_directions
from ..lighting import lighting_coefficients

__all__ = [
    "sg_norm",
    "sg_zonal_factors",
    "SGMipStack",
    "sg_mip_stack",
    "GaussianLobes",
    "fit_gaussian_lobes",
    "transfer_samples",
    "GaussianLobeModel",
]

SIGMA_MIN, SIGMA_MAX = 0.01, 4.0


def sg_norm(sigma: np.ndarray | float) -> np.ndarray:
    """N(σ) = ∫ exp((μ·ω − 1)/σ²) dω = 2πσ²(1 − e^{−2/σ²})."""
    s2 = np.asarray(sigma, dtype=np.float64) ** 2
    return 2.0 * np.pi * s2 * -np.expm1(-2.0 / s2)


def sg_zonal_factors(sigma: float, lmax: int) -> np.ndarray:
    """a_l = 4π e^{−λ} i_l(λ) / N(σ), l = 0..lmax: (G_σ * L)_lm = a_l L_lm, a_0 = 1.

    e^{−λ} i_l(λ) = sqrt(π/(2λ)) I_{l+½}(λ) e^{−λ} is evaluated with scipy's scaled Bessel
    function ``ive`` (no overflow for narrow lobes).
    """
    from scipy.special import ive  # the Gaussian-lobe mode only: ~0.4 s of import every report would pay

    lam = 1.0 / float(sigma) ** 2
    l = np.arange(lmax + 1, dtype=np.float64)
    scaled = np.sqrt(np.pi / (2.0 * lam)) * ive(l + 0.5, lam)
    return 4.0 * np.pi * scaled / sg_norm(sigma)


def sg_eval(cos_gamma: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Normalized spherical Gaussian G_σ(cos γ) = exp((cos γ − 1)/σ²)/N(σ)."""
    return np.exp((cos_gamma - 1.0) / sigma**2) / sg_norm(sigma)




def _node_weights(pos: np.ndarray, n: int):
    """Linear-interpolation weights of fractional node positions ``pos`` (in [0, n−1]) over
    ``n`` nodes: yields (node, weights) for every node some position uses."""
    i0 = np.minimum(np.floor(pos).astype(np.int64), max(n - 2, 0))
    f = pos - i0
    for node in range(n):
        w = np.where(i0 == node, 1.0 - f, 0.0) + np.where(i0 + 1 == node, f, 0.0)
        if np.any(w > 0):
            yield node, w

@dataclass(frozen=True, eq=False)
class SGMipStack:
    """The environment convolved with normalized spherical Gaussians of doubling widths.

    Attributes
    ----------
    sigmas
        (J,) widths σ_j = σ_0 2^j in radians.
    levels
        J float32 lat-long maps (H_j, 2H_j, 3) of (G_σj * L), z-up frame.
    seconds
        Time to build the stack (SH analysis + J syntheses).
    """

    sigmas: np.ndarray
    levels: tuple[np.ndarray, ...]
    seconds: float = 0.0

    @property
    def nbytes(self) -> int:
        """float32 storage of all levels in bytes."""
        return int(sum(level.nbytes for level in self.levels))

    def lookup(self, dirs: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """(G_σ * L)(d) for directions (n, 3) and widths (n,), interpolating linearly in log2 σ."""
        dirs = np.atleast_2d(dirs)
        sigma = np.broadcast_to(np.asarray(sigma, dtype=np.float64), dirs.shape[:1])
        J = len(self.levels)
        t = np.clip(np.log2(np.maximum(sigma, 1e-300) / self.sigmas[0]), 0.0, J - 1.0)
        out = np.zeros((dirs.shape[0], 3))
        for j, w in _node_weights(t, J):
            sel = w > 0
            out[sel] += w[sel, None] * bilinear_lookup(self.levels[j], dirs[sel])
        return out


def sg_mip_stack(
    env: Any, *, sigma0: float | None = None, n_levels: int | None = None, sigma_max: float = 2.0, nthreads: int = 1
) -> SGMipStack:
    """Build the SG mip stack of an environment by SH products ([Green07] §4).

    The environment convolved with G_σj for σ_{j+1} = 2σ_j, computed as an SH product
    (G * L)_lm = a_l(σ) L_lm with the exact zonal factor a_l = 4π e^{−λ} i_l(λ) / N(σ), λ = 1/σ²
    (Funk–Hecke with e^{λt} = Σ (2l+1) i_l(λ) P_l(t), i_l the modified spherical Bessel
    function; :func:`sg_zonal_factors`), then one fast SH synthesis per level. The Gaussian's
    coefficients decay like exp(−l²σ²/2): the narrowest level is σ_0 = 4/H for an H-row
    environment (a_l < 4e-4 at the truncation l = H − 1, so no visible ringing); level j is
    stored at the power of two of rows >= 4π/σ_j (pixel pitch <= σ_j/4), between 8 and H rows.

    Parameters
    ----------
    env
        EnvironmentMap or (H, 2H, 3) lat-long radiance.
    sigma0
        Narrowest width (default 4/H).
    n_levels
        Number of levels (default: until σ ≥ ``sigma_max``).
    """
    radiance = np.asarray(getattr(env, "radiance", env), dtype=np.float64)
    height = radiance.shape[0]
    s0 = 4.0 / height if sigma0 is None else float(sigma0)
    if not (np.isfinite(s0) and s0 > 0):
        raise BadInputError(None, f"sigma0 must be a positive number, got {sigma0!r}")
    J = int(np.ceil(np.log2(sigma_max / s0))) + 1 if n_levels is None else int(n_levels)
    J = max(J, 1)
    t0 = time.perf_counter()
    lmax = height - 1
    lighting = lighting_coefficients(radiance, lmax, nthreads=nthreads)
    l_of = np.concatenate([np.arange(m, lmax + 1) for m in range(lmax + 1)])
    m_of = np.concatenate([np.full(lmax + 1 - m, m) for m in range(lmax + 1)])
    sigmas = s0 * 2.0 ** np.arange(J)
    levels = []
    for sigma in sigmas:
        # pixel pitch π/h at most σ/4: bilinear lookup of the blurred map then errs by ~(π/h)²/8σ² < 1%
        h = int(min(height, max(8, 2 ** int(np.ceil(np.log2(4.0 * np.pi / sigma))))))
        lj = min(lmax, h - 1)
        a = sg_zonal_factors(sigma, lmax)
        keep = l_of <= lj
        # re-index the m >= 0 layout from lmax to lj
        idx_new = m_of[keep] * (2 * lj + 1 - m_of[keep]) // 2 + l_of[keep]
        level = np.empty((h, 2 * h, 3), dtype=np.float32)
        for c in range(3):
            alm = np.zeros((lj + 1) * (lj + 2) // 2, dtype=np.complex128)
            alm[idx_new] = lighting.alm[c, keep] * a[l_of[keep]]
            level[..., c] = ducc0.sht.experimental.synthesis_2d(
                alm=alm[None], spin=0, lmax=lj, geometry="F1", ntheta=h, nphi=2 * h,
                phi0=np.pi / (2 * h), nthreads=nthreads,
            )[0]
        levels.append(level)
    return SGMipStack(sigmas, tuple(levels), time.perf_counter() - t0)


# ----------------------------------------------------------------------------------------
# Fitting T_θo'(L') with K lobes
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class TransferSamples:
    """T sampled on a (θ_i', ψ) grid at each elevation: ``values`` (N, n, 3), ``dirs`` (n, 3)
    reflection-frame L' (R = +z, V' at azimuth 0), quadrature ``weights`` (n,)."""

    theta_v: np.ndarray
    dirs: np.ndarray
    weights: np.ndarray
    values: np.ndarray


def transfer_samples(brdf: BRDF, theta_v: np.ndarray, *, n_theta: int = 120, n_psi: int = 60) -> TransferSamples:
    """Sample T_θo'(L') = ρ̂(θ_i', θ_o' = 2θ_v, φ') on a midpoint grid over θ_i' ∈ (0, π), ψ ∈ (0, π).

    ψ is the azimuth of L' measured from V' (ψ = −φ'); ρ̂ is even in φ' so the half range
    (weights doubled) covers the sphere.
    """
    theta_v = np.asarray(theta_v, dtype=np.float64)
    th = (np.arange(n_theta) + 0.5) * np.pi / n_theta
    ps = (np.arange(n_psi) + 0.5) * np.pi / n_psi
    T_grid, P_grid = np.meshgrid(th, ps, indexing="ij")
    T, P = T_grid.ravel(), P_grid.ravel()
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    weights = 2.0 * np.sin(T) * (np.pi / n_theta) * (np.pi / n_psi)
    values = np.empty((theta_v.size, T.size, 3))
    for n, tv in enumerate(theta_v):
        L, V = reparam_directions(np.cos(T), np.cos(2.0 * tv), -P)
        if brdf.kind == "analytic":
            values[n] = brdf.rho_hat(L, V)
        else:
            rho, _ = brdf.eval_counted(L, V)
            values[n] = rho * np.maximum(L[..., 2], 0.0)[..., None]
    if not np.all(np.isfinite(values)):
        raise BadInputError(brdf.name, "the BRDF returned NaN or infinite values on the fit grid")
    return TransferSamples(theta_v, dirs, weights, values)


def _design(dirs: np.ndarray, x: np.ndarray) -> np.ndarray:
    mu, sigma = x[0::2], np.exp(x[1::2])
    cos_g = dirs[:, 0:1] * np.sin(mu)[None] + dirs[:, 2:3] * np.cos(mu)[None]
    return sg_eval(cos_g, sigma[None])


def _solve_weights(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float]:
    """Per-channel NNLS; returns weights (K, 3) and the summed squared residual."""
    from scipy.optimize import nnls  # imported on use: scipy.optimize costs ~0.5 s CPU in every report's start-up

    w = np.zeros((A.shape[1], 3))
    total = 0.0
    for c in range(3):
        w[:, c], r = nnls(A, b[:, c])
        total += r * r
    return w, total


@dataclass(frozen=True, eq=False)
class GaussianLobes:
    """K-lobe fits at N view elevations (Green et al. 2007 §3).

    Attributes
    ----------
    theta_v
        (N,) view elevations (radians from the normal), increasing; θ_o' = 2θ_v.
    mu
        (N, K) signed lobe offsets θ_μ from R, positive toward V (radians).
    sigma
        (N, K) lobe widths (radians).
    weight
        (N, K, 3) RGB lobe energies (integrals of w_k G_σk).
    residual
        (N,) relative RMS fit error sqrt(∫|T − fit|² / ∫|T|²) per elevation.
    meta
        ``seconds``, ``evaluations``, ``brdf``.
    """

    theta_v: np.ndarray
    mu: np.ndarray
    sigma: np.ndarray
    weight: np.ndarray
    residual: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def K(self) -> int:
        return int(self.mu.shape[1])

    @property
    def nbytes(self) -> int:
        """float32 storage of the lobe table: N·K·(2 + 3) values."""
        return int(self.mu.size * 5 * 4)


def _fit_one(dirs, sw, b, starts, max_evals, bounds) -> tuple[np.ndarray, np.ndarray, float, int]:
    n_eval = 0
    lo, hi = bounds

    def objective(x, grad):
        nonlocal n_eval
        n_eval += 1
        A = _design(dirs, x) * sw[:, None]
        return _solve_weights(A, b)[1]

    best: tuple[np.ndarray | None, float] = (None, np.inf)
    for x0 in starts:
        x0 = np.clip(x0, lo, hi)
        opt = nlopt.opt(nlopt.LN_BOBYQA, x0.size)
        opt.set_lower_bounds(lo)
        opt.set_upper_bounds(hi)
        opt.set_min_objective(objective)
        opt.set_xtol_rel(1e-6)
        opt.set_maxeval(max_evals)
        opt.set_initial_step(np.where(np.arange(x0.size) % 2 == 0, 0.05, 0.3))
        try:
            x = opt.optimize(x0)
            f = opt.last_optimum_value()
        except nlopt.RoundoffLimited:
            x, f = x0, objective(x0, None)
        if f < best[1]:
            best = (x, f)
    x = best[0]
    assert x is not None  # at least one start
    w, f = _solve_weights(_design(dirs, x) * sw[:, None], b)
    return x, w, f, n_eval


def fit_gaussian_lobes(
    brdf: BRDF,
    K: int = 3,
    n_elevations: int = 15,
    *,
    max_theta_v_deg: float = 89.0,
    n_theta: int = 120,
    n_psi: int = 60,
    max_evals: int = 400,
    samples: TransferSamples | None = None,
) -> GaussianLobes:
    """Fit K isotropic Gaussian lobes to T_θo' at ``n_elevations`` view elevations ([Green07] §3).

    At each view elevation θ_v (the angle between N and V; our reparameterized θ_o' = 2θ_v,
    DESIGN §3) the transfer function in the reflection frame, T_θo'(L') = ρ̂(θ_i', θ_o', φ'), is
    fitted by K isotropic spherical Gaussians

        T(L') ≈ Σ_k w_k G_σk(μ_k · L'),   G_σ(t) = exp((t − 1)/σ²) / N(σ),
        N(σ) = 2πσ²(1 − e^{−2/σ²})  (unit integral over the sphere),

    with RGB weights w_k (the energy of lobe k), width σ_k (radians; G ≈ exp(−γ²/2σ²)) and
    mean μ_k in the plane of R and V at signed angle θ_μ,k from R (positive toward V). T is
    even in φ' so the lobes need no out-of-plane offset. Least squares over the sphere
    (solid-angle weighted), nlopt LN_BOBYQA over the shapes (θ_μ, ln σ), with the weights
    solved in closed form by non-negative least squares for each trial shape (variable
    projection), continuation from the neighbouring elevation plus fixed starts.

    Parameters
    ----------
    brdf
        Any evaluable BRDF (scattered measurements must be fitted first).
    K
        Lobes per elevation (1–8).
    n_elevations
        Elevations θ_v uniformly spaced on [0, ``max_theta_v_deg``].
    n_theta, n_psi
        Midpoint grid over θ_i' ∈ (0, π) and ψ ∈ (0, π) (:func:`transfer_samples`).
    samples
        Reuse samples (e.g. for several K on one BRDF).

    Returns
    -------
    GaussianLobes
    """
    if not 1 <= K <= 8:
        raise BadInputError(None, f"number of Gaussian lobes K must be in [1, 8], got {K}")
    if samples is None:
        if n_elevations < 1 or not 0.0 <= max_theta_v_deg < 90.0:
            raise BadInputError(None, f"need n_elevations >= 1 and max_theta_v_deg in [0, 90), got "
                                      f"{n_elevations}, {max_theta_v_deg}")
        theta_v = np.linspace(0.0, np.radians(max_theta_v_deg), n_elevations)
        samples = transfer_samples(brdf, theta_v, n_theta=n_theta, n_psi=n_psi)
    t0 = time.perf_counter()
    theta_v = samples.theta_v
    N = theta_v.size
    sw = np.sqrt(samples.weights)
    lo = np.tile([-np.pi / 2, np.log(SIGMA_MIN)], K)
    hi = np.tile([np.pi / 2, np.log(SIGMA_MAX)], K)
    mu = np.zeros((N, K))
    sigma = np.zeros((N, K))
    weight = np.zeros((N, K, 3))
    residual = np.zeros(N)
    evaluations = 0
    spread = np.log(np.geomspace(0.05, 1.0, K)) if K > 1 else np.log([0.2])
    prev = None
    for n in range(N):
        b = samples.values[n] * sw[:, None]
        norm2 = float(np.sum(b * b))
        if norm2 == 0.0:
            raise BadInputError(brdf.name, f"the BRDF is zero at view elevation {np.degrees(theta_v[n]):.1f} deg")
        starts = []
        if prev is not None:
            starts.append(prev)
        # fixed starts: widths spread out, centred on R, or on the normal (θ_v toward V)
        starts.append(np.ravel(np.column_stack([np.zeros(K), spread])))
        starts.append(np.ravel(np.column_stack([np.linspace(0.0, theta_v[n], K), spread])))
        x, w, f, ne = _fit_one(samples.dirs, sw, b, starts, max_evals, (lo, hi))
        evaluations += ne
        order = np.argsort(x[1::2])  # lobes sorted by width
        mu[n], sigma[n], weight[n] = x[0::2][order], np.exp(x[1::2])[order], w[order]
        residual[n] = np.sqrt(f / norm2)
        prev = x
    meta = {"seconds": time.perf_counter() - t0, "evaluations": evaluations, "brdf": brdf.name}
    return GaussianLobes(theta_v, mu, sigma, weight, residual, meta)


# ----------------------------------------------------------------------------------------
# Rendering
# ----------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class GaussianLobeModel:
    """Lobes + mip stack: B(R, V) = Σ_k w_k (G_σk * L)(d_k), interpolated in θ_v.

    d_k = cos θ_μ R + sin θ_μ t, t the unit vector toward V perpendicular to R; σ between levels
    is interpolated linearly in log2 σ (σ below σ_0 uses level 0: the environment's own
    resolution limit), and the radiance is interpolated linearly in θ_v between the two
    neighbouring elevations.
    """

    lobes: GaussianLobes
    stack: SGMipStack

    @property
    def nbytes(self) -> int:
        return self.lobes.nbytes + self.stack.nbytes

    def radiance(self, R: np.ndarray, V: np.ndarray, *, visibility: Any = None) -> np.ndarray:
        """Predicted radiance (n, 3).

        ``visibility``: optional callable ``visibility(dirs (n, 3), k_rows) -> (n,)`` multiplying
        each lobe by V(d_k) (Green et al. 2007 eq. 7); see :mod:`.selfshadow`.
        """
        R = np.atleast_2d(np.asarray(R, dtype=np.float64))
        V = np.atleast_2d(np.asarray(V, dtype=np.float64))
        cos_o = np.clip(np.sum(R * V, axis=-1), -1.0, 1.0)
        tv = 0.5 * np.arccos(cos_o)
        t = V - cos_o[:, None] * R
        tn = np.linalg.norm(t, axis=-1, keepdims=True)
        # V parallel to R: any perpendicular works (the lobes are then centred, θ_μ ≈ 0)
        helper = np.where(np.abs(R[:, 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
        alt = np.cross(R, helper)
        alt /= np.linalg.norm(alt, axis=-1, keepdims=True)
        t = np.where(tn > 1e-9, t / np.maximum(tn, 1e-300), alt)
        nodes = self.lobes.theta_v
        N = nodes.size
        pos = np.interp(tv, nodes, np.arange(N)) if N > 1 else np.zeros_like(tv)
        out = np.zeros((R.shape[0], 3))
        for n, a in _node_weights(pos, N):
            sel = a > 0
            for k in range(self.lobes.K):
                m = self.lobes.mu[n, k]
                d = np.cos(m) * R[sel] + np.sin(m) * t[sel]
                value = self.stack.lookup(d, np.full(d.shape[0], self.lobes.sigma[n, k]))
                if visibility is not None:
                    value = value * visibility(d, np.flatnonzero(sel))[:, None]
                out[sel] += a[sel, None] * self.lobes.weight[n, k] * value
        return out
