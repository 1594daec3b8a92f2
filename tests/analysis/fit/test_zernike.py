"""Koenderink's Zernike-basis BRDF expansion and fit (analysis/fit/zernike.py)."""

from __future__ import annotations

from math import factorial

import numpy as np
import pytest
from scipy.special import roots_legendre

import shrmkit.brdf_io.zernike as zmod
from shrmkit.analysis.fit.sampling import FitSamples
from shrmkit.analysis.fit.zernike import (
    TERMS_PER_ORDER,
    ZernikeBRDF,
    basis_count,
    basis_terms,
    disc_radius,
    fit_zernike,
    order_for_count,
    zernike,
    zernike_basis,
    zernike_radial,
)
from shrmkit.analysis.orders import orders_on_grid_for
from shrmkit.brdf_io.cornell import ScatteredBRDF
from shrmkit.brdf_io.curet import read_curet
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.gonio import read_gonio_csv
from shrmkit.brdf_io.models import Lambert


def _hemisphere(n: int, rng: np.random.Generator) -> np.ndarray:
    """n directions uniform on the upper hemisphere, (n, 3)."""
    z = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def _rotate_z(d: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * d[..., 0] - s * d[..., 1], s * d[..., 0] + c * d[..., 1], d[..., 2]], axis=-1)


def _random_model(n_max: int, seed: int) -> ZernikeBRDF:
    rng = np.random.default_rng(seed)
    return ZernikeBRDF(rng.normal(size=(basis_count(n_max), 3)), n_max, name="random")


# ------------------------------------------------------------------------------ the basis


def test_terms_per_order_table() -> None:
    """The documented count table (module docstring), CURET's 5 and 55, and the term lists."""
    assert [TERMS_PER_ORDER[n] for n in range(11)] == [1, 2, 5, 8, 14, 20, 30, 40, 55, 70, 91]
    assert order_for_count(5) == 2 and order_for_count(55) == 8
    for n_max in range(13):
        terms = basis_terms(n_max)
        assert len(terms) == basis_count(n_max) == len(set(terms))
        assert all(0 <= m <= n <= n2 <= n_max and (n - m) % 2 == 0 and (n2 - m) % 2 == 0 for m, n, n2 in terms)
        # every valid (m, n, n') is present, and lower orders are a prefix
        valid = {(m, n, n2) for n2 in range(n_max + 1) for m in range(n2 % 2, n2 + 1, 2) for n in range(m, n2 + 1, 2)}
        assert set(terms) == valid
        assert terms[: basis_count(max(n_max - 1, 0))] == basis_terms(max(n_max - 1, 0))


@pytest.mark.parametrize("bad", [-1, 21, 2.0, True, "8"])
def test_bad_order(bad: object) -> None:
    with pytest.raises(BadInputError, match="n_max"):
        basis_count(bad)  # type: ignore[arg-type]


def test_order_for_count_lists_the_counts() -> None:
    with pytest.raises(BadInputError, match="1, 2, 5, 8, 14"):
        order_for_count(6)


def test_radial_matches_the_factorial_sum() -> None:
    """Jacobi form vs Born & Wolf's explicit sum, n <= 12."""
    rho = np.linspace(0.0, 1.0, 41)
    for n in range(13):
        for m in range(n % 2, n + 1, 2):
            a, b = (n + m) // 2, (n - m) // 2
            explicit = sum(
                (-1) ** k * factorial(n - k) / (factorial(k) * factorial(a - k) * factorial(b - k)) * rho ** (n - 2 * k)
                for k in range(b + 1)
            )
            np.testing.assert_allclose(zernike_radial(n, m, rho), explicit, atol=1e-11)
            assert zernike_radial(n, m, np.array(1.0)) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="n - \\|m\\| even"):
        zernike_radial(3, 2, rho)


def test_radial_recurrence_and_eval_against_the_jacobi_form() -> None:
    """The recurrence table behind ``eval`` and ``zernike_basis`` against scipy's Jacobi form
    (``zernike_radial``) on [0, 1], n <= MAX_ORDER; ``eval`` (per-m pair matrices) against the
    module docstring's basis sum Σ_a c_a c N N [R_n(ρ_i) R_n'(ρ_o) + R_n'(ρ_i) R_n(ρ_o)]/(1 + δ)
    cos mΔφ built from the Jacobi form, order 12."""
    rho = np.linspace(0.0, 1.0, 57)
    table = zmod._radial_table(zmod.MAX_ORDER, rho)
    for (n, m), values in table.items():
        np.testing.assert_allclose(values, zernike_radial(n, m, rho), atol=1e-12, err_msg=f"R_{n}^{m}")
    rng = np.random.default_rng(3)
    L, V = _hemisphere(400, rng), _hemisphere(400, rng)
    model = _random_model(12, 4)
    ri, ro = disc_radius(L[:, 2]), disc_radius(V[:, 2])
    dphi = np.arctan2(L[:, 1], L[:, 0]) - np.arctan2(V[:, 1], V[:, 0])
    expected = np.zeros((400, 3))
    for c, (m, n, n2) in zip(model.coefficients, basis_terms(12), strict=True):
        norm = np.sqrt((2.0 if m else 1.0) * (n + 1) / np.pi) * np.sqrt((2.0 if m else 1.0) * (n2 + 1) / np.pi)
        scale = norm / np.sqrt(4.0 * (2.0 if m else 1.0) * (2.0 if n != n2 else 1.0)) / (2.0 if n == n2 else 1.0)
        pair = (zernike_radial(n, m, ri) * zernike_radial(n2, m, ro)
                + zernike_radial(n2, m, ri) * zernike_radial(n, m, ro))
        expected += (scale * pair * np.cos(m * dphi))[:, None] * c
    np.testing.assert_allclose(model.eval(L, V), expected, rtol=1e-11, atol=1e-11 * np.abs(expected).max())


def test_zernike_orthonormal_on_the_disc() -> None:
    """∫∫ Z_n^m Z_n'^m' ρ dρ dφ = δ by exact quadrature (Gauss–Legendre in ρ², uniform in φ), n <= 10."""
    x, w = roots_legendre(12)  # exact for polynomials of degree <= 23 in u = ρ²
    u = 0.5 * (x + 1.0)
    rho, w_rho = np.sqrt(u), 0.25 * w  # ρ dρ = du / 2, du = dx / 2
    phi = 2.0 * np.pi * np.arange(24) / 24
    R, PHI = np.meshgrid(rho, phi, indexing="ij")
    W = (w_rho[:, None] * np.full(24, 2.0 * np.pi / 24)[None, :]).ravel()
    index = [(n, m) for n in range(11) for m in range(-n, n + 1, 2)]
    Z = np.array([zernike(n, m, R, PHI).ravel() for n, m in index])
    gram = (Z * W) @ Z.T
    np.testing.assert_allclose(gram, np.eye(len(index)), atol=1e-12)


def test_basis_orthonormal_on_the_hemispheres() -> None:
    """∫∫ B_a B_b dω_i dω_o = δ_ab for order 8 (dω = 2 ρ dρ dφ under ρ = √2 sin(θ/2))."""
    n_max = 8
    x, w = roots_legendre(10)
    u = 0.5 * (x + 1.0)
    rho, w_rho = np.sqrt(u), 0.25 * w
    cos_t = 1.0 - rho**2  # ρ² = 1 − cos θ
    sin_t = np.sqrt(1.0 - cos_t**2)
    n_phi = 20
    phi = 2.0 * np.pi * np.arange(n_phi) / n_phi
    # ρ depends on φ_i − φ_o only: fix φ_o = 0 and multiply by 2π
    Li = np.stack([sin_t[:, None] * np.cos(phi), sin_t[:, None] * np.sin(phi), np.repeat(cos_t[:, None], n_phi, 1)], -1)
    Vo = np.stack([sin_t, np.zeros_like(sin_t), cos_t], -1)
    B = zernike_basis(Li[:, None, :, :], Vo[None, :, None, :], n_max)  # (i, o, phi, K)
    weight = (2.0 * w_rho)[:, None, None] * (2.0 * w_rho)[None, :, None] * np.full(n_phi, 2.0 * np.pi / n_phi)
    weight = weight * 2.0 * np.pi
    B = B.reshape(-1, B.shape[-1])
    gram = (B * weight.ravel()[:, None]).T @ B
    np.testing.assert_allclose(gram, np.eye(basis_count(n_max)), atol=1e-12)


def test_disc_radius_is_area_preserving() -> None:
    """ρ = √2 sin(θ/2), rim at the horizon, and the disc area π for the hemisphere's 2π."""
    theta = np.linspace(0.0, np.pi / 2, 7)
    np.testing.assert_allclose(disc_radius(np.cos(theta)), np.sqrt(2.0) * np.sin(theta / 2.0), atol=1e-15)
    assert disc_radius(np.array(0.0)) == pytest.approx(1.0)
    # d(ρ²)/d(cos θ) = −1: the area π ρ² is proportional to the solid angle 2π (1 − cos θ)
    assert np.pi * disc_radius(np.array(0.3)) ** 2 == pytest.approx(2.0 * np.pi * (1.0 - 0.3) / 2.0)


# ------------------------------------------------------------------------------ the model


def test_reciprocity() -> None:
    rng = np.random.default_rng(1)
    L, V = _hemisphere(500, rng), _hemisphere(500, rng)
    model = _random_model(8, 2)
    a, b = model.eval(L, V), model.eval(V, L)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(a).max())


def test_isotropy() -> None:
    """A common rotation about the normal leaves ρ unchanged."""
    rng = np.random.default_rng(3)
    L, V = _hemisphere(500, rng), _hemisphere(500, rng)
    model = _random_model(8, 4)
    a = model.eval(L, V)
    for angle in (0.3, 1.7, -2.9):
        np.testing.assert_allclose(model.eval(_rotate_z(L, angle), _rotate_z(V, angle)), a, rtol=0,
                                   atol=1e-12 * np.abs(a).max())
    # and bilateral symmetry: mirroring both in the xz plane
    mirror = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(model.eval(L * mirror, V * mirror), a, rtol=0, atol=1e-12 * np.abs(a).max())


def test_zero_below_the_surface_and_shapes() -> None:
    model = _random_model(4, 5)
    N = np.array([0.0, 0.0, 1.0])
    below = np.array([0.6, 0.0, -0.8])
    np.testing.assert_array_equal(model.eval(N, below), 0.0)
    np.testing.assert_array_equal(model.eval(below, N), 0.0)
    rng = np.random.default_rng(0)
    L = _hemisphere(12, rng).reshape(3, 4, 3)
    assert model.eval(L, N).shape == (3, 4, 3)
    assert zernike_basis(L, N, 4).shape == (3, 4, basis_count(4))
    np.testing.assert_allclose(model.eval(L, N), zernike_basis(L, N, 4) @ model.coefficients, atol=1e-13)


def test_eval_in_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Block-wise evaluation (bounded memory) gives the same values as one block."""
    rng = np.random.default_rng(8)
    L, V = _hemisphere(50, rng), _hemisphere(50, rng)
    model = _random_model(6, 9)
    whole = model.eval(L, V)
    monkeypatch.setattr(zmod, "EVAL_BLOCK", 7)
    np.testing.assert_array_equal(model.eval(L, V), whole)


def test_constructor_checks() -> None:
    assert ZernikeBRDF(np.ones(55)).n_max == 8
    assert ZernikeBRDF(np.ones((5, 1))).coefficients.shape == (5, 3)
    with pytest.raises(BadInputError, match="order 8 has 55"):
        ZernikeBRDF(np.ones((5, 3)), 8)
    with pytest.raises(BadInputError, match="available counts"):
        ZernikeBRDF(np.ones((6, 3)))
    with pytest.raises(BadInputError, match="finite"):
        ZernikeBRDF(np.full((5, 3), np.nan))
    assert ZernikeBRDF(np.ones(5)).as_dict()["terms"][0] == [0, 0, 0]


# ------------------------------------------------------------------------------ the fit


def test_exact_recovery_of_a_brdf_in_the_span() -> None:
    """Random order-8 coefficients → samples → fit recovers them (and through a ScatteredBRDF)."""
    rng = np.random.default_rng(7)
    coeffs = rng.normal(scale=0.01, size=(55, 3))
    coeffs[0] += 3.0  # a large constant term keeps ρ positive (measurements must not be negative)
    truth = ZernikeBRDF(coeffs, 8)
    L, V = _hemisphere(600, rng), _hemisphere(600, rng)
    rho = truth.eval(L, V)
    assert rho.min() > 0
    scattered = ScatteredBRDF(L, V, rho, name="synthetic")
    fit = fit_zernike(scattered, n_coeffs=55)
    assert fit.n_max == 8 and fit.n_coeffs == 55 and fit.rank == 55
    np.testing.assert_allclose(fit.coefficients, coeffs, rtol=0, atol=1e-10)
    assert fit.rel_rms_rho < 1e-12 and fit.errors["rel_rms"] < 1e-12
    assert fit.bands and all(b.rel_rms < 1e-10 for b in fit.bands)
    # samples given directly, and "rel" weighting too
    coeffs2 = rng.normal(scale=0.01, size=(14, 3))
    coeffs2[0] += 2.0
    samples = FitSamples(L=L, V=V, rho=ZernikeBRDF(coeffs2, 4).eval(L, V), weight=np.ones(600), n_dropped=0,
                         source="synthetic")
    for metric in ("rho", "rel"):
        fit2 = fit_zernike(scattered, 4, samples=samples, metric=metric)
        np.testing.assert_allclose(fit2.coefficients, coeffs2, rtol=0, atol=1e-10)
    negative = FitSamples(L=L, V=V, rho=rho - 10.0, weight=np.ones(600), n_dropped=0, source="synthetic")
    with pytest.raises(BadInputError, match="non-negative"):
        fit_zernike(scattered, samples=negative)


def test_lower_order_fit_is_a_projection() -> None:
    """Orthonormal basis + (nearly) exact quadrature: fitting order 2 to an order-4 function on a
    dense uniform sample set gives approximately its first 5 coefficients."""
    rng = np.random.default_rng(11)
    coeffs = rng.normal(size=(14, 1))
    coeffs[0] += 20.0
    truth = ZernikeBRDF(coeffs, 4)
    L, V = _hemisphere(40000, rng), _hemisphere(40000, rng)
    fit = fit_zernike(ScatteredBRDF(L, V, truth.eval(L, V)), n_coeffs=5)
    np.testing.assert_allclose(fit.coefficients[:, 0], coeffs[:5, 0], atol=0.15)


def test_fit_of_a_lambertian_model_and_its_analysis() -> None:
    """Lambert lies in the span (the constant term): recovered exactly; the fitted model then
    has the same ε table as the Lambert model itself."""
    lam = Lambert(albedo=np.array([0.2, 0.5, 0.8]))
    fit = fit_zernike(lam, n_max=2, n_samples=2048)
    assert fit.rel_rms_rho < 1e-12
    np.testing.assert_allclose(fit.coefficients[0], 2.0 * np.array([0.2, 0.5, 0.8]), rtol=1e-12)  # 2π · a/π
    np.testing.assert_allclose(fit.coefficients[1:], 0.0, atol=1e-12)
    a = orders_on_grid_for(fit.brdf, 6, 2, criterion="rh02")
    b = orders_on_grid_for(lam, 6, 2, criterion="rh02")
    np.testing.assert_allclose(a.table, b.table, atol=1e-10)


def test_fit_option_errors() -> None:
    lam = Lambert(albedo=np.array([0.5, 0.5, 0.5]))
    with pytest.raises(BadInputError, match="not both"):
        fit_zernike(lam, 2, n_coeffs=5)
    with pytest.raises(BadInputError, match="metric"):
        fit_zernike(lam, metric="log")
    with pytest.raises(BadInputError, match="ridge"):
        fit_zernike(lam, ridge=-1.0)
    with pytest.raises(BadInputError, match="available counts"):
        fit_zernike(lam, n_coeffs=7)


def test_underdetermined_fit_says_so() -> None:
    rng = np.random.default_rng(5)
    L, V = _hemisphere(70, rng), _hemisphere(70, rng)
    fit = fit_zernike(ScatteredBRDF(L, V, np.ones((70, 3))), n_coeffs=91)
    assert fit.rank < 91 and "minimum-norm" in fit.message


# ------------------------------------------------------------------------------ real data


def test_curet_fits(shared_data) -> None:
    """CURET felt (sample 1): a well-posed 55-term fit with a small residual; the 5-term fit is
    coarser; ridge damping barely changes the residual and shrinks the extrapolation."""
    felt = read_curet(shared_data / "brdf" / "curet", 1)
    fit55 = fit_zernike(felt)
    fit5 = fit_zernike(felt, n_coeffs=5)
    assert fit55.rank == 55 and fit55.n_samples == 205
    assert fit55.rel_rms_rho < 0.08 < fit5.rel_rms_rho
    damped = fit_zernike(felt, ridge=1e-4)
    assert damped.rel_rms_rho < 1.1 * fit55.rel_rms_rho
    assert np.sum(damped.coefficients**2) < np.sum(fit55.coefficients**2)
    assert {b.lo_deg for b in fit55.bands} >= {0.0, 60.0}


def test_ptfe_random_fit_predicts_the_regular_set(shared_data) -> None:
    """NIST PTFE at 532 nm: a fit to the random set (positive θ_i, any φ_i) predicts the regular
    set (θ_i written negative) within 1 % RMS where both are measured (θ <= 70°) — which checks
    the readers' sign convention: reading the regular set's θ_i as |θ_i| at φ_i = 0 misses by
    6 % RMS and 38 % at worst (the forward-scattering peak lands on the wrong side)."""
    folder = shared_data / "brdf" / "nist_ptfe"
    random_set = read_gonio_csv(folder / "PTFE.data.random.csv")
    regular = read_gonio_csv(folder / "PTFE.data.csv", 532)
    fit = fit_zernike(random_set)
    assert fit.rel_rms_rho < 0.02  # near-Lambertian: smooth
    cos70 = np.cos(np.radians(70.0))
    inside = (regular.L[:, 2] > cos70) & (regular.V[:, 2] > cos70)
    y = regular.rgb[inside, 0]

    def rel_rms(L: np.ndarray) -> float:
        p = fit.brdf.eval(L[inside], regular.V[inside])[:, 0]
        return float(np.sqrt(np.mean((p - y) ** 2) / np.mean(y**2)))

    assert rel_rms(regular.L) < 0.012
    assert rel_rms(regular.L * np.array([-1.0, -1.0, 1.0])) > 0.05  # θ_i read as |θ_i|
