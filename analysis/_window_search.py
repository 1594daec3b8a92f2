"""The strength search of the ``auto`` window: the coarse samples of one scene, the least strength
that removes the undershoot, its error budget, and the raise of F_B under the ``"bands"`` rule
(:class:`WindowChoice` is what it decides). Driven by
:func:`shrmkit.analysis.window.choose_window` (module docs there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._undershoot import undershoot
from .brdf_coeffs import BRDFCoefficients
from .defaults import WINDOW_BUDGET_EPS, WINDOW_THRESHOLD
from .lighting import LightingCoefficients
from .scene import lanczos_sigma, reflected_error_parts
from .synthesis import local_view_field, sample_rows, windowed
from .view_bands import ViewProfile, bands_inside, shrm_view_bands


def _strength_for(before: np.ndarray, full: np.ndarray, threshold: float, t_max: float) -> float:
    """The window strength t in [0, t_max] for ``auto``: the smallest t (to t_max·2⁻¹³) with
    undershoot((1 − t)·before + t·full) <= threshold — the synthesis is linear in σ, so these are
    the samples of the map at strength t — or, when no t reaches the threshold, the t of a 33-point
    grid with the least undershoot (0 when the window does not reduce it: where the true radiance
    is 0 over large regions, any ringing is negative).

    Only two small subsets of the samples matter, per channel: those negative at some t
    (min(before, full) < 0), and those that can be the maximum at some t
    (max(before, full) >= max over samples of min(before, full))."""
    low_side = np.minimum(before, full)
    high_side = np.maximum(before, full)
    floor = low_side.max(axis=1, keepdims=True)  # <= the maximum at every t
    channels = []
    for c in range(before.shape[0]):
        keep = (low_side[c] < 0.0) | (high_side[c] >= floor[c])
        channels.append((before[c, keep].astype(np.float64), full[c, keep].astype(np.float64)))

    def under(t: float) -> float:
        worst = 0.0
        for b, f in channels:
            value = b + t * (f - b)
            peak = value.max(initial=0.0)
            if peak > 0.0:
                worst = max(worst, -value.min(initial=0.0) / peak)
        return worst

    grid = t_max * np.arange(33) / 32.0
    values = np.array([under(t) for t in grid])
    ok = np.flatnonzero(values <= threshold)
    if ok.size == 0:
        return float(grid[int(np.argmin(values))])
    if ok[0] == 0:
        return 0.0
    lo, hi = float(grid[ok[0] - 1]), float(grid[ok[0]])
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        if under(mid) <= threshold:
            hi = mid
        else:
            lo = mid
    return hi


@dataclass(frozen=True)
class WindowChoice:
    """What :func:`~shrmkit.analysis.window.choose_window` decided, and what the undershoot sample measured.

    Attributes
    ----------
    F
        The order the map is synthesized at (above the scene's F_B when the ``"bands"`` rule
        raised it for the window).
    strength, sigma
        Window strength t in [0, 1] and its σ_lp, (F+1, P+1) (None for t = 0).
    before
        Undershoot of the bare expansion at the scene's F_B (None for ``"lanczos"``: not measured).
    after, negative_fraction, normal_after
        Undershoot left, the share of sampled (R, V) pairs still negative (before clamping) and
        the undershoot of the normal views V = R alone.
    reason
        One line on what was decided and why.
    capped
        True when no order up to the lighting's (or the caps') could give a windowed field that
        meets ε: the least predicted error was taken (``reason`` says so).
    pairs, samples
        (R, V) pairs in one sample, and samples synthesized (each a bare or fully windowed field
        on the coarse grid).
    """

    F: int
    strength: float
    sigma: np.ndarray | None
    before: float | None
    after: float
    negative_fraction: float
    normal_after: float
    reason: str
    capped: bool = False
    pairs: int = 0
    samples: int = 0


class _Sample:
    """The coarse undershoot samples of one scene, synthesized once per (F, bare | full window)."""

    def __init__(self, lighting: LightingCoefficients, coefficients: BRDFCoefficients, P: int,
                 q_max: int | None, nthreads: int, map_rows: Any = None) -> None:
        self.lighting, self.coefficients, self.P = lighting, coefficients, P
        self.q_max, self.nthreads = q_max, nthreads
        self.map_rows = map_rows
        self.in_view = True
        self._cache: dict[tuple[int, bool], np.ndarray] = {}

    def rows(self, F: int) -> int:
        """:func:`~shrmkit.analysis.synthesis.sample_rows`, or the map's own rows when they are
        fewer: the renderer interpolates the map's pixel values bilinearly, which makes no new
        minimum, so the undershoot of what is displayed is the one at the map's pixel centres."""
        own = sample_rows(F, self.P)
        return own if self.map_rows is None else int(min(own, max(2, self.map_rows(F))))

    def __call__(self, F: int, full: bool) -> np.ndarray:
        key = (int(F), bool(full))
        if key not in self._cache:
            sigma = lanczos_sigma(F, self.P, in_view=self.in_view) if full else None
            rows = self.rows(F)
            self._cache[key] = local_view_field(
                self.lighting, windowed(self.coefficients, sigma, F, self.P), F, self.P, rows, q_max=self.q_max,
                nthreads=self.nthreads,
            )
        return self._cache[key]

    @property
    def count(self) -> int:
        return len(self._cache)

    def normal_pairs(self, F: int) -> int:
        rows = self.rows(F)
        return rows * 2 * rows


def _mix(bare: np.ndarray, full: np.ndarray, t: float) -> np.ndarray:
    """The sample at strength t: linear in σ."""
    return bare + np.float32(t) * (full - bare)



class _WindowSearch:
    """One :func:`choose_window` call: the scene, its undershoot samples, and the measures of a
    window of strength t at order F that the search compares (each sample synthesized once)."""

    def __init__(self, sample: _Sample, eps: float, criterion: str, profile: ViewProfile | None,
                 max_view_deg: float, band_energy: np.ndarray | None, projected: BRDFCoefficients | None) -> None:
        self.sample, self.eps, self.criterion, self.profile = sample, eps, criterion, profile
        self.max_view_deg, self.band_energy, self.projected = max_view_deg, band_energy, projected
        self.found: dict[int, tuple[float, float]] = {}
        self._inside: Any = None

    def shape(self, F: int, t: float) -> np.ndarray | None:
        """σ_lp of the Lanczos window at strength t (None for t = 0)."""
        return lanczos_sigma(F, self.sample.P, t, in_view=self.sample.in_view) if t > 0.0 else None

    def measure(self, F: int, t: float) -> tuple[float, float, float]:
        """(undershoot, share of negative pairs, undershoot of the normal views) at strength t."""
        sample = self.sample
        values = sample(F, t == 1.0) if t in (0.0, 1.0) else _mix(sample(F, False), sample(F, True), t)
        n_normal = sample.normal_pairs(F)
        return undershoot(values), float(np.mean(values.min(axis=0) < 0.0)), undershoot(values[:, :n_normal])

    def done(self, F: int, t: float, before: float | None, reason: str, capped: bool = False) -> WindowChoice:
        """The choice (F, t), with the undershoot the sample keeps at it."""
        after, fraction, normal = self.measure(F, t)
        sigma = self.shape(F, t)
        if after > 0.0:
            reason += (f"; undershoot left {_pct(after)} of the peak on {_pct(fraction)} of the sampled pairs, "
                       "clamped to 0 at the output")
        pairs = self.sample(F, t > 0.0).shape[1]
        return WindowChoice(F=int(F), strength=float(t), sigma=sigma, before=before, after=after,
                            negative_fraction=fraction, normal_after=normal, reason=reason, capped=capped,
                            pairs=pairs, samples=self.sample.count)

    def budget(self, F: int, projected: BRDFCoefficients) -> float:
        """The largest strength the error allows at F (:func:`_strength_budget`)."""
        s = self.sample
        return _strength_budget(self.criterion, s.lighting, projected, s.coefficients, self.profile,
                                self.band_energy, F, s.P, self.eps, s.q_max, self.max_view_deg, self.shape)

    def error(self, F: int, t: float) -> float:
        """The predicted error energy of the worst view band inside the limit (``"bands"``)."""
        assert self.band_energy is not None  # the "bands" rule is given the lighting's a_l
        assert self.profile is not None  # and the BRDF's view profile
        if self._inside is None:
            self._inside = bands_inside(self.profile, self.max_view_deg)
        s = self.sample
        bands = shrm_view_bands(self.profile, s.coefficients, self.band_energy, F, s.P, sigma=self.shape(F, t),
                                q_max=s.q_max).bands
        return max(bands[b]["predicted_rel_rms"] ** 2 for b in self._inside)

    def evaluate(self, F: int) -> tuple[float, float]:
        """(t(F), e(F, t(F))): the strength the undershoot needs at F (none when the bare field does
        not ring there) and the predicted worst-band error energy with it."""
        if F not in self.found:
            sample = self.sample
            if undershoot(sample(F, False)) <= WINDOW_THRESHOLD:
                t = 0.0
            else:
                t = _strength_for(sample(F, False), sample(F, True), WINDOW_THRESHOLD, 1.0)
            self.found[F] = (t, self.error(F, t))
        return self.found[F]


def _auto_at_orders(search: _WindowSearch, F: int, before: float, rings: str) -> WindowChoice:
    """``auto`` at the scene's orders: the least strength that removes the undershoot, capped by the
    error budget (``"rh02"``, or no view profile or no room above F_B)."""
    sample = search.sample
    t_budget = search.budget(F, search.projected if search.projected is not None else sample.coefficients)
    # no room for a window: the fully windowed sample is not needed
    t = 0.0 if t_budget <= 0.0 else _strength_for(sample(F, False), sample(F, True), WINDOW_THRESHOLD, t_budget)
    after, _, _ = search.measure(F, t)
    reason = rings
    if t == 0.0:
        reason += (", not reduced by the Lanczos window" if t_budget > 0.0 else
                   ", no window: the error budget leaves no room for one")
    elif after > WINDOW_THRESHOLD:
        reason += (f", strength capped by the error budget ({_budget_words(search.criterion)})"
                   if t >= t_budget and t_budget < 1.0 else ", strength of the least undershoot")
    capped = after > WINDOW_THRESHOLD and t_budget < 1.0 and t >= t_budget
    return search.done(F, t, before, reason, capped=capped)


def _auto_raising_order(search: _WindowSearch, F: int, top: int, before: float, rings: str) -> WindowChoice:
    """``auto`` under the ``"bands"`` rule: the smallest F' in [F_B, top] whose field, with the
    window its undershoot needs, meets ε in every view band inside the limit (bisection)."""
    eps = search.eps
    t0, e0 = search.evaluate(F)
    if e0 <= eps:
        return search.done(F, t0, before, rings + _strength_note(t0, search.measure(F, t0)[0]).replace(";", ",", 1))
    # the smallest F whose fully windowed field meets ε bounds the answer: there e(F, t) <= ε for
    # every t (each band's error is a convex quadratic in t, at most ε at both ends)
    F_hi = _first_meeting(lambda f: search.error(f, 1.0) <= eps and search.error(f, 0.0) <= eps, F + 1, top)
    if F_hi is None and search.evaluate(top)[1] <= eps:
        F_hi = top  # no full window meets ε, but the field at the top order needs less of one
    if F_hi is None:
        return _capped_at_top(search, F, top, before, rings)
    lo, hi = F, F_hi
    search.evaluate(hi)
    for _ in range(MAX_BISECTIONS):
        if hi - lo <= 1:
            break
        mid = (lo + hi) // 2
        if search.evaluate(mid)[1] <= eps:
            hi = mid
        else:
            lo = mid
    t, _ = search.found[hi]
    raised = f"; F_B raised from {F} to {hi} so that the windowed field meets eps in every view band"
    return search.done(hi, t, before, rings + raised + _strength_note(t, search.measure(hi, t)[0]))


def _capped_at_top(search: _WindowSearch, F: int, top: int, before: float, rings: str) -> WindowChoice:
    """No order the lighting holds meets ε with the window the undershoot needs: the accuracy comes
    first (the largest order, strength capped by the error budget there)."""
    t_budget = search.budget(top, search.sample.coefficients)
    t_top = search.evaluate(top)[0]
    t = min(t_top, t_budget)
    note = (f"; capped (window budget): no F up to {top} meets eps {search.eps:g} in every view band with the "
            f"window the undershoot needs, F_B raised from {F} to {top} with the strength the error budget allows")
    return search.done(top, t, before, rings + note + _strength_note(t, search.measure(top, t)[0]), capped=True)


#: Bisection steps of :func:`choose_window` between the scene's F_B and the smallest F whose fully
#: windowed field meets ε (each step may synthesize two coarse samples).
MAX_BISECTIONS = 2


def _strength_note(t: float, after: float) -> str:
    if t == 0.0:
        return "; no window needed there" if after <= WINDOW_THRESHOLD else "; not reduced by the window"
    if after > WINDOW_THRESHOLD:
        return f"; Lanczos strength {t:.3g} (least undershoot)"
    return f"; Lanczos strength {t:.3g}"


def _first_meeting(meets: Any, lo: int, hi: int) -> int | None:
    """The smallest f in [lo, hi] with meets(f), scanning with a doubling step and then back
    (meets is monotone in f up to quadrature: the windowed truncation error falls with F)."""
    if lo > hi:
        return None
    prev, f, step = lo - 1, lo, 1
    while True:
        if meets(f):
            for g in range(prev + 1, f):
                if meets(g):
                    return g
            return f
        if f >= hi:
            return None
        prev, f, step = f, min(f + step, hi), step * 2


def _pct(x: float) -> str:
    """A share in percent with three significant digits (never "0.000%" for a share that is not 0)."""
    return f"{100.0 * x:.3g}%"


def _budget_words(criterion: str) -> str:
    if criterion == "rh02":
        return f"{WINDOW_BUDGET_EPS:g} eps of added error energy"
    return "the predicted error may not pass eps in any view band inside the limit"


def _strength_budget(
    criterion: str, lighting: LightingCoefficients, projected: BRDFCoefficients, coefficients: BRDFCoefficients,
    profile: ViewProfile | None, band_energy: np.ndarray | None, F: int, P: int, eps: float, q_max: int | None,
    max_view_deg: float, shape: Any,
) -> float:
    """The largest strength t the error allows. ``"rh02"``: the window may add at most
    :data:`WINDOW_BUDGET_EPS`·ε to ε_B (in closed form: the window part of ε_B is t² times that of
    the full window, :func:`~shrmkit.analysis.scene.reflected_error_parts`). ``"bands"``: the
    predicted error energy of every view band inside the limit stays at most ε (or at most the
    bare expansion's, where that is already above ε), by bisection — so a tighter tolerance never
    allows a stronger window, and the error it states never grows (:mod:`~shrmkit.analysis.window`)."""
    if criterion == "rh02" or profile is None:
        full = shape(F, 1.0)
        truncation, cost = reflected_error_parts(lighting, projected, F, P, full, q_max=q_max)
        allowed = truncation.max() + WINDOW_BUDGET_EPS * eps  # ε_B may grow to this (worst channel)
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(np.min(np.sqrt(np.clip(allowed - truncation, 0.0, None) / cost), initial=1.0))
    inside = bands_inside(profile, max_view_deg)

    def worst(t: float) -> float:
        assert band_energy is not None  # the "bands" rule is given the lighting's a_l
        bands = shrm_view_bands(profile, coefficients, band_energy, F, P, sigma=shape(F, t), q_max=q_max).bands
        return max(bands[b]["predicted_rel_rms"] ** 2 for b in inside)

    limit = max(eps, worst(0.0))
    if worst(1.0) <= limit:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst(mid) <= limit else (lo, mid)
    return lo
