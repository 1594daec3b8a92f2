"""Parameterizations of the fitted models, split into nonlinear shape and linear colour.

Every model is written as rho(L, V) = Σ_j c_j B_j(L, V; x): a few *shape* parameters x
(optimized by nlopt) and per-channel *colour weights* c_j >= 0 that enter linearly and are
solved in closed form inside the objective (variable projection, see ``objective.py``).
Each basis column is returned divided by its largest value over the samples (stored as
``log_scale``), which keeps the small least-squares systems well conditioned and lets
lobes with exponents ~10⁴ be evaluated without overflow.

Energy conservation is one linear constraint per channel, Σ_j a_j c_j <= 1:

* Lafortune: kd + Σ_k ks_k 2π/(n_k + 2) <= 1 with lobes written in the max-normalized form
  max(|Cxy|, |Cz|) = 1 — the normalization of [Laf97] (and of [Ngan05]'s
  ρ_s (n+2)/(2π)); exact at normal incidence for a mirror lobe (Cxy = −Cz).
* Cook–Torrance: kd + ks <= 1 (Fresnel F <= 1 and a normalized D with Smith G keep the
  specular albedo <= ks).
* [RH02]'s simplified microfacet: ks <= 1 (for small σ its ρ̂ integrates to ks).

Lafortune lobe shape is shared by the three channels (the lobe weights ks are per
channel): one lobe direction/exponent per lobe is what the model means physically, and the
RGB ks carry the colour. The shape is (ψ, ln n) with (Cxy, Cz) ∝ (cos ψ, sin ψ), ψ ∈ [0, π]
(Cz >= 0: retro-reflective ψ < π/2, forward ψ > π/2; lobes with Cz < 0 are not fitted);
the result is reported max-normalized. Cook–Torrance's Fresnel term is linear too:
ks F = (ks f0) S₀ + (ks (1 − f0)) S₁ with S₀ = DG/(4 cos θ_i cos θ_o) and
S₁ = S₀ (1 − cos θ_d)⁵, so only ln α is nonlinear.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...brdf_io.models import AnalyticModel, CookTorrance, Lafortune, LafortuneLobe, SimplifiedMicrofacet, rgb
from ..defaults import FIT_MODELS as MODELS  # numpy-free home, for the CLI's parsers
from .sampling import FitSamples

__all__ = [
    "Geometry",
    "ModelParam",
    "LafortuneParam",
    "CookTorranceParam",
    "MicrofacetParam",
    "make_param",
    "MODELS",
]


@dataclass(frozen=True, eq=False)
class Geometry:
    """Per-sample quantities every basis needs, computed once per fit."""

    cos_i: np.ndarray
    cos_o: np.ndarray
    cos_h: np.ndarray
    cos_d: np.ndarray
    dot_xy: np.ndarray
    dot_z: np.ndarray

    @classmethod
    def of(cls, samples: FitSamples) -> Geometry:
        L, V = samples.L, samples.V
        H = L + V
        H = H / np.linalg.norm(H, axis=1, keepdims=True)
        return cls(
            cos_i=L[:, 2],
            cos_o=V[:, 2],
            cos_h=np.clip(H[:, 2], -1.0, 1.0),
            cos_d=np.clip(np.sum(L * H, axis=1), -1.0, 1.0),
            dot_xy=L[:, 0] * V[:, 0] + L[:, 1] * V[:, 1],
            dot_z=L[:, 2] * V[:, 2],
        )


def _normalized_columns(cols: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    B = np.stack(cols, axis=1)
    peak = np.max(B, axis=0)
    peak = np.where(peak > 0, peak, 1.0)
    return B / peak, np.log(peak)


@dataclass(frozen=True)
class ModelParam:
    """Base of the model parameterizations (see the module docstring)."""

    name: str = ""
    lower: np.ndarray = field(default_factory=lambda: np.zeros(0))
    upper: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def dim(self) -> int:
        return len(self.lower)

    def basis(self, x: np.ndarray, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        """Columns B (n, m) scaled to peak 1, and log of the scale: B_true = B · exp(log_scale)."""
        raise NotImplementedError

    def energy(self, x: np.ndarray) -> np.ndarray:
        """a (m,) of the constraint Σ a_j c_true_j <= 1 (true, unscaled weights)."""
        raise NotImplementedError

    def starts(self) -> np.ndarray:
        """Physically motivated starting points (k, dim) for the global stage."""
        raise NotImplementedError

    def canonical(self, x: np.ndarray) -> np.ndarray:
        """A canonical representative of x (e.g. lobes sorted), same model."""
        return x

    def build(self, x: np.ndarray, c: np.ndarray) -> tuple[AnalyticModel, dict[str, Any]]:
        """The fitted model object and its parameters from x and true weights c (m, 3)."""
        raise NotImplementedError

    def shape_names(self) -> list[tuple[str, str, str]]:
        """Per shape parameter: (name, its value at the lower bound, at the upper bound) for people."""
        raise NotImplementedError

    def bounds_reached(self, x: np.ndarray, c: np.ndarray) -> list[str]:
        """Sentences naming the parameters that ended at a bound of the search: shape parameters
        within 10⁻⁴ of the box's span of an end, and, per channel, the energy constraint
        Σ a_j c_j = 1 met with equality (to 10⁻⁶) — an optimum pressed against a bound is the best
        the model allows there, not a fit of the data."""
        out = []
        span = self.upper - self.lower
        for k, (name, at_lo, at_hi) in enumerate(self.shape_names()):
            if x[k] - self.lower[k] <= 1e-4 * span[k]:
                out.append(f"{name} at its lower bound {at_lo}")
            elif self.upper[k] - x[k] <= 1e-4 * span[k]:
                out.append(f"{name} at its upper bound {at_hi}")
        used = self.energy(x) @ c  # (3,): Σ a_j c_j per channel
        full = [ch for ch, u in zip("RGB", used, strict=True) if u >= 1.0 - 1e-6]
        if full:
            out.append(f"energy conservation bound reached in {', '.join(full)} ({self.energy_text})")
        return out + self._weight_bounds(c)

    energy_text = "Σ a_j c_j = 1"

    def _weight_bounds(self, c: np.ndarray) -> list[str]:
        return []


@dataclass(frozen=True)
class LafortuneParam(ModelParam):
    """kd/π + Σ_k ks_k max(Cxy_k (LxVx + LyVy) + Cz_k LzVz, 0)^n_k; x = (ψ_k, ln n_k)_k."""

    lobes: int = 1
    n_min: float = 0.5
    n_max: float = 5.0e4

    @classmethod
    def create(cls, lobes: int) -> LafortuneParam:
        lo = np.tile([0.0, np.log(0.5)], lobes)
        hi = np.tile([np.pi, np.log(5.0e4)], lobes)
        return cls(name="lafortune", lower=lo, upper=hi, lobes=lobes)

    @staticmethod
    def shape(psi: float) -> tuple[float, float, float]:
        """(Cxy, Cz) max-normalized, and C = max(|cos ψ|, |sin ψ|)."""
        cxy, cz = np.cos(psi), np.sin(psi)
        big = max(abs(cxy), abs(cz))
        return cxy / big, cz / big, big

    def basis(self, x: np.ndarray, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        cols = [np.full(len(geo.cos_i), 1.0)]
        log_scale = [np.log(1.0 / np.pi)]
        for k in range(self.lobes):
            psi, ln_n = x[2 * k], x[2 * k + 1]
            n = np.exp(ln_n)
            cxy, cz, big = self.shape(psi)
            base = cxy * geo.dot_xy + cz * geo.dot_z  # max-normalized base
            positive = base > 0
            with np.errstate(divide="ignore"):
                log_lobe = np.where(positive, n * np.log(np.where(positive, base, 1.0)), -np.inf)
            shift = np.max(log_lobe)
            if not np.isfinite(shift):
                shift = 0.0
            cols.append(np.exp(log_lobe - shift))
            log_scale.append(shift)
        return np.stack(cols, axis=1), np.asarray(log_scale)

    def energy(self, x: np.ndarray) -> np.ndarray:
        n = np.exp(x[1::2])
        return np.concatenate([[1.0], 2.0 * np.pi / (n + 2.0)])

    def starts(self) -> np.ndarray:
        singles = [
            (psi, np.log(n))
            for psi in (0.75 * np.pi, 0.25 * np.pi, 0.95 * np.pi)
            for n in (3.0, 15.0, 80.0, 500.0, 3000.0, 15000.0)
        ]
        singles += [(0.6 * np.pi, np.log(n)) for n in (5.0, 50.0)]
        if self.lobes == 1:
            return np.asarray(singles)
        rng = np.random.default_rng(12345)
        combos = [
            np.concatenate([singles[i] for i in idx])
            for idx in (rng.choice(len(singles), size=self.lobes, replace=False) for _ in range(150))
        ]
        # every pair of a forward lobe with another lobe, the common 2-lobe structure
        fwd = [s for s in singles if abs(s[0] - 0.75 * np.pi) < 1e-9]
        for a in fwd:
            for b in singles:
                if b is a:
                    continue
                rest = [singles[(i * 7) % len(singles)] for i in range(self.lobes - 2)]
                combos.append(np.concatenate([a, b, *rest]))
        return np.asarray(combos)

    energy_text = "kd + Σ ks 2π/(n + 2) = 1"

    def shape_names(self) -> list[tuple[str, str, str]]:
        names = []
        for k in range(1, self.lobes + 1):
            names += [(f"lobe {k} direction ψ", "0 (Cz = 0, retro-reflective)", "π (Cz = 0, forward)"),
                      (f"lobe {k} exponent n", f"{self.n_min:g}", f"{self.n_max:g}")]
        return names

    def _weight_bounds(self, c: np.ndarray) -> list[str]:
        scale = max(float(np.max(c)), 1e-300)
        return [f"lobe {k} unused (ks = 0 in every channel)" for k in range(1, self.lobes + 1)
                if not np.any(c[k] > 1e-9 * scale)]

    def canonical(self, x: np.ndarray) -> np.ndarray:
        pairs = x.reshape(self.lobes, 2)
        return pairs[np.argsort(-pairs[:, 1], kind="stable")].ravel()

    def build(self, x: np.ndarray, c: np.ndarray) -> tuple[AnalyticModel, dict[str, Any]]:
        kd = c[0]
        lobes, described = [], []
        for k in range(self.lobes):
            cxy, cz, _ = self.shape(x[2 * k])
            n = float(np.exp(x[2 * k + 1]))
            ks = c[k + 1]
            lobes.append(LafortuneLobe(cxy=rgb(cxy), cz=rgb(cz), n=rgb(n), ks=rgb(ks)))
            described.append({"cxy": float(cxy), "cz": float(cz), "n": n, "ks": ks.tolist()})
        model = Lafortune(kd=rgb(kd), lobes=tuple(lobes))
        return model, {"kd": kd.tolist(), "lobes": described}


@dataclass(frozen=True)
class CookTorranceParam(ModelParam):
    """kd/π + (ks f0) S₀ + (ks (1 − f0)) S₁ (module docstring); x = (ln α,)."""

    distribution: str = "beckmann"

    @classmethod
    def create(cls, distribution: str) -> CookTorranceParam:
        return cls(
            name="cook-torrance",
            lower=np.array([np.log(2.0e-3)]),
            upper=np.array([np.log(1.0)]),
            distribution=distribution,
        )

    def basis(self, x: np.ndarray, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        alpha = float(np.exp(x[0]))
        proto = CookTorrance(kd=rgb(0.0), ks=rgb(1.0), alpha=alpha, f0=rgb(1.0), distribution=self.distribution)
        s0 = proto.microfacet_term(geo.cos_i, geo.cos_o, geo.cos_h)
        s1 = s0 * (1.0 - np.clip(geo.cos_d, 0.0, 1.0)) ** 5
        B, log_scale = _normalized_columns([np.full(len(s0), 1.0 / np.pi), s0, s1])
        return B, log_scale

    def energy(self, x: np.ndarray) -> np.ndarray:
        return np.ones(3)

    energy_text = "kd + ks = 1"

    def shape_names(self) -> list[tuple[str, str, str]]:
        return [("roughness α", f"{np.exp(self.lower[0]):g}", f"{np.exp(self.upper[0]):g}")]

    def _weight_bounds(self, c: np.ndarray) -> list[str]:
        # ks f0 = c[1], ks (1 − f0) = c[2]: f0 = 1 where only the first is used, 0 where only the second
        # (to 10⁻⁶ of ks: the bounded least squares leave round-off above 0)
        out = []
        ks = c[1] + c[2]
        one = [ch for ch, a, b, k in zip("RGB", c[1], c[2], ks, strict=True) if k > 0 and b <= 1e-6 * k]
        zero = [ch for ch, a, b, k in zip("RGB", c[1], c[2], ks, strict=True) if k > 0 and a <= 1e-6 * k]
        if one:
            out.append(f"Fresnel f0 at its upper bound 1 in {', '.join(one)}")
        if zero:
            out.append(f"Fresnel f0 at its lower bound 0 in {', '.join(zero)}")
        return out

    def starts(self) -> np.ndarray:
        return np.log([[0.005], [0.02], [0.05], [0.1], [0.2], [0.35], [0.6]])

    def build(self, x: np.ndarray, c: np.ndarray) -> tuple[AnalyticModel, dict[str, Any]]:
        kd, a, b = c
        ks = a + b
        f0 = np.where(ks > 0, a / np.where(ks > 0, ks, 1.0), 0.04)
        alpha = float(np.exp(x[0]))
        model = CookTorrance(kd=rgb(kd), ks=rgb(ks), alpha=alpha, f0=rgb(f0), distribution=self.distribution)
        params = {
            "kd": kd.tolist(),
            "ks": ks.tolist(),
            "f0": f0.tolist(),
            "alpha": alpha,
            "distribution": self.distribution,
        }
        return model, params


@dataclass(frozen=True)
class MicrofacetParam(ModelParam):
    """RH02 eq. 11: ρ̂ = ks exp(−(θ_h/σ)²)/(4πσ²), so ρ = ρ̂ / cos θ_i; x = (ln σ,)."""

    @classmethod
    def create(cls) -> MicrofacetParam:
        return cls(name="microfacet", lower=np.array([np.log(5.0e-3)]), upper=np.array([np.log(1.5)]))

    def basis(self, x: np.ndarray, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        sigma = float(np.exp(x[0]))
        theta_h = np.arccos(geo.cos_h)
        rho_hat = np.exp(-((theta_h / sigma) ** 2)) / (4.0 * np.pi * sigma**2)
        return _normalized_columns([rho_hat / geo.cos_i])

    def energy(self, x: np.ndarray) -> np.ndarray:
        return np.ones(1)

    energy_text = "ks = 1"

    def shape_names(self) -> list[tuple[str, str, str]]:
        return [("width σ", f"{np.exp(self.lower[0]):g}", f"{np.exp(self.upper[0]):g}")]

    def starts(self) -> np.ndarray:
        return np.log([[0.01], [0.03], [0.08], [0.2], [0.5], [1.0]])

    def build(self, x: np.ndarray, c: np.ndarray) -> tuple[AnalyticModel, dict[str, Any]]:
        sigma = float(np.exp(x[0]))
        model = SimplifiedMicrofacet(sigma=sigma, ks=rgb(c[0]))
        return model, {"sigma": sigma, "ks": c[0].tolist()}


def make_param(model: str, *, lobes: int = 1, distribution: str = "beckmann") -> ModelParam:
    """The parameterization of ``model`` (one of :data:`MODELS`)."""
    if model == "lafortune":
        return LafortuneParam.create(lobes)
    if model == "cook-torrance":
        return CookTorranceParam.create(distribution)
    if model == "microfacet":
        return MicrofacetParam.create()
    raise ValueError(f"unknown model {model!r}; choose one of {MODELS}")
