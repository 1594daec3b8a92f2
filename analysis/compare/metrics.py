"""The one error metric of the project: relative RMS radiance error against a reference.

Used by ``shrm compare`` (every row and every strip panel) and meant for ``shrm report``,
so that the numbers of both are the same quantity on the same footing.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["relative_rms", "band_relative_rms", "beside_measured"]


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


def band_relative_rms(
    value: np.ndarray, reference: np.ndarray, theta_v: np.ndarray, edges_deg: Sequence[float],
    weights: np.ndarray | None = None,
) -> list[dict]:
    """:func:`relative_rms` per band of the view elevation θ_v, with its standard error.

    Parameters
    ----------
    value, reference
        (n, 3) radiance at n (R, V) pairs.
    theta_v
        (n,) view elevations in radians (as returned by the samplers of :mod:`.pairs`).
    edges_deg
        Band edges in degrees (e.g. ``analysis.view_bands.DEFAULT_BAND_EDGES_DEG``).
    weights
        Optional (n,) importance weights (1/pdf of each pair relative to the uniform law of
        :func:`~.pairs.sample_pairs`): both sums are weighted, so the ratio estimates the same
        quantity with less noise (:func:`~.pairs.sample_pairs_focused`).

    Returns
    -------
    list of dict, one per band: ``theta_v_deg`` [lo, hi], ``n`` pairs, ``measured_rel_rms``
    (NaN when the band has no pairs or no reference energy) and ``stderr``, the standard
    error of that estimate (delta method for the ratio of two means): a Monte Carlo number
    is quoted with its uncertainty.
    """
    value = np.asarray(value, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    w = np.ones(len(theta_v)) if weights is None else np.asarray(weights, dtype=np.float64)
    deg = np.degrees(np.asarray(theta_v, dtype=np.float64))
    a_all = w * ((value - reference) ** 2).sum(axis=1)
    b_all = w * (reference**2).sum(axis=1)
    out = []
    for lo, hi in zip(edges_deg[:-1], edges_deg[1:], strict=True):
        sel = (deg >= lo) & (deg < hi)
        n = int(sel.sum())
        a, b = a_all[sel], b_all[sel]
        if n == 0 or b.sum() == 0.0:
            out.append({"theta_v_deg": [float(lo), float(hi)], "n": n, "measured_rel_rms": float("nan"),
                        "stderr": float("nan")})
            continue
        A, B = a.mean(), b.mean()
        r2 = A / B
        if n > 1:
            cov = np.cov(np.stack([a, b]), ddof=1) / n
            var_r2 = (cov[0, 0] - 2.0 * r2 * cov[0, 1] + r2**2 * cov[1, 1]) / B**2
        else:
            var_r2 = float("inf")
        r = float(np.sqrt(r2))
        se = float(np.sqrt(max(var_r2, 0.0)) / (2.0 * r)) if r > 0.0 else float(np.sqrt(max(var_r2, 0.0)))
        out.append({"theta_v_deg": [float(lo), float(hi)], "n": n, "measured_rel_rms": r, "stderr": se})
    return out


def beside_measured(measured: list[dict], stated: list[dict] | None = None) -> list[dict]:
    """Per band, what :func:`band_relative_rms` measured as ``measured_rel_rms``,
    ``measured_stderr`` and ``n_pairs``, beside the band's statement when there is one
    (``SHRM.meta["view_bands"]``, same bands in the same order) — the one per-band record of
    ``shrm report`` and ``shrm compare``."""
    stated = stated or [{"theta_v_deg": m["theta_v_deg"]} for m in measured]
    return [{**s, "measured_rel_rms": m["measured_rel_rms"], "measured_stderr": m["stderr"], "n_pairs": m["n"]}
            for s, m in zip(stated, measured, strict=True)]
