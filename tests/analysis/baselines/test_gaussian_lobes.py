"""Green, Kautz & Durand 2007 Gaussian lobes: fit, SG mip stack, rendering.

References: a BRDF whose transfer function is exactly one normalized spherical Gaussian
(known width, weight and offset); Legendre–Gauss quadrature of the SG kernel (zonal
factors); direct pixel-sum convolution of the environment with the SG (mip stack); the
brute-force angular integral of analysis.reference (rendering).
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.gaussian_lobes import (
    GaussianLobeModel,
    fit_gaussian_lobes,
    sg_eval,
    sg_mip_stack,
    sg_norm,
    sg_zonal_factors,
)
from shrmkit.analysis.compare.pairs import sample_pairs
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.brdf import BRDF
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import pixel_directions, row_solid_angles


class SGLobeBRDF(BRDF):
    """ρ̂(L, V) = w · G_σ(μ·L) with μ at angle ``offset`` from the mirror direction R toward V
    (in the plane of R and V), no horizon clipping: T is exactly one normalized SG."""

    kind = "analytic"

    def __init__(self, sigma: float, weight, offset: float = 0.0) -> None:
        self.name = f"sg:sigma={sigma}"
        self.sigma, self.weight, self.offset = sigma, np.asarray(weight, float), offset

    def eval(self, L, V):  # pragma: no cover - only rho_hat is used
        raise NotImplementedError

    def rho_hat(self, L, V):
        L, V = np.broadcast_arrays(np.asarray(L, float), np.asarray(V, float))
        R = V * np.array([-1.0, -1.0, 1.0])
        t = V - np.sum(V * R, axis=-1, keepdims=True) * R
        n = np.linalg.norm(t, axis=-1, keepdims=True)
        # V = N (θ_v = 0): no plane of R and V, the lobe is centred on R
        mu = np.where(n > 1e-12, np.cos(self.offset) * R + np.sin(self.offset) * t / np.maximum(n, 1e-300), R)
        return sg_eval(np.sum(mu * L, axis=-1), self.sigma)[..., None] * self.weight


def test_sg_norm_and_zonal_factors_against_quadrature() -> None:
    """N(σ) and a_l = 2π ∫ G P_l dt / N by 400-point Gauss–Legendre quadrature."""
    from scipy.special import eval_legendre

    t, w = np.polynomial.legendre.leggauss(400)
    for sigma in (0.1, 0.4, 1.5):
        g = np.exp((t - 1.0) / sigma**2)
        assert sg_norm(sigma) == pytest.approx(2.0 * np.pi * np.sum(w * g), rel=1e-12)
        quad = np.array([2.0 * np.pi * np.sum(w * g * eval_legendre(l, t)) for l in range(30)]) / sg_norm(sigma)
        # atol: the quadrature of P_l loses ~1e-13 to cancellation
        np.testing.assert_allclose(sg_zonal_factors(sigma, 29), quad, rtol=1e-9, atol=1e-12)


def test_k1_fit_recovers_width_and_weight() -> None:
    """For a lobe that is exactly w·G_σ about an offset direction, K = 1 recovers σ and w
    within 2% (and the offset within 0.01 rad) at every elevation; starts are not at σ."""
    brdf = SGLobeBRDF(0.13, [0.3, 0.55, 0.8], offset=0.08)
    fit = fit_gaussian_lobes(brdf, 1, 4, max_theta_v_deg=60.0, n_theta=90, n_psi=45)
    np.testing.assert_allclose(fit.sigma[:, 0], 0.13, rtol=0.02)
    np.testing.assert_allclose(fit.weight[:, 0, :], np.broadcast_to([0.3, 0.55, 0.8], (4, 3)), rtol=0.02)
    np.testing.assert_allclose(fit.mu[1:, 0], 0.08, atol=0.01)  # θ_v = 0: the offset's direction is undefined
    assert fit.residual.max() < 0.05


def test_mip_stack_matches_direct_sg_convolution() -> None:
    """Each level equals ∫ L(ω) G_σ(d·ω) dω summed over the map's pixels (exact solid angles)
    within 1% of the level's maximum, at 200 of its pixel centres."""
    env = load_env("builtin:studio,height=32")
    stack = sg_mip_stack(env)
    rad = env.radiance
    H, W = rad.shape[:2]
    dirs = pixel_directions(H, W).reshape(-1, 3)
    omega = np.repeat(row_solid_angles(H, W), W)
    assert np.allclose(stack.sigmas / stack.sigmas[0], 2.0 ** np.arange(len(stack.sigmas)))
    for sigma, level in zip(stack.sigmas, stack.levels, strict=True):
        h = level.shape[0]
        d = pixel_directions(h, 2 * h).reshape(-1, 3)
        pick = np.random.default_rng(0).choice(len(d), size=min(200, len(d)), replace=False)
        direct = np.einsum("nk,k,kc->nc", sg_eval(d[pick] @ dirs.T, sigma), omega, rad.reshape(-1, 3))
        got = level.reshape(-1, 3)[pick]
        assert np.abs(got - direct).max() < 0.01 * np.abs(direct).max()
    # lookup between levels interpolates in log2 σ: halfway in log between levels 1 and 2
    d = dirs[:5]
    mid = stack.lookup(d, np.full(5, stack.sigmas[1] * np.sqrt(2.0)))
    both = 0.5 * (stack.lookup(d, np.full(5, stack.sigmas[1])) + stack.lookup(d, np.full(5, stack.sigmas[2])))
    np.testing.assert_allclose(mid, both, rtol=1e-12)


def test_gaussian_render_matches_reference_for_gaussian_brdf() -> None:
    """A BRDF that is one SG about R at a stack width (σ = 2σ_0) is rendered within 2% rel RMS
    of the angular reference (only the bilinear lookups, ~1%, remain). (An offset lobe would add
    the interpolation between θ_v = 0, where the test lobe is centred, and the next node.)"""
    env = load_env("builtin:studio,height=32")
    stack = sg_mip_stack(env)
    brdf = SGLobeBRDF(float(stack.sigmas[1]), [0.5, 0.6, 0.7])
    fit = fit_gaussian_lobes(brdf, 1, 8, max_theta_v_deg=70.0, n_theta=90, n_psi=45)
    R, V, _ = sample_pairs(300, seed=2, max_view_deg=70.0)
    ref = reference_radiance(env, brdf, R, V)
    got = GaussianLobeModel(fit, stack).radiance(R, V)
    assert np.sqrt(np.sum((got - ref) ** 2) / np.sum(ref**2)) < 0.02


def test_fit_rejects_bad_k_and_zero_brdf() -> None:
    with pytest.raises(BadInputError, match="K must be"):
        fit_gaussian_lobes(SGLobeBRDF(0.2, [1, 1, 1]), 0, 3)
    with pytest.raises(BadInputError, match="zero"):
        fit_gaussian_lobes(SGLobeBRDF(0.2, [0, 0, 0]), 1, 2)
