"""The energy bookkeeping of a band's error ε_b: which bands a rule must meet, which channels
count in a band, and ε_b(F) from the band sums of an error density.

Shared by :mod:`shrmkit.analysis.view_bands` (the tables and statements) and
:mod:`shrmkit.analysis._view_fit` (the view fit); the identity behind the sums is
:class:`~shrmkit.analysis.view_bands.ViewProfile`'s.

Reference: [RH02] §5.1 (``data_specs/bibliography.md``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from ._view_profile import ViewProfile

__all__ = ["CHANNEL_FLOOR", "live_channels", "bands_inside", "BandTotals", "profile_totals",
           "eps_from_band_residual"]

#: In the point-light tables a channel counts in a band when its energy there is at least this
#: fraction of the band's strongest channel (1 % in amplitude).
CHANNEL_FLOOR = 1e-4


def live_channels(total: np.ndarray) -> np.ndarray:
    """The channels (last axis) whose energy exceeds 10⁻¹² of the largest (same shape, bool)."""
    return total > 1e-12 * max(float(total.max(initial=0.0)), 1e-300)


def bands_inside(profile: ViewProfile, max_view_deg: float) -> np.ndarray:
    """Indices of the bands that start below ``max_view_deg`` (those a rule must meet)."""
    return np.nonzero(profile.edges_deg[:-1] < max_view_deg)[0]


class BandTotals(NamedTuple):
    """A profile's energies per (band, channel) when the orders l > F0 count as error."""

    full: np.ndarray  #: (nb, F0+1, 3) band sums of the resolved energy per l <= F0
    beyond: np.ndarray  #: (nb, 3) the energy at l > F0 and what the profile does not resolve
    total: np.ndarray  #: (nb, 3) all of the band's energy
    live: np.ndarray  #: (nb, 3) bool: the channels that count in the band (:data:`CHANNEL_FLOOR`)


def profile_totals(profile: ViewProfile, F0: int) -> BandTotals:
    """:class:`BandTotals` of ``profile`` cut at ``F0``.

    A channel counts in a band where it carries at least :data:`CHANNEL_FLOOR` of the band's
    strongest channel's energy (a specular-only red channel with f0 = 0 is ~0 at normal views:
    its relative error there is invisible, and would otherwise decide the orders)."""
    full = profile.band_full  # (nb, F0p+1, 3)
    beyond = profile.band_beyond + full[:, F0 + 1 :].sum(axis=1)  # unresolved by the table
    full = full[:, : F0 + 1]
    total = full.sum(axis=1) + beyond  # (nb, 3)
    live = live_channels(total.sum(axis=0))[None, :] & (total >= CHANNEL_FLOOR * total.max(axis=1, keepdims=True))
    return BandTotals(full, beyond, total, live)


def eps_from_band_residual(profile: ViewProfile, F0: int, band_residual: np.ndarray) -> np.ndarray:
    """ε_b(F) for F = 0..F0 of every band, worst live channel, (n_bands, F0+1), from the band sums
    of the error density of the kept orders l <= F0 per (band, l, channel) (nb, F0+1, 3): the
    error up to F plus the energy at l > F, over the band's energy."""
    full, _, total, live = profile_totals(profile, F0)
    after = total[:, None, :] - np.cumsum(full, axis=1)  # energy at l > f, (nb, F0+1, 3)
    safe = np.where(total > 0, total, 1.0)[:, None, :]
    err = np.cumsum(band_residual, axis=1) + after  # (nb, F0+1, 3)
    eps = np.where(live[:, None, :] & (total[:, None, :] > 0), err / safe, 0.0)
    return np.clip(eps, 0.0, None).max(axis=-1)
