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

from typing import Any

import numpy as np

from ..brdf_io.errors import BadInputError

# the `NAME as NAME` imports: public here before the split, importable from here still (patch them where read)
from ._undershoot import OBLIQUE_VIEWS as OBLIQUE_VIEWS
from ._undershoot import (
    UNDERSHOOT_MAX_VIEW_DEG,
    gibbs_negative,
    undershoot,
    undershoot_samples,
    undershoot_views,
)
from ._window_search import MAX_BISECTIONS as MAX_BISECTIONS
from ._window_search import (
    WindowChoice,
    _auto_at_orders,
    _auto_raising_order,
    _pct,
    _Sample,
    _WindowSearch,
)
from .brdf_coeffs import BRDFCoefficients
from .defaults import (  # numpy-free home, for the CLI's parsers
    DEFAULT_WINDOW,
    WINDOW_BUDGET_EPS,
    WINDOW_THRESHOLD,
    WINDOWS,
)
from .lighting import LightingCoefficients
from .view_bands import ViewProfile

__all__ = [
    "WINDOWS", "DEFAULT_WINDOW", "WINDOW_THRESHOLD", "WINDOW_BUDGET_EPS", "UNDERSHOOT_MAX_VIEW_DEG",
    "check_window", "undershoot", "gibbs_negative", "undershoot_views", "undershoot_samples", "WindowChoice",
    "choose_window",
]


def check_window(window: Any, name: str = "window") -> str:
    """The one validator of a window name (:data:`WINDOWS`); BadInputError otherwise."""
    if not isinstance(window, str) or window not in WINDOWS:
        raise BadInputError(None, f"{name}={window!r}: choose one of {', '.join(WINDOWS)}")
    return window


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
