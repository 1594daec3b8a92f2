"""Material snippets for other renderers: Mitsuba 3 (XML, Python dict), pbrt-v4, MaterialX.

A Lambert or Cook–Torrance BRDF (``brdf_io/models.py``) is converted to the closest material
each renderer offers (:func:`to_target`; what each target offers is stated there), as an
:class:`ExportedMaterial` that holds the renderer's own parameters (``native``, what the snippet
writes) and evaluates the BSDF *as that renderer defines it* (:meth:`ExportedMaterial.eval`), so
that the error of an export can be measured (``analysis/material_export.py``) instead of assumed.
The snippets are text: :func:`material_text` (one function per target in :data:`MATERIAL_TARGETS`),
written atomically by :func:`write_material`. Layout and mapping: ``data_specs/export.md``. The
material type, its conductor lobe and the Fresnel fit are in ``_exported_material.py``, the snippet
writers in ``_material_text.py``.

References: [Mitsuba3] (plugins ``diffuse``, ``roughconductor``, ``blendbsdf``); [PBRT4] §9.5
(``FrComplex``), §9.6 (Trowbridge–Reitz, height-correlated masking-shadowing), §14.3
(``CoatedDiffuseBxDF``) and the pbrt-v4 scene file format (``Material "conductor"``, ``"mix"``,
``"coateddiffuse"``, ``MakeNamedMaterial``); [StdSurface] and [MaterialX] (``standard_surface.mtlx``,
``mx_artistic_ior``, ``mx_fresnel_conductor``); [Gulbrandsen14]; [Walter07] (GGX, Smith G1).
Citation keys: ``data_specs/bibliography.md``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ._exported_material import (  # noqa: F401  (re-exported: the names stay importable from here)
    _FRESNEL_COS_MIN,
    _FRESNEL_NODES,
    Conductor,
    ExportedMaterial,
    artistic_ior,
    fit_conductor_fresnel,
    fresnel_conductor,
    lobe_fresnel_weight,
    schlick,
)
from ._material_text import _text_materialx, _text_mitsuba, _text_mitsuba_dict, _text_pbrt, mitsuba_dict
from .atomic import atomic_path
from .brdf import BRDF
from .errors import BadInputError
from .models import CookTorrance, Lambert
from .pbrt_coated import COAT_THICKNESS, coated_diffuse_from_cook_torrance, fit_dielectric_eta

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
