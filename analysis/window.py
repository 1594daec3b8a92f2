"""The window against Gibbs ringing (DESIGN §7): which σ-factors a prefiltered SHRM gets, decided
from the coefficients and a small sample of the reflected field.

Truncating the product spectrum of a sharp light and a sharp lobe rings: the expansion dips
below zero around bright regions. ``--window`` chooses what to do about it (:data:`WINDOWS`):

- ``none``: the bare truncated expansion;
- ``lanczos``: the Lanczos σ-factors in full (:func:`~shrmkit.analysis.scene.lanczos_sigma`):
  in (l, p) under [RH02]'s rule, whose projected view dependence rings too, and in l under the
  ``"bands"`` rule, whose fitted view dependence does not need damping (a window in p would cost
  the grazing bands most);
- ``auto`` (default): the bare expansion when its undershoot (−min/max of the sampled radiance,
  worst channel: :func:`undershoot`) is at most :data:`WINDOW_THRESHOLD`; else the σ-factors at
  the smallest strength t (σ(t) = 1 − t(1 − σ)) that brings it under the threshold, capped by an
  error budget (:func:`choose_window`): under ``"bands"`` the predicted error may not pass ε in
  any view band inside the limit, so a tighter tolerance never gives a larger error; under
  ``"rh02"`` the window may add :data:`WINDOW_BUDGET_EPS`·ε to ε_B.

The undershoot is measured on a sample, never on full maps: the reflected field at the normal
view and three fixed oblique views of every pixel of a coarse grid of about 3(F + P) rows
(:func:`~shrmkit.analysis.synthesis.local_view_field`), for the bare and the fully windowed
coefficients; the synthesis is linear in σ, so the sample at strength t is (1 − t)·bare +
t·full without another synthesis. The map itself is synthesized once, at the chosen strength.

References: [RH02]; [Lanczos56] (σ-factors).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..brdf_io.errors import BadInputError
from ..brdf_io.latlong import pixel_angles, pixel_directions
from .brdf_coeffs import BRDFCoefficients
from .defaults import (  # numpy-free home, for the CLI's parsers
    DEFAULT_WINDOW,
    WINDOW_BUDGET_EPS,
    WINDOW_THRESHOLD,
    WINDOWS,
)
from .lighting import LightingCoefficients
from .scene import lanczos_sigma, reflected_error_parts
from .sh import real_sph_harm
from .synthesis import local_view_field, sample_rows, windowed
from .view_bands import ViewProfile, bands_inside, shrm_view_bands

__all__ = [
    "WINDOWS", "DEFAULT_WINDOW", "WINDOW_THRESHOLD", "WINDOW_BUDGET_EPS", "UNDERSHOOT_MAX_VIEW_DEG",
    "check_window", "undershoot", "gibbs_negative", "undershoot_views", "undershoot_samples", "WindowChoice",
    "choose_window",
]

#: Largest view angle θ_v = angle(N, V) of the full-map undershoot sample (:func:`undershoot_samples`).
UNDERSHOOT_MAX_VIEW_DEG = 85.0


def check_window(window: Any, name: str = "window") -> str:
    """The one validator of a window name (:data:`WINDOWS`); BadInputError otherwise."""
    if not isinstance(window, str) or window not in WINDOWS:
        raise BadInputError(None, f"{name}={window!r}: choose one of {', '.join(WINDOWS)}")
    return window


def gibbs_negative(coeffs: np.ndarray, P: int) -> float:
    """Ringing measure: −min / max of the normal-view radiance B(R, V = R) over the map
    (worst channel; 0 when nothing is negative). Truncating a sharp lobe creates
    negative lobes (Gibbs); a window reduces them."""
    height, width = coeffs.shape[1:3]
    dirs = pixel_directions(height, width)
    peak = np.full(3, -np.inf)
    low = np.full(3, np.inf)
    for r0 in range(0, height, 32):  # row blocks keep the basis array small at high P
        basis = real_sph_harm(P, dirs[r0 : r0 + 32]).astype(np.float32)  # (h, W, n_coef)
        normal_view = np.einsum("hwk,khwc->hwc", basis, coeffs[:, r0 : r0 + 32])
        peak = np.maximum(peak, normal_view.max(axis=(0, 1)))
        low = np.minimum(low, normal_view.min(axis=(0, 1)))
    return undershoot(np.stack([low, peak], axis=1))


_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
#: Oblique views per pixel of the undershoot sample when P > 0 (:func:`undershoot_views`).
OBLIQUE_VIEWS = 2


def undershoot_views(
    height: int, width: int, P: int, *, max_view_deg: float = UNDERSHOOT_MAX_VIEW_DEG
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The view directions of the undershoot sample of an H × W map, one (θ_V, Δφ_V) pair of
    (H,) arrays per view: at pixel (i, j) (reflection direction R_ij) the view V_ij has polar
    angle θ_V[i] and azimuth φ_j + Δφ_V[i], φ_j the pixel column's azimuth.

    The first is the normal view V = R (what :func:`gibbs_negative` measures). When P > 0,
    :data:`OBLIQUE_VIEWS` more give each pixel a view at θ_v = angle(N, V) in
    (0, ``max_view_deg``], N = normalize(R + V), since the view-order (P) truncation rings at
    oblique views too: for row i and extra view e, k = i·OBLIQUE_VIEWS + e, θ_v at
    1 − frac((k + ½)·0.618…) of the range, and V = cos 2θ_v R + sin 2θ_v (cos ψ t + sin ψ b)
    with ψ = 2π frac(k·√2), t = z × R / |z × R| and b = R × t. The choice depends on the row
    only, so rotating the environment about z by whole columns shifts the sample with it (and
    ``prefilter``'s ``auto`` decision does not change). For P = 0, B does not depend on V.
    """
    theta, _ = pixel_angles(height, width)
    views = [(theta, np.zeros(height))]
    if P > 0:
        # R in the x-z plane (φ = 0): t = (0, 1, 0), b = R × t; then rotate by each column's φ
        R0 = np.stack([np.sin(theta), np.zeros(height), np.cos(theta)], axis=-1)
        t_axis = np.array([0.0, 1.0, 0.0])
        b_axis = np.cross(R0, t_axis)
        for extra in range(OBLIQUE_VIEWS):
            k = np.arange(height, dtype=np.float64) * OBLIQUE_VIEWS + extra
            two_theta = (2.0 * np.radians(max_view_deg) * (1.0 - ((k + 0.5) * _GOLDEN) % 1.0))[:, None]
            psi = (2.0 * np.pi * ((k * np.sqrt(2.0)) % 1.0))[:, None]
            V0 = np.cos(two_theta) * R0 + np.sin(two_theta) * (np.cos(psi) * t_axis + np.sin(psi) * b_axis)
            views.append((np.arccos(np.clip(V0[:, 2], -1.0, 1.0)), np.arctan2(V0[:, 1], V0[:, 0])))
    return views


def _row_basis(P: int, theta: np.ndarray, offset: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Real SH Y^r_k (k < (P+1)²) at the directions (θ[i], offset[i] + φ[j]): float32 (h, W, n_coef).

    Y^r_lm = A_l|m|(θ) cos(mφ) for m >= 0 and A_l|m|(θ) sin(|m|φ) for m < 0 (the real basis of
    ``analysis.sh``), so the θ part is evaluated once per row, at φ = 0."""
    n = (P + 1) ** 2
    l_of = np.floor(np.sqrt(np.arange(n))).astype(int)
    m_of = np.arange(n) - l_of * l_of - l_of
    at_zero = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    amplitude = real_sph_harm(P, at_zero)[:, l_of * l_of + l_of + np.abs(m_of)].astype(np.float32)  # (h, n)
    angle = (offset[:, None, None] + phi[None, :, None]) * np.arange(P + 1)  # (h, W, P+1): mφ
    trig = np.concatenate([np.cos(angle), np.sin(angle)], axis=-1).astype(np.float32)
    pick = np.where(m_of < 0, P + 1 - m_of, m_of)  # cos(mφ) for m >= 0, sin(|m|φ) for m < 0
    basis = trig[..., pick]
    basis *= amplitude[:, None, :]
    return basis


def undershoot_samples(coeffs: np.ndarray, P: int, views: list | None = None) -> np.ndarray:
    """B(R, V) of a global SHRM (unclamped) on its undershoot sample, channel-major float32
    (3, n): R at every pixel centre (the renderer interpolates bilinearly between them, which
    creates no new minimum at a fixed V), V from :func:`undershoot_views` (computed here when
    not given); the first H·W columns are the normal views."""
    height, width = coeffs.shape[1:3]
    views = undershoot_views(height, width, P) if views is None else views
    _, phi = pixel_angles(height, width)
    out = np.empty((3, len(views) * height * width), dtype=np.float32)
    for i, (theta_v, offset) in enumerate(views):
        block = out[:, i * height * width : (i + 1) * height * width].reshape(3, height, width)
        for r0 in range(0, height, 32):  # row blocks keep the basis array small at high P
            rows = slice(r0, r0 + 32)
            basis = _row_basis(P, theta_v[rows], offset[rows], phi)  # (h, W, n_coef)
            # per pixel (1, n_coef) @ (n_coef, 3): a batched product over (h, W)
            per_pixel = np.matmul(basis[:, :, None, :], coeffs[:, rows].transpose(1, 2, 0, 3))  # (h, W, 1, 3)
            block[:, rows] = per_pixel[:, :, 0, :].transpose(2, 0, 1)
    return out


def undershoot(values: np.ndarray) -> float:
    """−min / max of sampled radiance, channel-major (3, n); worst channel, 0 when nothing is
    negative (the measure of ``eps["gibbs_negative"]`` and ``meta["negative_after"]``)."""
    peak = values.max(axis=1)
    low = values.min(axis=1)
    live = peak > 0
    return float(np.max(np.clip(-low[live] / peak[live], 0.0, None), initial=0.0))


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
    """What :func:`choose_window` decided, and what the undershoot sample measured.

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


def choose_window(
    window: str,
    lighting: LightingCoefficients,
    coefficients: BRDFCoefficients,
    F: int,
    P: int,
    eps: float,
    *,
    criterion: str,
    profile: ViewProfile | None = None,
    max_view_deg: float = 80.0,
    band_energy: np.ndarray | None = None,
    projected: BRDFCoefficients | None = None,
    q_max: int | None = None,
    top: int | None = None,
    map_rows: Any = None,
    nthreads: int = 1,
) -> WindowChoice:
    """The window of :func:`~shrmkit.analysis.shrm.prefilter` at the scene's orders (module docs).

    Parameters
    ----------
    window
        One of :data:`WINDOWS`.
    lighting, coefficients
        L_lm and the ρ̂_lpq the map is made of (the view fit at P for ``"bands"``).
    F, P, eps
        The scene's orders (F_B, P_B) and the tolerance; the orders never change here.
    criterion, profile, max_view_deg, band_energy
        The order rule; for ``"bands"`` the BRDF's view profile, the view limit and the lighting's
        a_l (:meth:`~shrmkit.analysis.lighting.LightingCoefficients.band_energy_all`), from which
        the predicted error per view band of a windowed field follows
        (:func:`~shrmkit.analysis.view_bands.shrm_view_bands`).
    projected
        RH02's projected coefficients (``"rh02"``: the error budget of the strength).
    q_max
        ``q_max=0`` for the azimuth-free SHRM.
    top
        The largest F the lighting and the coefficients hold (``"bands"``: F_B may be raised up to
        it for the window); None keeps the orders.
    map_rows
        Optional callable F -> rows of the map that will be made at that F: the sample is taken at
        the map's own pixel centres when they are fewer than the coarse sample's rows.

    Returns
    -------
    WindowChoice

    Notes
    -----
    ``auto`` takes the smallest strength t whose sampled undershoot is at most the threshold,
    capped by the error budget (:func:`_strength_budget`): under ``"bands"`` the windowed field's
    predicted error may not pass ε in any view band inside the limit. That makes the result
    monotone in ε: a tighter tolerance gives the same or a larger F_B (the scene rule takes the
    first F whose bare error meets ε); at the same F_B it allows the same or a weaker window (the
    error grows with t); at a larger F_B the bare error of the looser choice was already above the
    tighter ε, while the new error is at most that ε. So the stated error never grows as ε
    shrinks. Ringing the budget cannot remove stays in the sample's numbers and is clamped to 0
    where radiance is produced; bright compact lights are what rings, and taking them out of the
    map as lights removes the cause.
    """
    check_window(window)
    sample = _Sample(lighting, coefficients, P, q_max, nthreads, map_rows)
    # RH02's projection rings in the view order p too: its window is in (l, p); the bands rule's
    # view fit does not need one in p, and one there would cost the grazing bands most
    sample.in_view = criterion == "rh02" or profile is None
    search = _WindowSearch(sample, eps, criterion, profile, max_view_deg, band_energy, projected)
    if window == "none":
        before = undershoot(sample(F, False))
        return search.done(F, 0.0, before, "requested")
    if window == "lanczos":
        return search.done(F, 1.0, None, "requested")
    before = undershoot(sample(F, False))
    if before <= WINDOW_THRESHOLD:
        return search.done(F, 0.0, before,
                           f"auto: undershoot {_pct(before)} of the peak <= threshold {WINDOW_THRESHOLD:.1%}")
    rings = f"auto: undershoot {_pct(before)} of the peak > threshold {WINDOW_THRESHOLD:.1%}"
    if criterion == "rh02" or profile is None or top is None or top <= F:
        return _auto_at_orders(search, F, before, rings)
    return _auto_raising_order(search, F, top, before, rings)


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
    allows a stronger window, and the error it states never grows (module docs)."""
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
