"""What the map's size costs the stated errors (analysis.map_budget, issue 29).

References: closed forms (the bytes of (P+1)² float32 RGB maps of S × 2S; the flag's definition
on hand-made bands), and brute-force angular integration (``analysis.reference``) of the SHRM a
small memory budget shrinks: its measured per-band error stays below its stated bound, the bound
without lookup error is what a map of the offered size states, and that map meets it.
"""

from __future__ import annotations

import numpy as np

import shrmkit
from shrmkit.analysis.compare import band_error, band_sample
from shrmkit.analysis.map_budget import UNINFORMATIVE_FACTOR, assess_map, map_bytes
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.shrm import default_size, prefilter


def _band(lo: float, pred: float, bound: float, mp: float = 0.0) -> dict:
    return {"theta_v_deg": [lo, lo + 15.0], "predicted_rel_rms": pred, "bound_rel_rms": bound, "map_rel_rms": mp}


def test_map_bytes_closed_form():
    assert map_bytes(185, 17) == 18**2 * 185 * 370 * 3 * 4 == 266_133_600
    # default_size keeps the map within its budget
    for P in (0, 5, 17):
        assert map_bytes(default_size(400, P), P) <= 256 << 20


def test_flags_and_costs_on_hand_made_bands():
    """Band 0 informative; band 1 bound above 1; band 2 bound above 10× the prediction; band 3 is
    outside the limit (annotated, not counted). Costs are raw minus exact bounds."""
    bands = [_band(0, 0.02, 0.03, 0.001), _band(15, 0.05, 1.2, 0.04), _band(30, 0.01, 0.2, 0.01),
             _band(45, 0.1, 5.0, 0.5)]
    raw = [dict(b) for b in bands]
    exact = [{**b, "bound_rel_rms": e} for b, e in zip(bands, (0.029, 0.06, 0.02, 0.3), strict=True)]
    calls = []
    out = assess_map(bands, raw, exact, rows=100, P=3, inside=[0, 1, 2], budget_bytes=1 << 20, capped=True,
                     rows_needed=lambda: calls.append(1) or 400)
    assert [b["bound_informative"] for b in bands] == [True, False, False, False]
    assert 0.2 > UNINFORMATIVE_FACTOR * 0.01 * 0.99 and out.uninformative_bands == [[15.0, 30.0], [30.0, 45.0]]
    np.testing.assert_allclose([b["map_bound_cost"] for b in bands], [0.001, 1.14, 0.18, 4.7])
    np.testing.assert_allclose([b["bound_rel_rms_exact_lookup"] for b in bands], [0.029, 0.06, 0.02, 0.3])
    assert np.isclose(out.map_bound_cost, 1.14) and np.isclose(out.bound_without_lookup, 0.06)
    assert np.isclose(out.map_rel_rms, 0.04)
    assert out.rows_needed == 400 and out.bytes_needed == map_bytes(400, 3) and len(calls) == 1
    assert "uninformative in 2 view band(s)" in out.note and "400 rows" in out.note and "MiB" in out.note
    # nothing to say: the rows are not searched
    quiet = assess_map([_band(0, 0.02, 0.03)], [_band(0, 0.02, 0.03)], [_band(0, 0.02, 0.029)], rows=64, P=1,
                       inside=[0], budget_bytes=1 << 28, capped=False, rows_needed=lambda: 1 / 0)
    assert quiet.note == "" and quiet.rows_needed is None and quiet.uninformative_bands == []


def _measured(env, brdf, shrm, sample, ref) -> list[tuple[dict, dict]]:
    """(measured, stated) per band of ``sample`` (the statement's band holding the sample's)."""
    measured = band_error(shrm.radiance(sample.R, sample.V), ref, sample)
    stated = {tuple(b["theta_v_deg"]): b for b in shrm.meta["view_bands"]}
    return [(m, stated[tuple(m["theta_v_deg"])]) for m in measured]


def test_small_budget_states_its_cost_against_brute_force():
    """Microfacet σ = 0.1 under a sun kept in the map (64 rows, no explicit lights), F_B 63, P_B 10.

    - A 4 MiB budget holds the map below 10 F: the meta says so (capped_by, map_budget.capped, the
      rows and bytes that meet ε, beyond the budget, in orders_message); per band the bound holds
      against brute force (3 s.e. of slack) and the bound without lookup is below it.
    - ``size=12``: the lookup's term takes the bound past 1 at grazing views; those bands are
      flagged uninformative and the note says what the lookup costs and which rows meet ε.
    - The offered rows: the bound is within 25 % of the bound without lookup (``map_rows``'s
      share), informative in every band inside the limit, and holds against brute force."""
    env = shrmkit.load_env("builtin:sun,height=64,elevation=35,azimuth=20")
    brdf = shrmkit.load_brdf("microfacet:sigma=0.1")
    small = prefilter(env, brdf, eps=0.03, budget_bytes=4 << 20, pixel_rule=False, lights="none")
    mb = small.meta["map_budget"]
    assert mb["capped"] and "map budget: 4 MiB" in small.meta["capped_by"]
    assert mb["bytes"] <= 4 << 20 < mb["bytes_needed"] and mb["rows_needed"] > small.height
    assert mb["bytes_needed"] == map_bytes(mb["rows_needed"], small.P)
    assert f"{mb['rows_needed']} rows" in small.meta["orders_message"]

    tiny = prefilter(env, brdf, eps=0.03, size=12, pixel_rule=False, lights="none")
    flagged = tiny.meta["map_budget"]["uninformative_bands"]
    assert flagged and all(b["bound_rel_rms"] > 1.0 for b in tiny.meta["view_bands"]
                           if b["theta_v_deg"] in flagged)
    assert tiny.meta["map_budget"]["map_bound_cost"] > 0.5 > tiny.meta["map_budget"]["bound_without_lookup"]
    assert "uninformative" in tiny.meta["orders_message"] and f"{mb['rows_needed']} rows" in tiny.meta["orders_message"]

    big = prefilter(env, brdf, eps=0.03, size=mb["rows_needed"], pixel_rule=False, lights="none")
    assert (big.F, big.P) == (small.F, small.P) and big.meta["map_budget"]["uninformative_bands"] == []
    sample = band_sample(env.radiance, 24, (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0), seed=2)
    ref = reference_radiance(env, brdf, sample.R, sample.V)
    for shrm in (small, big):
        for m, b in _measured(env, brdf, shrm, sample, ref):
            assert m["measured_rel_rms"] <= b["bound_rel_rms"] + 3 * m["stderr"], (shrm.height, m, b)
            assert b["bound_rel_rms_exact_lookup"] <= b["bound_rel_rms"] + 1e-12
    for b_small, b_big in zip(small.meta["view_bands"], big.meta["view_bands"], strict=True):
        if b_small["inside"]:
            assert b_big["bound_rel_rms"] <= 1.25 * b_small["bound_rel_rms_exact_lookup"] + 1e-9
            assert b_small["map_bound_cost"] > b_big["map_bound_cost"] and b_big["bound_informative"]
