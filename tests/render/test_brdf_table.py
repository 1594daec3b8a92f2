"""The lights' BRDF table: the below-surface fill and the partial tabulation against slow paths."""

import numpy as np

from shrmkit.brdf_io.halfdiff import halfdiff_to_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render._brdf_table import _lookup_mask, table_angles, tabulate_brdf


def _slow_table(brdf, shape, periodic):
    """Every sample evaluated alone, ρ cos θ_L cos θ_V; past the last sample above the surface along θ_d,
    that sample."""
    nh, nd, npd = shape
    th, td, pd = table_angles(shape, periodic)
    out = np.zeros((nh, nd, npd, 3))
    for i in range(nh):
        for k in range(npd):
            L, V = halfdiff_to_directions(np.full(nd, th[i]), td, np.full(nd, pd[k]))
            rho = np.asarray(brdf.eval(L, V), np.float64) * (np.maximum(L[:, 2], 0) * np.maximum(V[:, 2], 0))[:, None]
            above = np.flatnonzero((L[:, 2] > 0) & (V[:, 2] > 0))
            if above.size and above[-1] < nd - 1:
                rho[above[-1] + 1:] = rho[above[-1]]
            out[i, :, k] = rho
    return out.astype(np.float32)


def test_table_and_its_partial_tabulation_match_sample_by_sample_evaluation():
    brdf = load_brdf("cook-torrance:alpha=0.2,kd=0.1,ks=0.5")
    shape = (9, 11, 13)
    slow = _slow_table(brdf, shape, periodic=False)
    full = tabulate_brdf(brdf, shape, periodic=False)
    np.testing.assert_allclose(full.values, slow, rtol=1e-6, atol=0)
    # the samples read by lookups at random directions, evaluated alone, hold the same values
    rng = np.random.default_rng(3)
    L = rng.normal(size=(200, 3))
    V = rng.normal(size=(200, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]), np.abs(V[:, 2])
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    mask = _lookup_mask(shape, False, L, V)
    assert 0 < mask.sum() < mask.size
    part = tabulate_brdf(brdf, shape, periodic=False, only=mask)
    np.testing.assert_array_equal(part.values[mask], full.values[mask])
    assert not part.values[~mask].any()


def test_light_near_the_horizon_is_not_blown_up_by_the_table(shared_data):
    """An RGL material's ρ grows like 1/cos θ_L toward the horizon: a table of ρ itself spread a node's
    value at cos θ_L ≈ 0.001 over its cell, and lights 1-3° above the horizon came out up to 24× too
    bright in `shrm render` (issue 29's Mitsuba comparison). The table holds ρ cos θ_L cos θ_V."""
    from shrmkit.render.brdf_glsl import table_lookup

    brdf = load_brdf(str(shared_data / "brdf" / "rgl" / "colodur_napoli_4f_rgb.bsdf"))
    table = tabulate_brdf(brdf, (46, 46, 91), periodic=False)
    rng = np.random.default_rng(5)
    n = 4000
    lz, vz = rng.uniform(0.01, 0.05, n), rng.uniform(0.5, 1.0, n)
    pl, pv = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 2 * np.pi, n)
    L = np.stack([np.sqrt(1 - lz**2) * np.cos(pl), np.sqrt(1 - lz**2) * np.sin(pl), lz], axis=1)
    V = np.stack([np.sqrt(1 - vz**2) * np.cos(pv), np.sqrt(1 - vz**2) * np.sin(pv), vz], axis=1)
    exact = np.asarray(brdf.eval(L, V)) * lz[:, None]
    got = table_lookup(table, L, V)
    rel = np.sqrt(np.sum((got - exact) ** 2) / np.sum(exact**2))
    assert rel < 0.2, rel
    assert np.max(got[:, 1] / np.maximum(exact[:, 1], 1e-12)) < 3.0
