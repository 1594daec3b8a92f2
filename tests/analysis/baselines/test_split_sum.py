"""Split-sum prefiltered lighting (Karis 2013): the environment-BRDF table, the zonal
prefilter, and the split sum where it is exact.

References: the brute-force angular integral of ``analysis.reference.reference_radiance``
on a constant map (the directional albedo of the Cook–Torrance GGX model, summed over every
pixel: independent of the table's GGX sample warp); a direct sum over every pixel for the
FFT zonal convolution. No test claims the split sum is exact for non-constant lighting:
``benchmarks/prefilter_speed.py`` measures its error there.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.split_sum import (
    env_brdf_lut,
    ggx_kernel,
    ggx_prefiltered,
    split_sum,
    zonal_convolution,
)
from shrmkit.analysis.compare import sample_pairs
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import pixel_directions, row_solid_angles
from shrmkit.brdf_io.specs import load_brdf


@pytest.fixture(scope="module")
def constant_env():
    return load_env("builtin:constant,height=128")


@pytest.fixture(scope="module")
def lut():
    return env_brdf_lut()


def _pairs_at(mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R, V) with N = +z and N·V = μ."""
    V = np.stack([np.sqrt(1.0 - mu**2), np.zeros_like(mu), mu], axis=1)
    return V * [-1.0, -1.0, 1.0], V


def test_lut_is_the_directional_albedo(constant_env) -> None:
    """At a node (μ, r = √α) the table's A + B (F0 = 1) and B (F0 = 0) equal the specular
    directional albedo summed over every pixel of a constant map (brute force), within 1e-3."""
    mu = np.array([0.15, 0.4, 0.7, 0.95])
    for alpha in (0.2, 0.5):
        lut = env_brdf_lut(mu=mu, roughness=[np.sqrt(alpha)])
        R, V = _pairs_at(mu)
        one = reference_radiance(constant_env, load_brdf(f"cook-torrance:alpha={alpha},f0=1,dist=ggx"), R, V)[:, 0]
        zero = reference_radiance(constant_env, load_brdf(f"cook-torrance:alpha={alpha},f0=0,dist=ggx"), R, V)[:, 0]
        a, b = lut.lookup(mu, alpha)
        np.testing.assert_allclose(a + b, one, rtol=1e-3)
        np.testing.assert_allclose(b, zero, rtol=2e-3, atol=1e-5)


@pytest.mark.parametrize(
    "spec",
    ["cook-torrance:alpha=0.3,dist=ggx", "cook-torrance:alpha=0.1,kd=0.3,f0=0.9/0.6/0.3,dist=ggx",
     "cook-torrance:alpha=0.6,kd=0.2,ks=0.5,dist=ggx"],
)
def test_exact_for_constant_lighting(constant_env, lut, spec: str) -> None:
    """Constant lighting: L̄ = L and E = πL, so the split sum is the directional albedo — equal
    to the brute-force sum up to the default 32 × 32 table's interpolation (<= 1 % at θ_v <= 80°)."""
    brdf = load_brdf(spec)
    R, V, _ = sample_pairs(50, seed=4, max_view_deg=80.0)
    ref = reference_radiance(constant_env, brdf, R, V)
    ss = split_sum(constant_env, brdf, lut=lut, rows=16)
    np.testing.assert_allclose(ss.prefiltered(R), 1.0, rtol=1e-6)
    np.testing.assert_allclose(ss.radiance(R, V), ref, rtol=1e-2)


def test_zonal_convolution_equals_direct_sum() -> None:
    """The FFT zonal convolution equals Σ_p L_p Ω_p k(R·ω_p) summed directly over every pixel
    (a non-symmetric map, output grid coarser than the map), and the GGX level is that sum
    normalized by the same sum for a map of ones."""
    rng = np.random.default_rng(8)
    radiance = rng.random((16, 32, 3))
    dirs = pixel_directions(16, 32).reshape(-1, 3)
    omega = np.repeat(row_solid_angles(16, 32), 32)
    kernel = ggx_kernel(0.4)
    conv, norm = zonal_convolution(radiance, kernel, 8)
    R = pixel_directions(8, 16).reshape(-1, 3)
    k = kernel(np.clip(R @ dirs.T, -1.0, 1.0)) * omega[None, :]
    np.testing.assert_allclose(conv.reshape(-1, 3), k @ radiance.reshape(-1, 3), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.repeat(norm, 16), k.sum(axis=1), rtol=1e-10)
    level = ggx_prefiltered(radiance, 0.4, 8)
    np.testing.assert_allclose(level.reshape(-1, 3), (k @ radiance.reshape(-1, 3)) / k.sum(axis=1)[:, None],
                               rtol=1e-6)


def test_mip_chain_interpolates_in_roughness(constant_env, lut) -> None:
    """A chain of levels: the material's α between two levels blends them linearly in √α;
    constant lighting stays exact through the blend."""
    env = load_env("builtin:sky,height=32,sun_ratio=0")
    brdf = load_brdf("cook-torrance:alpha=0.3,dist=ggx")
    chain = split_sum(env, brdf, levels=[0.2, 0.3, 0.5], lut=lut)
    single = split_sum(env, brdf, lut=chain.lut)
    R, V, _ = sample_pairs(20, seed=1, max_view_deg=60.0)
    np.testing.assert_allclose(chain.radiance(R, V), single.radiance(R, V), rtol=1e-6)
    between = split_sum(env, load_brdf("cook-torrance:alpha=0.25,dist=ggx"), levels=[0.2, 0.3], lut=chain.lut)
    f = (np.sqrt(0.25) - np.sqrt(0.2)) / (np.sqrt(0.3) - np.sqrt(0.2))
    a, b = (split_sum(env, load_brdf(f"cook-torrance:alpha={x},dist=ggx"), lut=chain.lut, rows=m.shape[0])
            for x, m in zip((0.2, 0.3), (lvl for _, lvl in between.levels), strict=True))
    np.testing.assert_allclose(between.prefiltered(R), (1 - f) * a.prefiltered(R) + f * b.prefiltered(R), rtol=1e-6)
    assert chain.nbytes == sum(m.nbytes for _, m in chain.levels) + chain.lut.nbytes
    flat = split_sum(load_env("builtin:constant,height=32"), load_brdf("cook-torrance:alpha=0.25,dist=ggx"),
                     levels=[0.2, 0.3], lut=lut)
    np.testing.assert_allclose(flat.prefiltered(R), 1.0, rtol=1e-6)
    assert chain.view_map(np.array([0.0, 0.0, 1.0])).shape == (max(m.shape[0] for _, m in chain.levels),
                                                              2 * max(m.shape[0] for _, m in chain.levels), 3)


def test_refuses_other_materials() -> None:
    env = np.ones((8, 16, 3))
    for spec in ("microfacet:sigma=0.2", "cook-torrance:alpha=0.2", "cook-torrance:alpha=1.5,dist=ggx"):
        with pytest.raises(BadInputError):
            split_sum(env, load_brdf(spec))
    with pytest.raises(BadInputError, match="multiple"):
        zonal_convolution(env, np.cos, 3)
