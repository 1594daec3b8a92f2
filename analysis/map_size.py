"""Rows of the SHRM's S × 2S lat-long maps: [RH02]'s S ≈ 10F within a memory budget (``"rh02"``
rule), the error-driven size of the ``"bands"`` rule, and sizes with fast FFTs.

The global SHRM holds (P+1)² float32 RGB maps; their rows decide the bilinear lookup error the
statement counts (``view_bands.shrm_view_bands``' map term) and the memory the maps take
(``analysis.map_budget`` says when a budget made a bound uninformative).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .synthesis import fast_rows
from .view_bands import DEFAULT_MAX_VIEW_DEG, bands_inside, shrm_view_bands

__all__ = ["DEFAULT_MAP_BUDGET_BYTES", "MAP_ERROR_SHARE", "MAP_BOUND_SHARE", "MAP_MIN_SAMPLES", "default_size",
           "fast_map_rows", "map_rows"]

#: The memory budget of the default map size (bytes; ``prefilter(budget_bytes=)``).
DEFAULT_MAP_BUDGET_BYTES = 256 << 20


def default_size(F: int, P: int = 0, budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES) -> int:
    """S_B from the rule S ≈ 10F (RH02 §5.2), clamped to [32, 1024] and to a memory budget.

    The global SHRM holds (P+1)² float32 RGB maps of S × 2S: the default S is lowered
    until they fit in ``budget_bytes`` (256 MiB), which keeps high-P materials usable;
    pass ``size=`` to override.
    """
    rule = int(np.clip(10 * F, 32, 1024))
    per_row_squared = (P + 1) ** 2 * 2 * 3 * 4  # bytes per S² texels of all maps
    fits = int(np.sqrt(budget_bytes / per_row_squared))
    return max(8, min(rule, fits))


def fast_map_rows(rows: int, F: int, P: int, budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES) -> int:
    """``rows`` raised to the next size with fast FFTs (:func:`~shrmkit.analysis.synthesis.fast_rows`)
    while that stays within the memory budget's :func:`default_size`, else ``rows``."""
    fast = fast_rows(rows)
    return fast if fast <= max(default_size(F, P, budget_bytes), rows) else rows


#: Under the ``"bands"`` rule the map is the smallest whose bilinear lookup adds at most this
#: fraction of ε to the predicted error energy of every view band inside the limit (:func:`map_rows`).
MAP_ERROR_SHARE = 0.01
#: … and whose bound (which takes the lookup error of the global maps at degree l + P, RH02 eq. 8)
#: is at most this fraction above the bound of exact evaluation.
MAP_BOUND_SHARE = 0.25
#: … and holds at least this many samples per period of the highest degree F + P (S >= 2.5 (F + P)).
MAP_MIN_SAMPLES = 5.0


def map_rows(
    profile: Any, coefficients: Any, band_energy: np.ndarray, F: int, P: int, eps: float, *,
    sigma: np.ndarray | None = None, q_max: int | None = None, lighting_rows: tuple[int, int] | None = None,
    max_view_deg: float = DEFAULT_MAX_VIEW_DEG, budget_bytes: int = DEFAULT_MAP_BUDGET_BYTES,
) -> tuple[int, bool]:
    """Rows S of the S × 2S maps for the ``"bands"`` rule, and whether the memory budget bound them.

    The error-driven size: the smallest S in [max(32, 2.5 (F + P)), :func:`default_size`] (five
    samples per period of the highest degree; RH02's 10 F within the budget) for which bilinear
    lookup in the maps adds at most :data:`MAP_ERROR_SHARE` × ε to the predicted error energy of
    every view band inside the limit (the map term of
    :func:`~shrmkit.analysis.view_bands.shrm_view_bands`, κ_l ≈ (l(l+1))² h⁴/160 per degree,
    h = π/S, beside the same statement without lookup) and raises no band's bound by more than
    :data:`MAP_BOUND_SHARE`. The lookup error falls as h⁴, so this is typically S ≈ 3–5 F instead
    of RH02's 10 F: what the stated error needs, not more.
    """
    rule_hi = int(np.clip(10 * F, 32, 1024))
    hi = default_size(F, P, budget_bytes)
    inside = bands_inside(profile, max_view_deg)

    def statement(rows: int | None) -> list:
        return shrm_view_bands(profile, coefficients, band_energy, F, P, sigma=sigma, q_max=q_max, map_rows=rows,
                               lighting_rows=lighting_rows, max_view_deg=max_view_deg).bands

    exact = statement(None)
    allowed = MAP_ERROR_SHARE * eps

    def fits(rows: int) -> bool:
        bands = statement(rows)
        return all(
            bands[b]["map_rel_rms"] ** 2 - exact[b]["map_rel_rms"] ** 2 <= allowed
            and bands[b]["bound_rel_rms"] <= (1.0 + MAP_BOUND_SHARE) * exact[b]["bound_rel_rms"]
            for b in inside
        )

    # at least MAP_MIN_SAMPLES samples per period of the highest degree F + P in R: the lookup error
    # is an average over R, and near a sharp feature (what is left of a light) it is larger
    lo = min(max(32, int(np.ceil(MAP_MIN_SAMPLES * (F + P) / 2.0))), hi)
    if not fits(hi):
        return hi, hi < rule_hi
    if fits(lo):
        return lo, False
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    return hi, False
