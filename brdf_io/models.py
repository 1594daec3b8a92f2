"""Analytic isotropic BRDF models.

Each model is an immutable object with ``eval`` (rho, 1/sr, no cosine) and
``rho_hat`` (rho * cos, [RH02] §3.1). Parameters may be scalars or RGB triples.

Models
------
``phong``
    [RH02] §6.3 (eq. in Appendix D): rho_hat = (s+1)/(2π) max(R·L, 0)^s with R the mirror
    direction of V. The model *defines* rho_hat; there is no horizon clipping, so the
    lobe is exactly radially symmetric about R; ``eval`` = rho_hat / max(cos θ_i, 1e-20).
``microfacet``
    [RH02] eq. 11: rho_hat = exp(-(θ_h/σ)²) / (4πσ²), θ_h the angle between N and the half
    vector; zero where N·L <= 0. The model defines rho_hat; ``eval`` divides by
    max(cos θ_i, 1e-20).
``lambert``
    rho = albedo / π.
``lafortune``
    [Laf97], isotropic: rho = kd/π + Σ_k ks_k max(Cxy_k (LxVx + LyVy)
    + Cz_k LzVz, 0)^n_k.
``cook-torrance``
    [CT82] with a Beckmann ([Walter07] Smith G1 rational approximation) or GGX (exact
    separable Smith G1) distribution and Schlick's Fresnel [Schlick94]:
    rho = kd/π + ks D(θ_h) F(V·H) G(L, V) / (4 cos θ_i cos θ_o).

Parameter bounds (``MAX_SCALE`` ... ``COS_FLOOR`` below; data_specs/spec_strings.md) keep
every model's values finite for every pair of unit directions; the spec parser enforces them.

References: [RH02], [Laf97], [CT82], [Walter07], [Schlick94] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .brdf import BRDF, Kind, as_directions

__all__ = [
    "COS_FLOOR",
    "MAX_SCALE",
    "MAX_EXPONENT",
    "SIGMA_RANGE",
    "ALPHA_RANGE",
    "MAX_LAFORTUNE_COEFF",
    "MAX_LOBE_PEAK",
    "MAX_LOBES",
    "lafortune_lobe_peak",
    "PhongLobe",
    "SimplifiedMicrofacet",
    "Lambert",
    "LafortuneLobe",
    "Lafortune",
    "CookTorrance",
    "smith_g1_over_cos",
    "rgb",
]


# Parameter bounds (data_specs/spec_strings.md; enforced by the spec parser, brdf_io/specs.py).
# Inside them every model's ρ and ρ̂ are finite for every pair of unit directions, at most
# about 1e33 1/sr (ρ̂/cos θ_i right at the horizon), checked on dense direction grids at the
# extreme parameters (tests/brdf_io/test_hostile_brdf_files.py).

#: ρ = ρ̂ / max(cos θ_i, COS_FLOOR) for the models that define ρ̂ (Phong, RH02 microfacet):
#: a light direction within 1e-20 rad of the horizon (closer than any direction made from a
#: float angle: cos(π/2) = 6.1e-17) no longer divides by zero or a denormal.
COS_FLOOR = 1e-20
#: Largest ``ks`` of ``phong``, ``microfacet`` and ``cook-torrance`` (and ``phong`` ρ̂ peak
#: ks (s+1)/(2π) ≤ 1.6e12 with s at :data:`MAX_EXPONENT`).
MAX_SCALE = 1e6
#: Largest exponent: Phong ``s`` and Lafortune ``n`` (a lobe narrower than 0.03°).
MAX_EXPONENT = 1e7
#: RH02 microfacet σ, radians: 0.005 (0.29°, ρ̂ peak 3200 ks; the fit's own lower bound, and about
#: where the frequency analysis still fits in memory) to 2.
SIGMA_RANGE = (5e-3, 2.0)
#: Cook–Torrance roughness α.
ALPHA_RANGE = (1e-4, 4.0)
#: Largest |Cxy|, |Cz| of a Lafortune lobe.
MAX_LAFORTUNE_COEFF = 1e6
#: Largest peak ks max(|Cxy|, |Cz|)^n of one Lafortune lobe, 1/sr (its maximum over all
#: pairs of unit directions, since |LxVx + LyVy| + |LzVz| ≤ 1).
MAX_LOBE_PEAK = 1e12
#: Most lobes of a Lafortune model.
MAX_LOBES = 16


def lafortune_lobe_peak(cxy: np.ndarray, cz: np.ndarray, n: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """Per channel, the largest value ks max(Cxy (LxVx+LyVy) + Cz LzVz, 0)^n of a Lafortune
    lobe over all unit directions, ks max(|Cxy|, |Cz|)^n (1/sr; ``inf`` if it overflows)."""
    big = np.maximum(np.abs(np.asarray(cxy, dtype=np.float64)), np.abs(np.asarray(cz, dtype=np.float64)))
    n = np.asarray(n, dtype=np.float64)
    ks = np.asarray(ks, dtype=np.float64)
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        log_peak = np.log(ks) + np.where(n > 0, n * np.log(np.where(big > 0, big, 1.0)), 0.0)
        log_peak = np.where((big == 0) & (n > 0), -np.inf, log_peak)
        return np.where(ks > 0, np.exp(np.minimum(log_peak, 1000.0)), 0.0)


def rgb(value: float | tuple[float, float, float] | np.ndarray) -> np.ndarray:
    """A scalar or an RGB triple as a float64 array of shape (3,)."""
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        return np.full(3, float(a))
    if a.shape != (3,):
        raise ValueError(f"expected a scalar or an RGB triple, got shape {a.shape}")
    return a.copy()


def _fmt(a: np.ndarray) -> str:
    a = np.asarray(a)
    if np.all(a == a[0]):
        return f"{a[0]:.9g}"
    return "/".join(f"{v:.9g}" for v in a)


def _with_scale(spec: str, ks: np.ndarray) -> str:
    """Append ``,ks=...`` to a spec unless the scale is the default 1."""
    return spec if np.all(ks == 1.0) else f"{spec},ks={_fmt(ks)}"


def _safe_pow(base: np.ndarray, exponent: np.ndarray) -> np.ndarray:
    """max(base, 0) ** exponent without overflow warnings for huge exponents."""
    with np.errstate(divide="ignore", over="ignore", under="ignore"):
        positive = base > 0
        out = np.where(positive, np.exp(exponent * np.log(np.where(positive, base, 1.0))), 0.0)
    return out


def _half_vector_cos(L: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(cos θ_h, cos θ_d) of the half vector H = normalize(L + V)."""
    H = L + V
    norm = np.sqrt(np.einsum("...k,...k->...", H, H))
    norm = np.where(norm > 0, norm, 1.0)
    cos_h = np.clip(H[..., 2] / norm, -1.0, 1.0)
    cos_d = np.clip(np.einsum("...k,...k->...", L, H) / norm, -1.0, 1.0)
    return cos_h, cos_d


@dataclass(frozen=True, eq=False, repr=False)
class _Analytic(BRDF):
    kind: Kind = field(default="analytic", init=False)

    @property
    def name(self) -> str:  # type: ignore[override]
        return self.to_spec()

    def to_spec(self) -> str:  # pragma: no cover - every model overrides it
        raise NotImplementedError


#: The type every model of this module shares (a BRDF that writes itself back with ``to_spec()``),
#: for annotations.
AnalyticModel = _Analytic


@dataclass(frozen=True, eq=False, repr=False)
class _DefinedByRhoHat(_Analytic):
    """A model that defines ρ̂ = ρ cos θ_i directly (RH02's Phong and simplified microfacet)."""

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """ρ = ρ̂ / max(cos θ_i, :data:`COS_FLOOR`) above the surface, 0 below."""
        L, V = as_directions(L, V)
        cos_i = L[..., 2]
        above = (cos_i > 0) & (V[..., 2] > 0)
        divisor = np.where(above, np.maximum(cos_i, COS_FLOOR), 1.0)
        return np.where(above[..., None], self.rho_hat(L, V) / divisor[..., None], 0.0)


@dataclass(frozen=True, eq=False, repr=False)
class PhongLobe(_DefinedByRhoHat):
    """RH02 Phong lobe about the mirror direction (RH02 §6.3, Appendix D)."""

    s: float
    ks: np.ndarray = field(default_factory=lambda: rgb(1.0))

    def rho_hat(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        L, V = as_directions(L, V)
        # R = mirror of V about the normal +z; R.L = -Vx Lx - Vy Ly + Vz Lz
        r_dot_l = -V[..., 0] * L[..., 0] - V[..., 1] * L[..., 1] + V[..., 2] * L[..., 2]
        lobe = (self.s + 1.0) / (2.0 * np.pi) * _safe_pow(r_dot_l, np.float64(self.s))
        return lobe[..., None] * self.ks

    def to_spec(self) -> str:
        return _with_scale(f"phong:s={self.s:.9g}", self.ks)


@dataclass(frozen=True, eq=False, repr=False)
class SimplifiedMicrofacet(_DefinedByRhoHat):
    """RH02 eq. 11: rho_hat = exp(-(θ_h/σ)²)/(4πσ²), zero where N·L <= 0."""

    sigma: float
    ks: np.ndarray = field(default_factory=lambda: rgb(1.0))

    def rho_hat(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        L, V = as_directions(L, V)
        cos_h, _ = _half_vector_cos(L, V)
        theta_h = np.arccos(cos_h)
        lobe = np.exp(-((theta_h / self.sigma) ** 2)) / (4.0 * np.pi * self.sigma**2)
        lobe = np.where((L[..., 2] > 0) & (V[..., 2] > 0), lobe, 0.0)
        return lobe[..., None] * self.ks

    def to_spec(self) -> str:
        return _with_scale(f"microfacet:sigma={self.sigma:.9g}", self.ks)


@dataclass(frozen=True, eq=False, repr=False)
class Lambert(_Analytic):
    """rho = albedo / π."""

    albedo: np.ndarray

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        L, V = as_directions(L, V)
        above = (L[..., 2] > 0) & (V[..., 2] > 0)
        return np.where(above[..., None], self.albedo / np.pi, 0.0)

    def to_spec(self) -> str:
        return f"lambert:albedo={_fmt(self.albedo)}"


@dataclass(frozen=True, eq=False, repr=False)
class LafortuneLobe:
    """One isotropic generalized-cosine lobe: ks * max(Cxy (LxVx+LyVy) + Cz LzVz, 0)^n.

    Each parameter is an RGB array of shape (3,).
    """

    cxy: np.ndarray
    cz: np.ndarray
    n: np.ndarray
    ks: np.ndarray

    def value(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        dot_xy = (L[..., 0] * V[..., 0] + L[..., 1] * V[..., 1])[..., None]
        dot_z = (L[..., 2] * V[..., 2])[..., None]
        return self.ks * _safe_pow(self.cxy * dot_xy + self.cz * dot_z, self.n)


@dataclass(frozen=True, eq=False, repr=False)
class Lafortune(_Analytic):
    """Lafortune et al. 1997: kd/π + Σ_k generalized-cosine lobes (isotropic)."""

    kd: np.ndarray
    lobes: tuple[LafortuneLobe, ...]

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        L, V = as_directions(L, V)
        out = np.broadcast_to(self.kd / np.pi, L.shape[:-1] + (3,)).copy()
        for lobe in self.lobes:
            out += lobe.value(L, V)
        above = (L[..., 2] > 0) & (V[..., 2] > 0)
        return np.where(above[..., None], out, 0.0)

    def to_spec(self) -> str:
        parts = [f"kd={_fmt(self.kd)}"]
        for k, lobe in enumerate(self.lobes, start=1):
            sfx = "" if k == 1 else str(k)
            parts += [
                f"cxy{sfx}={_fmt(lobe.cxy)}",
                f"cz{sfx}={_fmt(lobe.cz)}",
                f"n{sfx}={_fmt(lobe.n)}",
                f"ks{sfx}={_fmt(lobe.ks)}",
            ]
        return "lafortune:" + ",".join(parts)


def smith_g1_over_cos(cos_t: np.ndarray, alpha: float, distribution: str) -> np.ndarray:
    """Smith masking G1(θ) divided by cos θ, finite down to grazing (Walter et al. 2007).

    GGX (exact): G1/cos = 2 / (cos θ + sqrt(cos² θ + α² sin² θ)), 2/α at grazing.
    Beckmann (Walter's rational approximation in a = cos θ/(α sin θ)): for a < 1.6,
    G1/cos = (3.535 + 2.181 a) / (α sin θ (1 + 2.276 a + 2.577 a²)), else 1/cos θ.
    Dividing analytically keeps ρ = D F G/(4 cos θ_i cos θ_o) finite where a cosine
    underflows (a MERL sample exactly on the horizon, say).
    """
    c = np.clip(cos_t, 0.0, 1.0)
    s = np.sqrt(1.0 - c * c)
    if distribution == "ggx":
        return 2.0 / (c + np.sqrt(c * c + alpha**2 * s * s))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # branches np.where discards
        a = np.where(s > 0, c / (alpha * np.where(s > 0, s, 1.0)), np.inf)
        rational = (3.535 + 2.181 * a) / (alpha * s * (1.0 + 2.276 * a + 2.577 * a * a))
        return np.where(a < 1.6, rational, 1.0 / np.where(c > 0, c, 1.0))


@dataclass(frozen=True, eq=False, repr=False)
class CookTorrance(_Analytic):
    """Cook–Torrance microfacet BRDF + Lambert (Beckmann or GGX D, Schlick F, Smith G)."""

    kd: np.ndarray
    ks: np.ndarray
    alpha: float
    f0: np.ndarray
    distribution: str = "beckmann"

    def distribution_value(self, cos_h: np.ndarray) -> np.ndarray:
        """Normal distribution D(θ_h), normalized so ∫ D cos θ_h dω = 1."""
        a2 = self.alpha**2
        c2 = np.clip(cos_h, 1e-12, 1.0) ** 2
        if self.distribution == "ggx":
            return a2 / (np.pi * (c2 * (a2 - 1.0) + 1.0) ** 2)
        return np.exp(-(1.0 - c2) / (c2 * a2)) / (np.pi * a2 * c2**2)

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        L, V = as_directions(L, V)
        cos_i, cos_o = L[..., 2], V[..., 2]
        above = (cos_i > 0) & (cos_o > 0)
        cos_h, cos_d = _half_vector_cos(L, V)
        m = 1.0 - np.clip(cos_d, 0.0, 1.0)
        m2 = m * m
        fresnel = self.f0 + (1.0 - self.f0) * (m2 * m2 * m)[..., None]  # Schlick (1 - cos θ_d)^5: products, not pow
        spec = self.microfacet_term(cos_i, cos_o, cos_h)[..., None] * fresnel * self.ks
        return np.where(above[..., None], self.kd / np.pi + spec, 0.0)

    def microfacet_term(self, cos_i: np.ndarray, cos_o: np.ndarray, cos_h: np.ndarray) -> np.ndarray:
        """D(θ_h) G(θ_i, θ_o) / (4 cos θ_i cos θ_o), finite down to grazing angles."""
        D = np.where(cos_h > 0, self.distribution_value(cos_h), 0.0)
        return (
            D
            * smith_g1_over_cos(cos_i, self.alpha, self.distribution)
            * smith_g1_over_cos(cos_o, self.alpha, self.distribution)
            / 4.0
        )

    def to_spec(self) -> str:
        return (
            f"cook-torrance:kd={_fmt(self.kd)},ks={_fmt(self.ks)},alpha={self.alpha:.9g},"
            f"f0={_fmt(self.f0)},dist={self.distribution}"
        )
