"""Lobe-truncated angular sum (RH02 Table 4's baseline): cones, cone queries, radiance.

References: the brute-force angular integral of ``analysis.reference.reference_radiance``
(every pixel); the closed-form 1e-3 widths of the Phong lobe (cos^s θ = 1e-3) and of RH02's
microfacet lobe at normal view (θ_i' = 2σ√ln 1000); a direct test R·ω_p ≥ cos c over every
pixel for the cone queries.
"""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.baselines.lobe_truncated import (
    cone_pixels,
    lobe_cones,
    lobe_truncated_radiance,
    lobe_truncated_sum,
)
from shrmkit.analysis.compare import sample_pairs
from shrmkit.analysis.reference import reference_radiance
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import pixel_directions
from shrmkit.brdf_io.specs import load_brdf


@pytest.fixture(scope="module")
def smooth_env():
    """A sky without its sun: smooth lighting, where 1e-3 of the peak is ~1e-3 of the result."""
    return load_env("builtin:sky,height=48,sun_ratio=0")


@pytest.mark.parametrize("s", [8.0, 32.0, 512.0, 1e4])
def test_phong_cone_is_the_closed_form_width(s: float) -> None:
    """RH02 Phong ρ̂ = (s+1)/2π cos^s(angle to R) at every view: the lobe is above 1e-3 of
    its peak exactly within arccos(1e-3^(1/s)); the table rounds up by at most two nodes."""
    cones = lobe_cones(load_brdf(f"phong:s={s:g}"))
    exact = np.arccos(1e-3 ** (1.0 / s))
    assert np.all(cones.half_angle >= exact)
    assert np.all(cones.half_angle <= exact + 2.0 * cones.step + 1e-12)
    np.testing.assert_allclose(cones.peak[:, 0], (s + 1.0) / (2.0 * np.pi), rtol=1e-10)


@pytest.mark.parametrize("sigma", [0.02, 0.1, 0.2])
def test_microfacet_cone_at_normal_view(sigma: float) -> None:
    """RH02 eq. 11 at θ_v = 0 (V = R = N): θ_h = θ_i'/2, so exp(−(θ_h/σ)²) = 1e-3 at
    θ_i' = 2σ√ln 1000 (closed form)."""
    cones = lobe_cones(load_brdf(f"microfacet:sigma={sigma:g}"))
    exact = 2.0 * sigma * np.sqrt(np.log(1e3))
    assert exact <= cones.half_angle[0] <= exact + 2.0 * cones.step + 1e-12


def test_cone_queries_agree_with_direct_test() -> None:
    """Both queries (lat-long rows, KD-tree) return every pixel centre within the cone and
    nothing farther than 1e-6 rad beyond it, cones from tiny to the whole sphere, poles included."""
    height, width = 24, 48
    dirs = pixel_directions(height, width).reshape(-1, 3)
    rng = np.random.default_rng(3)
    R = rng.normal(size=(60, 3))
    R /= np.linalg.norm(R, axis=1, keepdims=True)
    R[:2] = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    c = np.concatenate([[0.3, 1.0], rng.uniform(0.01, 3.5, 58)])
    angle = np.arccos(np.clip(R @ dirs.T, -1.0, 1.0))  # (60, n)
    for query in ("rows", "kdtree"):
        owner, pixel = cone_pixels(R, c, height, width, query=query)
        got = np.zeros(angle.shape, dtype=bool)
        got[owner, pixel] = True
        assert owner.size == got.sum(), f"{query}: a pixel listed twice"
        assert np.all(got[angle <= np.minimum(c, np.pi)[:, None] - 1e-9]), f"{query}: missed pixels"
        assert np.all(angle[got] <= np.broadcast_to(np.minimum(c, np.pi)[:, None], angle.shape)[got] + 1e-6)


@pytest.mark.parametrize("spec", ["phong:s=32", "phong:s=512", "microfacet:sigma=0.1", "microfacet:sigma=0.3"])
def test_agrees_with_brute_force_within_dropped_fraction(smooth_env, spec: str) -> None:
    """Against the full sum over every pixel (analysis.reference): relative RMS <= 1.5e-3
    under smooth lighting, and every pair within its stated bound (threshold × peak × the flux
    outside the cone)."""
    brdf = load_brdf(spec)
    R, V, _ = sample_pairs(150, seed=5, max_view_deg=85.0)
    ref = reference_radiance(smooth_env, brdf, R, V)
    out, bound, terms = lobe_truncated_sum(smooth_env, brdf).radiance_and_bound(R, V)
    assert np.sqrt(((out - ref) ** 2).sum() / (ref**2).sum()) <= 1.5e-3
    assert np.all(out <= ref * (1 + 1e-12) + 1e-300)  # only non-negative terms are dropped
    assert np.all(ref - out <= bound * (1 + 1e-9) + 1e-300)


def test_sharp_lobe_sums_few_pixels(smooth_env) -> None:
    """Why it is fast for sharp lobes: Phong s = 512 sums < 1 % of the (output, pixel) terms
    of the brute-force sum (the 9.4° cone is 0.7 % of the sphere), the KD-tree query the same."""
    brdf = load_brdf("phong:s=512")
    R, V, _ = sample_pairs(100, seed=6, max_view_deg=80.0)
    lit = int(np.any(smooth_env.radiance != 0, axis=2).sum())
    rows = lobe_truncated_sum(smooth_env, brdf)
    out, _, terms = rows.radiance_and_bound(R, V)
    assert terms < 0.01 * 100 * lit
    kd = lobe_truncated_sum(smooth_env, brdf, cones=rows.cones, query="kdtree")
    out_kd, _, terms_kd = kd.radiance_and_bound(R, V)
    assert terms_kd <= terms
    np.testing.assert_allclose(out_kd, out, rtol=1e-12, atol=1e-14 * out.max())


def test_view_map_and_bright_source_bound() -> None:
    """With a one-pixel sun 1e5× the sky the dropped tail can matter: the result still never
    exceeds the reference, stays within its bound per pair, and the distant-view map equals
    the pair-wise evaluation at its pixel centres."""
    env = load_env("builtin:sun,height=32,elevation=30,azimuth=40")
    brdf = load_brdf("microfacet:sigma=0.15")
    ts = lobe_truncated_sum(env, brdf)
    view = np.array([0.3, -0.2, 0.9])
    m = ts.view_map(view, 8, 16)
    R = pixel_directions(8, 16).reshape(-1, 3)
    V = np.broadcast_to(view / np.linalg.norm(view), R.shape)
    ref = reference_radiance(env, brdf, R, V)
    out, bound, _ = ts.radiance_and_bound(R, np.ascontiguousarray(V))
    np.testing.assert_allclose(m.reshape(-1, 3), out, rtol=1e-12)
    assert np.all(ref - out >= -1e-12 * ref.max())
    assert np.all(ref - out <= bound * (1 + 1e-9) + 1e-300)
    np.testing.assert_allclose(lobe_truncated_radiance(env, brdf, R, V), out, rtol=1e-12)


def test_bad_input() -> None:
    brdf = load_brdf("phong:s=8")
    with pytest.raises(BadInputError, match="threshold"):
        lobe_cones(brdf, threshold=0.0)
    with pytest.raises(BadInputError, match="cone query"):
        lobe_truncated_sum(np.ones((4, 8, 3)), brdf, query="octree")
    with pytest.raises(BadInputError, match="zero or not finite"):
        lobe_cones(load_brdf("lambert:albedo=0"))
