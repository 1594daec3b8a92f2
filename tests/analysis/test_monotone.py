"""A tighter tolerance never gives a larger error (the fast, honest default).

For a fixed BRDF and map, ``prefilter`` at ε = 0.1 … 0.005 with the defaults (bands rule, auto
window, explicit lights, error-driven map size): the stated (predicted) worst-band error inside the
view limit falls as ε falls, and so does the error measured against brute-force angular integration
(``analysis.reference``) on one fixed set of (R, V) pairs, up to its Monte Carlo error; the bound
stays above the measured error and below the loosest tolerance's (or √ε of its own). Cases: the demo's materials under
``builtin:studio`` — the gold metal is the case where the window used to make ε = 0.01 worse than
ε = 0.03 (F_B 18 / 25 / 16 / 18 for ε 0.1 / 0.03 / 0.01 / 0.005) — and a view-dependent
microfacet lobe under the sun of ``builtin:sky``.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.compare import band_pairs, band_relative_rms
from shrmkit.analysis.reference import reference_radiance
from shrmkit.analysis.view_bands import DEFAULT_BAND_EDGES_DEG, worst_inside

TOLERANCES = (0.1, 0.03, 0.01, 0.005)
CASES = [
    ("builtin:studio,height=32", "lafortune:kd=0.02/0.015/0.005,cxy=-1,cz=1,n=300,ks=36/26/10"),  # gold metal
    ("builtin:studio,height=32", "lafortune:kd=0.45/0.07/0.05,cxy=-1,cz=1,n=60,ks=3"),  # red plastic
    ("builtin:sky,height=32", "microfacet:sigma=0.2"),
]


def _worst_measured(shrm, env, brdf, R, V, theta_v, weights) -> tuple[float, float]:
    """Worst measured relative RMS over the bands inside the view limit, and its standard error."""
    got = band_relative_rms(shrm.radiance(R, V), reference_radiance(env, brdf, R, V), theta_v,
                            DEFAULT_BAND_EDGES_DEG, weights)
    inside = [(m, b) for m, b in zip(got, shrm.meta["view_bands"], strict=True) if b["inside"]]
    worst = max(inside, key=lambda mb: mb[0]["measured_rel_rms"])[0]
    return worst["measured_rel_rms"], worst["stderr"]


@pytest.mark.slow
@pytest.mark.parametrize("env_spec, spec", CASES)
def test_tighter_tolerance_never_gives_a_larger_error(env_spec, spec):
    env = shrmkit.load_env(env_spec)
    brdf = shrmkit.load_brdf(spec)
    R, V, theta_v, weights = band_pairs(env.radiance, 60, DEFAULT_BAND_EDGES_DEG, seed=2)
    stated, bounds, measured = [], [], []
    for eps in TOLERANCES:
        shrm = shrmkit.prefilter(env, brdf, eps=eps)
        stated.append(worst_inside(shrm.meta["view_bands"], "predicted_rel_rms"))
        bounds.append(worst_inside(shrm.meta["view_bands"], "bound_rel_rms"))
        measured.append(_worst_measured(shrm, env, brdf, R, V, theta_v, weights))
        # what is stated holds: within the tolerance (plus the map's documented 1 % of ε) unless capped
        if not shrm.meta["scene_capped"]:
            assert stated[-1] ** 2 <= 1.011 * eps, (eps, stated[-1])
    for a, b in itertools.pairwise(stated):
        assert b <= a + 1e-12, stated
    # the bound holds whatever the tolerance (it is never below the measured error) but is not a
    # function of ε alone: its worst-case lighting weight multiplies the energy the order search's
    # grid leaves unresolved, which changes with the grid, and the pixel rule raises F_B most at the
    # loosest tolerances (sky, σ 0.2: F_B 1 → 5 at ε 0.1, bound 0.057 → 0.016). No bound exceeds the
    # loosest tolerance's, unless it meets the relative RMS its own tolerance stands for.
    for bound, eps in zip(bounds, TOLERANCES, strict=True):
        assert bound <= max(bounds[0] + 1e-12, np.sqrt(eps)), (bounds, TOLERANCES)
    for (m, se), bound in zip(measured, bounds, strict=True):
        assert m - 2.0 * se <= bound, (measured, bounds)
    for (a, sa), (b, sb) in itertools.pairwise(measured):
        assert b <= a + 2.0 * np.hypot(sa, sb), measured
    # and it falls by much: the loosest against the tightest tolerance
    assert measured[-1][0] < 0.6 * measured[0][0], measured
