"""The lights' BRDF table: the below-surface fill and the partial tabulation against slow paths."""

import numpy as np

from shrmkit.brdf_io.halfdiff import halfdiff_to_directions
from shrmkit.brdf_io.specs import load_brdf
from shrmkit.render.brdf_glsl import _lookup_mask, table_angles, tabulate_brdf


def _slow_table(brdf, shape, periodic):
    """Every sample evaluated alone; past the last sample above the surface along θ_d, that sample."""
    nh, nd, npd = shape
    th, td, pd = table_angles(shape, periodic)
    out = np.zeros((nh, nd, npd, 3))
    for i in range(nh):
        for k in range(npd):
            L, V = halfdiff_to_directions(np.full(nd, th[i]), td, np.full(nd, pd[k]))
            rho = np.asarray(brdf.eval(L, V), np.float64)
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
