"""The view profile's transform and the view fit (analysis.view_bands, analysis._view_fit) against
slow direct computations.

References: the transform of ρ̂ in φ' and θ_i' as plain sums over every sample of the whole φ'
period (no DCT, no folding by parity); the view fit as weighted least squares per (l, q, channel)
by ``numpy.linalg.lstsq`` with every reweighting pass's band errors from the whole fitted set;
the order choice of the implementation before the fit was rewritten (git f8f9259, recorded).
"""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis import _view_fit
from shrmkit.analysis.brdf_coeffs import BRDFCoefficients, rho_lpq, weighted_legendre
from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.sh import legendre_f
from shrmkit.analysis.view_bands import (
    FIT_PASSES,
    OUTSIDE_WEIGHT,
    _band_eps_all,
    band_eps_column,
    bands_inside,
    fit_view_coefficients,
    view_profile,
)
from shrmkit.brdf_io.reparam import ReparamGrid, reparameterize, sample_rho_hat


@pytest.mark.parametrize("n_theta_i, n_phi", [(21, 15), (20, 16)])
def test_profile_transform_equals_the_direct_sums(n_theta_i, n_phi):
    """T_lq, the per-q energy and the unresolved energy of view_profile (half period, DCT, folded by
    parity in cos θ_i') equal plain sums over every sample of the whole φ' period, for odd and even
    node counts (the middle θ_i' node, the odd-period rfft)."""
    brdf = shrmkit.load_brdf("cook-torrance:kd=0.3/0.2/0.1,alpha=0.3,f0=0.04")
    grid = ReparamGrid(n_theta_i, 8, n_phi)
    F0, P0 = n_theta_i - 1, 6
    profile = view_profile(brdf, grid, F0, P0)
    xi, wi = grid.theta_i()
    phi = grid.phi()
    dphi = 2.0 * np.pi / n_phi
    rho, _ = sample_rho_hat(brdf, xi, np.cos(2.0 * profile.theta_v), phi)  # (n_i, K, n_phi, 3)
    n_q = n_phi // 2 + 1
    g = np.einsum("ikjc,qj->ikqc", rho, np.cos(np.outer(np.arange(n_q), phi))) * dphi
    T = 2.0 * np.pi * np.einsum("lqi,ikqc->lkqc", weighted_legendre(F0, P0, n_theta_i), g[:, :, : P0 + 1])
    np.testing.assert_allclose(profile.T, T, rtol=0, atol=1e-12 * np.abs(T).max())
    mult = np.where((np.arange(n_q) == 0) | (2 * np.arange(n_q) == n_phi), 1.0, 2.0)
    q_energy = np.einsum("i,ikqc->kqc", wi, g * g) * mult[None, :, None]
    np.testing.assert_allclose(profile.q_energy, q_energy, rtol=0, atol=1e-12 * q_energy.max())
    energy = 2.0 * np.pi * dphi * np.einsum("i,ikjc->kc", wi, rho * rho)
    resolved = np.einsum("lkqc,q->kc", T * T, np.where(np.arange(P0 + 1) == 0, 1.0, 2.0)) / (2.0 * np.pi)
    np.testing.assert_allclose(profile.beyond, np.clip(energy - resolved, 0.0, None), rtol=0,
                               atol=1e-12 * energy.max())


def _fit_direct(profile, coefficients, P, max_view_deg):
    """The view fit written out slowly: per (l, q, channel) weighted least squares by
    ``numpy.linalg.lstsq`` on the nodes, and every reweighting pass's band errors from
    ``_band_eps_all`` of the whole fitted set (what ``fit_view_coefficients`` computes
    incrementally)."""
    F0 = min(profile.F0, coefficients.F0)
    inside = np.zeros(profile.n_bands, dtype=bool)
    inside[bands_inside(profile, max_view_deg)] = True
    signal = (profile.band_full.sum(axis=1) + profile.band_beyond).sum(axis=1)
    band_w = np.where(inside, 1.0, OUTSIDE_WEIGHT) / np.where(signal > 0, signal, 1.0)
    fo = legendre_f(P, P, np.cos(2.0 * profile.theta_v))
    out = np.zeros_like(coefficients.coeffs)
    fitted = BRDFCoefficients(coeffs=out, energy=coefficients.energy, name=coefficients.name)
    prev = np.inf
    for npass in range(FIT_PASSES + 1):
        sw = np.sqrt(profile.weight * band_w[profile.band])
        for q in range(P + 1):
            A = 2.0 * np.pi * fo[q : P + 1, q, :].T * sw[:, None]
            for l in range(F0 + 1):
                for c in range(3):
                    out[l, q : P + 1, q, c] = np.linalg.lstsq(A, sw * profile.T[l, :, q, c], rcond=None)[0]
        if npass == FIT_PASSES:
            break
        eps = _band_eps_all(profile, fitted, p_list=[P])[:, F0, 0]
        worst = eps[inside].max()
        if worst <= 0.0 or worst > 0.995 * prev:
            break
        prev = worst
        band_w = band_w * np.where(inside, np.sqrt(np.clip(eps / worst, 1e-3, 1.0)), 1.0)
    return fitted


@pytest.mark.parametrize("solver", ["normal equations", "QR"])
@pytest.mark.parametrize("spec, P", [("cook-torrance:kd=0.2,alpha=0.1,f0=0.04", 3), ("microfacet:sigma=0.3", 2),
                                     ("lambert:albedo=0.5", 4)])
def test_view_fit_equals_the_direct_least_squares(spec, P, solver, monkeypatch):
    """fit_view_coefficients (normal equations from band-summed normal matrices, or QR of the
    weighted basis where they are ill conditioned — both forced here; band errors of each pass from
    the Gram matrices) equals per-coefficient lstsq with the band errors of the whole fitted set
    recomputed every pass, to rounding; band_eps_column is the direct fit's worst band inside."""
    monkeypatch.setattr(_view_fit, "NORMAL_EQUATIONS_COND", np.inf if solver == "normal equations" else 0.0)
    brdf = shrmkit.load_brdf(spec)
    grid = ReparamGrid.for_orders(16, 6)
    F0, P0 = 16, 6
    coefficients = rho_lpq(reparameterize(brdf, grid), F0, P0)
    profile = view_profile(brdf, grid, F0, P0)
    fast = fit_view_coefficients(profile, coefficients, P, 80.0)
    slow = _fit_direct(profile, coefficients, P, 80.0)
    scale = np.abs(slow.coeffs).max()
    np.testing.assert_allclose(fast.coeffs, slow.coeffs, rtol=0, atol=1e-9 * scale)
    assert np.abs(fast.coeffs[:, P + 1 :]).max(initial=0.0) == 0.0
    direct = _band_eps_all(profile, slow, p_list=[P])
    np.testing.assert_allclose(_band_eps_all(profile, fast, p_list=[P]), direct, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(band_eps_column(profile, P, 80.0), direct[bands_inside(profile, 80.0), :, 0].max(axis=0),
                               rtol=1e-8, atol=1e-14)


@pytest.mark.parametrize("spec, F, P, eps", [("microfacet:sigma=0.1", 72, 10, 0.029899298886822114),
                                             ("cook-torrance:alpha=0.1,dist=ggx", 87, 14, 0.029971672014794257)])
def test_order_choice_is_the_previous_implementations(spec, F, P, eps):
    """The order choice at ε = 0.03 as the implementation before the faster view fit and profile
    made it (git f8f9259: the same orders, ε to rounding)."""
    choice = choose_orders(spec, eps=0.03)
    assert (choice.F, choice.P) == (F, P)
    assert choice.eps == pytest.approx(eps, rel=1e-9)
