"""An exported material as its renderer defines it (:class:`ExportedMaterial`), its conductor lobe and Fresnel.

:class:`ExportedMaterial` evaluates ρ = (1 − w)·diffuse/π + w·conductor (+ pbrt-v4's coat) as
the target renderer defines it; :class:`Conductor` is the microfacet conductor of Mitsuba 3,
pbrt-v4 and MaterialX (Beckmann or GGX D, separable or height-correlated Smith G, conductor
Fresnel of a complex index η + ik, or F = 1); :func:`fit_conductor_fresnel` finds the index whose
Fresnel is closest to a target curve (Schlick's, :func:`schlick`) on θ_d ≤ 80°;
:func:`artistic_ior` is Gulbrandsen's map from MaterialX's colours to η, k.
:mod:`.export_material` converts models to these materials and re-exports the public names; the
mapping is in ``data_specs/export.md``.

References: [PBRT4] §9.5 (``FrComplex``), §9.6 (height-correlated masking-shadowing), §14.3
(``CoatedDiffuseBxDF``); [Mitsuba3] (``roughconductor``, ``blendbsdf``); [MaterialX]
(``mx_artistic_ior``, ``mx_fresnel_conductor``); [Gulbrandsen14]; [Walter07] (GGX, Smith G1).
Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .brdf import as_directions
from .halfdiff import halfdiff_to_directions
from .models import CookTorrance, smith_g1_over_cos
from .pbrt_coated import DielectricCoat

#: Gauss–Legendre nodes in cos θ_d on which a conductor Fresnel is fitted to a target curve.
_FRESNEL_NODES = 48
#: The fit covers θ_d ≤ 80° (cos θ_d ≥ cos 80°), the angles an export's error is measured on: a
#: conductor's rise to 1 at grazing incidence would otherwise outweigh the whole curve.
_FRESNEL_COS_MIN = float(np.cos(np.radians(80.0)))


def schlick(f0: np.ndarray, cos_d: np.ndarray) -> np.ndarray:
    """Schlick's Fresnel f0 + (1 − f0)(1 − cos θ_d)⁵, shape ``cos_d.shape + (3,)``."""
    m = 1.0 - np.clip(np.asarray(cos_d, dtype=np.float64), 0.0, 1.0)
    return np.asarray(f0, dtype=np.float64) + (1.0 - np.asarray(f0, dtype=np.float64)) * (m**5)[..., None]


def fresnel_conductor(cos_d: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Unpolarized Fresnel reflectance of a conductor of complex index η + ik seen from a medium
    of index 1, per channel: shape ``cos_d.shape + (3,)`` for (3,) ``eta`` and ``k``.

    The closed form of pbrt-v3's ``FrConductor``, Mitsuba 3's ``fresnel_conductor`` and
    MaterialX's ``mx_fresnel_conductor`` (pbrt-v4's complex ``FrComplex`` is the same function):
    F(1) = ((η − 1)² + k²)/((η + 1)² + k²), F(0) = 1.
    """
    c = np.clip(np.asarray(cos_d, dtype=np.float64), 0.0, 1.0)[..., None]
    return _fresnel(c, np.asarray(eta, dtype=np.float64), np.asarray(k, dtype=np.float64))


def _fresnel(c: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """:func:`fresnel_conductor` on arrays that already broadcast against each other."""
    c2 = c * c
    s2 = 1.0 - c2
    eta2, k2 = eta * eta, k * k
    t0 = eta2 - k2 - s2
    a2b2 = np.sqrt(t0 * t0 + 4.0 * eta2 * k2)
    t1 = a2b2 + c2
    a = np.sqrt(np.maximum(0.5 * (a2b2 + t0), 0.0))
    t2 = 2.0 * c * a
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = np.where(t1 + t2 > 0, (t1 - t2) / np.where(t1 + t2 > 0, t1 + t2, 1.0), 1.0)
        t3 = c2 * a2b2 + s2 * s2
        t4 = t2 * s2
        rp = rs * np.where(t3 + t4 > 0, (t3 - t4) / np.where(t3 + t4 > 0, t3 + t4, 1.0), 1.0)
    return 0.5 * (rp + rs)


def fit_conductor_fresnel(
    target: Callable[[np.ndarray], np.ndarray], weight: Callable[[np.ndarray], np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """The conductor Fresnel closest to ``target`` (a function of cos θ_d returning (n, 3)):
    per channel the (η, k) minimizing ∫ W(c) (F(c; η, k) − T(c))² dc over c = cos θ_d ∈
    [cos 80°, 1] (:data:`_FRESNEL_COS_MIN`), W = ``weight(c)`` (default 1; :func:`lobe_fresnel_weight`
    makes this the lobe's own squared error), by a log-spaced grid search
    over η ∈ [0.01, 100], k ∈ {0} ∪ [10⁻³, 10³] refined three times around the best node.

    Returns
    -------
    eta, k
        (3,) float64.
    rms
        The largest per-channel RMS of F − T over that range (a number of the fit, not the
        BRDF's error).
    """
    x, w = np.polynomial.legendre.leggauss(_FRESNEL_NODES)
    lo = _FRESNEL_COS_MIN
    c, w = lo + (x + 1.0) * (1.0 - lo) / 2.0, w / 2.0
    if weight is not None:
        extra = np.asarray(weight(c), dtype=np.float64)
        if np.all(np.isfinite(extra)) and np.sum(w * extra) > 0:
            w = w * extra / np.sum(w * extra)
    t = np.asarray(target(c), dtype=np.float64)  # (n, 3)
    eta_out, k_out, worst = np.empty(3), np.empty(3), 0.0
    for ch in range(3):
        log_eta = np.linspace(np.log(0.01), np.log(100.0), 61)
        log_k = np.linspace(np.log(1e-3), np.log(1e3), 61)
        with_zero_k = True
        best = (1.0, 0.0, np.inf)
        for _ in range(4):
            e = np.exp(log_eta)
            kk = np.concatenate(([0.0], np.exp(log_k))) if with_zero_k else np.exp(log_k)
            E, K = np.meshgrid(e, kk, indexing="ij")
            F = _fresnel(c[:, None], E.ravel()[None, :], K.ravel()[None, :])  # (nodes, grid)
            err = (w[:, None] * (F - t[:, ch : ch + 1]) ** 2).sum(axis=0)
            j = int(np.argmin(err))
            if err[j] < best[2]:
                best = (float(E.ravel()[j]), float(K.ravel()[j]), float(err[j]))
            de, dk = (log_eta[1] - log_eta[0]) * 2, (log_k[1] - log_k[0]) * 2
            log_eta = np.linspace(np.log(best[0]) - de, np.log(best[0]) + de, 41)
            centre_k = np.log(best[1]) if best[1] > 0 else np.log(1e-3)
            log_k = np.linspace(centre_k - dk, centre_k + dk, 41)
            with_zero_k = best[1] == 0.0
        eta_out[ch], k_out[ch] = best[0], best[1]
        worst = max(worst, math.sqrt(best[2]))
    return eta_out, k_out, worst


def lobe_fresnel_weight(lobe: Conductor) -> Callable[[np.ndarray], np.ndarray]:
    """W(c) for :func:`fit_conductor_fresnel` that makes its objective the squared error of the
    lobe's ρ cos θ_i (the numerator of the relative RMS an export states) integrated over
    direction pairs with θ_i, θ_o ≤ 80°: W(c) = 2π ∫∫ (f(L, V) cos θ_i)² 4 c sin θ_h dθ_h dφ_d at
    cos θ_d = c, with f the lobe without Fresnel (dω_i dω_o = 4 cos θ_d sin θ_h sin θ_d dθ_h dθ_d
    dφ_h dφ_d, Rusinkiewicz 1998; 2π for φ_h by isotropy); θ_h on 64 Gauss–Legendre nodes in
    √(θ_h/(π/2)), φ_d on 48 midpoints of [0, 2π)."""
    bare = replace(lobe, eta=None, k=None, scale=np.ones(3))
    x, wx = np.polynomial.legendre.leggauss(64)
    u, wu = (x + 1.0) / 2.0, wx / 2.0
    theta_h = u * u * np.pi / 2.0
    d_theta_h = wu * np.pi * u  # dθ_h = π u du
    phi_d = (np.arange(48) + 0.5) * 2.0 * np.pi / 48.0  # all of [0, 2π): (f cos θ_i)² is not reciprocal
    cos_max = math.cos(math.radians(80.0))

    def weight(c: np.ndarray) -> np.ndarray:
        th, td, pd = np.meshgrid(theta_h, np.arccos(np.clip(c, -1.0, 1.0)), phi_d, indexing="ij")
        L, V = halfdiff_to_directions(th, td, pd)
        value = bare.eval(L, V)[..., 0] * L[..., 2]
        inside = (L[..., 2] >= cos_max) & (V[..., 2] >= cos_max)
        jac = 4.0 * np.cos(td) * np.sin(th) * d_theta_h[:, None, None] * (2.0 * np.pi / 48.0) * (2.0 * np.pi)
        return np.sum(np.where(inside, value * value * jac, 0.0), axis=(0, 2))

    return weight


def artistic_ior(reflectivity: np.ndarray, edge_color: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gulbrandsen's (2014) complex index (η, k) of a metal from its normal-incidence
    reflectivity r and edge tint g, as MaterialX's ``mx_artistic_ior``: r clamped to [0, 0.99],
    η = g (1 − r)/(1 + r) + (1 − g)(1 + √r)/(1 − √r), k = √max(((η + 1)² r − (η − 1)²)/(1 − r), 0)."""
    r = np.clip(np.asarray(reflectivity, dtype=np.float64), 0.0, 0.99)
    g = np.asarray(edge_color, dtype=np.float64)
    n_min = (1.0 - r) / (1.0 + r)
    n_max = (1.0 + np.sqrt(r)) / (1.0 - np.sqrt(r))
    eta = n_max * (1.0 - g) + n_min * g
    k2 = ((eta + 1.0) ** 2 * r - (eta - 1.0) ** 2) / (1.0 - r)
    return eta, np.sqrt(np.maximum(k2, 0.0))


@dataclass(frozen=True, eq=False)
class Conductor:
    """A rough-conductor lobe as a renderer defines it.

    Attributes
    ----------
    distribution
        ``"ggx"`` or ``"beckmann"`` (normalized D of ``CookTorrance.distribution_value``).
    alpha
        Roughness α (the D's width, not a "perceptual" roughness).
    eta, k
        (3,) complex index per channel, or None for F = 1 (Mitsuba's ``material="none"``).
    scale
        (3,) factor on the lobe (Mitsuba's ``specular_reflectance``; 1 elsewhere).
    shadowing
        ``"separable"`` G1(ω_i) G1(ω_o) (Mitsuba) or ``"height-correlated"``
        1/(1 + Λ(ω_i) + Λ(ω_o)) (pbrt-v4, MaterialX; GGX only).
    """

    distribution: str
    alpha: float
    eta: np.ndarray | None
    k: np.ndarray | None
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    shadowing: str = "separable"

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """ρ (..., 3) of the lobe alone, 1/sr; 0 where L or V is below the surface."""
        L, V = as_directions(L, V)
        cos_i, cos_o = L[..., 2], V[..., 2]
        above = (cos_i > 0) & (cos_o > 0)
        H = L + V
        H = H / np.where((n := np.linalg.norm(H, axis=-1, keepdims=True)) > 0, n, 1.0)
        cos_h = H[..., 2]
        cos_d = np.clip(np.einsum("...k,...k->...", L, H), 0.0, 1.0)
        proxy = CookTorrance(kd=np.zeros(3), ks=np.ones(3), alpha=self.alpha, f0=np.ones(3),
                             distribution=self.distribution)
        D = np.where(cos_h > 0, proxy.distribution_value(cos_h), 0.0)
        if self.shadowing == "separable":
            g_over = (smith_g1_over_cos(cos_i, self.alpha, self.distribution)
                      * smith_g1_over_cos(cos_o, self.alpha, self.distribution))
        else:  # height-correlated GGX: G2 / (cos_i cos_o), Λ(θ) = (√(1 + α² tan² θ) − 1)/2
            ci, co = np.clip(cos_i, 1e-300, 1.0), np.clip(cos_o, 1e-300, 1.0)
            a2 = self.alpha**2
            # G2/(ci co) = 2 / (co √(a² + (1−a²) ci²) + ci √(a² + (1−a²) co²)), finite at grazing
            g_over = 2.0 / (co * np.sqrt(a2 + (1.0 - a2) * ci * ci) + ci * np.sqrt(a2 + (1.0 - a2) * co * co))
        if self.eta is None:
            F = np.ones(cos_d.shape + (3,))
        else:
            assert self.k is not None, "a conductor's eta and k are given together"
            F = fresnel_conductor(cos_d, self.eta, self.k)
        spec = (D * g_over / 4.0)[..., None] * F * self.scale
        return np.where(above[..., None], spec, 0.0)


@dataclass(frozen=True, eq=False)
class ExportedMaterial:
    """A material as one renderer defines it: ρ = (1 − w)·diffuse/π + w·conductor.

    Attributes
    ----------
    target
        Key of :data:`MATERIAL_TARGETS`.
    source
        Spec of the model it was converted from (``brdf.to_spec()``).
    diffuse
        (3,) Lambert albedo of the diffuse part, or None.
    conductor
        The rough-conductor part, or None.
    weight
        w, the conductor's share (Mitsuba ``blendbsdf`` weight, pbrt ``mix`` amount, MaterialX
        ``metalness``); 1 without a diffuse part, 0 without a conductor.
    native
        The renderer's own parameters, what the snippet writes (``data_specs/export.md``).
    exact
        The renderer's BSDF equals the source model (up to float rounding).
    note
        Why it is not exact (empty when it is).
    coat
        pbrt-v4's ``coateddiffuse`` (a rough dielectric coat over a Lambertian base,
        ``brdf_io/pbrt_coated.py``), added to the rest (then ``diffuse`` and ``conductor`` are None).
    """

    target: str
    source: str
    diffuse: np.ndarray | None
    conductor: Conductor | None
    weight: float
    native: dict[str, Any]
    exact: bool
    note: str = ""
    coat: DielectricCoat | None = None

    def eval(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        """ρ (..., 3) in 1/sr of the exported material as the renderer evaluates it (single
        scattering), 0 where L or V is below the surface."""
        L, V = as_directions(L, V)
        out = np.zeros(L.shape[:-1] + (3,))
        above = (L[..., 2] > 0) & (V[..., 2] > 0)
        if self.diffuse is not None:
            out += np.where(above[..., None], (1.0 - self.weight) * self.diffuse / np.pi, 0.0)
        if self.conductor is not None:
            out += self.weight * self.conductor.eval(L, V)
        if self.coat is not None:
            out += self.coat.eval(L, V)
        return out
