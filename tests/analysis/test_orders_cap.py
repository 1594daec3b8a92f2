"""A cap on F caps the choice only: the order search's quadrature grids and its resolution check do
not change with it (analysis/orders.py, ``_GridData.profile``; view_bands.band_eps_column's F0)."""

from __future__ import annotations

import numpy as np
import pytest

from shrmkit.analysis.orders import choose_orders_many
from shrmkit.analysis.view_bands import band_eps_column, view_profile
from shrmkit.brdf_io.reparam import ReparamGrid
from shrmkit.brdf_io.specs import load_brdf


def test_column_of_a_profile_cut_at_F0():
    # the column at F0 from a profile holding every order of the grid equals the column of a profile
    # computed only up to F0 (the slow, direct path: a second profile)
    brdf = load_brdf("microfacet:sigma=0.2")
    grid = ReparamGrid.for_orders(40, 8)
    whole = view_profile(brdf, grid, grid.n_theta_i - 1, 8)
    cut = view_profile(brdf, grid, 30, 8)
    for P in (0, 3, 8):
        np.testing.assert_allclose(band_eps_column(whole, P, 80.0, 30), band_eps_column(cut, P, 80.0),
                                   rtol=1e-9, atol=1e-13)
    assert band_eps_column(whole, 3, 80.0).shape == (grid.n_theta_i,)


def test_cap_above_the_choice_changes_nothing():
    # microfacet sigma = 0.1 needs F 50 / 72 at eps 0.1 / 0.03: a cap at 96 (the quick report's) must
    # give the same orders from the same quadrature grids as no cap; with the profile cut at the cap,
    # the energy the grids resolve above 96 counted as unresolved and every choice sampled a 1.5x
    # finer grid (eps 0.03: 324 nodes instead of 216)
    brdf = load_brdf("microfacet:sigma=0.1")
    capped = choose_orders_many(brdf, (0.1, 0.03), max_F=96)
    free = choose_orders_many(brdf, (0.1, 0.03), max_F=512)
    for a, b in zip(capped, free, strict=True):
        assert (a.F, a.P, a.capped, a.converged) == (b.F, b.P, b.capped, b.converged)
        assert a.grid == b.grid
        # the view fits differ (made for l <= 96 or for every order of the grid): the same error to 1 % of eps
        assert max(a.eps, b.eps) <= a.tolerance and abs(a.eps - b.eps) <= 0.01 * a.tolerance
        assert a.F0 <= 96


def test_capped_choice_states_the_error_of_its_coefficients():
    # the coefficients a prefilter takes (coefficients_for) are the fit the chosen column was made with:
    # its worst band inside the view limit at (F, P) is the choice's eps, also when max_F cuts the table
    # below the profile's orders
    choice = choose_orders_many(load_brdf("microfacet:sigma=0.1"), (0.03,), max_F=60)[0]
    assert choice.F <= 60 < choice.profile.F0
    assert choice.coefficients_for(choice.P).F0 == choice.F0 == 60
    worst = max(b["eps"] for b in choice.view_bands() if b["inside"])
    assert worst == pytest.approx(choice.eps, rel=1e-9)
