"""Accuracy table ε(F, P) and the error-driven choice of orders ([RH02] §5.1, Appendix C).

    A(F, P) = Σ_{l<=F, p<=P, |q|<=min(l,p)} ρ̂_{lq,pq}² / ∫∫ ρ̂² dω_i dω_o,   ε = 1 − A,

with the total energy computed independently by quadrature of ρ̂² (not by summing
coefficients). RGB: ε is computed per channel and the *worst* channel is reported (a
material is as hard as its sharpest channel); channels with no energy are ignored.

Choice rule ([RH02] §5.1): with (F0, P0) large enough that ε(F0, P0) <= tol,
P = min{p : ε(F0, p) <= tol}, then F = min{f : ε(f, P) <= tol}.

Two tables ε(F, P) feed that rule (``criterion``):

- ``"bands"`` (default): the worst view band θ_v inside the view limit ``max_view_deg``
  (default 80°) under a point light (:func:`~shrmkit.analysis.view_bands.band_eps_table`),
  with the view dependence fitted to those views
  (:func:`~shrmkit.analysis.view_bands.fit_view_coefficients`) — every band the user looks
  at meets the tolerance, grazing views included;
- ``"rh02"``: [RH02]'s unweighted energy over all views, with the projected coefficients
  (reproduces [RH02] Table 5 and the Phong closed form F ≈ sqrt(−s ln ε)).

(F0, P0) are the full capacity of the quadrature grid (every order the grid integrates
orthonormally), so the rule sees all the energy the samples hold. When ε(F0, P0) > tol
the grid is refined (doubled) until the tolerance is met or the caps ``max_F``/``max_P``
are hit; then the result says so (``capped``) instead of looping. The choice is
re-checked on a 1.5× finer grid (``converged``).

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from ..brdf_io.brdf import BRDF
from ..brdf_io.errors import BadInputError
from ..brdf_io.reparam import ReparamBRDF, ReparamGrid, reparameterize
from ..brdf_io.specs import load_brdf
from .brdf_coeffs import BRDFCoefficients, rho_lpq
from .defaults import DEFAULT_MAX_F, DEFAULT_MAX_P  # numpy-free home, for the CLI's parsers
from .notebook import order_choice_html
from .order_rule import OrderRule, resolve_rule
from .threads import single_threaded_blas
from .tolerance import check_eps
from .view_bands import (
    DEFAULT_CRITERION,
    DEFAULT_MAX_VIEW_DEG,
    ViewProfile,
    band_eps_column,
    brdf_view_bands,
    check_criterion,
    check_max_view,
    fit_view_coefficients,
    projected_eps,
    resolution_tail,
    view_order_floor,
    view_profile,
)

__all__ = [
    "OrderChoice",
    "eps_table",
    "choose_from_table",
    "choose_orders",
    "choose_orders_many",
    "orders_on_grid_for",
    "forced_orders_note",
    "OrdersClampedWarning",
    "DEFAULT_MAX_F",
    "DEFAULT_MAX_P",
]


class OrdersClampedWarning(UserWarning):
    """Orders given to ``prefilter(F=, P=)`` were beyond what the map or the BRDF's grid holds and
    were lowered (:func:`forced_orders_note`)."""


@dataclass(frozen=True, eq=False)
class OrderChoice:
    """Result of :func:`choose_orders`.

    Attributes
    ----------
    F, P
        Chosen orders.
    eps
        Achieved ε(F, P) of the rule's table (worst channel; worst band for ``"bands"``).
    tolerance
        Requested tolerance.
    table
        ε[F, P] for F <= F0, P <= P0 of the rule (``criterion``), worst channel. For
        ``"bands"`` the columns the rule did not need are fitted when ``table`` is first read
        (:meth:`eps_at` reads one entry without that).
    searched_table
        ``table`` as the search left it: NaN in the columns it did not need.
    capped
        True when the tolerance could not be met within ``max_F``/``max_P``; (F, P) are
        then the caps and ``eps`` what they achieve.
    converged
        True when the quadrature grid resolves the choice: under ``"bands"``, the energy just
        above the chosen orders is at most :data:`RESOLVED_TAIL` × ε in every band inside the
        view limit (:func:`~shrmkit.analysis.view_bands.resolution_tail`), or a 1.5× finer grid
        agrees (same P, and F within 1 or ε at the choice within :data:`AGREE_FRACTION` × ε);
        under ``"rh02"``, a 1.5× finer grid gives the same choice (ΔF <= 1, same P).
    message
        Human-readable notes (caps, convergence, missing data).
    coefficients
        The projected ρ̂_lpq (RH02 eq. 13) on the final grid (computed on first use under
        ``"bands"``, whose rule needs only the profile); :meth:`coefficients_for` gives the ones
        a representation at view order P uses.
    criterion, max_view_deg
        The order rule and its view limit (degrees of θ_v).
    rule
        The :class:`~shrmkit.analysis.order_rule.OrderRule` asked for, with ``eps`` = ``tolerance``
        (None only for a choice built by hand).
    profile
        ρ̂ resolved by view band (:class:`~shrmkit.analysis.view_bands.ViewProfile`).
    rh02_table
        RH02's unweighted ε[F, P] (the ``"rh02"`` table), whatever the criterion (computed on
        first use under ``"bands"``).
    """

    F: int
    P: int
    eps: float
    tolerance: float
    searched_table: np.ndarray
    capped: bool
    converged: bool
    message: str
    seconds: float
    grid: ReparamGrid
    n_without_data: int
    criterion: str = DEFAULT_CRITERION
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG
    source: _GridData | None = field(default=None, repr=False)
    rule: OrderRule | None = field(default=None, repr=False)

    _repr_html_ = order_choice_html  # notebook card (analysis.notebook)

    @property
    def F0(self) -> int:
        return self.searched_table.shape[0] - 1

    @property
    def P0(self) -> int:
        return self.searched_table.shape[1] - 1

    @property
    def _data(self) -> _GridData:
        assert self.source is not None, "an OrderChoice of choose_orders holds its grid data"
        return self.source

    @property
    def coefficients(self) -> BRDFCoefficients:
        return self._data.coefficients

    @property
    def profile(self) -> ViewProfile:
        return self._data.profile

    @property
    def rh02_table(self) -> np.ndarray:
        return self._data.rh02_table

    @cached_property
    def table(self) -> np.ndarray:
        """The whole ε[F, P] table, (F0+1, P0+1) (computed once, on first use)."""
        if not np.isnan(self.searched_table).any():
            return self.searched_table
        out = np.empty_like(self.searched_table)
        for p in range(self.P0 + 1):
            out[:, p] = self._data.column(p)
        return out

    def eps_at(self, F: int, P: int) -> float:
        """ε[F, P] of the rule's table (F <= F0, P <= P0), without filling the whole table."""
        value = self.searched_table[F, P]
        return float(self._data.column(P)[F] if np.isnan(value) else value)

    @cached_property
    def eps_rh02(self) -> float:
        """RH02's unweighted ε at the chosen (F, P) (energy fraction over all views, eq. 13 and §5.1).

        Under ``"rh02"`` the rule's own table; under ``"bands"`` the projection by the view
        profile's quadrature (:func:`~shrmkit.analysis.view_bands.projected_eps`: no 3-D grid is
        sampled), which agrees with the 3-D quadrature of eq. 13 within 1 % of ε for the model
        families (``tests/analysis/test_view_bands.py``) and 3–5 % for the sharpest RGL file of
        ../shared/data, cc_iris_purple_gem (ε 0.254 vs 0.247 at (111, 5), 0.102 vs 0.097 at (197, 14)),
        whose 3-D value itself moves by 0.6 % between grids 1× and 2.5× as fine)."""
        if self.criterion == "rh02":
            return float(self.rh02_table[self.F, self.P])
        return projected_eps(self.profile, self.F, self.P)

    @cached_property
    def _fitted(self) -> dict[int, BRDFCoefficients]:
        return {}

    def coefficients_for(self, P: int) -> BRDFCoefficients:
        """ρ̂_lpq for a representation of view order ``P``: the projection (``"rh02"``) or the
        fit to the views inside the limit (``"bands"``, depends on P; computed once per P)."""
        if self.criterion == "rh02":
            return self.coefficients
        P = int(P)
        if P not in self._fitted:
            # the fit the choice's column was made with (l <= F0, which a cap on F may hold below the profile's)
            self._fitted[P] = fit_view_coefficients(self.profile, None, P, self.max_view_deg, self.F0)
        return self._fitted[P]

    def view_bands(self, F: int | None = None, P: int | None = None) -> list[dict]:
        """Per θ_v band at (F, P) (default: the chosen orders) under a point light:
        ``eps``, ``rel_rms_point_light`` (= √ε), ``inside``, ``extrapolated_samples``
        (:func:`~shrmkit.analysis.view_bands.brdf_view_bands`)."""
        F = self.F if F is None else int(F)
        P = self.P if P is None else int(P)
        return brdf_view_bands(self.profile, self.coefficients_for(P), F, P, self.max_view_deg)


def eps_table(coefficients: BRDFCoefficients) -> np.ndarray:
    """ε(F, P) for every F <= F0, P <= P0, worst channel (RH02 §5.1).

    Raises
    ------
    BadInputError
        If the BRDF has no energy at all (an all-zero BRDF has no meaningful orders).
    """
    energy = coefficients.energy
    if not np.any(energy > 0):
        raise BadInputError(coefficients.name, "the BRDF is zero everywhere: no orders to choose")
    live = energy > 1e-12 * energy.max()
    terms = coefficients.parseval_terms().sum(axis=2)  # (F0+1, P0+1, 3)
    captured = np.cumsum(np.cumsum(terms, axis=0), axis=1)
    eps = 1.0 - captured[..., live] / energy[live]
    return eps.max(axis=-1)


#: When the tolerance cannot be met, orders whose ε is within this fraction of the tolerance
#: of the best reachable ε are taken as reaching it (:func:`choose_from_table`).
CAPPED_SLACK = 0.01


def choose_from_table(table: np.ndarray, tolerance: float) -> tuple[int, int, bool]:
    """(F, P, capped) by the RH02 rule: smallest P at F0, then smallest F at that P.

    When no entry meets ``tolerance`` (``capped``), the smallest P, then the smallest F, whose
    error is within :data:`CAPPED_SLACK` × ``tolerance`` (an absolute ε difference) of the
    best error the table holds: the caps are not chosen where they buy nothing the tolerance
    can see — Phong needs no P > 0 at any F, and a view-dependent lobe held at P = 0 gains
    only ~1e-8 from F beyond its own band limit — while a lobe whose error still falls keeps
    the cap. The error reported is that of the chosen entry.

    RH02's table falls monotonically in F and P, so "a column meets the tolerance" is its
    F0 row; the bands table (worst band of a fit) need not, so each column's minimum is used.
    NaN columns (not computed: :func:`~shrmkit.analysis.view_bands.band_eps_table`'s
    ``stop_at``) count as not meeting anything.
    """
    table = np.where(np.isnan(table), np.inf, table)
    column_best = table.min(axis=0)
    ok_p = np.nonzero(column_best <= tolerance)[0]
    if ok_p.size:
        P = int(ok_p[0])
        F = int(np.nonzero(table[:, P] <= tolerance)[0][0])
        return F, P, False
    reach = float(column_best.min()) + CAPPED_SLACK * tolerance
    P = int(np.nonzero(column_best <= reach)[0][0])
    F = int(np.nonzero(table[:, P] <= reach)[0][0])
    return F, P, True


class _GridData:
    """Everything one quadrature grid gives, each part computed when first needed: the view
    profile (the ``"bands"`` rule's only input), its ε columns one view order P at a time, and
    the 3-D reparameterization with RH02's projected ρ̂_lpq and unweighted table (the ``"rh02"``
    rule, or a reader of :attr:`OrderChoice.coefficients`)."""

    def __init__(self, brdf: BRDF, grid: ReparamGrid, max_F: int, max_P: int, criterion: str,
                 max_view_deg: float) -> None:
        self.brdf, self.grid = brdf, grid
        self.F0 = min(grid.n_theta_i - 1, max_F)
        self.P0 = min(grid.n_theta_o - 1, (grid.n_phi - 1) // 2, max_P)
        self.criterion, self.max_view_deg = criterion, max_view_deg
        self._columns: dict[int, np.ndarray] = {}

    @cached_property
    def profile(self) -> ViewProfile:
        # every order the grid resolves, also above max_F, which caps the table (F0: the columns are those
        # of a profile cut there, ``band_eps_column``'s F0) and so the choice: with the profile itself cut
        # at max_F, the energy the grid resolves above the cap counted as unresolved in the resolution
        # check (``resolution_tail``), which then failed and sampled a 1.5× finer grid for every tolerance
        # (the quick report's max_F = 96: 7 grids instead of 5 for microfacet σ = 0.1)
        return view_profile(self.brdf, self.grid, self.grid.n_theta_i - 1, self.P0)

    @cached_property
    def reparam(self) -> ReparamBRDF:
        return reparameterize(self.brdf, self.grid)

    @cached_property
    def coefficients(self) -> BRDFCoefficients:
        """RH02's projected ρ̂_lpq (eq. 13) on this grid."""
        return rho_lpq(self.reparam, self.F0, self.P0)

    @cached_property
    def rh02_table(self) -> np.ndarray:
        """RH02's unweighted ε[F, P] (raises for an all-zero BRDF)."""
        return eps_table(self.coefficients)

    @cached_property
    def zero(self) -> bool:
        """True when the samples of this grid hold no energy at all."""
        if self.criterion == "rh02":
            return not np.any(self.coefficients.energy > 0)
        return not np.any(self.profile.energy() > 0)

    def raise_zero(self) -> None:
        """The error of an all-zero BRDF (:func:`eps_table`'s)."""
        raise BadInputError(self.brdf.name, "the BRDF is zero everywhere: no orders to choose")

    @property
    def missing(self) -> int:
        """Samples without a measurement: the view profile's (and the 3-D grid's under ``"rh02"``)."""
        extra = self.reparam.n_without_data if self.criterion == "rh02" else 0
        return extra + int(self.profile.missing.sum())

    def column(self, p: int) -> np.ndarray:
        """ε[:, p] of the rule's table (computed once)."""
        if p not in self._columns:
            if self.criterion == "rh02":
                self._columns[p] = self.rh02_table[:, p]
            else:
                self._columns[p] = band_eps_column(self.profile, p, self.max_view_deg, self.F0)
        return self._columns[p]

    def table(self) -> np.ndarray:
        """ε[F, P] as far as computed: NaN in the columns no choice has needed."""
        if self.criterion == "rh02":
            return self.rh02_table
        out = np.full((self.F0 + 1, self.P0 + 1), np.nan)
        for p, col in self._columns.items():
            out[:, p] = col
        return out

    def choose(self, tolerance: float, hint: int | None) -> tuple[int, int, bool]:
        """(F, P, capped) by :func:`choose_from_table`'s rule, computing only the columns it needs.

        The best error of a column falls as P grows (a larger view order fits the views better:
        the fits nest, up to their reweighting passes — +1 % of ε at ε ≈ 3·10⁻⁵ for Lafortune
        n = 20; checked against a scan of every column in ``tests/analysis/test_orders.py``),
        so the first column that meets the tolerance is found from ``hint`` (the previous
        grid's P) by a galloping search and bisection, or, without a hint (a search's first
        grid), by bisection above the floor of :func:`~shrmkit.analysis.view_bands.view_order_floor`
        (no column below it can meet it)."""
        best = lambda p: float(self.column(p).min())  # noqa: E731
        floor = lambda tol: view_order_floor(self.profile, tol, self.max_view_deg)  # noqa: E731
        P = _first_true(lambda p: best(p) <= tolerance, self.P0, hint, floor(tolerance))
        capped = P is None
        reach = tolerance
        if P is None:  # capped
            reach = best(self.P0) + CAPPED_SLACK * tolerance
            P = _first_true(lambda p: best(p) <= reach, self.P0, hint, floor(reach))
            P = self.P0 if P is None else P
        F = int(np.nonzero(self.column(P) <= reach)[0][0])
        return F, int(P), capped


def _first_true(pred: Callable[[int], bool], top: int, hint: int | None, low: int = 0) -> int | None:
    """Smallest x in [low, top] with ``pred(x)`` for a monotone ``pred`` (False … False True … True;
    every x < ``low`` is known False), None when ``pred(top)`` is False: from ``hint`` one step at a
    time for two steps (a hint from the previous grid is usually within one), then galloping, then
    bisection; without a hint, bisection from [low, top] (``pred(top)`` first)."""
    def steps():
        yield from (1, 1)
        step = 2
        while True:
            yield step
            step *= 2

    low = min(max(int(low), 0), top)
    if hint is None:
        if not pred(top):
            return None
        good, bad = top, low - 1
    elif pred(x := min(max(int(hint), low), top)):
        good, bad = x, low - 1
        for step in steps():
            y = good - step
            if y < low:
                break
            if not pred(y):
                bad = y
                break
            good = y
    else:
        bad = x
        for step in steps():
            y = min(bad + step, top)
            if y == bad:
                return None
            if pred(y):
                good = y
                break
            bad = y
    while good - bad > 1:
        mid = (good + bad) // 2
        if pred(mid):
            good = mid
        else:
            bad = mid
    return good


def _validate(tolerance: float, max_F: int, max_P: int, criterion: str = DEFAULT_CRITERION,
              max_view_deg: float = DEFAULT_MAX_VIEW_DEG) -> float:
    """The tolerance as a float (``check_eps``) after checking the caps and the rule."""
    tolerance = check_eps(tolerance)
    check_criterion(criterion)
    check_max_view(max_view_deg)
    if int(max_F) < 1 or int(max_F) > 2000:
        raise BadInputError(None, f"max_F must be in [1, 2000], got {max_F!r}")
    if int(max_P) < 0 or int(max_P) > 64:
        raise BadInputError(None, f"max_P must be in [0, 64], got {max_P!r}")
    return tolerance


def choose_orders(
    brdf: BRDF | str | Path,
    *,
    eps: float | None = None,
    max_F: int | None = None,
    max_P: int | None = None,
    start_F: int = 24,
    start_P: int = 4,
    criterion: str | None = None,
    max_view_deg: float | None = None,
    rule: OrderRule | None = None,
) -> OrderChoice:
    """Choose (F, P) for ``brdf`` at tolerance ``eps`` (RH02 §5.1, Appendix C).

    Parameters
    ----------
    brdf
        Any evaluable BRDF (model, MERL, table, fitted model), or a spec string or path for
        :func:`~shrmkit.brdf_io.specs.load_brdf`.
    rule
        The order rule (:class:`~shrmkit.analysis.order_rule.OrderRule`: criterion, view limit,
        tolerance, caps); default ``OrderRule()``.
    eps, max_F, max_P, criterion, max_view_deg
        The rule's fields as loose keywords (None: not given), as before the rule: with ``rule``
        they must agree with it; without it they build it (defaults 0.03, 512, 20, ``"bands"``,
        80°). ``eps``: tolerance on the uncaptured energy fraction, in (0, 1); ``max_F``,
        ``max_P``: caps on the orders, beyond them the result is ``capped`` (documented, no
        loop); ``criterion``: ``"bands"``, every θ_v band that starts below ``max_view_deg``
        meets ``eps`` under a point light, or ``"rh02"``, RH02's energy over all views (module
        docs); ``max_view_deg``: view limit of the ``"bands"`` rule in degrees of θ_v, in (0, 90].
    start_F, start_P
        Orders the first quadrature grid is sized for.

    Returns
    -------
    OrderChoice

    Raises
    ------
    BadInputError
        ε outside (0, 1), caps or view limit out of range, an unknown criterion, an all-zero
        or non-finite BRDF, a loose keyword that disagrees with ``rule``.
    """
    rule = resolve_rule(rule, eps=eps, max_F=max_F, max_P=max_P, criterion=criterion, max_view_deg=max_view_deg)
    return choose_orders_many(brdf, (rule.eps,), start_F=start_F, start_P=start_P, rule=rule)[0]


def choose_orders_many(
    brdf: BRDF | str | Path,
    tolerances: Sequence[float],
    *,
    max_F: int | None = None,
    max_P: int | None = None,
    start_F: int = 24,
    start_P: int = 4,
    criterion: str | None = None,
    max_view_deg: float | None = None,
    rule: OrderRule | None = None,
) -> list[OrderChoice]:
    """:func:`choose_orders` at each of ``tolerances`` (in that order), sharing the work.

    Every choice starts on the same quadrature grid and the searches of nearby tolerances
    visit the same grids: each grid's view profile, table columns (and, when read, its 3-D
    reparameterization and projected coefficients) are computed once for all of them. Each
    result equals the one :func:`choose_orders` gives alone; its ``seconds`` is the time of
    its own search given the grids already computed for the tolerances before it.

    ``rule`` and the loose keywords are those of :func:`choose_orders`; ``rule.eps`` is not used
    (each choice's ``rule`` is ``rule`` at its own tolerance).

    Raises
    ------
    BadInputError
        As :func:`choose_orders`; also an empty ``tolerances``.
    """
    rule = resolve_rule(rule, max_F=max_F, max_P=max_P, criterion=criterion, max_view_deg=max_view_deg)
    max_F, max_P, criterion, max_view_deg = rule.max_F, rule.max_P, rule.criterion, rule.max_view_deg
    tolerances = [_validate(t, max_F, max_P, criterion, max_view_deg) for t in tolerances]
    if not tolerances:
        raise BadInputError(None, "no tolerance to choose orders for")
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    resolved = getattr(brdf, "resolved_order", None)
    table_cap = resolved() if callable(resolved) else None
    cap_note = None
    if table_cap is not None and (table_cap < max_F or table_cap < max_P):
        # a table resolves no order, F or P, beyond its grid's: the search stops there instead of growing
        # grids after the interpolation's kinks (TableBRDF.resolved_order; one measured sample among 216
        # nodes at max_P = 24 grew grids to 222 × 216 × 378, 11.6 s and 1.1 GB, and did not settle)
        max_F, max_P = min(max_F, max(int(table_cap), 1)), min(max_P, int(table_cap))
        cap_note = "the highest order this table's grid resolves: 2π / its finest measured spacing"
    cache: dict[tuple[int, int, int], _GridData] = {}

    def data_for(grid: ReparamGrid) -> _GridData:
        key = (grid.n_theta_i, grid.n_theta_o, grid.n_phi)
        if key not in cache:
            cache[key] = _GridData(brdf, grid, max_F, max_P, criterion, max_view_deg)
        return cache[key]

    with single_threaded_blas():
        return [_with_rule(_search(data_for, tol, max_F, max_P, min(start_F, max_F), start_P, criterion,
                                   max_view_deg, cap_note), rule) for tol in tolerances]


def _with_rule(choice: OrderChoice, rule: OrderRule) -> OrderChoice:
    """``choice`` stating the rule it was made under, at its own tolerance."""
    return replace(choice, rule=rule.replace(eps=choice.tolerance))


#: ``"bands"``: a grid resolves a choice when the energy just above the chosen orders is at most
#: this fraction of ε in every band inside the view limit (:func:`~shrmkit.analysis.view_bands.resolution_tail`).
RESOLVED_TAIL = 0.05
#: ``"bands"``: otherwise a 1.5× finer grid agrees when it keeps P and moves F by at most 1, or keeps
#: P and ε at its choice differs from the coarser grid's by at most this fraction of ε (a flat
#: ε(F) near the tolerance moves the first F that meets it with every grid, not the error).
AGREE_FRACTION = 0.05
#: A choice is taken from a grid sized for orders up to (F_goal, P_goal) when F <= this × F_goal + 2
#: (the grid's 2F_goal + 24 nodes still resolve it) and P <= P_goal.
GRID_SLACK = 1.15


def _finer(grid: ReparamGrid) -> ReparamGrid:
    return ReparamGrid(int(grid.n_theta_i * 1.5), int(grid.n_theta_o * 1.5), int(grid.n_phi * 1.5) + (grid.n_phi % 2))


def _search(data_for: Callable[[ReparamGrid], _GridData], eps: float, max_F: int, max_P: int, start_F: int,
            start_P: int, criterion: str, max_view_deg: float, cap_note: str | None = None) -> OrderChoice:
    """The order search of :func:`choose_orders` at one tolerance, grids from ``data_for``.

    Grids are sized for the choice they give (``ReparamGrid.for_orders``) until the choice fits
    the grid; a choice pressed against the grid's capacity (F > 0.8 F0: the unresolved energy
    counts as error there) sizes the next grid for 1.5× it. Then the resolution check
    (:class:`OrderChoice` ``converged``)."""
    t0 = time.perf_counter()
    notes: list[str] = []
    F_goal, P_goal = min(start_F, max_F), min(start_P, max_P)
    hint: int | None = None  # the first grid: bisection above the view-order floor
    for _ in range(24):
        on = data_for(ReparamGrid.for_orders(F_goal, P_goal))
        at_caps = on.F0 >= max_F and on.P0 >= max_P
        if on.zero:
            if not at_caps:
                # a lobe far sharper than this grid (Phong s = 1e6) can fall between its nodes
                F_goal, P_goal = min(2 * F_goal, max_F), min(P_goal + 4, max_P)
                continue
            on.raise_zero()
        F, P, capped = _choose(on, eps, hint)
        hint = P
        if capped and not at_caps:
            # the grid holds too few orders: the next holds half again as many as this one does
            # (a grid for F_goal has 2 F_goal + 24 nodes and holds ~2 F_goal + 23 orders)
            F_goal = min(max(2 * F_goal, int(np.ceil(1.5 * on.F0))), max_F)
            P_goal = min(max(P_goal + 4, P + 2), max_P)
        elif F > GRID_SLACK * F_goal + 2 or P > P_goal:
            # the grid holds orders up to ~2x what it resolves well: resize it for the choice
            grow = 1.5 if F > 0.8 * on.F0 else 1.25
            F_goal, P_goal = min(max(F_goal, int(np.ceil(grow * F))), max_F), max(P_goal, P)
        else:
            break
    converged = False
    for _ in range(3):
        tail = None if criterion == "rh02" else resolution_tail(on.profile, F, P, max_view_deg, on.grid.n_phi)
        if tail is not None and tail <= RESOLVED_TAIL * eps:
            converged = True
            break
        fine = data_for(_finer(on.grid))
        F2, P2, capped2 = _choose(fine, eps, P)
        same = P2 == P and capped2 == capped and abs(F2 - F) <= 1
        if criterion != "rh02" and not same and P2 == P and capped2 == capped and F2 <= on.F0:
            same = abs(fine.column(P2)[F2] - on.column(P2)[F2]) <= AGREE_FRACTION * eps
        on, F, P, capped = fine, F2, P2, capped2
        if same:
            converged = True
            break
    if on.zero:
        on.raise_zero()
    if capped and cap_note is not None:
        notes.append(f"tolerance {eps:g} not met within F<={max_F} ({cap_note}), P<={max_P}: "
                     f"ε({F}, {P}) = {on.column(P)[F]:.3g}; a finer table is needed")
    elif capped:
        notes.append(
            f"tolerance {eps:g} not met within the caps F<={max_F}, P<={max_P}: "
            f"ε({F}, {P}) = {on.column(P)[F]:.3g}; raise max_F/max_P"
        )
    if not converged:
        notes.append("the order choice did not settle under quadrature refinement (table too coarse?)")
    if on.missing:
        notes.append(f"{on.missing} reparameterized samples had no measurement to interpolate (set to 0)")
    return _choice(on, F, P, eps, capped, converged, notes, time.perf_counter() - t0, criterion, max_view_deg)


def _choose(on: _GridData, eps: float, hint: int | None) -> tuple[int, int, bool]:
    if on.criterion == "rh02":
        return choose_from_table(on.rh02_table, eps)
    return on.choose(eps, hint)


def _choice(on: _GridData, F: int, P: int, eps: float, capped: bool, converged: bool, notes: list[str],
            seconds: float, criterion: str, max_view_deg: float) -> OrderChoice:
    achieved = float(on.column(P)[F])
    if not achieved <= 1.0 + 1e-9:
        # an energy fraction above 1 (or NaN): the truncation misses more than the BRDF holds, which only
        # inconsistent samples make (values no reader should have let through); never a result
        raise BadInputError(on.brdf.name, f"the order rule's error ε({F}, {P}) = {achieved:.4g} is not an energy "
                            "fraction in [0, 1]: the BRDF's samples are inconsistent")
    return OrderChoice(
        F=F, P=P, eps=float(on.column(P)[F]), tolerance=float(eps), searched_table=on.table(), capped=capped,
        converged=converged, message="; ".join(notes), seconds=seconds, grid=on.grid,
        n_without_data=on.missing, criterion=criterion, max_view_deg=float(max_view_deg), source=on,
    )


def orders_on_grid_for(
    brdf: BRDF, F: int, P: int, *, eps: float | None = None, criterion: str | None = None,
    max_view_deg: float | None = None, rule: OrderRule | None = None,
) -> OrderChoice:
    """ρ̂_lpq and ε(F, P) on one quadrature grid sized for given orders (no search).

    For callers that force (F, P): the rule's choice on this grid is still reported in
    ``F``/``P`` (capped if the grid cannot meet ``eps``), but the grid is neither grown
    nor refined (``converged`` is False and ``message`` says so). ``rule`` and the loose
    keywords as in :func:`choose_orders`; the rule's caps are not used (F and P are).
    """
    rule = resolve_rule(rule, eps=eps, criterion=criterion, max_view_deg=max_view_deg)
    eps, criterion, max_view_deg = rule.eps, rule.criterion, rule.max_view_deg
    eps = _validate(eps, max(F, 1), P, criterion, max_view_deg)
    t0 = time.perf_counter()
    grid = ReparamGrid.for_orders(F, P)
    on = _GridData(brdf, grid, grid.n_theta_i - 1, max(P, 1), criterion, max_view_deg)
    if on.zero:
        on.raise_zero()
    F_rule, P_rule, capped = _choose(on, eps, P)
    notes = [f"orders asked (F={F}, P={P}): the grid was sized for them and not refined"]
    if on.missing:
        notes.append(f"{on.missing} reparameterized samples had no measurement to interpolate (set to 0)")
    return _with_rule(_choice(on, F_rule, P_rule, eps, capped, False, notes, time.perf_counter() - t0, criterion,
                              max_view_deg), rule)


def forced_orders_note(
    F_asked: int | None, P_asked: int | None, F_used: int, P_used: int, *, F_limit: int, P_limit: int
) -> str:
    """The note, and one :class:`OrdersClampedWarning` (a single line), when orders given to
    ``prefilter(F=, P=)`` were lowered to what is there to use: ``F_limit`` the highest lighting
    order computed (the map's rows − 1, or the BRDF grid's F0), ``P_limit`` the BRDF grid's P0.
    ``""`` when nothing was asked or nothing was lowered."""
    parts = []
    if F_asked is not None and F_used < int(F_asked):
        parts.append(f"F={F_used} used, F={int(F_asked)} asked (the lighting is computed to l <= {F_limit}: "
                     "the map's rows - 1 or the BRDF grid's order)")
    if P_asked is not None and P_used < int(P_asked):
        parts.append(f"P={P_used} used, P={int(P_asked)} asked (the BRDF grid holds p <= {P_limit})")
    if not parts:
        return ""
    note = "orders clamped: " + "; ".join(parts)
    warnings.warn(note, OrdersClampedWarning, stacklevel=3)
    return note
