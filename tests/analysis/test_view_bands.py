"""Per-view-band error statements (analysis.view_bands) against independent references.

References: quadrature of ρ̂² on the reparameterized grid (Parseval), RH02's closed form for
Phong (F ≈ sqrt(−s ln ε), RH02 Appendix D), and brute-force angular integration
(``analysis.reference``) on (R, V) pairs drawn per band — uniform R plus caps around the
brightest pixel with importance weights, so that a one-pixel sun is measured with small
Monte Carlo error — quoted with its standard error.
"""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.compare import band_pairs, band_relative_rms, relative_rms, sample_pairs
from shrmkit.analysis.lighting import lighting_coefficients
from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.scene import scene_orders
from shrmkit.analysis.shrm import WINDOW_THRESHOLD, prefilter
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG, view_profile
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.reparam import ReparamGrid, reparameterize

EPS = 0.03
PROMISE = 2.0 * np.sqrt(EPS) + 0.01  # README: relative RMS inside the view limit


def _env(name: str, shared_data=None):
    if name == "grace":
        return shrmkit.load_env(shared_data / "env" / "grace_latlong.exr", up="y", flip=True, height=64)
    if name == "venice":
        return shrmkit.load_env(shared_data / "env" / "polyhaven_cc0" / "venice_sunset_1k.hdr", up="y", height=64)
    return shrmkit.load_env("builtin:sun,height=128,elevation=35,azimuth=20")  # 1e5 over the sky


def _measure(shrm, env, brdf, per_band: int, seed: int = 5) -> list[dict]:
    R, V, theta_v, w = band_pairs(env.radiance, per_band, DEFAULT_BAND_EDGES_DEG, seed=seed)
    ref = reference_radiance(env, brdf, R, V)
    return band_relative_rms(shrm.radiance(R, V), ref, theta_v, DEFAULT_BAND_EDGES_DEG, w)


def test_profile_holds_all_the_energy_of_the_brdf():
    """Σ_bands ∫ (resolved + unresolved density) sin θ_o' dθ_o' is ∫∫ ρ̂² by the grid's own
    quadrature (ReparamBRDF.energy), for a view-dependent lobe."""
    brdf = shrmkit.load_brdf("cook-torrance:alpha=0.3,f0=0.5,dist=ggx")
    grid = ReparamGrid.for_orders(24, 6)
    energy = reparameterize(brdf, grid).energy()
    profile = view_profile(brdf, grid, grid.n_theta_i - 1, 6)
    density = profile.full().sum(axis=0) + profile.beyond  # (K, 3)
    total = (profile.weight[:, None] * density * 2.0 * np.sin(2.0 * profile.theta_v)[:, None]).sum(axis=0)
    np.testing.assert_allclose(total, energy, rtol=2e-3)
    with pytest.raises(BadInputError):
        view_profile(brdf, grid, 10, 2, edges_deg=(0.0, 45.0, 80.0))


@pytest.mark.parametrize("s", [32, 256])
def test_phong_is_the_same_in_every_band_and_matches_rh02(s):
    """Phong's ρ̂ = (s+1)/2π cos^s θ_i' does not depend on the view: every band has RH02's ε,
    and the bands rule gives RH02's closed form F ≈ sqrt(−s ln ε) with P = 0."""
    bands = choose_orders(f"phong:s={s}", eps=0.01)
    rh02 = choose_orders(f"phong:s={s}", eps=0.01, criterion="rh02")
    assert (bands.F, bands.P) == (rh02.F, rh02.P) and abs(bands.F - np.sqrt(-s * np.log(0.01))) <= 1
    eps = [b["eps"] for b in bands.view_bands()]
    np.testing.assert_allclose(eps, rh02.eps, rtol=1e-6)


def test_physically_based_lobe_rh02_rule_hides_grazing_error():
    """The issue's case: RH02's rule picks (7, 2) for microfacet σ = 0.3, whose point-light error
    is small at normal views and large near grazing; the bands rule meets ε in every band to 80°."""
    rh02 = choose_orders("microfacet:sigma=0.3", eps=EPS, criterion="rh02")
    assert (rh02.F, rh02.P) == (7, 2)
    at_rh02 = rh02.view_bands()
    assert at_rh02[0]["eps"] < EPS < at_rh02[6]["eps"]  # 0–15° fine, 75–80° not
    bands = choose_orders("microfacet:sigma=0.3", eps=EPS)
    inside = [b["eps"] for b in bands.view_bands() if b["inside"]]
    assert max(inside) <= EPS and not bands.capped and bands.eps_rh02 > 0.0
    assert [b["inside"] for b in bands.view_bands()] == [True] * 7 + [False] * 2


@pytest.mark.slow
@pytest.mark.parametrize("spec", [
    "cook-torrance:alpha=0.092,f0=0.1",
    "cook-torrance:alpha=0.05,f0=0.9,dist=ggx",
    "cook-torrance:alpha=0.5,f0=0.04",
    "cook-torrance:kd=0.2/0.1/0.05,ks=1,alpha=0.3,f0=0.9/0.6/0.3,dist=ggx",
])
def test_physically_based_materials_get_uncapped_orders(spec):
    """Cook–Torrance and GGX with Fresnel and Smith shadowing: capped under RH02's rule (ε over all
    views is dominated by θ_v > 80°), uncapped under the bands rule with default caps."""
    o = choose_orders(spec, eps=EPS)
    assert not o.capped and o.eps <= EPS and o.converged, o.message
    assert o.eps_rh02 > EPS  # what RH02's rule would have to meet at these orders


@pytest.mark.slow
def test_cornell_fits_get_uncapped_orders(shared_data):
    """The Cornell measurements, fitted by Cook–Torrance (``shrm fit``'s model for them): the
    glossy fits (garnet_red α ≈ 0.16, krylon_blue α ≈ 0.09, f0 down to 0.03) meet ε in every
    band with default caps; a near-mirror fit (acryl_blue, α ≈ 0.008) needs F beyond what the
    caps allow — reported as capped, with the error left stated (> 0), never silently."""
    from shrmkit.analysis.fit import fit_brdf

    cornell = shared_data / "brdf" / "cornell"
    for name in ("garnet_red", "krylon_blue"):
        fit = fit_brdf(cornell / f"{name}.brdf", "cook-torrance", n_samples=8192, starts=2)
        assert fit.params["alpha"] >= 0.05
        o = choose_orders(fit.brdf, eps=EPS)
        assert not o.capped and o.eps <= EPS, (name, o.F, o.P, o.message)
    fit = fit_brdf(cornell / "acryl_blue.brdf", "cook-torrance", n_samples=8192, starts=2)
    o = choose_orders(fit.brdf, eps=EPS, max_F=96)
    assert fit.params["alpha"] < 0.02 and o.capped and o.eps > EPS and "not met within the caps" in o.message


def test_scene_orders_come_from_the_product_spectrum():
    """F_B from the reflected field's own spectrum per band (DESIGN §4), not min(F_ρ, F_L): a
    one-pixel sun (flat spectrum) under microfacet σ = 0.1 gets more than RH02's F_ρ, because its
    grazing bands need it; a sharp Phong lobe under a disc light gets less than F_ρ, because the
    light has little energy there. Both meet ε in every band inside the limit, and the statement
    at RH02's F_B shows what min() misses."""
    from shrmkit.analysis.view_bands import shrm_view_bands

    cases = [("builtin:sun,height=256", "microfacet:sigma=0.1", "more"),
             ("builtin:spot,height=256,radius=5.5,value=50,background=0.2,elevation=30", "phong:s=3000", "less")]
    for env_spec, spec, expect in cases:
        env = shrmkit.load_env(env_spec)
        bands = choose_orders(spec, eps=EPS)
        rh02 = choose_orders(spec, eps=EPS, criterion="rh02")
        lighting = lighting_coefficients(env.radiance, min(env.height - 1, bands.coefficients.F0))
        s_bands, s_rh02 = scene_orders(bands, lighting), scene_orders(rh02, lighting)
        assert s_rh02.F_B == min(rh02.F, s_rh02.F_L)
        assert (s_bands.F_B > s_rh02.F_B) if expect == "more" else (s_bands.F_B < s_rh02.F_B), (s_bands, s_rh02)
        assert not s_bands.capped
        assert max(b["predicted_rel_rms"] for b in s_bands.view_bands if b["inside"]) <= np.sqrt(EPS) + 1e-9
        if expect == "more":
            at_min = shrm_view_bands(bands.profile, bands.coefficients_for(bands.P), lighting.band_energy(),
                                     s_rh02.F_B, bands.P).bands
            assert max(b["predicted_rel_rms"] for b in at_min if b["inside"]) > np.sqrt(EPS)


CASES = [
    ("grace", "microfacet:sigma=0.05"), ("grace", "microfacet:sigma=0.3"), ("grace", "phong:s=1000"),
    ("grace", "cook-torrance:alpha=0.092,f0=0.1"),
    ("sun", "microfacet:sigma=0.1"), ("sun", "phong:s=32"), ("sun", "cook-torrance:alpha=0.3,dist=ggx"),
    ("venice", "cook-torrance:alpha=0.1,dist=ggx"), ("venice", "phong:s=1000"),
]


@pytest.mark.slow
@pytest.mark.parametrize("env_name, spec", CASES)
def test_band_statement_holds_against_brute_force(shared_data, env_name, spec):
    """Per band: the measured relative RMS (brute force, ± s.e.) is within its Monte Carlo error
    of the prediction, never above the bound (2 s.e. allowance), the bound is at most 3× loose in
    the median band, and inside the view limit the README promise 2√ε + 1 % holds unless the
    scene's F_B is capped by the map (then the bound says so). The one-pixel sun keeps its sun in
    the map (``lights="none"``): the statement's hardest case (with the sun taken out as a light the
    residual is a constant sky: tests/analysis/test_lights.py); Grace and venice_sunset use the
    default, so their statements include the lights (whole-map relative errors)."""
    env = _env(env_name, shared_data)
    brdf = shrmkit.load_brdf(spec)
    shrm = prefilter(env, brdf, eps=EPS, lights="none" if env_name == "sun" else "auto")
    # Grace's many bright windows make the focused sampler's weights heavy-tailed: its standard error
    # is optimistic at 200 pairs a band there (a 4 s.e. outlier seen), so 400
    measured = _measure(shrm, env, brdf, per_band=400 if env_name == "grace" else 200)
    ratios = []
    for band, m in zip(shrm.meta["view_bands"], measured, strict=True):
        got, se = m["measured_rel_rms"], m["stderr"]
        assert band["predicted_rel_rms"] > 0.0
        assert got - 2.0 * se <= band["bound_rel_rms"], (band, m)
        assert abs(got - band["predicted_rel_rms"]) <= 3.0 * se + 0.15 * band["predicted_rel_rms"], (band, m)
        ratios.append(band["bound_rel_rms"] / got)
        if band["inside"] and not shrm.meta["scene_capped"]:
            assert got - 2.0 * se <= PROMISE, (band, m)
    assert np.median(ratios) <= 3.0
    assert shrm.meta["negative_after"] <= max(WINDOW_THRESHOLD, shrm.meta["negative_before"] or 0.0)


def test_capped_orders_state_a_nonzero_error_that_is_not_exceeded():
    """Caps reached (ε = 1e-4 with small caps): the stated error is > 0 and at least the measured
    one, in every band (the issue: eps["reflected"] was exactly 0 while 2–8 % was measured)."""
    env = shrmkit.load_env("builtin:studio,height=32")
    brdf = shrmkit.load_brdf("microfacet:sigma=0.3")
    shrm = prefilter(env, brdf, eps=1e-4, max_F=12, max_P=2, window="none")
    assert shrm.eps["reflected"] > 0.0 and shrm.eps["bound"] >= shrm.eps["reflected"]
    R, V, theta_v = sample_pairs(3000, seed=2, max_view_deg=89.9)
    ref = reference_radiance(env, brdf, R, V)
    measured = band_relative_rms(shrm.radiance(R, V), ref, theta_v, DEFAULT_BAND_EDGES_DEG)
    for band, m in zip(shrm.meta["view_bands"], measured, strict=True):
        assert band["bound_rel_rms"] >= band["predicted_rel_rms"] > 1e-3
        assert m["measured_rel_rms"] - 2.0 * m["stderr"] <= band["bound_rel_rms"], (band, m)


def test_budget_shrunk_map_is_counted():
    """A map shrunk below what the error needs (here 24 rows for F ≈ 46) adds bilinear-lookup
    error: the statement grows with it, and still bounds the measured error. The default size is
    the smallest whose lookup adds at most 1 % of ε to any band's predicted error energy, far
    below RH02's S ≈ 10F (``analysis.map_size.map_rows``)."""
    from shrmkit.analysis.map_size import MAP_ERROR_SHARE

    env = shrmkit.load_env("builtin:studio,height=64")
    brdf = shrmkit.load_brdf("phong:s=400")
    # the energy rule's F (the pixel rule raises it to where the bound needs RH02's 10 F anyway)
    fine = prefilter(env, brdf, eps=EPS, window="none", pixel_rule=False)
    rh02_size = prefilter(env, brdf, eps=EPS, window="none", size=10 * fine.F, pixel_rule=False)
    coarse = prefilter(env, brdf, eps=EPS, window="none", size=24, pixel_rule=False)
    assert coarse.F == fine.F == rh02_size.F and 24 < fine.height < 10 * fine.F
    for default, exact in zip(fine.meta["view_bands"], rh02_size.meta["view_bands"], strict=True):
        assert default["map_rel_rms"] ** 2 - exact["map_rel_rms"] ** 2 <= MAP_ERROR_SHARE * EPS
    assert coarse.meta["view_bands"][0]["map_rel_rms"] > 5 * rh02_size.meta["view_bands"][0]["map_rel_rms"]
    R, V, theta_v = sample_pairs(2000, seed=4, max_view_deg=89.9)
    ref = reference_radiance(env, brdf, R, V)
    got = relative_rms(coarse.radiance(R, V), ref)
    assert got <= max(b["bound_rel_rms"] for b in coarse.meta["view_bands"])
    assert got >= 0.5 * min(b["predicted_rel_rms"] for b in coarse.meta["view_bands"])


def test_missing_measurements_are_marked_extrapolated(tmp_path):
    """A MERL table with no data beyond θ_h index 60: the bands whose samples fell in the hole say
    so, and their bound is flagged as not holding there (DESIGN §7)."""
    from shrmkit.brdf_io.merl import tabulate_merl, write_merl

    values = tabulate_merl(shrmkit.load_brdf("microfacet:sigma=0.3"))
    values[:, 60:, :, :] = np.nan
    path = write_merl(tmp_path / "holes.binary", values)
    o = choose_orders(shrmkit.load_brdf(path), eps=0.1, max_F=24, max_P=3)
    bands = o.view_bands()
    assert any(b["extrapolated_samples"] > 0 for b in bands)
    env = shrmkit.load_env("builtin:studio,height=16")
    shrm = prefilter(env, path, eps=0.1, max_F=24, max_P=3)
    flagged = [b for b in shrm.meta["view_bands"] if b["extrapolated_samples"]]
    assert flagged and all(not b["bound_holds"] for b in flagged)
    assert shrm.meta["extrapolated_samples"] > 0


def test_bad_rule_arguments_are_refused():
    with pytest.raises(BadInputError):
        choose_orders("phong:s=8", criterion="energy")
    with pytest.raises(BadInputError):
        choose_orders("phong:s=8", max_view_deg=0.0)
    with pytest.raises(BadInputError):
        prefilter("builtin:constant,height=8", "phong:s=8", max_view_deg=91.0)


def test_a_channel_without_energy_in_a_band_does_not_decide_the_orders():
    """Red channel specular-only with f0 = 0 (Schlick: no reflection at normal incidence, as a
    Cornell fit produced): its relative error where it carries nothing is invisible and must not
    drive ε above 1 (it made the rule return F = P = 0, 'capped', ε = 1.0017)."""
    o = choose_orders("cook-torrance:kd=0/0.03/0.05,ks=0.16,alpha=0.2,f0=0", eps=EPS, max_F=64)
    assert not o.capped and 0.0 < o.eps <= EPS and o.F > 10
    assert all(0.0 <= b["eps"] <= 1.0 for b in o.view_bands())


@pytest.mark.parametrize("spec, F, P", [("microfacet:sigma=0.1", 72, 10), ("cook-torrance:alpha=0.1,dist=ggx", 60, 14),
                                        ("lambert:albedo=0.5", 4, 5)])
def test_projected_eps_from_the_profile_matches_the_3d_quadrature(spec, F, P):
    """RH02's ε by the view profile's band nodes against eq. 13 on an oversampled 3-D grid."""
    from shrmkit.analysis.brdf_coeffs import rho_lpq
    from shrmkit.analysis.orders import eps_table
    from shrmkit.analysis.view_bands import projected_eps

    brdf = shrmkit.load_brdf(spec)
    grid = ReparamGrid.for_orders(F, P)
    profile = view_profile(brdf, grid, grid.n_theta_i - 1, P + 2)
    fine = ReparamGrid.for_orders(F, P, oversample=1.5)
    reference = eps_table(rho_lpq(reparameterize(brdf, fine), F, P))[F, P]
    assert projected_eps(profile, F, P) == pytest.approx(reference, rel=0.01)
