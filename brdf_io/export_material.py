"""Material snippets for other renderers: Mitsuba 3 (XML, Python dict), pbrt-v4, MaterialX.

A Lambert or Cook–Torrance BRDF (``brdf_io/models.py``) is converted to the closest material
each renderer offers (:func:`to_target`; what each target offers is stated there), as an
:class:`ExportedMaterial` that holds the renderer's own parameters (``native``, what the snippet
writes) and evaluates the BSDF *as that renderer defines it* (:meth:`ExportedMaterial.eval`), so
that the error of an export can be measured (``analysis/material_export.py``) instead of assumed.
The snippets are text: :func:`material_text` (one function per target in :data:`MATERIAL_TARGETS`),
written atomically by :func:`write_material`. Layout and mapping: ``data_specs/export.md``.

References: [Mitsuba3] (plugins ``diffuse``, ``roughconductor``, ``blendbsdf``); [PBRT4] §9.5
(``FrComplex``), §9.6 (Trowbridge–Reitz, height-correlated masking-shadowing), §14.3
(``CoatedDiffuseBxDF``) and the pbrt-v4 scene file format (``Material "conductor"``, ``"mix"``,
``"coateddiffuse"``, ``MakeNamedMaterial``); [StdSurface] and [MaterialX] (``standard_surface.mtlx``,
``mx_artistic_ior``, ``mx_fresnel_conductor``); [Gulbrandsen14]; [Walter07] (GGX, Smith G1).
Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from .atomic import atomic_path
from .brdf import BRDF, as_directions
from .errors import BadInputError
from .halfdiff import halfdiff_to_directions
from .models import CookTorrance, Lambert, smith_g1_over_cos
from .pbrt_coated import COAT_THICKNESS, DielectricCoat, coated_diffuse_from_cook_torrance, fit_dielectric_eta

__all__ = [
    "Conductor",
    "ExportedMaterial",
    "MATERIAL_TARGETS",
    "MaterialTarget",
    "to_target",
    "material_text",
    "mitsuba_dict",
    "write_material",
    "fresnel_conductor",
    "fit_conductor_fresnel",
    "lobe_fresnel_weight",
    "artistic_ior",
    "schlick",
]

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


def _triple(a: np.ndarray) -> list[float]:
    return [float(f"{float(x):.9g}") for x in np.asarray(a, dtype=np.float64)]


def _split(brdf: BRDF, target: str) -> tuple[np.ndarray, CookTorrance | None]:
    """(kd, Cook–Torrance or None) of a Lambert or Cook–Torrance model."""
    if isinstance(brdf, Lambert):
        return np.asarray(brdf.albedo, dtype=np.float64), None
    if isinstance(brdf, CookTorrance):
        spec = brdf if np.any(np.asarray(brdf.ks) > 0) else None
        return np.asarray(brdf.kd, dtype=np.float64) * np.ones(3), spec
    raise BadInputError(getattr(brdf, "name", None), f"{target} export takes a Lambert or Cook-Torrance model "
                        "(other models go through their closest Cook-Torrance fit, analysis.material_export)")


def _mix_weight(kd: np.ndarray, ks: np.ndarray) -> float:
    """The conductor's share w of a two-part mix (1 − w)·diffuse + w·conductor: inside
    [max ks, 1 − max kd] when that interval exists (its middle: neither part needs a reflectance
    above 1), else the compromise max ks/(max ks + max kd)."""
    d, s = float(np.max(kd)), float(np.max(ks))
    if s + d <= 1.0:
        return s + (1.0 - s - d) / 2.0
    return s / (s + d)


def _mitsuba(brdf: BRDF) -> ExportedMaterial:
    kd, ct = _split(brdf, "mitsuba")
    assert isinstance(brdf, (Lambert, CookTorrance))  # _split refused every other model
    if ct is None:
        return ExportedMaterial("mitsuba", brdf.to_spec(), kd, None, 0.0,
                                {"type": "diffuse", "reflectance": _triple(kd)}, exact=True)
    f0, ks = np.asarray(ct.f0, float) * np.ones(3), np.asarray(ct.ks, float) * np.ones(3)
    has_diffuse = bool(np.any(kd > 0))
    weight = _mix_weight(kd, ks) if has_diffuse else 1.0
    exact = bool(np.all(f0 == 1.0))
    note = ""
    if exact:
        eta = k = None
    else:
        eta, k, _ = fit_conductor_fresnel(
            lambda c: schlick(f0, c), lobe_fresnel_weight(Conductor(ct.distribution, float(ct.alpha), None, None)))
        note = "Mitsuba 3 has no Schlick Fresnel: exported with the conductor Fresnel (eta, k) closest to it"
    # Mitsuba 3 refuses RGB reflectances above 1 (SRGBReflectanceSpectrum): clip, and say so
    scale, diffuse = ks / weight, (kd / (1.0 - weight) if has_diffuse else None)
    if np.any(scale > 1.0) or (diffuse is not None and np.any(diffuse > 1.0)):
        scale, diffuse = np.minimum(scale, 1.0), None if diffuse is None else np.minimum(diffuse, 1.0)
        exact = False
        note = "; ".join(filter(None, [note, "Mitsuba 3 takes RGB reflectances up to 1: kd/(1 - w) and ks/w "
                                       "clipped to 1 (max kd + max ks > 1)"]))
    lobe = Conductor(ct.distribution, float(ct.alpha), eta, k, scale=scale, shadowing="separable")
    conductor = {"type": "roughconductor", "distribution": ct.distribution, "alpha": float(f"{ct.alpha:.9g}"),
                 "specular_reflectance": _triple(lobe.scale)}
    conductor |= {"material": "none"} if eta is None or k is None else {"eta": _triple(eta), "k": _triple(k)}
    native = conductor if diffuse is None else {
        "type": "blendbsdf", "weight": float(f"{weight:.9g}"),
        "diffuse": {"type": "diffuse", "reflectance": _triple(diffuse)}, "specular": conductor}
    return ExportedMaterial("mitsuba", brdf.to_spec(), diffuse, lobe, weight, native, exact=exact, note=note)


def _pbrt(brdf: BRDF) -> ExportedMaterial:
    kd, ct = _split(brdf, "pbrt")
    assert isinstance(brdf, (Lambert, CookTorrance))  # _split refused every other model
    if ct is None:
        return ExportedMaterial("pbrt", brdf.to_spec(), kd, None, 0.0,
                                {"type": "diffuse", "reflectance": _triple(kd)}, exact=True)
    f0, ks = np.asarray(ct.f0, float) * np.ones(3), np.asarray(ct.ks, float) * np.ones(3)
    has_diffuse = bool(np.any(kd > 0))
    mix = _pbrt_mix(brdf.to_spec(), kd, ct, ks, f0)
    if has_diffuse and float(np.max(ks * f0)) <= _DIELECTRIC_F0_MAX:
        coated = _pbrt_coated(brdf.to_spec(), kd, ct, ks, f0)
        if _grid_rel_rms(brdf, coated) < _grid_rel_rms(brdf, mix):
            return coated
    return mix


def _grid_rel_rms(brdf: BRDF, material: ExportedMaterial) -> float:
    """Relative RMS of ρ cos θ_i of ``material`` against ``brdf`` over direction pairs with θ_i,
    θ_o ≤ 80°: a fixed product grid (16 Gauss–Legendre nodes in each cos θ, 24 midpoints in
    φ_o − φ_i; dω_i dω_o = d cos θ_i d cos θ_o dφ dφ'), used only to choose between two pbrt-v4
    materials (the stated error is measured by ``analysis/material_export.py``)."""
    x, w = np.polynomial.legendre.leggauss(16)
    c, w = _FRESNEL_COS_MIN + (x + 1.0) * (1.0 - _FRESNEL_COS_MIN) / 2.0, w
    phi = (np.arange(24) + 0.5) * 2.0 * np.pi / 24
    ci, co, ph = np.meshgrid(c, c, phi, indexing="ij")
    si, so = np.sqrt(1.0 - ci * ci), np.sqrt(1.0 - co * co)
    L = np.stack([si, np.zeros_like(si), ci], axis=-1)
    V = np.stack([so * np.cos(ph), so * np.sin(ph), co], axis=-1)
    weight = (w[:, None, None] * w[None, :, None] * ci * ci)[..., None]
    y, m = brdf.eval(L, V), material.eval(L, V)
    return float(np.sqrt(np.sum(weight * (m - y) ** 2) / np.sum(weight * y * y)))


def _pbrt_mix(source: str, kd: np.ndarray, ct: CookTorrance, ks: np.ndarray, f0: np.ndarray) -> ExportedMaterial:
    """A Cook–Torrance model as pbrt-v4's conductor, mixed with a diffuse when kd > 0."""
    has_diffuse = bool(np.any(kd > 0))
    # mix amount a = the conductor's share; pbrt clamps the diffuse reflectance kd/(1 - a) to [0, 1]
    weight = _mix_weight(kd, ks) if has_diffuse else 1.0
    diffuse = np.clip(kd / (1.0 - weight), 0.0, 1.0) if has_diffuse else None
    eta, k, _ = fit_conductor_fresnel(
        lambda c: schlick(f0, c) * ks / weight,
        lobe_fresnel_weight(Conductor("ggx", float(ct.alpha), None, None, shadowing="height-correlated")))
    lobe = Conductor("ggx", float(ct.alpha), eta, k, shadowing="height-correlated")
    notes = ["pbrt-v4's conductor has a height-correlated Smith G, a conductor Fresnel and no scale: "
             "ks x Schlick exported as the closest conductor Fresnel"]
    if ct.distribution != "ggx":
        notes.append("pbrt-v4 has no Beckmann distribution: Trowbridge-Reitz (GGX) of the same alpha")
    conductor = {"type": "conductor", "roughness": float(f"{ct.alpha:.9g}"), "remaproughness": False,
                 "eta": _triple(eta), "k": _triple(k)}
    native = conductor if diffuse is None else {
        "type": "mix", "amount": float(f"{weight:.9g}"),
        "materials": [{"type": "diffuse", "reflectance": _triple(diffuse)}, conductor]}
    return ExportedMaterial("pbrt", source, diffuse, lobe, weight,
                            native, exact=False, note="; ".join(notes))


#: A Cook–Torrance model with a diffuse term whose normal-incidence specular reflectance ks·f0 is at
#: most this in every channel (a dielectric of index ≤ 3) goes to pbrt-v4 as ``coateddiffuse``.
_DIELECTRIC_F0_MAX = 0.25


def _pbrt_coated(source: str, kd: np.ndarray, ct: CookTorrance, ks: np.ndarray, f0: np.ndarray) -> ExportedMaterial:
    """A diffuse base under a dielectric-like specular lobe as pbrt-v4's ``coateddiffuse``
    (``data_specs/export.md``): roughness = α (``remaproughness`` false), η the dielectric whose
    Fresnel is closest to the channel mean of ks·Schlick(f0) (weighted by the lobe's own squared
    ρ cos θ_i, :func:`lobe_fresnel_weight`), the base reflectance whose albedo through the coat is
    kd (:func:`~shrmkit.brdf_io.pbrt_coated.coated_diffuse_from_cook_torrance`)."""
    alpha = float(ct.alpha)
    x, w = np.polynomial.legendre.leggauss(_FRESNEL_NODES)
    c, w = _FRESNEL_COS_MIN + (x + 1.0) * (1.0 - _FRESNEL_COS_MIN) / 2.0, w / 2.0
    lobe = Conductor("ggx", alpha, None, None, shadowing="height-correlated")
    eta = fit_dielectric_eta(lambda cos: np.mean(schlick(f0, cos) * ks, axis=-1), lobe_fresnel_weight(lobe), c, w)
    coat, clipped = coated_diffuse_from_cook_torrance(kd, alpha, eta)
    notes = ["pbrt-v4's coateddiffuse: a GGX dielectric coat (height-correlated Smith G, the dielectric Fresnel "
             "of eta closest to ks x Schlick(f0)) over a Lambertian base whose albedo through the coat is kd"]
    spec0 = ks * f0
    if float(np.max(spec0) - np.min(spec0)) > 1e-6:
        notes.append("the coat is colourless: its Fresnel matches the channel mean of ks x Schlick(f0)")
    if clipped:
        notes.append("kd is above what the coat lets through: the base reflectance clipped to 1")
    if ct.distribution != "ggx":
        notes.append("pbrt-v4 has no Beckmann distribution: Trowbridge-Reitz (GGX) of the same alpha")
    native = {"type": "coateddiffuse", "reflectance": _triple(coat.reflectance),
              "roughness": float(f"{alpha:.9g}"), "eta": float(f"{eta:.9g}"), "thickness": COAT_THICKNESS,
              "maxdepth": coat.maxdepth(), "remaproughness": False}
    return ExportedMaterial("pbrt", source, None, None, 0.0, native, exact=False, note="; ".join(notes),
                            coat=coat)


#: standard_surface inputs written with their defaults turned off (Autodesk Standard Surface 1.0.1)
_STANDARD_SURFACE_OFF = {"coat": 0.0, "sheen": 0.0, "subsurface": 0.0, "transmission": 0.0,
                         "thin_film_thickness": 0.0, "emission": 0.0, "specular_anisotropy": 0.0}


def _materialx(brdf: BRDF) -> ExportedMaterial:
    kd, ct = _split(brdf, "materialx")
    assert isinstance(brdf, (Lambert, CookTorrance))  # _split refused every other model
    if ct is None:
        native = {"base": 1.0, "base_color": _triple(kd), "diffuse_roughness": 0.0, "metalness": 0.0,
                  "specular": 0.0, **_STANDARD_SURFACE_OFF}
        return ExportedMaterial("materialx", brdf.to_spec(), kd, None, 0.0, native, exact=True)
    f0, ks = np.asarray(ct.f0, float) * np.ones(3), np.asarray(ct.ks, float) * np.ones(3)
    notes = ["standard_surface's metal has a height-correlated Smith G and Gulbrandsen's artistic Fresnel"]
    if ct.distribution != "ggx":
        notes.append("no Beckmann distribution: GGX of the same alpha")
    if np.any(kd > 0):
        # diffuse and metal share base_color: (1 - m) r ~ kd and m r ~ ks f0, so r ~ kd + ks f0
        spec0 = ks * f0
        metalness = float(np.mean(spec0) / (np.mean(spec0) + np.mean(kd)))
        base_color = np.clip(kd + spec0, 0.0, 1.0)
        specular, edge = 0.0, np.zeros(3)  # specular 0: no dielectric coat over the diffuse
        notes.append("its diffuse and metal share base_color: mixed by metalness")
    else:
        metalness, specular = 1.0, 1.0
        base_color, edge = np.clip(ks * f0, 0.0, 1.0), np.clip(ks, 0.0, 1.0)
    eta, k = artistic_ior(base_color, edge * specular)
    lobe = Conductor("ggx", float(ct.alpha), eta, k, shadowing="height-correlated")
    native = {"base": 1.0, "base_color": _triple(base_color), "diffuse_roughness": 0.0, "metalness": metalness,
              "specular": specular, "specular_color": _triple(edge if specular else np.ones(3)),
              "specular_roughness": float(f"{math.sqrt(ct.alpha):.9g}"), **_STANDARD_SURFACE_OFF}
    return ExportedMaterial("materialx", brdf.to_spec(), base_color if metalness < 1 else None, lobe, metalness,
                            native, exact=False, note="; ".join(notes))


# ----------------------------------------------------------------------------------------
# snippet text
# ----------------------------------------------------------------------------------------
def _rgb(values: list[float]) -> str:
    return ", ".join(f"{v:.9g}" for v in values)


def _mitsuba_xml(node: dict[str, Any], indent: str, name: str | None = None) -> list[str]:
    head = f'{indent}<bsdf type="{node["type"]}"' + (f" id={quoteattr(name)}" if name else "") + ">"
    lines = [head]
    inner = indent + "    "
    for key, value in node.items():
        if key == "type":
            continue
        if isinstance(value, dict):
            lines += _mitsuba_xml(value, inner)
        elif isinstance(value, list):
            lines.append(f'{inner}<rgb name="{key}" value="{_rgb(value)}"/>')
        elif isinstance(value, str):
            lines.append(f'{inner}<string name="{key}" value={quoteattr(value)}/>')
        else:
            lines.append(f'{inner}<float name="{key}" value="{value:.9g}"/>')
    return lines + [f"{indent}</bsdf>"]


def mitsuba_dict(material: ExportedMaterial) -> dict[str, Any]:
    """The material as a Mitsuba 3 Python dict for ``mitsuba.load_dict`` (RGB values as
    ``{"type": "rgb", "value": [r, g, b]}``)."""
    def convert(node: dict[str, Any]) -> dict[str, Any]:
        return {key: convert(v) if isinstance(v, dict) else {"type": "rgb", "value": v} if isinstance(v, list) else v
                for key, v in node.items()}
    return convert(material.native)


def _header(material: ExportedMaterial, comment: str, error: str | None, model_note: str | None) -> list[str]:
    """The snippet's comment lines: what the JSON of ``shrm export`` states (``exact`` only when the
    renderer's BSDF is the source BRDF: no closest model, no approximate mapping)."""
    lines = [f"exported by shrmkit from {material.source}"]
    if model_note:
        lines.append(f"not exact: {model_note}")
    if not material.exact:
        lines.append(f"not exact: {material.note}")
    elif not model_note:
        lines.append("exact: the renderer's BSDF equals the model")
    if error:
        lines.append(error)
    return [f"{comment} {line}" for line in lines]


def _text_mitsuba(material: ExportedMaterial, name: str, error: str | None,
                 model_note: str | None = None) -> str:
    comments = "\n".join(f"    <!-- {c[2:].replace('--', '-')} -->" for c in _header(material, "# ", error, model_note))
    return "\n".join(['<?xml version="1.0" encoding="utf-8"?>', '<scene version="3.0.0">', comments,
                      *_mitsuba_xml(material.native, "    ", name), "</scene>", ""])


def _text_mitsuba_dict(material: ExportedMaterial, name: str, error: str | None,
                      model_note: str | None = None) -> str:
    doc = {"format": "shrmkit-mitsuba-dict", "name": name, "source": material.source,
           "exact": material.exact and not model_note, "model_note": model_note or None,
           "note": material.note, "error": error, "bsdf": mitsuba_dict(material)}
    return json.dumps(doc, indent=2) + "\n"


def _pbrt_params(node: dict[str, Any]) -> str:
    parts = []
    for key, value in node.items():
        if key in ("type", "materials"):
            continue
        if isinstance(value, bool):
            parts.append(f'"bool {key}" {str(value).lower()}')
        elif isinstance(value, int):
            parts.append(f'"integer {key}" {value}')
        elif isinstance(value, list):
            parts.append(f'"rgb {key}" [ {" ".join(f"{v:.9g}" for v in value)} ]')
        else:
            parts.append(f'"float {key}" {value:.9g}')
    return " ".join(parts)


def _text_pbrt(material: ExportedMaterial, name: str, error: str | None,
              model_note: str | None = None) -> str:
    lines = _header(material, "#", error, model_note)
    node = material.native
    if node["type"] == "mix":
        names = [f"{name}-diffuse", f"{name}-conductor"]
        for part, part_name in zip(node["materials"], names, strict=True):
            lines.append(f'MakeNamedMaterial "{part_name}" "string type" "{part["type"]}" {_pbrt_params(part)}')
        lines.append(f'MakeNamedMaterial "{name}" "string type" "mix" "string materials" [ "{names[0]}" '
                     f'"{names[1]}" ] {_pbrt_params(node)}')
    else:
        lines.append(f'MakeNamedMaterial "{name}" "string type" "{node["type"]}" {_pbrt_params(node)}')
    lines.append(f'# use it with: NamedMaterial "{name}"')
    return "\n".join(lines) + "\n"


def _text_materialx(material: ExportedMaterial, name: str, error: str | None,
                   model_note: str | None = None) -> str:
    lines = ['<?xml version="1.0"?>', '<materialx version="1.38">']
    lines += [f"  <!-- {c[2:].replace('--', '-')} -->" for c in _header(material, "# ", error, model_note)]
    shader = f"SR_{name}"
    lines.append(f'  <standard_surface name={quoteattr(shader)} type="surfaceshader">')
    for key, value in material.native.items():
        if isinstance(value, list):
            lines.append(f'    <input name="{key}" type="color3" value="{_rgb(value)}" />')
        else:
            lines.append(f'    <input name="{key}" type="float" value="{value:.9g}" />')
    lines += ["  </standard_surface>",
              f'  <surfacematerial name={quoteattr(name)} type="material">',
              f'    <input name="surfaceshader" type="surfaceshader" nodename={quoteattr(shader)} />',
              "  </surfacematerial>", "</materialx>", ""]
    return "\n".join(lines)


@dataclass(frozen=True)
class MaterialTarget:
    """One renderer's material format: how to convert a model and how to write the snippet."""

    name: str
    suffix: str
    convert: Callable[[BRDF], ExportedMaterial]
    text: Callable[[ExportedMaterial, str, str | None, str | None], str]
    description: str


#: Material targets, by ``shrm export --to`` name.
MATERIAL_TARGETS: dict[str, MaterialTarget] = {
    t.name: t for t in (
        MaterialTarget("mitsuba", ".xml", _mitsuba, _text_mitsuba, "Mitsuba 3 scene XML (a <bsdf> with an id)"),
        MaterialTarget("mitsuba-dict", ".json", _mitsuba, _text_mitsuba_dict,
                       "Mitsuba 3 Python dict as JSON (mitsuba.load_dict(doc['bsdf']))"),
        MaterialTarget("pbrt", ".pbrt", _pbrt, _text_pbrt, "pbrt-v4 scene text (MakeNamedMaterial)"),
        MaterialTarget("materialx", ".mtlx", _materialx, _text_materialx,
                       "MaterialX document with a standard_surface and its surfacematerial"),
    )
}


def _target(target: str) -> MaterialTarget:
    if target not in MATERIAL_TARGETS:
        raise BadInputError(None, f"unknown material target {target!r}; choose from {', '.join(MATERIAL_TARGETS)}")
    return MATERIAL_TARGETS[target]


def to_target(brdf: BRDF, target: str) -> ExportedMaterial:
    """Convert a Lambert or Cook–Torrance model to ``target``'s closest material.

    What each target offers (single scattering; the renderers' BSDF definitions):

    * **Mitsuba 3** — ``diffuse`` (ρ = R/π), ``roughconductor`` (Beckmann or GGX D, separable
      Smith G with the same exact GGX / Walter-rational Beckmann G1 as ours, conductor Fresnel of a
      complex index η + ik, or F = 1 for ``material="none"``, times ``specular_reflectance``) and
      ``blendbsdf`` ((1 − w)·first + w·second). Exact for Lambert and for Cook–Torrance with
      f0 = 1; otherwise Schlick's Fresnel becomes the conductor Fresnel closest to it.
    * **pbrt-v4** — ``diffuse`` (reflectance clamped to [0, 1]), ``conductor`` (Trowbridge–Reitz =
      GGX D, height-correlated Smith G = 1/(1 + Λ(ω_i) + Λ(ω_o)), conductor Fresnel, no scale),
      ``mix`` (a stochastic choice: (1 − amount)·first + amount·second on average) and
      ``coateddiffuse`` (a rough dielectric coat over a Lambertian base, ``brdf_io/pbrt_coated.py``),
      written instead of the mix for a diffuse base under a dielectric-like lobe (ks·f0 ≤ 0.25)
      when it is the closer of the two. Exact for Lambert only.
    * **MaterialX** ``standard_surface`` — Lambert (``diffuse_roughness`` 0, ``specular`` 0) and a
      GGX conductor (height-correlated G, Fresnel from Gulbrandsen's artistic IOR of ``base_color``
      and the edge colour ``specular_color``·``specular``) mixed by ``metalness``; the diffuse and
      the metal share ``base_color``. Exact for Lambert only.

    Raises
    ------
    BadInputError
        An unknown target, or another model (``analysis.material_export.export_material`` first
        finds the closest Cook–Torrance model of any BRDF).
    """
    return replace(_target(target).convert(brdf), target=target)


def material_text(material: ExportedMaterial, name: str, error: str | None = None, *,
                  model_note: str | None = None) -> str:
    """The snippet of ``material`` in its target's syntax, the material called ``name``;
    ``error`` (one line, the measured error) is written as a comment, and ``model_note`` (why the
    material is a closest model of the source BRDF, ``ExportResult.model_note``) as a "not exact"
    comment: the comments state what the JSON of ``shrm export`` states (``exact`` false then)."""
    if not name or any(ch in name for ch in "\"'<>&\n\r\t"):
        raise BadInputError(None, f"material name {name!r}: use letters, digits, '-', '_' or '.'")
    return _target(material.target).text(material, name, error, model_note)


def write_material(path: str | os.PathLike[str], text: str) -> Path:
    """Write a snippet atomically (temporary file + ``os.replace``), UTF-8."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)
