"""Spherical harmonics and rotation matrices against scipy and the defining identity."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import roots_legendre, sph_harm_y

from shrmkit.analysis.sh import (
    LEGENDRE_TESTED_LMAX,
    Lambda,
    NumericalLimitWarning,
    complex_sph_harm,
    legendre_f,
    real_sph_harm,
)
from shrmkit.analysis.wigner import WIGNER_TESTED_LMAX, rotation_D, wigner_d_tilde


def _unit(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _rot(alpha, beta):
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    return np.array([[cb, -sb, 0], [sb, cb, 0], [0, 0, 1]]) @ np.array([[ca, 0, sa], [0, 1, 0], [-sa, 0, ca]])


def test_complex_sh_matches_scipy():
    """Reference: scipy.special.sph_harm_y (same Condon–Shortley convention)."""
    d = _unit(np.random.default_rng(0), 40)
    theta, phi = np.arccos(d[:, 2]), np.arctan2(d[:, 1], d[:, 0])
    Y = complex_sph_harm(12, d)
    for l in range(13):
        for m in range(-l, l + 1):
            np.testing.assert_allclose(Y[:, l * l + l + m], sph_harm_y(l, m, theta, phi), atol=1e-13)


def test_legendre_stable_at_l500():
    """Normalized recurrence stays accurate at l = 500 (scipy reference), no overflow."""
    x = np.cos(np.linspace(0.01, 3.13, 25))
    f = legendre_f(500, 4, x)
    assert np.all(np.isfinite(f))
    for m in range(5):
        np.testing.assert_allclose(f[500, m], sph_harm_y(500, m, np.arccos(x), 0.0).real, atol=1e-12)


def test_real_basis_orthonormal():
    """Gauss–Legendre × uniform quadrature (exact for degree <= 2·lmax)."""
    lmax = 6
    x, w = np.polynomial.legendre.leggauss(lmax + 2)
    nphi = 2 * lmax + 3
    phi = 2 * np.pi * np.arange(nphi) / nphi
    s = np.sqrt(1 - x**2)
    dirs = np.stack([s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), np.repeat(x[:, None], nphi, 1)], -1)
    Y = real_sph_harm(lmax, dirs.reshape(-1, 3))
    gram = np.einsum("na,nb,n->ab", Y, Y, np.repeat(w, nphi) * 2 * np.pi / nphi)
    np.testing.assert_allclose(gram, np.eye((lmax + 1) ** 2), atol=1e-12)


@pytest.mark.parametrize("l", [0, 1, 2, 5, 17, 33, 60])
def test_rotation_identity_random_points(l):
    """DESIGN §5: Y_lm(R_{α,β} ω) = Σ_q 𝒟^l_mq(α, β) Y_lq(ω) at random points, up to l = 60."""
    rng = np.random.default_rng(l)
    for _ in range(3):
        alpha, beta = rng.uniform(0, np.pi), rng.uniform(0, 2 * np.pi)
        w = _unit(rng, 4)
        lhs = complex_sph_harm(l, w @ _rot(alpha, beta).T)[:, l * l :]
        rhs = complex_sph_harm(l, w)[:, l * l :] @ rotation_D(l, alpha, beta).T
        np.testing.assert_allclose(lhs, rhs, atol=1e-11)


def test_q0_column_is_funk_hecke():
    """𝒟^l_m0(α, β) = Λ_l Y_lm(α, β) (DESIGN §5 check)."""
    alpha, beta = 0.7, 2.2
    d = np.array([np.sin(alpha) * np.cos(beta), np.sin(alpha) * np.sin(beta), np.cos(alpha)])
    for l in (3, 40):
        D = rotation_D(l, alpha, beta)
        np.testing.assert_allclose(D[:, l], Lambda(l) * complex_sph_harm(l, d[None])[0, l * l :], atol=1e-12)


def test_wigner_unitary_high_degree():
    D = rotation_D(200, 1.1, 0.4)
    np.testing.assert_allclose(D @ D.conj().T, np.eye(401), atol=1e-10)


def test_legendre_orthonormal_at_the_tested_limit():
    """At l = LEGENDRE_TESTED_LMAX the f_lm stay orthonormal under Gauss–Legendre quadrature
    (exact for these polynomial degrees): 2π Σ_k w_k f_lm(x_k) f_l'm(x_k) = δ_ll'. The nodes and
    weights are SciPy's ``roots_legendre`` (asymptotic expansions, 0.2 s), not NumPy's ``leggauss``
    (a 2002 × 2002 companion-matrix eigenproblem, 5.5 s CPU): the same nodes to 1e-16 and weights to
    1e-10 relative; the Gram matrix is within 1.6e-10 of the identity with either."""
    L = LEGENDRE_TESTED_LMAX
    x, w = roots_legendre(L + 2)
    f = legendre_f(L, 8, x)
    for m in (0, 4, 8):
        gram = 2.0 * np.pi * (f[m:, m, :] * w) @ f[m:, m, :].T
        assert np.abs(gram - np.eye(L + 1 - m)).max() < 1e-9


def test_beyond_the_tested_degree_warns():
    with pytest.warns(NumericalLimitWarning, match="legendre_f: degree 2001"):
        legendre_f(LEGENDRE_TESTED_LMAX + 1, 0, np.array([0.5]))
    with pytest.warns(NumericalLimitWarning, match="wigner_d_tilde: degree 201"):
        wigner_d_tilde(WIGNER_TESTED_LMAX + 1, 0.3)
