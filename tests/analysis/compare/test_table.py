"""``shrmkit.compare``: the table's numbers against independent computations.

References: the SHRM storage (P+1)²·H·W·3·4 bytes and the relative RMS of the closed form;
the angular reference (analysis.reference) recomputed here on the same pairs.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from shrmkit.analysis.compare import (
    REGISTRY,
    BuildContext,
    BuiltRepresentation,
    CompareOptions,
    Representation,
    compare,
    compare_representations,
    relative_rms,
    sample_pairs,
)
from shrmkit.analysis.compare import registry as registry_module
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import prefilter
from shrmkit.analysis.tolerance import DEFAULT_EPS
from shrmkit.brdf_io.envmap import load_env
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.specs import load_brdf

KEYS = ["shrm", "shrm_low_p", "kautz_mccool", "rsibr", "rsibr_reference", "gaussian_lobes_k1"]


@pytest.fixture(scope="module")
def small():
    env = load_env("builtin:studio,height=16")
    options = CompareOptions(n_pairs=200, lobes=(1,), elevations=4, rsibr_reference_height=8)
    return env, compare_representations("microfacet:sigma=0.3", env, options)


def test_relative_rms_closed_form() -> None:
    assert relative_rms(np.array([1.0, 2.0]), np.array([1.0, 1.0])) == pytest.approx(np.sqrt(1.0 / 2.0))
    assert np.isnan(relative_rms(np.ones(3), np.zeros(3)))
    assert np.isnan(relative_rms(np.ones((0, 3)), np.ones((0, 3))))
    with pytest.raises(ValueError, match="shape"):
        relative_rms(np.ones(3), np.ones(2))


def test_sample_pairs_geometry() -> None:
    """R is the mirror of V about N with angle(N, V) = θ_v: R·V = cos 2θ_v; θ_v spans [0, max]
    stratified uniformly in angle (one sample per stratum)."""
    R, V, tv = sample_pairs(500, seed=1, max_view_deg=88.0)
    np.testing.assert_allclose(np.sum(R * V, axis=1), np.cos(2.0 * tv), atol=1e-12)
    assert tv.min() < np.radians(1.0) and np.radians(87.0) < tv.max() <= np.radians(88.0)
    assert np.mean(tv > np.radians(70.0)) == pytest.approx(18.0 / 88.0, abs=0.01)
    strata = np.floor(np.sort(tv) / np.radians(88.0) * 500).astype(int)
    np.testing.assert_array_equal(strata, np.arange(500))
    R2, V2, tv2 = sample_pairs(500, seed=1, max_view_deg=88.0)
    assert np.array_equal(R, R2) and np.array_equal(V, V2) and np.array_equal(tv, tv2)


def test_table_rows_json_and_independent_numbers(small) -> None:
    env, comparison = small
    result = comparison.result
    json.dumps(result)  # JSON-able as returned
    assert "strip" not in result
    keys = [r["key"] for r in result["rows"]]
    assert keys == KEYS
    rows = {r["key"]: r for r in result["rows"]}
    shrm = prefilter(env, load_brdf("microfacet:sigma=0.3"), eps=DEFAULT_EPS)
    p = rows["shrm"]["params"]
    assert (p["F"], p["P"]) == (shrm.F, shrm.P)
    assert result["eps"] == DEFAULT_EPS
    assert rows["shrm"]["storage_bytes"] == (shrm.P + 1) ** 2 * shrm.height * shrm.width * 3 * 4
    assert rows["rsibr_reference"]["storage_bytes"] == 12 * 8 * 16 * 3 * 4
    # the SHRM's error recomputed from scratch on the same pairs
    R, V, _ = sample_pairs(200, seed=0, max_view_deg=88.0)
    ref = reference_radiance(env, load_brdf("microfacet:sigma=0.3"), R, V)
    assert rows["shrm"]["rel_rms"] == pytest.approx(relative_rms(shrm.radiance(R, V), ref), rel=1e-6)
    for r in result["rows"]:
        assert np.isfinite(r["rel_rms"]) and r["precompute_s"] > 0 and r["storage_bytes"] > 0
    assert rows["shrm"]["rel_rms"] < rows["shrm_low_p"]["rel_rms"]
    # the comparison table (header, rule, one line per row), then the SHRM's per-band table
    # (header, rule, one line per view band)
    assert result["markdown"].count("\n|") == len(keys) + 2 + 2 + 9
    shrm_bands = rows["shrm"]["view_bands"]
    assert len(shrm_bands) == 9 and all("predicted_rel_rms" in b and "measured_rel_rms" in b for b in shrm_bands)
    assert all("predicted_rel_rms" not in b for b in rows["gaussian_lobes_k1"]["view_bands"])
    # every band measured on its own importance-sampled pairs
    assert all(b["n_pairs"] == result["band_pairs_per_band"] >= 16 for b in shrm_bands)
    assert all(b["measured_rel_rms"] > 0.0 and b["measured_stderr"] >= 0.0 for b in shrm_bands)


def test_representations_follow_the_protocol(small) -> None:
    """Every built representation satisfies :class:`Representation`: its radiance on the
    table's pairs is the row's error, its view map is float32 (H, W, 3), its short label fits
    a panel, and its update time is 0 exactly for the static Gaussian lobes."""
    env, comparison = small
    reps = comparison.representations
    assert [rep.key for rep in reps] == KEYS
    assert comparison.env is not None and comparison.brdf.name == "microfacet:sigma=0.3"
    R, V, _ = sample_pairs(200, seed=0, max_view_deg=88.0)
    ref = reference_radiance(comparison.env, comparison.brdf, R, V)
    view = np.array([0.0, 0.6, 0.8])
    for rep, row in zip(reps, comparison.result["rows"], strict=True):
        assert isinstance(rep, Representation)
        assert rep.label == row["label"] and 0 < len(rep.short_label) <= 10
        assert relative_rms(rep.radiance(R, V), ref) == pytest.approx(row["rel_rms"], rel=1e-9)
        image = rep.view_map(view)
        assert image.dtype == np.float32 and image.ndim == 3 and image.shape[2] == 3
        assert np.all(np.isfinite(image))
        assert (rep.update_s == 0.0) == rep.key.startswith("gaussian")
    shrm = reps[0]
    assert shrm.short_label == f"SHRM P={shrm.params['P']}"
    assert [rep.short_label for rep in reps[2:]] == [f"KM P={shrm.params['P']}", "RSIBR", "RSIBR ref", "Lobes K=1"]


def test_registry_kinds_and_a_new_kind(monkeypatch) -> None:
    """The registry lists one builder per kind, in row order; a new kind is one entry (here a
    constant-radiance representation replacing them all) and shows up as a row."""
    assert list(REGISTRY) == ["shrm", "shrm_low_p", "kautz_mccool", "rsibr", "rsibr_reference", "gaussian_lobes"]

    class Constant:
        def radiance(self, R: np.ndarray, V: np.ndarray) -> np.ndarray:
            return np.ones((len(R), 3))

        def view_map(self, view: np.ndarray) -> np.ndarray:
            return np.ones((4, 8, 3), np.float32)

    def build_constant(ctx: BuildContext) -> list[BuiltRepresentation]:
        return [ctx.make("constant", "constant 1", "one", Constant(), storage_bytes=12, precompute_s=0.0,
                         params={"value": 1.0})]

    monkeypatch.setattr(registry_module, "REGISTRY", {"constant": build_constant})
    comparison = compare_representations("phong:s=4", "builtin:studio,height=8", CompareOptions(n_pairs=10))
    (row,) = comparison.result["rows"]
    assert (row["key"], row["label"], row["storage_bytes"], row["params"]) == ("constant", "constant 1", 12,
                                                                                {"value": 1.0})
    assert row["update_s"] > 0 and np.isfinite(row["rel_rms"])


def test_options_validation() -> None:
    assert CompareOptions().eps == DEFAULT_EPS
    assert CompareOptions(lobes=[2, 3]).lobes == (2, 3)
    for bad, match in (({"eps": 1.5}, "eps"), ({"n_pairs": 3}, "n_pairs"), ({"lobes": (9,)}, "lobes"),
                       ({"sample_max_view_deg": 90.0}, "sample_max_view_deg"), ({"elevations": 0}, "elevations"),
                       ({"update_view": (0.0, 0.0, 0.0)}, "update_view")):
        with pytest.raises(BadInputError, match=match):
            CompareOptions(**bad)
    with pytest.raises(TypeError):
        CompareOptions(0.1)  # eps is keyword-only


def test_compare_bad_input() -> None:
    env = load_env("builtin:studio,height=16")
    with pytest.raises(BadInputError, match="eps"):
        compare("phong:s=4", env, eps=1.5)
    with pytest.raises(BadInputError, match="n_pairs"):
        compare("phong:s=4", env, n_pairs=3)


def test_compare_strip_options_moved_to_render() -> None:
    """compare() computes numbers only: the strip options name the render-side function."""
    for name, value in (("strip", "strip.png"), ("strip_size", 32), ("mesh", None)):
        with pytest.raises(TypeError, match="write_strip"):
            compare("phong:s=4", "builtin:studio,height=8", **{name: value})
    with pytest.raises(TypeError):
        compare("phong:s=4", "builtin:studio,height=8", no_such_option=1)


def test_compare_refuses_scattered_measurements(shared_data) -> None:
    with pytest.raises(BadInputError, match="fit"):
        compare(shared_data / "brdf" / "cornell" / "krylon_blue.brdf", "builtin:studio,height=16")
