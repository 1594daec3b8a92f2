"""Analytic models against closed forms; spec-string parsing and its errors."""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.models import CookTorrance, rgb


def _hemisphere(n_theta: int = 400, n_phi: int = 256) -> tuple[np.ndarray, np.ndarray]:
    """Directions and weights of a Gauss–Legendre product rule on the upper hemisphere."""
    x, w = np.polynomial.legendre.leggauss(n_theta)
    cos_t = 0.5 * (x + 1.0)
    w = 0.5 * w
    phi = 2 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    s = np.sqrt(1 - cos_t**2)
    dirs = np.stack(
        [s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), np.repeat(cos_t[:, None], n_phi, 1)], -1
    ).reshape(-1, 3)
    return dirs, np.repeat(w, n_phi) * (2 * np.pi / n_phi)


def test_phong_lobe_integrates_to_one_about_mirror():
    """Closed form: ∫ (s+1)/(2π) cos^s θ dω over the lobe's hemisphere = 1 (RH02 §6.3)."""
    brdf = shrmkit.load_brdf("phong:s=40")
    V = np.array([0.0, 0.0, 1.0])  # R = +z: the lobe hemisphere is the upper hemisphere
    dirs, w = _hemisphere()
    total = np.sum(brdf.rho_hat(dirs, V)[:, 0] * w)
    assert total == pytest.approx(1.0, rel=1e-6)


def test_microfacet_value_closed_form():
    """RH02 eq. 11 at a hand-computed configuration: θ_h = 0.1 exactly."""
    brdf = shrmkit.load_brdf("microfacet:sigma=0.25")
    H = np.array([np.sin(0.1), 0.0, np.cos(0.1)])
    V = np.array([0.0, np.sin(0.3), np.cos(0.3)])
    V = V / np.linalg.norm(V)
    L = 2 * np.dot(V, H) * H - V
    expected = np.exp(-((0.1 / 0.25) ** 2)) / (4 * np.pi * 0.25**2)
    assert brdf.rho_hat(L, V)[0] == pytest.approx(expected, rel=1e-12)
    assert brdf.eval(L, V)[0] == pytest.approx(expected / L[2], rel=1e-12)
    assert brdf.rho_hat(np.array([0.0, 0.6, -0.8]), V)[0] == 0.0  # below the horizon


def test_lambert_albedo():
    """∫ (albedo/π) cos θ dω = albedo."""
    brdf = shrmkit.load_brdf("lambert:albedo=0.2/0.5/0.7")
    dirs, w = _hemisphere(64, 64)
    total = np.einsum("nc,n->c", brdf.rho_hat(dirs, np.array([0.3, 0.0, 0.954])), w)
    np.testing.assert_allclose(total, [0.2, 0.5, 0.7], rtol=1e-10)


@pytest.mark.parametrize("dist", ["beckmann", "ggx"])
def test_cook_torrance_distribution_normalized(dist):
    """∫ D(θ_h) cos θ_h dω_h = 1 for both distributions (closed-form normalization)."""
    model = CookTorrance(kd=rgb(0), ks=rgb(1), alpha=0.3, f0=rgb(1), distribution=dist)
    from scipy.integrate import quad

    def integrand(theta: float) -> float:
        return float(model.distribution_value(np.array(np.cos(theta))) * np.cos(theta) * np.sin(theta))

    total = 2 * np.pi * quad(integrand, 0, np.pi / 2, epsabs=1e-12, epsrel=1e-10, limit=200)[0]
    assert total == pytest.approx(1.0, rel=1e-6)


def test_lafortune_formula_and_spec_round_trip():
    """Value against the hand-written formula; to_spec() parses back to the same model."""
    spec = "lafortune:kd=0.1/0.2/0.3,cxy=-1,cz=0.9,n=12,ks=2,cxy2=-0.5,cz2=0.5,n2=3,ks2=0.1"
    brdf = shrmkit.load_brdf(spec)
    L = np.array([0.3, 0.2, np.sqrt(1 - 0.13)])
    V = np.array([-0.25, -0.1, np.sqrt(1 - 0.0725)])
    dot_xy = L[0] * V[0] + L[1] * V[1]
    dot_z = L[2] * V[2]
    expected = np.array([0.1, 0.2, 0.3]) / np.pi + 2 * (-dot_xy + 0.9 * dot_z) ** 12 + 0.1 * (
        -0.5 * dot_xy + 0.5 * dot_z
    ) ** 3
    np.testing.assert_allclose(brdf.eval(L, V), expected, rtol=1e-12)
    again = shrmkit.load_brdf(brdf.to_spec())
    np.testing.assert_allclose(again.eval(L, V), expected, rtol=1e-8)


@pytest.mark.parametrize(
    "spec, fragment",
    [
        ("nosuch:x=1", "unknown BRDF model"),
        ("phong", "missing parameter 's'"),
        ("phong:s=abc", "not a number"),
        ("phong:s=nan", "not finite"),
        ("phong:s=8,q=2", "unknown parameter"),
        ("microfacet:sigma=0", "outside"),
        ("lambert:albedo=1.5", "outside"),
        ("cook-torrance:alpha=0.2,dist=phong", "choose one of"),
        ("phong:s=1,s=2", "given twice"),
        ("lafortune:n2=3", "numbered"),
        ("phong:s", "key=value"),
    ],
)
def test_bad_specs_name_the_problem(spec, fragment):
    with pytest.raises(BadInputError) as info:
        shrmkit.load_brdf(spec)
    assert fragment in str(info.value)
    assert spec in str(info.value)


def test_missing_file_and_unknown_extension(tmp_path):
    with pytest.raises(BadInputError, match="no such file"):
        shrmkit.load_brdf(tmp_path / "absent.binary")
    odd = tmp_path / "data.xyz"
    odd.write_text("1 2 3")
    with pytest.raises(BadInputError, match="unknown BRDF file type"):
        shrmkit.load_brdf(odd)


def test_model_json_file(tmp_path):
    path = tmp_path / "fit.json"
    path.write_text('{"model_spec": "phong:s=16"}')
    assert shrmkit.load_brdf(path).to_spec() == "phong:s=16"
    path.write_text('{"other": 1}')
    with pytest.raises(BadInputError, match="model_spec"):
        shrmkit.load_brdf(path)


@pytest.mark.parametrize("dist, limit", [("ggx", 2 / 0.3), ("beckmann", 3.535 / 0.3)])
def test_cook_torrance_finite_at_grazing(dist, limit):
    """G1/cos θ → 2/α (GGX) and 3.535/α (Walter's Beckmann) as θ → 90°: a light direction
    on the horizon up to round-off must not blow ρ up (regression: 1.8e3 at cos θ_i = 1e-16)."""
    from shrmkit.brdf_io.models import smith_g1_over_cos

    assert smith_g1_over_cos(np.array(1e-16), 0.3, dist) == pytest.approx(limit, rel=1e-9)
    model = CookTorrance(kd=rgb(0), ks=rgb(1), alpha=0.3, f0=rgb(1), distribution=dist)
    V = np.array([0.0, np.sin(0.2), np.cos(0.2)])
    for cos_i in (1e-16, 1e-8, 1e-4):
        L = np.array([-np.sqrt(1 - cos_i**2), 0.0, cos_i])
        value = model.eval(L, V)[0]
        assert np.isfinite(value) and value < 10.0
