"""pbrt-v4's ``coateddiffuse`` material ([PBRT4] §14.3): a rough dielectric coat over a Lambertian
base, evaluated as pbrt-v4 defines it, and the mapping of a Cook–Torrance model onto it.

With no medium in the layer (``albedo`` 0, the default) and a thin layer (transmittance
exp(−thickness/|cos|) ≈ 1), the expectation of pbrt-v4's random walk has a closed form, because a
Lambertian base forgets the direction light arrived from:

    f(ω_i, ω_o) = f_top(ω_i, ω_o) + T(θ_i) T(θ_o) R / (π η² (1 − R ρ))

with f_top the coat's own reflection, T(θ) its transmittance (:func:`coat_transmittance`), ρ its
internal reflectance (:func:`coat_internal_reflectance`) and R the base's ``reflectance``; in the
limit α → 0, T → 1 − F(θ) and this is the smooth-coat formula of [WW07].
:class:`DielectricCoat` evaluates it, :func:`coated_diffuse_from_cook_torrance` maps a Cook–Torrance
model onto it; the mapping, its checks and its error: ``data_specs/export.md`` §1.1.

References: [PBRT4] §9.5–9.7, §14.3 and pbrt-v4's ``src/pbrt/materials.cpp``; [Walter07]; [WW07]
(``data_specs/bibliography.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .brdf import as_directions

__all__ = [
    "DielectricCoat",
    "fresnel_dielectric",
    "coat_transmittance",
    "coat_internal_reflectance",
    "fit_dielectric_eta",
    "coated_diffuse_from_cook_torrance",
]

#: Gauss–Legendre nodes in u (GGX's CDF variable) and midpoints in φ ∈ [0, π] over the microfacet
#: normals (the integrands, for a direction at φ = 0, are even in φ).
_NORMAL_NODES = (128, 64)
#: cos θ nodes on which T(θ) is tabulated (uniform in [0, 1], interpolated linearly).
_TABLE_NODES = 129
#: The share of the base's light pbrt's truncated walk may miss (sets ``maxdepth``).
_WALK_TAIL = 1e-3
#: pbrt-v4's default ``maxdepth``: never written lower.
_PBRT_MAXDEPTH = 10
#: Layer thickness written (pbrt's default 0.01 dims every pass through the layer by
#: exp(−0.01/|cos θ|), ~1–2 %; 1e-4 makes it ≤ 0.1 % for |cos θ| ≥ 0.1).
COAT_THICKNESS = 1e-4


def fresnel_dielectric(cos_i: np.ndarray, eta: float | np.ndarray) -> np.ndarray:
    """Unpolarized Fresnel reflectance of a dielectric interface of relative index η, pbrt-v4's
    ``FrDielectric``: cos θ_i < 0 means incidence from the inside (index 1/η); total internal
    reflection gives 1. Same shape as ``cos_i``."""
    c = np.clip(np.asarray(cos_i, dtype=np.float64), -1.0, 1.0)
    e = np.where(c < 0, 1.0 / eta, eta)
    c = np.abs(c)
    sin2_t = (1.0 - c * c) / (e * e)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    r_parl = (e * c - cos_t) / (e * c + cos_t)
    r_perp = (c - e * cos_t) / (c + e * cos_t)
    return np.where(sin2_t >= 1.0, 1.0, (r_parl**2 + r_perp**2) / 2.0)


def _lambda(cos_t: np.ndarray, alpha: float) -> np.ndarray:
    """Trowbridge–Reitz Λ(θ) = (√(1 + α² tan² θ) − 1)/2 (pbrt-v4 ``Lambda``; |cos θ| used)."""
    c2 = np.clip(np.asarray(cos_t, dtype=np.float64) ** 2, 1e-300, 1.0)
    return (np.sqrt(1.0 + alpha * alpha * (1.0 - c2) / c2) - 1.0) / 2.0


def _normals(alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """Microfacet normals m (n, 3) and weights (n,) with Σ w g(m) ≈ ∫ g(m) D(m) cos θ_m dm for
    GGX of width α and g even in φ: u = tan²θ_m/(α² + tan²θ_m) is uniform under D cos θ_m dm
    (GGX's CDF), taken on Gauss–Legendre nodes, φ on midpoints of [0, π]."""
    n_u, n_phi = _NORMAL_NODES
    x, w = np.polynomial.legendre.leggauss(n_u)
    u, wu = (x + 1.0) / 2.0, w / 2.0
    tan_m = alpha * np.sqrt(u / (1.0 - u))
    cos_m = 1.0 / np.sqrt(1.0 + tan_m * tan_m)
    sin_m = tan_m * cos_m
    phi = (np.arange(n_phi) + 0.5) * np.pi / n_phi
    m = np.stack([sin_m[:, None] * np.cos(phi), sin_m[:, None] * np.sin(phi),
                  np.broadcast_to(cos_m[:, None], (n_u, n_phi))], axis=-1).reshape(-1, 3)
    return m, np.repeat(wu / n_phi, n_phi)


def coat_transmittance(cos_t: np.ndarray, alpha: float, eta: float) -> np.ndarray:
    """T(θ): the share of the flux arriving from direction θ (outside, cos θ = ``cos_t`` > 0)
    that pbrt-v4's rough dielectric (GGX α, index η) transmits below the surface, single
    scattering (what masking removes is lost, as in pbrt's BTDF):
    ∫ (ω·m) D(m) (1 − F(ω·m)) G₂(ω, ω_t) / cos θ dm, ω_t = ω refracted about m
    ([Walter07]), counted where ω_t points down. Same shape as ``cos_t``; 0 at grazing."""
    c = np.clip(np.asarray(cos_t, dtype=np.float64), 1e-6, 1.0)
    m, w = _normals(alpha)
    wo = np.stack([np.sqrt(1.0 - c * c), np.zeros_like(c), c], axis=-1)  # (..., 3)
    dot = np.einsum("...k,nk->...n", wo, m)  # ω·m, (..., n)
    inv = 1.0 / eta
    cos_in = np.sqrt(np.maximum(1.0 - inv * inv * (1.0 - dot * dot), 0.0))
    wt = -inv * wo[..., None, :] + (inv * dot - cos_in)[..., None] * m  # refracted direction (unit)
    g2 = 1.0 / (1.0 + _lambda(c, alpha)[..., None] + _lambda(wt[..., 2], alpha))
    value = dot / (m[:, 2] * c[..., None]) * (1.0 - fresnel_dielectric(dot, eta)) * g2
    value = np.where((dot > 0) & (wt[..., 2] < 0), value, 0.0)
    return np.asarray(np.sum(value * w, axis=-1))


def coat_internal_reflectance(alpha: float, eta: float, n_cos: int = 48) -> float:
    """ρ: the share of the flux a cosine-distributed source below the coat (the Lambertian base)
    sends back down by reflecting off the coat's inside (Fresnel of index 1/η, total internal
    reflection included; single scattering, G₂ as pbrt), averaged over the base's
    cosine-distributed light with weight 2 cos θ: ∫₀¹ ρ(c) 2c dc on ``n_cos`` Gauss–Legendre nodes."""
    x, wx = np.polynomial.legendre.leggauss(n_cos)
    c, wc = (x + 1.0) / 2.0, wx / 2.0
    m, w = _normals(alpha)
    # mirror the layer: inside directions as if above an interface of index 1/η (D, Λ are even in z)
    wo = np.stack([np.sqrt(1.0 - c * c), np.zeros_like(c), c], axis=-1)
    dot = np.einsum("ck,nk->cn", wo, m)
    wr = 2.0 * dot[..., None] * m - wo[:, None, :]
    g2 = 1.0 / (1.0 + _lambda(c, alpha)[:, None] + _lambda(wr[..., 2], alpha))
    value = dot / (m[:, 2] * c[:, None]) * fresnel_dielectric(dot, 1.0 / eta) * g2
    value = np.where((dot > 0) & (wr[..., 2] > 0), value, 0.0)
    rho_c = np.sum(value * w, axis=-1)
    return float(np.sum(rho_c * 2.0 * c * wc))


@dataclass(frozen=True, eq=False)
class DielectricCoat:
    """pbrt-v4's ``coateddiffuse`` with no medium and a thin layer, evaluated in closed form
    (module docstring).

    pbrt-v4's ``CoatedDiffuseMaterial::Create`` (``src/pbrt/materials.cpp``; ``LayeredBxDF<DielectricBxDF,
    DiffuseBxDF>``, [PBRT4] §14.3) defaults: ``roughness`` 0, ``thickness`` 0.01, ``eta`` 1.5,
    ``maxdepth`` 10, ``nsamples`` 1, ``albedo`` 0, ``remaproughness`` true, with
    ``TrowbridgeReitzDistribution::RoughnessToAlpha(r) = √r``.

    Attributes
    ----------
    alpha
        The coat's GGX width α (pbrt ``roughness`` with ``remaproughness`` false).
    eta
        The coat's index of refraction η (pbrt ``eta``).
    reflectance
        (3,) the Lambertian base's albedo R, in [0, 1] (pbrt ``reflectance``).
    table
        T(θ) on :data:`_TABLE_NODES` values of cos θ uniform in [0, 1].
    rho
        The coat's internal reflectance ρ.
    """

    alpha: float
    eta: float
    reflectance: np.ndarray
    table: np.ndarray
    rho: float

    @classmethod
    def make(cls, alpha: float, eta: float, reflectance: np.ndarray) -> DielectricCoat:
        """Tabulate T(θ) and ρ for a coat of GGX width ``alpha`` and index ``eta`` (> 1)."""
        grid = np.linspace(0.0, 1.0, _TABLE_NODES)
        return cls(float(alpha), float(eta), np.asarray(reflectance, dtype=np.float64) * np.ones(3),
                   coat_transmittance(grid, alpha, eta), coat_internal_reflectance(alpha, eta))

    def transmittance(self, cos_t: np.ndarray) -> np.ndarray:
        """T(θ) interpolated from :attr:`table`."""
        return np.interp(np.clip(cos_t, 0.0, 1.0), np.linspace(0.0, 1.0, _TABLE_NODES), self.table)

    def albedo_scale(self) -> float:
        """τ²/η² with τ = ∫ T(θ) 2 cos θ d cos θ: the base's albedo seen through the coat is
        (τ²/η²) R/(1 − R ρ) for cosine-weighted light in and out."""
        grid = np.linspace(0.0, 1.0, _TABLE_NODES)
        tau = float(np.trapezoid(self.table * 2.0 * grid, grid))
        return tau * tau / (self.eta * self.eta)

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """ρ (..., 3) in 1/sr: the coat's reflection plus the base seen through it; 0 where L or
        V is below the surface.

        The coat's reflection f_top is pbrt's rough ``DielectricBxDF`` ([PBRT4] §9.5–9.7):
        Trowbridge–Reitz (GGX) D of width α, height-correlated Smith G = 1/(1 + Λ(ω_i) + Λ(ω_o)),
        the exact unpolarized dielectric Fresnel of index η (``FrDielectric``), D G F/(4 cos θ_i
        cos θ_o). The base adds T(θ_i) T(θ_o) R / (π η² (1 − R ρ)): leaving the layer, radiance is
        divided by η² (pbrt's radiance-mode BTDF, reciprocity), and the series Σ (R ρ)^k of the
        factor 1/(1 − R ρ) is the walk's repeated bounces between base and coat."""
        L, V = as_directions(L, V)
        cos_i, cos_o = L[..., 2], V[..., 2]
        above = (cos_i > 0) & (cos_o > 0)
        H = L + V
        H = H / np.where((n := np.linalg.norm(H, axis=-1, keepdims=True)) > 0, n, 1.0)
        cos_h = np.clip(H[..., 2], 1e-12, 1.0)
        cos_d = np.clip(np.einsum("...k,...k->...", L, H), 0.0, 1.0)
        a2 = self.alpha**2
        D = a2 / (np.pi * (cos_h * cos_h * (a2 - 1.0) + 1.0) ** 2)
        ci, co = np.clip(cos_i, 1e-300, 1.0), np.clip(cos_o, 1e-300, 1.0)
        # G2/(ci co) = 2 / (co √(a² + (1−a²) ci²) + ci √(a² + (1−a²) co²)), finite at grazing
        g_over = 2.0 / (co * np.sqrt(a2 + (1.0 - a2) * ci * ci) + ci * np.sqrt(a2 + (1.0 - a2) * co * co))
        top = D * g_over / 4.0 * fresnel_dielectric(cos_d, self.eta)
        R = self.reflectance
        base = (self.transmittance(cos_i) * self.transmittance(cos_o))[..., None] * R / (
            np.pi * self.eta**2 * (1.0 - R * self.rho))
        return np.where(above[..., None], top[..., None] + base, 0.0)

    def maxdepth(self) -> int:
        """The ``maxdepth`` that leaves pbrt's walk at most :data:`_WALK_TAIL` of the base's light:
        2⌈ln(tail)/ln(R_max ρ)⌉, at least pbrt's default 10. pbrt truncates the walk after
        ``maxdepth`` interface events and the base is hit at events 0, 2, 4, …, so the missing
        share is (R ρ)^⌈maxdepth/2⌉ ≤ 10⁻³."""
        q = float(np.max(self.reflectance)) * self.rho
        if q <= 0.0:
            return _PBRT_MAXDEPTH
        return max(_PBRT_MAXDEPTH, 2 * math.ceil(math.log(_WALK_TAIL) / math.log(q)))


def fit_dielectric_eta(target: Callable[[np.ndarray], np.ndarray],
                       weight: Callable[[np.ndarray], np.ndarray] | None, cos_nodes: np.ndarray,
                       cos_weights: np.ndarray) -> float:
    """The η ∈ [1.001, 4] whose dielectric Fresnel F(c; η) is closest to ``target(c)`` (n,) in
    Σ W(c)(F − T)² over the given cos θ_d nodes (W = ``weight(c)``, default 1): a log grid in
    η − 1, refined three times around the best node."""
    c = np.asarray(cos_nodes, dtype=np.float64)
    w = np.asarray(cos_weights, dtype=np.float64)
    if weight is not None:
        extra = np.asarray(weight(c), dtype=np.float64)
        if np.all(np.isfinite(extra)) and np.sum(w * extra) > 0:
            w = w * extra
    t = np.asarray(target(c), dtype=np.float64)
    grid = np.linspace(math.log(1e-3), math.log(3.0), 121)
    best = (0.5, math.inf)
    for _ in range(4):
        eta = 1.0 + np.exp(grid)
        err = (w[:, None] * (fresnel_dielectric(c[:, None], eta[None, :]) - t[:, None]) ** 2).sum(axis=0)
        j = int(np.argmin(err))
        if err[j] < best[1]:
            best = (float(eta[j]), float(err[j]))
        step = (grid[1] - grid[0]) * 2.0
        grid = np.linspace(math.log(best[0] - 1.0) - step, math.log(best[0] - 1.0) + step, 41)
    return best[0]


def coated_diffuse_from_cook_torrance(kd: np.ndarray, alpha: float, eta: float) -> tuple[DielectricCoat, bool]:
    """The coat of GGX width ``alpha`` and index ``eta`` over the base whose albedo, seen through
    the coat by cosine-weighted light, is ``kd`` (3,): R = kd η²/(τ² + kd η² ρ)
    (:meth:`DielectricCoat.albedo_scale`), clipped to [0, 1].

    Returns
    -------
    coat, clipped
        The coat, and whether some channel of R needed more than 1 (kd above what the coat
        lets through: (τ²/η²)/(1 − ρ)).
    """
    probe = DielectricCoat.make(alpha, eta, np.zeros(3))
    s = probe.albedo_scale()
    kd = np.asarray(kd, dtype=np.float64) * np.ones(3)
    R = kd / (s + kd * probe.rho)
    clipped = bool(np.any(R > 1.0))
    return DielectricCoat(probe.alpha, probe.eta, np.clip(R, 0.0, 1.0), probe.table, probe.rho), clipped
