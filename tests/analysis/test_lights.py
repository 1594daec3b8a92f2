"""Bright lights as lights (analysis.lights, DESIGN §5a) against independent references.

References: exact sums over the map's pixels (flux conservation, the one-pixel sun's closed
form), brute-force angular integration (``analysis.reference``: the lights' samples are the
pixels it sums, so lights + residual reproduce it to rounding), and per-band / away-from-the-light
errors of the prefiltered scene against it.
"""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.compare import band_pairs, band_relative_rms, sample_pairs
from shrmkit.analysis.lights import (
    MAX_LIGHTS,
    MAX_SAMPLES_PER_LIGHT,
    LightSet,
    check_lights,
    extract_lights,
    light_radiance,
)
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG
from shrmkit.brdf_io.envmap import EnvironmentMap
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.latlong import pixel_directions, row_solid_angles

EPS = 0.03


def _flux(radiance: np.ndarray) -> np.ndarray:
    h, w = radiance.shape[:2]
    return np.einsum("h,hwc->c", row_solid_angles(h, w), np.asarray(radiance, dtype=np.float64))


def _map_with(height: int, spots: list[tuple[int, int, float]], background: float = 0.05) -> EnvironmentMap:
    """A constant map with bright pixels at (row, column, radiance)."""
    image = np.full((height, 2 * height, 3), background)
    for row, col, value in spots:
        image[row, col] = value
    return EnvironmentMap(image, name="spots")


def test_one_pixel_sun_is_one_light_and_the_sky_is_left_exactly():
    """builtin:sun: one pixel at ratio × sky in a constant sky. Closed form: one light, one sample at
    that pixel's centre with power (ratio − 1)·sky·Ω, and the residual is the constant sky."""
    env = shrmkit.load_env("builtin:sun,height=64")
    got = extract_lights(env)
    sky = float(np.median(env.radiance))
    row, col = np.unravel_index(np.argmax(env.radiance[..., 1]), env.radiance.shape[:2])
    omega = row_solid_angles(64, 128)[row]
    assert len(got.lights.lights) == 1 and len(got.lights) == 1
    np.testing.assert_allclose(got.lights.directions[0], pixel_directions(64, 128)[row, col], atol=1e-12)
    np.testing.assert_allclose(got.lights.power[0], (env.radiance[row, col] - sky) * omega, rtol=1e-12)
    np.testing.assert_allclose(got.residual.radiance, sky, rtol=1e-6)
    assert got.lights.lights[0].merge_deg == 0.0 and got.lights.lights[0].pixels == 1


@pytest.mark.parametrize("spec", ["builtin:sky,height=128", "builtin:sun,height=32"])
def test_lights_plus_residual_is_the_map(spec, shared_data):
    """Per pixel residual <= original, >= 0, and the flux is conserved to rounding; with the real
    Grace probe too (several merged lights)."""
    envs = [shrmkit.load_env(spec),
            shrmkit.load_env(shared_data / "env" / "grace_latlong.exr", up="y", flip=True, height=256)]
    for env in envs:
        got = extract_lights(env)
        assert len(got.lights) > 0
        assert np.all(got.residual.radiance <= env.radiance) and np.all(got.residual.radiance >= 0.0)
        total = _flux(env.radiance)
        np.testing.assert_allclose(_flux(got.residual.radiance) + got.lights.total_power, total, rtol=1e-12)
        assert all(light.samples <= MAX_SAMPLES_PER_LIGHT for light in got.lights.lights)


def test_lights_and_residual_reproduce_the_angular_reference():
    """The samples of unmerged lights are pixels as the reference reads them: reference(map) =
    reference(residual) + Σ ρ̂ E_k to rounding, for a physically based lobe at grazing views too."""
    env = _map_with(32, [(10, 7, 500.0), (12, 40, 300.0), (20, 63, 800.0)])
    got = extract_lights(env)
    assert len(got.lights.lights) == 3 and len(got.lights) == 3
    brdf = shrmkit.load_brdf("cook-torrance:alpha=0.2,f0=0.5,dist=ggx")
    R, V, _ = sample_pairs(400, seed=3, max_view_deg=89.0)
    whole = reference_radiance(env, brdf, R, V)
    split = reference_radiance(got.residual, brdf, R, V) + got.lights.radiance(brdf, R, V)
    np.testing.assert_allclose(split, whole, rtol=1e-9, atol=1e-12 * np.abs(whole).max())


def test_regions_join_across_the_seam_and_around_the_pole():
    """A bright region split by the φ = 0 seam is one light; pixels of the first row on opposite
    sides of the pole touch it and are one light."""
    env = _map_with(32, [(15, 0, 400.0), (15, 63, 400.0), (0, 5, 400.0), (0, 37, 400.0)])
    got = extract_lights(env)
    assert len(got.lights.lights) == 2
    assert sorted(light.pixels for light in got.lights.lights) == [2, 2]


def test_large_bright_regions_stay_in_the_map_and_counts_are_limited():
    """A bright region wider than a 5° cap is smooth enough for the SHRM and is left; lights=N keeps
    the N brightest; lights='none' none."""
    image = np.full((32, 64, 3), 0.05)
    image[4:12, 10:30] = 50.0  # ~45° × 110°: not a light
    image[20, 50] = 400.0
    image[22, 10] = 300.0
    env = EnvironmentMap(image, name="wide")
    got = extract_lights(env)
    assert len(got.lights.lights) == 2 and got.skipped == 1
    one = extract_lights(env, 1)
    assert len(one.lights.lights) == 1 and one.lights.lights[0].power[0] > got.lights.lights[1].power[0]
    assert len(extract_lights(env, "none").lights) == 0 and extract_lights(env, 0).residual is env


def test_lights_option_has_one_validator():
    assert check_lights("auto") == "auto" and check_lights("None") == "none" and check_lights("3") == 3
    assert check_lights(0) == "none"
    for bad in ("many", -1, MAX_LIGHTS + 1, 2.5, None, True):
        with pytest.raises(BadInputError, match="lights"):
            check_lights(bad)
    with pytest.raises(BadInputError, match="lights"):
        shrmkit.prefilter("builtin:sun,height=16", "phong:s=8", lights="bright")


def test_light_radiance_of_no_light_is_zero_and_bad_samples_are_refused():
    R = np.array([[0.0, 0.0, 1.0]])
    assert np.all(light_radiance(shrmkit.load_brdf("phong:s=8"), np.zeros((0, 3)), np.zeros((0, 3)), R, R) == 0.0)
    with pytest.raises(BadInputError):
        LightSet(np.array([[0.0, 0.0, 1.0]]), np.array([[-1.0, 0.0, 0.0]]), np.array([0]))
    with pytest.raises(BadInputError):
        LightSet(np.array([[0.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]), np.array([0]))


@pytest.mark.parametrize("spec", [
    "microfacet:sigma=0.05", "microfacet:sigma=0.1", "microfacet:sigma=0.3", "phong:s=32", "phong:s=512",
    "cook-torrance:alpha=0.1,dist=ggx", "cook-torrance:alpha=0.3,dist=ggx",
])
def test_one_pixel_sun_needs_low_orders_and_its_statement_holds(spec):
    """The issue's target: under a one-pixel sun (10⁵× the sky) F_B <= 30 (it was 79–127 for these
    lobes), and per view band the measured relative RMS (brute force, ± s.e.) is within the bound."""
    env = shrmkit.load_env("builtin:sun,height=64,elevation=35,azimuth=20")
    brdf = shrmkit.load_brdf(spec)
    shrm = shrmkit.prefilter(env, brdf, eps=EPS)
    assert shrm.has_lights and shrm.F <= 30, (shrm.F, shrm.meta["window_reason"])
    R, V, theta_v, w = band_pairs(env.radiance, 60, DEFAULT_BAND_EDGES_DEG, seed=4)
    measured = band_relative_rms(shrm.radiance(R, V), reference_radiance(env, brdf, R, V), theta_v,
                                 DEFAULT_BAND_EDGES_DEG, w)
    for band, m in zip(shrm.meta["view_bands"], measured, strict=True):
        assert m["measured_rel_rms"] - 2.0 * m["stderr"] <= band["bound_rel_rms"], (band, m)
        if band["inside"]:
            assert m["measured_rel_rms"] - 2.0 * m["stderr"] <= 2.0 * np.sqrt(EPS) + 0.01


@pytest.mark.slow
def test_statement_holds_away_from_the_sun():
    """The issue's case: Phong s = 512 under builtin:sky. Without lights the statement is an average
    the sun dominates (the error over the directions farther than 6° from it is ~3× the bound);
    with them, the residual statement holds there, and the whole-map statement on average."""
    env = shrmkit.load_env("builtin:sky,height=128")
    brdf = shrmkit.load_brdf("phong:s=512")
    R, V, _ = sample_pairs(3000, seed=7, max_view_deg=80.0)
    ref = reference_radiance(env, brdf, R, V)
    sun = pixel_directions(128, 256)[np.unravel_index(np.argmax(env.radiance[..., 1]), (128, 256))]
    far = R @ sun < np.cos(np.radians(6.0))

    def rel(a, b):
        return float(np.sqrt(((a - b) ** 2).sum() / (b**2).sum()))

    bare = shrmkit.prefilter(env, brdf, eps=EPS, lights="none")
    bare_bound = max(b["bound_rel_rms"] for b in bare.meta["view_bands"] if b["inside"])
    assert rel(bare.radiance(R, V)[far], ref[far]) > 2.0 * bare_bound  # the failure the lights remove
    lit = shrmkit.prefilter(env, brdf, eps=EPS)
    assert lit.has_lights
    residual_bound = max(b["bound_rel_rms_residual"] for b in lit.meta["view_bands"] if b["inside"])
    whole_bound = max(b["bound_rel_rms"] for b in lit.meta["view_bands"] if b["inside"])
    assert rel(lit.radiance(R, V)[far], ref[far]) <= residual_bound
    assert rel(lit.radiance(R, V), ref) <= whole_bound * 1.1
    assert lit.F < bare.F


def test_shrm_with_lights_round_trips_and_refuses_broken_light_arrays(tmp_path):
    env = shrmkit.load_env("builtin:sky,height=32")
    shrm = shrmkit.prefilter(env, "microfacet:sigma=0.2", eps=0.1)
    assert shrm.has_lights and shrm.meta["lights_brdf"] == "microfacet:sigma=0.2"
    back = shrmkit.load_shrm(shrm.save(tmp_path / "lit.shrm.npz"))
    R, V, _ = sample_pairs(100, seed=1)
    np.testing.assert_array_equal(back.radiance(R, V), shrm.radiance(R, V))
    np.testing.assert_array_equal(back.radiance(R, V, lights=False) + back.light_radiance(R, V),
                                  shrm.radiance(R, V))
    # a file with part of the light arrays, or lights without a BRDF, is refused naming the file
    with np.load(tmp_path / "lit.shrm.npz") as npz:
        arrays = {key: npz[key] for key in npz.files}
    partial = dict(arrays)
    del partial["light_power"]
    np.savez(tmp_path / "partial.shrm.npz", **partial)
    with pytest.raises(BadInputError, match="partial.shrm.npz.*light arrays"):
        shrmkit.load_shrm(tmp_path / "partial.shrm.npz")
    negative = dict(arrays)
    negative["light_power"] = -arrays["light_power"]
    np.savez(tmp_path / "negative.shrm.npz", **negative)
    with pytest.raises(BadInputError, match="negative.shrm.npz"):
        shrmkit.load_shrm(tmp_path / "negative.shrm.npz")
