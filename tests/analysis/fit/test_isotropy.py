"""Anisotropy of scattered measurements (analysis/fit/isotropy.py), at CURET's 205 geometries.

Independent references: synthetic materials with a known answer sampled at the real CURET
geometries — isotropic lobes (Cook–Torrance, a Lambertian surface) must give a small residual
share, a Lambertian surface with a grain ρ = kd/π (1 + ½ sin²θ_h cos 2φ_h) (φ_h the half vector's
absolute azimuth: it changes when light and view turn together) a large one.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit import load_brdf
from shrmkit.analysis.fit.isotropy import ANISOTROPIC_ABOVE, anisotropic_basis, measure_isotropy
from shrmkit.analysis.fit.representation import incident_azimuths_vary
from shrmkit.analysis.fit.sampling import FitSamples, collect_samples
from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.curet import read_curet


def _turn(d: np.ndarray, a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=-1)


def _grain(L: np.ndarray, V: np.ndarray, amplitude: float) -> np.ndarray:
    H = L + V
    H /= np.linalg.norm(H, axis=-1, keepdims=True)
    phi_h = np.arctan2(H[:, 1], H[:, 0])
    return 0.3 / np.pi * (1.0 + amplitude * (H[:, 0] ** 2 + H[:, 1] ** 2) * np.cos(2.0 * phi_h))


def _at_curet(shared_data, rho: np.ndarray | None = None, spec: str | None = None) -> FitSamples:
    geo = read_curet(shared_data / "brdf" / "curet", 1)
    if spec is not None:
        rho = load_brdf(spec).eval(geo.L, geo.V)[:, 0]
    return collect_samples(ScatteredBRDF(geo.L, geo.V, np.repeat(rho[:, None], 3, axis=1), name="synthetic"))


def test_anisotropic_terms_are_reciprocal_and_not_rotation_invariant() -> None:
    rng = np.random.default_rng(0)
    z = rng.uniform(0.1, 1.0, (2, 40))
    p = rng.uniform(0, 2 * np.pi, (2, 40))
    L, V = (np.stack([np.sqrt(1 - z[k] ** 2) * np.cos(p[k]), np.sqrt(1 - z[k] ** 2) * np.sin(p[k]), z[k]], -1)
            for k in range(2))
    B = anisotropic_basis(L, V)
    assert B.shape == (40, 16)
    np.testing.assert_allclose(anisotropic_basis(V, L), B, atol=1e-12)
    turned = anisotropic_basis(_turn(L, 0.7), _turn(V, 0.7))
    assert np.all(np.max(np.abs(turned - B), axis=0) > 1e-3)  # every term changes under a common turn


@pytest.mark.parametrize("spec", ["cook-torrance:kd=0.3,ks=0.5,alpha=0.3", "lambert:albedo=0.5"])
def test_isotropic_materials_give_a_small_share(shared_data, spec: str) -> None:
    iso = measure_isotropy(_at_curet(shared_data, spec=spec), 8)
    assert not iso.anisotropic and iso.judged
    assert iso.residual_share < 0.25


def test_a_grain_gives_a_large_share(shared_data) -> None:
    geo = read_curet(shared_data / "brdf" / "curet", 1)
    samples = _at_curet(shared_data, rho=_grain(geo.L, geo.V, 0.5))
    iso = measure_isotropy(samples, 8)
    assert iso.anisotropic and iso.residual_share > 0.9 > ANISOTROPIC_ABOVE
    assert iso.held_out_anisotropic < 0.2 * iso.held_out_isotropic
    iso_ct = measure_isotropy(_at_curet(shared_data, spec="cook-torrance:kd=0.3,ks=0.5,alpha=0.3"), 8)
    assert iso.residual_share > 3.0 * iso_ct.residual_share


def test_one_axis_of_incidence_is_not_measurable(shared_data) -> None:
    """Cornell's geometries hold φ_i = 0 only: isotropy cannot be tested there; CURET's can."""
    cornell = load_brdf(shared_data / "brdf" / "cornell" / "acryl_blue.brdf")
    assert not incident_azimuths_vary(collect_samples(cornell))
    assert incident_azimuths_vary(_at_curet(shared_data, spec="lambert:albedo=0.5"))


@pytest.mark.slow
def test_real_curet_corduroy_and_felt(shared_data) -> None:
    """Corduroy (42) has a grain: most of its isotropic misfit is φ-dependent; felt (1) does not."""
    folder = shared_data / "brdf" / "curet"
    corduroy = measure_isotropy(collect_samples(read_curet(folder, 42)), 6)
    felt = measure_isotropy(collect_samples(read_curet(folder, 1)), 5)
    assert corduroy.anisotropic and corduroy.residual_share > 0.6
    assert not felt.anisotropic and felt.residual_share < 0.3
