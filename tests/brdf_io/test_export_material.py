"""Material snippets for Mitsuba 3, pbrt-v4 and MaterialX (brdf_io/export_material.py) and the
measured error of an export (analysis/material_export.py).

References: closed forms of the Fresnel equations (normal and grazing incidence) and pbrt-v4's
complex-arithmetic ``FrComplex`` transcribed independently; Smith's height-correlated G from Λ;
the source model evaluated directly; Mitsuba 3's own BSDF evaluation (``mitsuba`` 3.9.1, variant
``scalar_rgb``, where installed); MaterialX's own document validation (``MaterialX`` 1.39.5, where
installed); an independent Monte Carlo estimate of the error; pbrt-v4's rough ``DielectricBxDF::f``
and ``FrDielectric`` transcribed independently and integrated over the hemisphere (the coat's
transmittance and internal reflectance); a small reader of pbrt-v4's scene syntax.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from shrmkit.analysis.material_export import export_material
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.export_formats import EXPORT_FORMATS, export_format
from shrmkit.brdf_io.export_material import (
    Conductor,
    artistic_ior,
    fit_conductor_fresnel,
    fresnel_conductor,
    lobe_fresnel_weight,
    material_text,
    mitsuba_dict,
    schlick,
    to_target,
    write_material,
)
from shrmkit.brdf_io.pbrt_coated import coat_internal_reflectance, coat_transmittance
from shrmkit.brdf_io.specs import brdf_from_spec

LAMBERT = "lambert:albedo=0.2/0.4/0.8"
CT_F1 = "cook-torrance:kd=0.1/0.2/0.05,ks=0.6,alpha=0.2,f0=1,dist=ggx"  # exact in Mitsuba 3
CT_BECKMANN = "cook-torrance:kd=0,ks=0.7,alpha=0.3,f0=1,dist=beckmann"
CT_SCHLICK = "cook-torrance:kd=0.1/0.2/0.3,ks=0.5,alpha=0.25,f0=0.9/0.6/0.3,dist=ggx"


def _directions(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.05
    return v / np.linalg.norm(v, axis=1, keepdims=True)


L, V = _directions(40, 1), _directions(40, 2)


def _fr_complex(cos_i: np.ndarray, eta: complex) -> np.ndarray:
    """pbrt-v4 FrComplex (complex arithmetic, Snell's law), an independent transcription."""
    sin2_i = 1 - cos_i**2
    sin2_t = sin2_i / eta**2
    cos_t = np.sqrt(1 - sin2_t)
    r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return (np.abs(r_parl) ** 2 + np.abs(r_perp) ** 2) / 2


def test_fresnel_conductor_closed_forms_and_pbrt_v4():
    """Normal incidence ((η−1)² + k²)/((η+1)² + k²), grazing 1, and pbrt-v4's FrComplex."""
    eta, k = np.array([0.2, 1.5, 3.0]), np.array([3.0, 0.0, 0.5])
    c = np.linspace(0.0, 1.0, 21)
    F = fresnel_conductor(c, eta, k)
    assert np.allclose(F[-1], ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2), rtol=1e-12)
    assert np.allclose(F[0], 1.0)
    for ch in range(3):
        assert np.allclose(F[1:, ch], _fr_complex(c[1:], complex(eta[ch], k[ch])), rtol=1e-10, atol=1e-12)


def test_conductor_fit_and_artistic_ior():
    """A conductor's own Fresnel is recovered by the fit; Gulbrandsen's η, k reflect r at normal
    incidence (their defining property)."""
    eta, k = np.array([0.3, 1.2, 2.5]), np.array([2.0, 1.0, 0.0])
    fit_eta, fit_k, rms = fit_conductor_fresnel(lambda c: fresnel_conductor(c, eta, k))
    assert rms < 2e-3
    c = np.linspace(0, 1, 50)
    assert np.max(np.abs(fresnel_conductor(c, fit_eta, fit_k) - fresnel_conductor(c, eta, k))) < 5e-3
    _, _, rms_schlick = fit_conductor_fresnel(lambda c: schlick(np.array([0.95, 0.6, 0.3]), c))
    assert rms_schlick < 0.02  # a metal's Schlick curve is close to some conductor's
    r = np.array([0.9, 0.5, 0.04])
    for g in (np.zeros(3), np.full(3, 0.5), np.ones(3)):
        n, kk = artistic_ior(r, g)
        assert np.allclose(fresnel_conductor(np.array([1.0]), n, kk)[0], r, rtol=1e-9)


def test_height_correlated_g_against_lambda():
    """pbrt-v4 / MaterialX G2 = 1/(1 + Λ(ω_i) + Λ(ω_o)), Λ = (√(1 + α² tan²θ) − 1)/2."""
    alpha = 0.35
    lobe = Conductor("ggx", alpha, None, None, shadowing="height-correlated")
    H = L + V
    H /= np.linalg.norm(H, axis=1, keepdims=True)
    c2 = H[:, 2] ** 2
    D = alpha**2 / (np.pi * (c2 * (alpha**2 - 1) + 1) ** 2)

    def lam(cos):
        return (np.sqrt(1 + alpha**2 * (1 - cos**2) / cos**2) - 1) / 2

    G2 = 1 / (1 + lam(L[:, 2]) + lam(V[:, 2]))
    expected = D * G2 / (4 * L[:, 2] * V[:, 2])
    assert np.allclose(lobe.eval(L, V)[:, 0], expected, rtol=1e-10)


def test_fresnel_weight_integrates_the_lobe_energy():
    """∫ W(c) dc over cos θ_d ∈ [cos 80°, 1] is ∫∫ (f cos θ_i)² dω_i dω_o over θ_i, θ_o ≤ 80°
    (Rusinkiewicz's measure), checked by Monte Carlo over uniform directions."""
    lobe = Conductor("ggx", 0.3, None, None)
    x, w = np.polynomial.legendre.leggauss(48)
    lo = np.cos(np.radians(80))
    c = lo + (x + 1) * (1 - lo) / 2
    integral = np.sum(w * (1 - lo) / 2 * lobe_fresnel_weight(lobe)(c))
    rng = np.random.default_rng(3)
    n = 200_000
    z = rng.uniform(lo, 1, (2, n))
    phi = rng.uniform(0, 2 * np.pi, (2, n))
    d = np.stack([np.sqrt(1 - z**2) * np.cos(phi), np.sqrt(1 - z**2) * np.sin(phi), z], axis=-1)
    H = d[0] + d[1]
    inside_d = H @ np.array([0, 0, 1.0]) > 0
    value = lobe.eval(d[0], d[1])[:, 0] * d[0][:, 2]
    mc = np.mean(np.where(inside_d, value**2, 0)) * (2 * np.pi * (1 - lo)) ** 2
    assert integral == pytest.approx(mc, rel=0.05)


@pytest.mark.parametrize("spec", [LAMBERT, CT_F1, CT_BECKMANN])
def test_exact_exports_equal_the_model(spec):
    """Lambert (every target) and Cook–Torrance with f0 = 1 (Mitsuba) are exact: the renderer's
    BSDF is the model."""
    brdf = brdf_from_spec(spec)
    targets = ["mitsuba", "pbrt", "materialx"] if spec == LAMBERT else ["mitsuba"]
    for target in targets:
        material = to_target(brdf, target)
        assert material.exact
        assert np.allclose(material.eval(L, V), brdf.eval(L, V), rtol=1e-8)


def test_mitsuba_xml_structure_and_values():
    """The XML: a <scene version="3.0.0"> holding a blendbsdf (weight w) of a diffuse with
    reflectance kd/(1 − w) and a roughconductor with alpha, F = 1 and specular_reflectance ks/w."""
    material = to_target(brdf_from_spec(CT_F1), "mitsuba")
    root = ET.fromstring(material_text(material, "steel", "error line"))
    assert root.tag == "scene" and root.get("version") == "3.0.0"
    blend = root.find("bsdf")
    assert blend.get("type") == "blendbsdf" and blend.get("id") == "steel"
    w = float(blend.find("float[@name='weight']").get("value"))
    kd, ks = np.array([0.1, 0.2, 0.05]), 0.6
    assert ks <= w <= 1 - kd.max()
    diffuse, conductor = blend.findall("bsdf")
    assert diffuse.get("type") == "diffuse"
    refl = [float(x) for x in diffuse.find("rgb[@name='reflectance']").get("value").split(",")]
    assert np.allclose(refl, kd / (1 - w), rtol=1e-8)
    assert conductor.get("type") == "roughconductor"
    assert conductor.find("string[@name='distribution']").get("value") == "ggx"
    assert conductor.find("string[@name='material']").get("value") == "none"
    assert float(conductor.find("float[@name='alpha']").get("value")) == pytest.approx(0.2)
    spec_refl = [float(x) for x in conductor.find("rgb[@name='specular_reflectance']").get("value").split(",")]
    assert np.allclose(spec_refl, ks / w, rtol=1e-8)
    assert "error line" in material_text(material, "steel", "error line")
    doc = mitsuba_dict(material)
    assert doc["type"] == "blendbsdf" and doc["specular"]["alpha"] == pytest.approx(0.2)
    assert doc["diffuse"]["reflectance"] == {"type": "rgb", "value": refl}


def test_pbrt_and_materialx_text():
    """pbrt-v4: named diffuse + conductor under a mix of amount w; MaterialX: a standard_surface
    with metalness, specular_roughness = √α, connected to a surfacematerial."""
    brdf = brdf_from_spec(CT_SCHLICK)
    pbrt = to_target(brdf, "pbrt")
    text = material_text(pbrt, "paint")
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    assert [re.match(r'MakeNamedMaterial "([^"]+)" "string type" "(\w+)"', line).groups() for line in lines] == [
        ("paint-diffuse", "diffuse"), ("paint-conductor", "conductor"), ("paint", "mix")]
    assert '"bool remaproughness" false' in lines[1] and '"float roughness" 0.25' in lines[1]
    amount = float(re.search(r'"float amount" ([0-9.e-]+)', lines[2]).group(1))
    assert amount == pytest.approx(pbrt.weight) and not pbrt.exact and "not exact" in text
    refl = [float(x) for x in re.search(r'"rgb reflectance" \[ ([^\]]+) \]', lines[0]).group(1).split()]
    assert np.allclose(refl, np.clip(np.array([0.1, 0.2, 0.3]) / (1 - amount), 0, 1), rtol=1e-8)

    mtlx = to_target(brdf, "materialx")
    root = ET.fromstring(material_text(mtlx, "paint"))
    shader = root.find("standard_surface")
    inputs = {i.get("name"): i.get("value") for i in shader.findall("input")}
    assert float(inputs["specular_roughness"]) == pytest.approx(0.5)
    assert 0 < float(inputs["metalness"]) < 1 and float(inputs["coat"]) == 0
    assert root.find("surfacematerial/input").get("nodename") == shader.get("name")


# ---------------------------------------------------------------------------------------------
# pbrt-v4 coateddiffuse
# ---------------------------------------------------------------------------------------------
CT_PLASTIC = "cook-torrance:kd=0.3/0.2/0.1,ks=1,alpha=0.2,f0=0.04,dist=ggx"


def _fr_dielectric(cos_i: np.ndarray, eta: float) -> np.ndarray:
    """pbrt-v4 FrDielectric (cos θ_i < 0: from inside; total internal reflection 1), transcribed."""
    c = np.clip(cos_i, -1, 1)
    e = np.where(c < 0, 1 / eta, eta)
    c = np.abs(c)
    sin2_t = (1 - c * c) / e**2
    cos_t = np.sqrt(np.maximum(0, 1 - sin2_t))
    r_parl = (e * c - cos_t) / (e * c + cos_t)
    r_perp = (c - e * cos_t) / (c + e * cos_t)
    return np.where(sin2_t >= 1, 1.0, (r_parl**2 + r_perp**2) / 2)


def _pbrt_dielectric_f(wo: np.ndarray, wi: np.ndarray, eta: float, alpha: float) -> np.ndarray:
    """pbrt-v4 ``DielectricBxDF::f`` (rough, radiance mode), transcribed: generalized half vector,
    back-facing microfacets discarded, Trowbridge–Reitz D, G = 1/(1 + Λ(ω_o) + Λ(ω_i)),
    transmission divided by etap²."""
    co, ci = wo[..., 2], wi[..., 2]
    reflect = ci * co > 0
    etap = np.where(reflect, 1.0, np.where(co > 0, eta, 1 / eta))
    wm = wi * etap[..., None] + wo
    n = np.linalg.norm(wm, axis=-1, keepdims=True)
    wm = wm / np.where(n > 0, n, 1)
    wm = wm * np.where(wm[..., 2:] < 0, -1, 1)
    di, do = np.sum(wm * wi, -1), np.sum(wm * wo, -1)
    ok = (ci != 0) & (co != 0) & (n[..., 0] > 0) & (di * ci >= 0) & (do * co >= 0)
    F = _fr_dielectric(do, eta)
    cm2 = wm[..., 2] ** 2
    D = 1 / (np.pi * alpha**2 * cm2**2 * (1 + (1 - cm2) / cm2 / alpha**2) ** 2)

    def lam(w):
        return (np.sqrt(1 + alpha**2 * (1 - w[..., 2] ** 2) / w[..., 2] ** 2) - 1) / 2

    G = 1 / (1 + lam(wo) + lam(wi))
    fr = D * G * F / np.abs(4 * ci * co)
    ft = D * (1 - F) * G * np.abs(di * do / ((di + do / etap) ** 2 * ci * co)) / etap**2
    return np.where(ok, np.where(reflect, fr, ft), 0.0)


def _lower_hemisphere(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions below the surface (Gauss–Legendre in cos θ, midpoints in φ) and their dω."""
    x, w = np.polynomial.legendre.leggauss(n)
    c, wc = (x + 1) / 2, w / 2
    phi = (np.arange(2 * n) + 0.5) * np.pi / n
    s = np.sqrt(1 - c * c)
    d = np.stack([s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), -np.broadcast_to(c[:, None], (n, 2 * n))], -1)
    return d, wc[:, None] * np.full(2 * n, np.pi / n)


def test_coat_transmittance_and_internal_reflectance_against_pbrt_btdf():
    """T(θ) equals ∫ f(ω_in ← ω_θ) |cos| dω of pbrt-v4's rough dielectric BTDF (transcribed),
    integrated over the lower hemisphere, and the exit ∫ f(ω_θ ← ω_in) |cos| dω is T(θ)/η²
    (reciprocity: the 1/η² of the closed form); ρ equals the cosine-weighted internal reflection
    integrated the same way; α → 0 gives the smooth coat's 1 − F(θ) and 1 − (1 − r_e)/η²."""
    alpha, eta = 0.3, 1.5
    d, dw = _lower_hemisphere(160)
    for theta in (0.0, 60.0, 80.0):
        t = np.radians(theta)
        w = np.broadcast_to([np.sin(t), 0.0, np.cos(t)], d.shape)
        into = np.sum(_pbrt_dielectric_f(d, w, eta, alpha) * np.abs(d[..., 2]) * dw)
        out = np.sum(_pbrt_dielectric_f(w, d, eta, alpha) * np.abs(d[..., 2]) * dw)
        assert coat_transmittance(np.cos(t), alpha, eta) == pytest.approx(into, rel=4e-3)
        assert out * eta**2 == pytest.approx(into, rel=1e-9)
    x, wx = np.polynomial.legendre.leggauss(8)
    c, wc = (x + 1) / 2, wx / 2
    rho = 0.0
    for ci, wi in zip(c, wc, strict=True):  # a cosine-weighted source below the coat, reflected back down
        src = np.broadcast_to([np.sqrt(1 - ci * ci), 0.0, -ci], d.shape)
        rho += 2 * ci * wi * np.sum(_pbrt_dielectric_f(d, src, eta, alpha) * np.abs(d[..., 2]) * dw)
    assert coat_internal_reflectance(alpha, eta, n_cos=8) == pytest.approx(rho, rel=4e-3)
    c = np.cos(np.radians([0.0, 30.0, 60.0]))
    assert np.allclose(coat_transmittance(c, 0.005, eta), 1 - _fr_dielectric(c, eta), rtol=2e-3)
    r_e = np.sum(_fr_dielectric(c_ := (np.polynomial.legendre.leggauss(64)[0] + 1) / 2, eta) * 2 * c_
                 * np.polynomial.legendre.leggauss(64)[1] / 2)
    assert coat_internal_reflectance(0.005, eta) == pytest.approx(1 - (1 - r_e) / eta**2, rel=3e-3)


def _parse_pbrt(text: str) -> list[tuple[str, str, dict[tuple[str, str], list]]]:
    """A small reader of pbrt-v4's scene syntax (pbrt-v4 ``parser.cpp``): ``#`` comments, a
    directive, its quoted name, then ``"type name" value`` or ``"type name" [ values ]`` pairs."""
    tokens = re.findall(r'"[^"]*"|\[|\]|[^\s\[\]"]+', re.sub(r"#[^\n]*", "", text))
    out, i = [], 0
    while i < len(tokens):
        directive, name = tokens[i], tokens[i + 1].strip('"')
        i += 2
        params: dict[tuple[str, str], list] = {}
        while i < len(tokens) and tokens[i].startswith('"'):
            kind, key = tokens[i].strip('"').split()
            i += 1
            if tokens[i] == "[":
                j = tokens.index("]", i)
                raw, i = tokens[i + 1 : j], j + 1
            else:
                raw, i = [tokens[i]], i + 1
            convert = {"float": float, "integer": int, "bool": lambda v: {"true": True, "false": False}[v],
                       "rgb": float, "string": lambda v: v.strip('"')}[kind]
            params[(kind, key)] = [convert(v) for v in raw]
        out.append((directive, name, params))
    return out


def test_pbrt_coateddiffuse_snippet_and_mapping():
    """A diffuse base under a dielectric-like lobe (ks f0 = 0.04, ks = 1) is written as one
    ``coateddiffuse``: the snippet parses; roughness = α with remaproughness false (pbrt's
    default true would read α = √roughness); η the dielectric closest to Schlick(0.04), near
    (1 + √0.04)/(1 − √0.04) = 1.5; the base's albedo seen through the coat (cosine-weighted in and
    out, integrated here over the exported BSDF less the coat's own reflection) is kd; maxdepth
    leaves the walk (R ρ)^(maxdepth/2) ≤ 10⁻³; a scaled-down lobe (ks = 0.5) stays a mix."""
    brdf = brdf_from_spec(CT_PLASTIC)
    material = to_target(brdf, "pbrt")
    [(directive, name, params)] = _parse_pbrt(material_text(material, "plastic"))
    assert (directive, name, params[("string", "type")]) == ("MakeNamedMaterial", "plastic", ["coateddiffuse"])
    assert params[("float", "roughness")] == [0.2] and params[("bool", "remaproughness")] == [False]
    eta = params[("float", "eta")][0]
    assert 1.35 < eta < 1.55 and params[("float", "thickness")] == [1e-4]
    R = np.array(params[("rgb", "reflectance")])
    coat = material.coat
    assert coat is not None and np.allclose(coat.reflectance, R, rtol=1e-8) and coat.eta == pytest.approx(eta)
    maxdepth = params[("integer", "maxdepth")][0]
    assert maxdepth >= 10 and (R.max() * coat.rho) ** (maxdepth / 2) <= 1e-3
    # the base's albedo through the coat: ∫∫ (f − f_top) cos θ_i cos θ_o dω_i dω_o / π = kd
    x, w = np.polynomial.legendre.leggauss(24)
    c, wc = (x + 1) / 2, w / 2
    phi = (np.arange(16) + 0.5) * 2 * np.pi / 16
    ci, co, ph = np.meshgrid(c, c, phi, indexing="ij")
    Li = np.stack([np.sqrt(1 - ci**2), 0 * ci, ci], -1)
    Vo = np.stack([np.sqrt(1 - co**2) * np.cos(ph), np.sqrt(1 - co**2) * np.sin(ph), co], -1)
    top = _pbrt_dielectric_f(Vo, Li, eta, 0.2)[..., None]
    weight = (wc[:, None, None] * wc[None, :, None] * ci * co * 2 * np.pi / 16 * 2 * np.pi)[..., None]
    albedo = np.sum((material.eval(Li, Vo) - top) * weight, axis=(0, 1, 2)) / np.pi
    assert np.allclose(albedo, [0.3, 0.2, 0.1], rtol=5e-3)
    assert to_target(brdf_from_spec(CT_PLASTIC.replace("ks=1", "ks=0.5")), "pbrt").native["type"] == "mix"


def test_measured_error_matches_an_independent_monte_carlo():
    """The stated relative RMS of ρ cos θ_i (Sobol, view bands) agrees with a plain Monte Carlo
    estimate over uniform directions (θ_i, θ_o ≤ 80°) of the same integral ratio."""
    brdf = brdf_from_spec(CT_SCHLICK)
    result = export_material(brdf, "pbrt", n_samples=4096)
    assert not result.exact and result.worst is not None and result.worst.rel_rms >= result.rel_rms * 0.9
    rng = np.random.default_rng(5)
    n = 40_000
    cos_max = np.cos(np.radians(80))

    def uniform(n):
        z = rng.uniform(cos_max, 1, n)
        phi = rng.uniform(0, 2 * np.pi, n)
        s = np.sqrt(1 - z * z)
        return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)

    Li, Vo = uniform(n), uniform(n)
    y, m = brdf.eval(Li, Vo) * Li[:, 2:], result.material.eval(Li, Vo) * Li[:, 2:]
    mc = np.sqrt(np.sum((m - y) ** 2) / np.sum(y**2))
    assert result.rel_rms == pytest.approx(mc, rel=0.05)


def test_model_without_counterpart_says_so():
    """A Lafortune lobe has no counterpart: its closest Cook–Torrance GGX fit is exported, the note
    says so, and the error is measured against the Lafortune model itself."""
    result = export_material(brdf_from_spec("lafortune:kd=0.1,cxy=-1,cz=1,n=8,ks=0.5"), "mitsuba",
                             n_samples=4096, fit_samples=4096, fit_starts=1)
    assert "no exact counterpart for Lafortune" in result.model_note and not result.exact
    assert result.model.to_spec().startswith("cook-torrance:") and 0 < result.rel_rms < 1
    assert "measured error against lafortune:" in result.error_line()
    lobeless = export_material(brdf_from_spec("lafortune:kd=0.4,n=1,ks=0"), "pbrt", n_samples=2048)
    assert lobeless.model.to_spec().startswith("lambert:") and lobeless.rel_rms < 1e-12


def test_registry_and_refusals(tmp_path):
    assert export_format(None, "a.mtlx").name == "materialx" and export_format("merl", "x.binary").kind == "brdf-table"
    assert {f.suffix for f in EXPORT_FORMATS.values()} >= {".xml", ".pbrt", ".mtlx", ".binary", ".dds"}
    with pytest.raises(BadInputError, match="suffix '.png'"):
        export_format(None, "a.png")
    with pytest.raises(BadInputError, match="end in .pbrt"):
        export_format("pbrt", "a.xml")
    with pytest.raises(BadInputError, match="Lambert or Cook-Torrance"):
        to_target(brdf_from_spec("phong:s=8"), "mitsuba")
    with pytest.raises(BadInputError, match="material name"):
        material_text(to_target(brdf_from_spec(LAMBERT), "pbrt"), 'a"b')
    out = write_material(tmp_path / "m.json", material_text(to_target(brdf_from_spec(LAMBERT), "mitsuba-dict"), "m"))
    assert json.loads(out.read_text())["bsdf"] == {"type": "diffuse",
                                                   "reflectance": {"type": "rgb", "value": [0.2, 0.4, 0.8]}}


def _mitsuba_eval(mi, bsdf, L: np.ndarray, V: np.ndarray) -> np.ndarray:
    ctx = mi.BSDFContext()
    out = []
    for light, view in zip(L, V, strict=True):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*view)
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        out.append(np.array(bsdf.eval(ctx, si, mi.Vector3f(*light))) / light[2])  # eval includes cos θ_light
    return np.array(out)


@pytest.mark.parametrize("spec", [LAMBERT, CT_F1, CT_BECKMANN, CT_SCHLICK])
def test_mitsuba_loads_and_evaluates_the_export(spec):
    """Mitsuba 3 (3.9.1, scalar_rgb) loads the XML and the dict; its BSDF values equal the exported
    material's (float32 rounding), and the source model's where the export is exact."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    brdf = brdf_from_spec(spec)
    material = to_target(brdf, "mitsuba")
    element = ET.fromstring(material_text(material, "m")).find("bsdf")
    element.set("version", "3.0.0")
    from_xml = _mitsuba_eval(mi, mi.load_string(ET.tostring(element, encoding="unicode")), L, V)
    from_dict = _mitsuba_eval(mi, mi.load_dict(mitsuba_dict(material)), L, V)
    ours = material.eval(L, V)
    assert np.allclose(from_xml, ours, rtol=2e-5, atol=1e-7)
    assert np.allclose(from_dict, from_xml, rtol=1e-6, atol=1e-9)
    if material.exact:
        assert np.allclose(from_xml, brdf.eval(L, V), rtol=2e-5, atol=1e-7)


def test_materialx_document_validates():
    """MaterialX 1.39's own parser and validator accept the document against its standard library."""
    mx = pytest.importorskip("MaterialX")
    for spec in (LAMBERT, CT_SCHLICK):
        doc = mx.createDocument()
        mx.readFromXmlString(doc, material_text(to_target(brdf_from_spec(spec), "materialx"), "m"))
        lib = mx.createDocument()
        mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
        doc.setDataLibrary(lib)
        valid, message = doc.validate()
        assert valid, message
        node = doc.getNode("SR_m")
        assert node.getCategory() == "standard_surface" and doc.getNode("m").getType() == "material"
