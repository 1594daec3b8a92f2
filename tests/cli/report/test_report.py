"""Per-BRDF reports: schema (data_specs/report_json.md), closed-form anchors, reproducibility.

References used: RH02 Appendix D (Phong needs F ≈ sqrt(−s ln ε), P = 0); closed-form
directional albedos (Lambert: a = albedo; a normalized Phong lobe seen at normal
incidence: a = 1; a Lafortune lobe at normal incidence: kd + ks·2π/(n + 2)); Helmholtz
reciprocity of the Lafortune model (exact) and the non-reciprocity of Phong's ρ = ρ̂/cos θ_i.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import shrmkit
from shrmkit.cli.report.collect import collect_report, strip_timings
from shrmkit.cli.report.options import profile
from shrmkit.render.preview import PreviewImage

NUM = (int, float)
OPT_NUM = (int, float, type(None))
STR = str
OPT_STR = (str, type(None))

# The schema of data_specs/report_json.md, written out independently of the code:
# key -> type, tuple of types, nested dict, or [item schema] for arrays.
RGB = [NUM]
OPTIONS = {
    "eps": NUM, "tolerances": [NUM], "envs": [STR], "env_height": int, "env_up": OPT_STR, "env_flip": bool,
    "env_azimuth": NUM, "models": [STR], "lobes": int,
    "fit_samples": int, "fit_starts": int, "n_pairs": int, "seed": int, "max_F": int, "max_P": int,
    "preview": STR, "preview_size": int, "mesh": OPT_STR, "albedo_nodes": int, "profile": STR,
}
COMMON = {
    "format": STR, "format_version": int, "status": STR, "name": STR, "source": STR, "options": OPTIONS,
    "error": OPT_STR, "provenance": {"shrmkit_version": STR, "numpy_version": STR}, "total_seconds": NUM,
}
OK_SCHEMA = {
    **COMMON,
    "brdf": {"name": STR, "kind": STR, "analysis_of": STR},
    "orders": [{"tolerance": NUM, "F": int, "P": int, "eps": NUM, "capped": bool, "converged": bool,
                "n_without_data": int, "message": STR, "orders_seconds": NUM}],
    "main": {"tolerance": NUM, "F": int, "P": int, "eps": NUM},
    "eps_table": {"tolerance": NUM, "F0": int, "P0": int, "eps": [[NUM]]},
    "environments": [{"name": STR, "spec": STR, "height": int, "width": int, "eps_L_curve": [OPT_NUM],
                      "tolerance": NUM, "F_L": int, "lighting_capped": bool, "F_B": int, "P_B": int, "eps_B": NUM,
                      "bound": NUM,
                      "measured_rel_rms": NUM, "n_pairs": int, "max_view_deg": NUM,
                      "reference_seconds": NUM}],
    "speed_vs_error": [{"env": STR, "tolerance": NUM, "F_rho": int, "P_rho": int, "F_L": int, "F_B": int,
                        "P_B": int, "size": [int], "eps_brdf": NUM, "eps_lighting": NUM, "eps_B": NUM,
                        "bound": NUM, "sqrt_eps_B": NUM, "measured_rel_rms": NUM, "prefilter_seconds": NUM,
                        "orders_seconds": NUM, "lighting_seconds": NUM, "synthesis_seconds": NUM,
                        "reference_map_seconds": NUM, "prefilter_cpu_seconds": NUM,
                        "measured_worst_band_rel_rms": NUM, "measured_worst_band_stderr": NUM,
                        "reference_map_cpu_seconds": NUM}],
    "fits": [{"model": STR, "spec": STR, "params": dict, "errors": {"rel_rms": NUM, "log_rms": NUM},
              "bands": [{"lo_deg": NUM, "hi_deg": NUM, "n": int, "rel_rms": NUM, "log_rms": NUM}],
              "status": STR, "success": bool, "message": STR, "evaluations": int, "n_samples": int,
              "n_dropped": int, "error": type(None), "fit_seconds": NUM}],
    "fit_slices": {"theta_deg": [NUM], "measured": STR,
                   "views": [{"view_deg": NUM, "measured_theta_deg": [NUM], "measured_rgb": [RGB],
                              "fitted_rgb": dict}]},
    "data_checks": {"n_measurements": (int, type(None)), "n_missing": int,
                    "n_missing_above_surface": (int, type(None)), "n_clamped": int,
                    "reciprocity": {"method": STR, "n_pairs": int, "max_rel": OPT_NUM, "rms_rel": OPT_NUM,
                                    "median_pair_rel": OPT_NUM, "p90_pair_rel": OPT_NUM},
                    "albedo": {"of": STR, "views_deg": [NUM], "rgb": [RGB], "max": NUM, "max_view_deg": NUM,
                               "nodes": int}},
    "warnings": [{"code": STR, "message": STR}],
    "preview": {"mode": STR, "env": STR, "tolerance": NUM, "F": int, "P": int,
                "images": [{"key": STR, "file": STR, "renderer": STR}], "notes": [STR], "error": OPT_STR,
                "preview_seconds": NUM},
}
WARNING_CODES = {"missing_measurements", "clamped_values", "non_reciprocal", "energy_gain", "orders_capped",
                 "orders_not_converged", "fit_failed", "preview", "analysis_on_fit"}


def validate(doc, schema, where="report") -> list[str]:
    """Problems of ``doc`` against ``schema`` (empty list: valid)."""
    problems = []
    if isinstance(schema, dict):
        if not isinstance(doc, dict):
            return [f"{where}: expected an object, got {type(doc).__name__}"]
        for key, sub in schema.items():
            if key not in doc:
                problems.append(f"{where}: missing key {key!r}")
            else:
                problems += validate(doc[key], sub, f"{where}.{key}")
        return problems
    if isinstance(schema, list):
        if not isinstance(doc, list):
            return [f"{where}: expected an array, got {type(doc).__name__}"]
        for i, item in enumerate(doc):
            problems += validate(item, schema[0], f"{where}[{i}]")
        return problems
    types = schema if isinstance(schema, tuple) else (schema,)
    # JSON has no int/float split for whole floats, but bool is not a number
    if isinstance(doc, bool) and bool not in types:
        return [f"{where}: bool where {types} expected"]
    if int in types and float not in types and isinstance(doc, float):
        return [f"{where}: float {doc} where int expected"]
    if not isinstance(doc, types):
        return [f"{where}: {type(doc).__name__} where {types} expected"]
    return []


def test_validator_catches_problems():
    """The validator itself must fail on a missing key, a wrong type and a bad array item."""
    schema = {"a": int, "b": [{"c": STR}]}
    assert validate({"a": 1, "b": [{"c": "x"}]}, schema) == []
    assert validate({"b": []}, schema) == ["report: missing key 'a'"]
    assert validate({"a": 1.5, "b": []}, schema)
    assert validate({"a": 1, "b": [{"c": 3}]}, schema)
    assert validate({"a": True, "b": []}, schema)


#: 2000 pairs: the auto window's error (the blur of builtin:sky's sun) sits on few pairs, so 300
#: pairs measure √ε_B only to ±30 % (0.71–1.0 over seeds 0–3); 2000 pairs to a few %.
QUICK = dict(preview="cpu", models=("lafortune",), n_pairs=2000, preview_size=48)


@pytest.fixture(scope="module")
def phong_report():
    """One quick report of Phong s = 32 (analytic; its ρ is not reciprocal by definition)."""
    options = profile("quick", **QUICK)
    doc, previews = collect_report("phong:s=32", options)
    return doc, previews, options


class TestPhongReport:
    """The tests of the phong_report fixture: one unit of work under xdist (tests/conftest.py), one report."""

    def test_report_matches_documented_schema(self, phong_report):
        doc, previews, _ = phong_report
        assert validate(doc, OK_SCHEMA) == []
        assert doc["format"] == "shrmkit-report" and doc["format_version"] == 1 and doc["status"] == "ok"
        assert {w["code"] for w in doc["warnings"]} <= WARNING_CODES
        # strict JSON: no NaN/Inf survives
        json.dumps(doc, allow_nan=False)
        # the preview image file named in the JSON is a PNG that was produced
        # (beside the preview images come the explorer's lit sphere and the live views: explorer.py)
        previews = [p for p in previews if isinstance(p, PreviewImage)]
        assert [img["key"] for img in doc["preview"]["images"]] == [p.key for p in previews] == ["sphere"]
        assert previews[0].png[:8] == b"\x89PNG\r\n\x1a\n"

    def test_phong_orders_follow_rh02_appendix_d(self, phong_report):
        """F ≈ sqrt(−s ln ε) and P = 0 for Phong (RH02 Appendix D), at every tolerance of the report."""
        doc, _, options = phong_report
        assert [o["tolerance"] for o in doc["orders"]] == [0.1, 0.03, 0.01]
        for o in doc["orders"]:
            expected = math.sqrt(-32.0 * math.log(o["tolerance"]))
            assert abs(o["F"] - expected) <= 1.5, (o, expected)
            assert o["P"] == 0
            assert o["eps"] <= o["tolerance"]
        table = np.array(doc["eps_table"]["eps"])
        # the table is ε: 1 at F = 0 minus the l = 0 energy, decreasing in F and in P
        assert np.all(np.diff(table, axis=0) <= 1e-12) and np.all(np.diff(table, axis=1) <= 1e-12)

    def test_phong_is_flagged_non_reciprocal_and_albedo_is_one_at_normal_view(self, phong_report):
        """Phong defines ρ̂ = (s+1)/(2π) cos^s about the mirror direction: at normal view the lobe is
        the whole upper hemisphere and ∫ρ̂ dω = 1 exactly; ρ = ρ̂/cos θ_i is not reciprocal."""
        doc, _, _ = phong_report
        checks = doc["data_checks"]
        assert checks["albedo"]["views_deg"][0] == 0.0
        np.testing.assert_allclose(checks["albedo"]["rgb"][0], [1.0, 1.0, 1.0], rtol=1e-6)
        assert checks["reciprocity"]["max_rel"] > 1e-2
        codes = [w["code"] for w in doc["warnings"]]
        assert "non_reciprocal" in codes
        assert "energy_gain" not in codes

    def test_measured_error_matches_predicted_energy_error(self, phong_report):
        """The predicted relative RMS per view band is the expected squared error of the SHRM over
        uniform R (analysis.view_bands); the brute-force angular reference (RH02 eq. 2) on the
        report's pairs measures it within its Monte Carlo error, and the bound is in the same units.
        Phong's ρ̂ does not depend on the view: every band states the same error."""
        doc, _, _ = phong_report
        rows = sorted(doc["speed_vs_error"], key=lambda r: -r["tolerance"])
        for r in rows:
            assert 0.7 * r["predicted_rel_rms"] <= r["measured_rel_rms"] <= 1.3 * r["bound_rel_rms"], r
            assert r["predicted_rel_rms"] <= r["bound_rel_rms"] and r["P_B"] == r["P_rho"] == 0
            assert r["bound"] >= r["eps_B"] - 1e-12  # energy bound (all views) never below the prediction
            predicted = [b["predicted_rel_rms"] for b in r["view_bands"]]
            assert max(predicted) - min(predicted) < 1e-3 * max(predicted)
            for b in r["view_bands"]:
                assert b["measured_rel_rms"] - 3 * b["measured_stderr"] <= b["bound_rel_rms"], b
        assert rows[-1]["measured_rel_rms"] < rows[0]["measured_rel_rms"]
        for r in rows:  # the headline's measure is the worst band's, the one its bound states
            worst = max((b for b in r["view_bands"] if b["inside"]), key=lambda b: b["measured_rel_rms"])
            assert r["measured_worst_band_rel_rms"] == worst["measured_rel_rms"]
            assert r["measured_worst_band_stderr"] == worst["measured_stderr"]
            assert r["measured_worst_band_rel_rms"] - 3 * r["measured_worst_band_stderr"] <= r["bound_rel_rms"]

    def test_fit_slice_of_phong_peaks_at_the_mirror_direction(self, phong_report):
        """Measured slice = the BRDF on the plane of incidence: Phong's ρ̂ = ρ cos θ_i is
        (s+1)/(2π) cos^s of the angle to the mirror direction θ_i = −θ_o (closed form)."""
        doc, _, _ = phong_report
        slices = doc["fit_slices"]
        theta = np.array(slices["theta_deg"])
        for view in slices["views"]:
            rho_hat = np.array(view["measured_rgb"])[:, 1] * np.cos(np.radians(theta))
            expected = 33.0 / (2.0 * np.pi) * np.cos(np.radians(theta + view["view_deg"])).clip(0.0) ** 32
            np.testing.assert_allclose(rho_hat, expected, rtol=1e-6, atol=1e-12)


def test_report_is_reproducible_except_timings():
    """Same inputs -> identical report.json once the *_seconds keys are removed."""
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=40)
    a, _ = collect_report("lafortune:kd=0.2,n=30,ks=2", options)
    b, _ = collect_report("lafortune:kd=0.2,n=30,ks=2", options)
    assert json.dumps(strip_timings(a), sort_keys=True) == json.dumps(strip_timings(b), sort_keys=True)
    assert "total_seconds" not in strip_timings(a)
    assert "fit_seconds" not in strip_timings(a)["fits"][0]


def test_energy_gain_is_flagged_with_closed_form_albedo():
    """Lafortune kd + ks cos^n at normal view: a(0) = kd + ks·2π/(n + 2) = 1.4424 (closed form;
    ``directional_albedo`` itself: tests/analysis/test_albedo.py)."""
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=20)
    doc, _ = collect_report("lafortune:kd=0.3,n=20,ks=4", options)
    assert any(w["code"] == "energy_gain" for w in doc["warnings"])
    assert doc["data_checks"]["albedo"]["max"] == pytest.approx(1.4424, rel=1e-3)
    assert doc["data_checks"]["reciprocity"]["max_rel"] < 1e-12  # Lafortune is reciprocal


def test_failed_load_raises_bad_input(tmp_path):
    bad = tmp_path / "bad.binary"
    bad.write_bytes(b"\x00" * 40)
    with pytest.raises(shrmkit.BadInputError, match="bad.binary"):
        collect_report(bad, profile("quick", preview="none"))


def test_options_are_validated():
    with pytest.raises(shrmkit.BadInputError, match="eps"):
        profile("quick", eps=1.5)
    with pytest.raises(shrmkit.BadInputError, match="unknown model"):
        profile("full", models=("blinn",))
    with pytest.raises(shrmkit.BadInputError, match="profile"):
        profile("fast")
    assert profile("quick", eps=0.05).all_tolerances == (0.1, 0.05, 0.03, 0.01)


@pytest.mark.slow
def test_scattered_cornell_report_uses_the_fit(shared_data):
    """Cornell krylon_blue (real scattered measurements, /work/shared/data): the analysis runs
    on the fitted model; out-of-gamut components clamped on input are reported; the measured
    slices come from the file's samples (1439 rows, θ_i in 10°…80°). The orders are capped at
    F = 16, P = 1 (the fit's lobe would take F = 96, the quick cap, and most of the time): the
    report states the cap (``orders_capped``), and none of the checks here is about the orders."""
    from shrmkit.brdf_io.cornell import read_cornell

    path = shared_data / "brdf" / "cornell" / "krylon_blue.brdf"
    raw = read_cornell(path)
    options = profile("quick", preview="none", models=("lafortune",), tolerances=(0.1,), eps=0.1, n_pairs=50,
                      max_F=16, max_P=1)
    doc, _ = collect_report(path, options)
    assert validate(doc, OK_SCHEMA) == []
    # through the representation with the smallest held-out error (analysis.fit.representation), which
    # need not be one of the report's own fits: the analysis note names it
    assert doc["brdf"]["kind"] == "scattered" and doc["brdf"]["analysis_of"].startswith("fit:")
    note = next(w["message"] for w in doc["warnings"] if w["code"] == "analysis_on_fit")
    assert doc["brdf"]["analysis_of"].removeprefix("fit:") in note
    assert doc["data_checks"]["n_measurements"] == len(raw) == 1439
    assert doc["data_checks"]["n_clamped"] == raw.n_clipped > 0
    codes = {w["code"] for w in doc["warnings"]}
    assert {"clamped_values", "analysis_on_fit"} <= codes
    views = [v["view_deg"] for v in doc["fit_slices"]["views"]]
    assert set(views) <= {10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0}
