"""The one error metric of the project: relative RMS radiance error against a reference.

Used by ``shrm compare`` (every row and every strip panel) and meant for ``shrm report``,
so that the numbers of both are the same quantity on the same footing.
"""

from __future__ import annotations

import numpy as np

__all__ = ["relative_rms"]


def relative_rms(value: np.ndarray, reference: np.ndarray) -> float:
    """Relative RMS error of ``value`` against ``reference``, over *all* entries:

        rel_rms = sqrt( Σ (value − reference)² / Σ reference² ),

    the sums running over every element (for radiance: every (R, V) pair and every RGB
    channel together, so bright channels and pairs weigh more; no per-pair normalization).

    Parameters
    ----------
    value, reference
        Arrays of the same shape (typically (n, 3) linear radiance), any units (the ratio is
        unitless). Both are compared as float64; different shapes raise ``ValueError``.

    Returns
    -------
    float
        The ratio above. **NaN rule**: NaN when Σ reference² is 0 (an all-zero or empty
        reference, e.g. a view band with no samples), since no relative error is defined;
        a non-finite entry in either input gives a non-finite result (NaN or inf).
    """
    value = np.asarray(value, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    if value.shape != reference.shape:
        raise ValueError(f"value and reference must have the same shape, got {value.shape} and {reference.shape}")
    den = float(np.sum(reference**2))
    if den == 0.0:
        return float("nan")
    return float(np.sqrt(np.sum((value - reference) ** 2) / den))
