"""``shrmkit.compare``: the table's numbers against independent computations.

References: the SHRM storage (P+1)²·H·W·3·4 bytes and the relative RMS of the closed form;
the angular reference (analysis.reference) recomputed here on the same pairs.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from shrmkit.analysis.compare import compare
from shrmkit.analysis.compare.pairs import sample_pairs
from shrmkit.analysis.compare.table import relative_rms
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import prefilter
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.specs import load_brdf


@pytest.fixture(scope="module")
def small():
    env = load_env("builtin:studio,height=16")
    result = compare("microfacet:sigma=0.3", env, n_pairs=200, lobes=(1,), n_elevations=4,
                     cabral_reference_height=8)
    return env, result


def test_relative_rms_closed_form() -> None:
    assert relative_rms(np.array([1.0, 2.0]), np.array([1.0, 1.0])) == pytest.approx(np.sqrt(1.0 / 2.0))
    assert np.isnan(relative_rms(np.ones(3), np.zeros(3)))


def test_sample_pairs_geometry() -> None:
    """R is the mirror of V about N with angle(N, V) = θ_v: R·V = cos 2θ_v; θ_v spans [0, max]."""
    R, V, tv = sample_pairs(500, seed=1, max_view_deg=88.0)
    np.testing.assert_allclose(np.sum(R * V, axis=1), np.cos(2.0 * tv), atol=1e-12)
    assert tv.min() < np.radians(1.0) and np.radians(87.0) < tv.max() <= np.radians(88.0)
    assert np.mean(tv > np.radians(70.0)) == pytest.approx(18.0 / 88.0, abs=0.01)


def test_table_rows_json_and_independent_numbers(small) -> None:
    env, result = small
    json.dumps(result)  # JSON-able as returned
    keys = [r["key"] for r in result["rows"]]
    assert keys == ["shrm", "shrm_low_p", "kautz_mccool", "cabral_shrm", "cabral_reference", "gaussian_k1"]
    rows = {r["key"]: r for r in result["rows"]}
    shrm = prefilter(env, load_brdf("microfacet:sigma=0.3"), eps=0.03)
    p = rows["shrm"]["params"]
    assert (p["F"], p["P"]) == (shrm.F, shrm.P)
    assert rows["shrm"]["storage_bytes"] == (shrm.P + 1) ** 2 * shrm.height * shrm.width * 3 * 4
    assert rows["cabral_reference"]["storage_bytes"] == 12 * 8 * 16 * 3 * 4
    # the SHRM's error recomputed from scratch on the same pairs
    R, V, _ = sample_pairs(200, seed=0, max_view_deg=88.0)
    ref = reference_radiance(env, load_brdf("microfacet:sigma=0.3"), R, V)
    assert rows["shrm"]["rel_rms"] == pytest.approx(relative_rms(shrm.radiance(R, V), ref), rel=1e-6)
    for r in result["rows"]:
        assert np.isfinite(r["rel_rms"]) and r["precompute_s"] > 0 and r["storage_bytes"] > 0
    assert rows["shrm"]["rel_rms"] < rows["shrm_low_p"]["rel_rms"]
    assert result["markdown"].count("\n|") == len(keys) + 2


def test_compare_bad_input() -> None:
    env = load_env("builtin:studio,height=16")
    with pytest.raises(BadInputError, match="eps"):
        compare("phong:s=4", env, eps=1.5)
    with pytest.raises(BadInputError, match="n_pairs"):
        compare("phong:s=4", env, n_pairs=3)


def test_compare_refuses_scattered_measurements(shared_data) -> None:
    with pytest.raises(BadInputError, match="fit"):
        compare(shared_data / "brdf" / "cornell" / "krylon_blue.brdf", "builtin:studio,height=16")
