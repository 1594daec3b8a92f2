"""ρ̂_lpq and the order choice against closed forms and RH02 Table 5."""

from __future__ import annotations

import numpy as np
import pytest

import shrmkit
from shrmkit.analysis.brdf_coeffs import rho_lpq, rho_lpq_direct
from shrmkit.analysis.orders import choose_orders
from shrmkit.analysis.sh import legendre_f
from shrmkit.brdf_io.errors import BadInputError
from shrmkit.brdf_io.reparam import ReparamBRDF, ReparamGrid, reparameterize


def test_fast_three_pass_matches_direct_sum():
    """Slow direct triple sum (reference) vs the three-pass transform."""
    r = reparameterize(shrmkit.load_brdf("cook-torrance:alpha=0.4,kd=0.3,dist=ggx"), ReparamGrid(14, 7, 10))
    c = rho_lpq(r, 6, 3)
    for l, p, q in [(0, 0, 0), (3, 2, 1), (5, 3, 3), (6, 1, 0), (4, 3, 2)]:
        np.testing.assert_allclose(c.coeffs[l, p, q], rho_lpq_direct(r, l, p, q), rtol=1e-10, atol=1e-14)


def test_recovers_known_band_limited_coefficients():
    """A table built from chosen coefficients (closed form) is transformed back exactly,
    and Parseval holds: Σ ρ̂² (q ≥ 1 twice) = quadrature energy."""
    grid = ReparamGrid(12, 8, 12)
    xi, _ = grid.theta_i()
    xo, _ = grid.theta_o()
    phi = grid.phi()
    known = {(0, 0, 0): 0.7, (2, 1, 1): -0.3, (3, 3, 2): 0.2, (5, 2, 0): 0.1}
    fi, fo = legendre_f(6, 3, xi), legendre_f(6, 3, xo)
    values = np.zeros((12, 8, 12))
    for (l, p, q), c in known.items():
        mult = 1.0 if q == 0 else 2.0  # ρ̂_lpq for ±q
        values += c * mult * fi[l, q][:, None, None] * fo[p, q][None, :, None] * np.cos(q * phi)
    r = ReparamBRDF(values=np.repeat(values[..., None], 3, -1), grid=grid, name="synthetic")
    c = rho_lpq(r, 6, 3)
    for (l, p, q), v in known.items():
        assert c.coeffs[l, p, q, 0] == pytest.approx(v, abs=1e-12)
    assert c.parseval_terms()[..., 0].sum() == pytest.approx(c.energy[0], rel=1e-12)


@pytest.mark.parametrize("s", [8, 16, 32, 64, 128, 256, 512])
def test_phong_order_closed_form(s):
    """RH02 Appendix D: F ≈ sqrt(−s ln ε) (±1) and P = 0 exactly for a radially symmetric lobe."""
    o = shrmkit.choose_orders(shrmkit.load_brdf(f"phong:s={s}"), eps=0.01)
    assert abs(o.F - np.sqrt(-s * np.log(0.01))) <= 1
    assert o.P == 0
    assert o.eps <= 0.01 and not o.capped and o.converged


@pytest.mark.parametrize("sigma, F, P", [(0.1, 24, 3), (0.2, 12, 2), (0.3, 7, 2), (0.4, 5, 2), (0.5, 5, 2)])
def test_microfacet_matches_rh02_table5(sigma, F, P):
    """RH02 Table 5 (simplified microfacet, ε < 0.03): (F, P) within ±1."""
    o = shrmkit.choose_orders(shrmkit.load_brdf(f"microfacet:sigma={sigma}"), eps=0.03, criterion="rh02")
    assert abs(o.F - F) <= 1 and abs(o.P - P) <= 1


def test_eps_table_monotone_and_rule():
    o = shrmkit.choose_orders(shrmkit.load_brdf("microfacet:sigma=0.3"), eps=0.05, criterion="rh02")
    t = o.table
    assert np.all(np.diff(t, axis=0) <= 1e-12) and np.all(np.diff(t, axis=1) <= 1e-12)
    assert np.all(t >= -1e-12)
    assert t[o.F, o.P] <= 0.05 and (o.F == 0 or t[o.F - 1, o.P] > 0.05) and (o.P == 0 or t[-1, o.P - 1] > 0.05)


def test_caps_are_reported_not_looped():
    """Capped: the smallest orders within 0.01·ε of the best error the caps allow. Phong's ρ̂ has no
    view dependence (closed form), so P = 0 reaches what P = 2 does; F stays at the cap (the
    error still falls fast there)."""
    o = shrmkit.choose_orders(shrmkit.load_brdf("phong:s=2000"), eps=0.01, max_F=20, max_P=2)
    assert o.capped and (o.F, o.P) == (20, 0) and "not met" in o.message
    assert o.eps > 0.01 and o.eps == pytest.approx(o.table[20, 2], rel=1e-9)


def test_capped_view_order_does_not_drag_F_to_its_cap():
    """microfacet σ = 0.2 held at P = 0 (``--max-P 0``): the uncaptured p > 0 energy stays; F
    stops where the P = 0 error stops falling, not at max_F (it was 512, a 46 MB map)."""
    o = shrmkit.choose_orders("microfacet:sigma=0.2", eps=0.03, max_P=0)
    assert o.capped and o.P == 0 and o.F < 100
    best = o.table[:, 0].min()
    assert best <= o.eps <= best + 0.01 * 0.03 < o.table[o.F - 1, 0]


def test_spec_strings_and_numeric_strings_are_accepted():
    a = shrmkit.choose_orders("phong:s=8", eps="0.03")
    b = shrmkit.choose_orders(shrmkit.load_brdf("phong:s=8"), eps=0.03)
    assert (a.F, a.P, a.eps) == (b.F, b.P, b.eps)


def test_zero_brdf_is_a_clear_error():
    with pytest.raises(BadInputError, match="zero everywhere"):
        shrmkit.choose_orders(shrmkit.load_brdf("lambert:albedo=0"), eps=0.03)


@pytest.mark.parametrize("eps", [0.0, 1.0, -0.1, 2.0])
def test_bad_tolerance(eps):
    with pytest.raises(BadInputError, match="eps"):
        shrmkit.choose_orders(shrmkit.load_brdf("phong:s=8"), eps=eps)


@pytest.mark.slow
def test_hard_cases_sharp_lobes():
    """DESIGN §7: Phong s = 10⁴ (F ≈ 215 at ε = 0.01) and σ = 0.02 without NaN/overflow."""
    o = shrmkit.choose_orders(shrmkit.load_brdf("phong:s=10000"), eps=0.01)
    assert abs(o.F - np.sqrt(-1e4 * np.log(0.01))) <= 2 and o.P == 0
    assert np.all(np.isfinite(o.table))
    o = shrmkit.choose_orders(shrmkit.load_brdf("microfacet:sigma=0.02"), eps=0.03, criterion="rh02")
    assert np.all(np.isfinite(o.table)) and 100 <= o.F <= 130 and o.P <= 3


def test_missing_merl_data_counted(tmp_path):
    """Missing measurements are excluded and counted, never NaN (DESIGN §7)."""
    from shrmkit.brdf_io.merl import tabulate_merl, write_merl

    values = tabulate_merl(shrmkit.load_brdf("microfacet:sigma=0.3"))
    values[:, 60:, :, :] = np.nan  # θ_h beyond index 60 unmeasured
    path = write_merl(tmp_path / "holes.binary", values)
    o = shrmkit.choose_orders(shrmkit.load_brdf(path), eps=0.1, max_F=24, max_P=3)
    assert np.all(np.isfinite(o.table))
    assert o.n_without_data > 0 and "no measurement" in o.message


def test_merl_tabulated_cook_torrance_keeps_its_orders(tmp_path):
    """A reciprocal model written to MERL needs the same (F, P) as the model itself (±1)."""
    from shrmkit.brdf_io.merl import write_merl

    spec = "cook-torrance:kd=0.2/0.1/0.05,ks=1,alpha=0.3,f0=0.9/0.6/0.3,dist=ggx"
    direct = shrmkit.choose_orders(shrmkit.load_brdf(spec), eps=0.05, max_F=64, max_P=10)
    merl = shrmkit.choose_orders(shrmkit.load_brdf(write_merl(tmp_path / "ct.binary", shrmkit.load_brdf(spec))),
                                 eps=0.05, max_F=64, max_P=10)
    assert not direct.capped and not merl.capped
    assert abs(direct.F - merl.F) <= 1 and abs(direct.P - merl.P) <= 1


def test_cap_on_F_below_cap_on_P_is_reported_not_a_crash():
    """max_F < max_P (e.g. --max-F 8): capped result, no IndexError (review finding)."""
    o = shrmkit.choose_orders(shrmkit.load_brdf("phong:s=32"), eps=0.03, max_F=8)
    assert o.capped and o.F == 8 and "not met" in o.message
    assert np.all(np.isfinite(o.table))
    # a library message names the parameters to raise, not the command line's options
    assert "raise max_F/max_P" in o.message and "--max" not in o.message


def test_lobe_sharper_than_the_first_grid_is_not_called_zero():
    """Phong s = 1e6 falls between the first grid's nodes: grow to the caps, report capped,
    with ε(512, ·) close to the closed form exp(−F²/s)."""
    o = shrmkit.choose_orders(shrmkit.load_brdf("phong:s=1e6"), eps=0.03)
    assert o.capped and o.F == 512
    assert o.eps == pytest.approx(np.exp(-(512**2) / 1e6), abs=0.15)


@pytest.mark.parametrize("spec", ["microfacet:sigma=0.3", "cook-torrance:kd=0.2,alpha=0.2,dist=ggx", "phong:s=64"])
def test_orders_for_several_tolerances_equal_separate_searches(spec):
    """choose_orders_many shares quadrature grids between tolerances: each result equals an
    independent choose_orders (orders, errors, flags and the whole table)."""
    from shrmkit.analysis.orders import choose_orders_many

    brdf = shrmkit.load_brdf(spec)
    tolerances = (0.1, 0.03, 0.01)
    shared = choose_orders_many(brdf, tolerances, max_F=96)
    for tol, got in zip(tolerances, shared, strict=True):
        alone = choose_orders(brdf, eps=tol, max_F=96)
        assert (got.F, got.P, got.capped, got.converged, got.tolerance) == (
            alone.F, alone.P, alone.capped, alone.converged, alone.tolerance)
        assert got.eps == alone.eps and got.message == alone.message
        assert got.grid == alone.grid
        np.testing.assert_array_equal(got.table, alone.table)
        assert got.eps_at(got.F, got.P) == got.table[got.F, got.P]
    with pytest.raises(BadInputError):
        choose_orders_many(brdf, ())


def test_prefilter_reuses_given_orders_and_refuses_mismatched_ones():
    """prefilter(orders=) gives the map prefilter chooses by itself; a choice made at another
    tolerance or rule is refused."""
    brdf = shrmkit.load_brdf("microfacet:sigma=0.3")
    env = "builtin:sky,height=32"
    choice = choose_orders(brdf, eps=0.03)
    own = shrmkit.prefilter(env, brdf, eps=0.03)
    given = shrmkit.prefilter(env, brdf, eps=0.03, orders=choice)
    assert (given.F, given.P) == (own.F, own.P) and given.meta["timings"]["orders"] < 0.01
    np.testing.assert_array_equal(given.coeffs, own.coeffs)
    assert given.eps == own.eps
    with pytest.raises(BadInputError, match="eps=0.03"):
        shrmkit.prefilter(env, brdf, eps=0.1, orders=choice)
    with pytest.raises(BadInputError, match="criterion"):
        shrmkit.prefilter(env, brdf, eps=0.03, criterion="rh02", orders=choice)


def test_table_orders_stop_at_the_resolution_of_its_grid(tmp_path):
    """A table holding one measured sample among 6 × 6 × 6 nodes 0.3 rad apart (issue 30: a 1.1 KB
    file sent `shrm orders` to F = 356 grids for minutes and never settled): F is capped at the
    order the grid resolves, ⌈2π / 0.3⌉ = 21, and the note says why; a table with measured nodes
    1° apart resolves F up to 360, beyond the default cap, so its orders are not limited."""
    from shrmkit.brdf_io.table import TableBRDF, read_table, write_table

    axis = np.linspace(0.0, 1.5, 6)
    values = np.full((6, 6, 6), np.nan)
    values[2, 3, 1] = 0.5
    path = write_table(tmp_path / "one_of_many.npz", values, theta_i=axis, theta_o=axis, phi_d=np.linspace(0, 1.5, 6))
    sparse = read_table(path)
    assert sparse.resolved_order() == int(np.ceil(2 * np.pi / 0.3)) == 21
    o = choose_orders(sparse, eps=0.03)
    assert o.F <= 21 and o.capped and "grid resolves" in o.message, (o.F, o.message)
    # nor P: at max_P = 24 the search grew its grids to 222 × 216 × 378 (11.6 s, 1.1 GB) without settling
    # (the fuzz harness's "one measured of 216" table)
    o = choose_orders(sparse, eps=0.1, max_F=48, max_P=24, criterion="rh02")
    assert o.F <= 21 and o.P <= 21 and o.converged and o.grid.n_theta_o < 120, (o.F, o.P, o.grid, o.message)
    fine = np.radians(np.arange(0.0, 90.0, 1.0))
    table = TableBRDF(fine, fine[:4], np.radians([0.0, 90.0, 180.0]), np.ones((90, 4, 3)))
    assert table.resolved_order() == 360


@pytest.mark.parametrize("spec", ["microfacet:sigma=0.1", "cook-torrance:alpha=0.1,dist=ggx", "lambert:albedo=0.5",
                                  "lafortune:cxy=-1,cz=1,n=20"])
def test_view_order_search_matches_a_linear_scan(spec):
    """The P search (bisection above the view-order floor, or galloping from a hint) against the
    slow direct path: every column of the table computed and scanned from P = 0."""
    from shrmkit.analysis.orders import CAPPED_SLACK, _GridData
    from shrmkit.analysis.view_bands import band_eps_column, view_order_floor

    brdf = shrmkit.load_brdf(spec)
    grid = ReparamGrid.for_orders(32, 5)  # P0 = 17
    on = _GridData(brdf, grid, 500, 64, "bands", 80.0)
    best = np.array([band_eps_column(on.profile, p, 80.0).min() for p in range(on.P0 + 1)])
    # the fits nest up to the reweighting passes (Lafortune n = 20: +1 % of ε near ε = 3·10⁻⁵), so
    # the search's predicate is monotone at every tolerance a user sets
    assert np.all(np.diff(best) <= 0.02 * best[1:])
    for tol in (0.1, 0.03, 0.01, 0.003):
        meets = np.nonzero(best <= tol)[0]
        assert np.all(best[meets[0]:] <= tol) if meets.size else True
        capped = meets.size == 0
        reach = best[-1] + CAPPED_SLACK * tol if capped else tol
        P_scan = int(np.nonzero(best <= reach)[0][0])
        F_scan = int(np.nonzero(band_eps_column(on.profile, P_scan, 80.0) <= reach)[0][0])
        floor = view_order_floor(on.profile, tol, 80.0)
        assert floor <= P_scan
        if floor > 0 and not capped:
            assert best[floor - 1] > tol
        for hint in (None, 0, 3, on.P0):
            fresh = _GridData(brdf, grid, 500, 64, "bands", 80.0)
            fresh.__dict__["profile"] = on.profile  # the same samples; its columns computed afresh
            assert fresh.choose(tol, hint) == (F_scan, P_scan, capped), (tol, hint)


def test_an_error_above_one_is_refused_not_reported():
    """ε is an energy fraction: a rule's table holding ε > 1 (only inconsistent samples make one) is one
    BadInputError naming the BRDF, never a result with ε = 1.02 and advice to raise --max-F (issue 30)."""
    from shrmkit.analysis.orders import _choice, _GridData

    brdf = shrmkit.load_brdf("phong:s=20")
    on = _GridData(brdf, ReparamGrid.for_orders(24, 4), 500, 64, "bands", 80.0)
    on._columns[0] = np.full(on.F0 + 1, 1.02)
    with pytest.raises(BadInputError, match=r"ε\(3, 0\) = 1.02 is not an energy fraction") as raised:
        _choice(on, 3, 0, 0.03, True, True, [], 0.0, "bands", 80.0)
    assert "phong:s=20" in str(raised.value)
    on._columns[0] = np.full(on.F0 + 1, 0.5)
    assert _choice(on, 3, 0, 0.03, True, True, [], 0.0, "bands", 80.0).eps == 0.5
