"""Property tests (DESIGN §8): φ'-evenness, Parseval, rotation equivariance of the SHRM."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import shrmkit
from shrmkit.analysis.brdf_coeffs import rho_lpq
from shrmkit.analysis.lighting import lighting_coefficients
from shrmkit.analysis.shrm import global_shrm_latlong
from shrmkit.brdf_io.reparam import ReparamBRDF, ReparamGrid, reparameterize

FAST = settings(max_examples=12, deadline=None)


@FAST
@given(
    alpha=st.floats(0.08, 0.8),
    kd=st.floats(0.0, 0.9),
    dist=st.sampled_from(["beckmann", "ggx"]),
    n=st.floats(1.0, 200.0),
    cxy=st.floats(-1.0, -0.2),
)
def test_reparameterized_tables_are_even_in_phi(alpha, kd, dist, n, cxy):
    """Isotropic ρ ⇒ ρ̂(θ_i', θ_o', φ') = ρ̂(θ_i', θ_o', −φ')."""
    grid = ReparamGrid(10, 6, 12)
    flip = (-np.arange(12)) % 12
    for spec in (f"cook-torrance:alpha={alpha},kd={kd},dist={dist}", f"lafortune:kd={kd},cxy={cxy},n={n}"):
        v = reparameterize(shrmkit.load_brdf(spec), grid).values
        np.testing.assert_allclose(v, v[:, :, flip], rtol=1e-9, atol=1e-12 * max(1.0, np.abs(v).max()))


@FAST
@given(seed=st.integers(0, 2**31 - 1))
def test_parseval_for_band_limited_tables(seed):
    """Σ ρ̂_lpq² (q ≥ 1 twice) equals ∫∫ ρ̂² when the table holds orders the grid resolves."""
    rng = np.random.default_rng(seed)
    grid = ReparamGrid(10, 6, 10)
    from shrmkit.analysis.sh import legendre_f

    xi, _ = grid.theta_i()
    xo, _ = grid.theta_o()
    fi, fo = legendre_f(4, 2, xi), legendre_f(2, 2, xo)
    values = np.zeros((10, 6, 10))
    for l in range(5):
        for p in range(3):
            for q in range(min(l, p) + 1):
                c = rng.normal()
                values += c * (1 if q == 0 else 2) * fi[l, q][:, None, None] * fo[p, q][None, :, None] * np.cos(
                    q * grid.phi()
                )
    coeffs = rho_lpq(ReparamBRDF(np.repeat(values[..., None], 3, -1), grid, "random"), 4, 2)
    np.testing.assert_allclose(coeffs.parseval_terms().sum(axis=(0, 1, 2)), coeffs.energy, rtol=1e-10)


@FAST
@given(shift=st.integers(1, 31), seed=st.integers(0, 1000))
def test_rotating_the_environment_rotates_the_map(shift, seed):
    """A z-rotation of the lighting by whole columns shifts every global SHRM map... after the
    view basis is rotated too: compare B(R, V) at rotated (R, V) pairs."""
    rng = np.random.default_rng(seed)
    img = rng.uniform(size=(16, 32, 3))
    rolled = np.roll(img, shift, axis=1)  # feature at column j moves to j + shift: φ += 2π shift/32
    o = shrmkit.choose_orders(shrmkit.load_brdf("microfacet:sigma=0.4"), eps=0.05)
    a = global_shrm_latlong(lighting_coefficients(img, 8), o.coefficients, 8, o.P, 16, 32)
    b = global_shrm_latlong(lighting_coefficients(rolled, 8), o.coefficients, 8, o.P, 16, 32)
    angle = 2 * np.pi * shift / 32
    m1 = shrmkit.SHRM(F=8, P=o.P, coeffs=a)
    m2 = shrmkit.SHRM(F=8, P=o.P, coeffs=b)
    R = rng.normal(size=(40, 3))
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    V = rng.normal(size=(40, 3))
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    c, s = np.cos(angle), np.sin(angle)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    # the map grid is shifted by the same whole number of columns, so bilinear lookups agree
    np.testing.assert_allclose(m2.radiance(R @ Rz.T, V @ Rz.T), m1.radiance(R, V), rtol=1e-4, atol=1e-5)
