"""Fit error per view-elevation band (in the spirit of [Green07] Fig. 4).

A model that is good on average can still fail at grazing views (Fresnel rise, off-specular
peaks) or near normal viewing. Splitting the fit samples by the view elevation θ_o and
computing each metric of ``metrics.py`` inside each band shows where.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from .metrics import log_epsilon, log_rms, rel_rms
from .sampling import FitSamples

__all__ = ["BandError", "DEFAULT_BANDS_DEG", "FIT_FAIL_BAND_REL_RMS", "MIN_BAND_SAMPLES", "band_errors", "worst_band"]

DEFAULT_BANDS_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 90.0)
#: A fit fails when its relative RMS error in any view band (of at least :data:`MIN_BAND_SAMPLES`
#: samples) exceeds this: an RMS error of half the measured value there is a model that does not
#: represent the material in that band, whatever its average over all bands (a Cook–Torrance fit of
#: Cornell's mystique: 0.055 over all samples, 0.94–1.13 in five of six bands).
FIT_FAIL_BAND_REL_RMS = 0.5
#: Bands with fewer samples are reported but do not decide the verdict (too few to judge).
MIN_BAND_SAMPLES = 10


@dataclass(frozen=True)
class BandError:
    """Errors of the samples whose view elevation θ_o lies in [lo_deg, hi_deg): a record of one
    band's numbers (``n`` samples, ``rel_rms`` and ``log_rms`` of ``metrics.py``), not an exception
    (nothing raises it)."""

    lo_deg: float
    hi_deg: float
    n: int
    rel_rms: float
    log_rms: float

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def band_errors(
    samples: FitSamples, model_rho: np.ndarray, edges_deg: Sequence[float] = DEFAULT_BANDS_DEG
) -> tuple[BandError, ...]:
    """Each metric of ``metrics.py`` restricted to view-elevation bands.

    Parameters
    ----------
    samples
        The fit samples (their quadrature weights are used inside each band).
    model_rho
        The model's rho (n, 3) at the samples.
    edges_deg
        Increasing band edges in degrees of θ_o; the last band includes its upper edge.
        Bands without samples are left out.

    Returns
    -------
    tuple of BandError
        ``rel_rms`` is relative to the band's own energy; ``log_rms`` uses the ε of the
        whole sample set so bands are comparable.
    """
    edges = np.asarray(edges_deg, dtype=np.float64)
    if edges.ndim != 1 or len(edges) < 2 or np.any(np.diff(edges) <= 0):
        raise ValueError(f"band edges must be increasing, got {list(edges_deg)}")
    theta_o = np.degrees(np.arccos(np.clip(samples.cos_o, -1.0, 1.0)))
    eps = log_epsilon(samples)
    out = []
    for k, (lo, hi) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        last = k == len(edges) - 2
        mask = (theta_o >= lo) & ((theta_o <= hi) if last else (theta_o < hi))
        n = int(np.count_nonzero(mask))
        if n == 0:
            continue
        out.append(
            BandError(
                lo_deg=float(lo),
                hi_deg=float(hi),
                n=n,
                rel_rms=rel_rms(samples, model_rho, mask),
                log_rms=log_rms(samples, model_rho, mask, eps=eps),
            )
        )
    return tuple(out)


def worst_band(bands: Sequence[BandError], min_samples: int = MIN_BAND_SAMPLES) -> BandError | None:
    """The band with the largest relative RMS among those with at least ``min_samples`` samples
    (None when there is none): the error a fit's headline states beside its average."""
    judged = [b for b in bands if b.n >= min_samples and np.isfinite(b.rel_rms)]
    return max(judged, key=lambda b: b.rel_rms) if judged else None
