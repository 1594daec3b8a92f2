"""Fit error metrics, and the per-sample least-squares weights each metric induces.

Both metrics compare the cosine-weighted transfer ρ̂ = ρ · cos θ_i ([RH02] §3.1) of a model
(m) and a measurement (y) on the fit samples, with the quadrature weights w of
``sampling.py`` (so the sums estimate integrals over dω_i dω_o):

``rel_rms`` — cosine-weighted relative RMS::

    sqrt( Σ_s w_s Σ_c (m_sc − y_sc)² cos² θ_i / Σ_s w_s Σ_c y_sc² cos² θ_i )

``log_rms`` — RMS difference of logarithms, robust to the huge grazing values of measured
data (a factor-of-e error counts 1 whether the value is 10⁻³ or 10³)::

    sqrt( Σ_s w_s Σ_c (ln(ε + m_sc cos θ_i) − ln(ε + y_sc cos θ_i))² / (3 Σ_s w_s) )

with ε = 1 % of the weighted mean of y cos θ_i (so that black regions do not dominate).

A fit minimizes a weighted least-squares sum; for ``rel`` it is exactly rel_rms²; for
``log`` the weights are w/(ε + y cos θ_i)², the first-order expansion of the log metric
about the data (ln(ε + m) − ln(ε + y) ≈ (m − y)/(ε + y)), which keeps the colour weights
linear (variable projection) and the objective smooth.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import numpy as np

from ..defaults import FIT_METRICS as METRICS  # numpy-free home, for the CLI's parsers
from .sampling import FitSamples

__all__ = ["METRICS", "log_epsilon", "rel_rms", "log_rms", "error_metrics", "lsq_weights"]


def log_epsilon(samples: FitSamples) -> float:
    """ε of the log metric: 1 % of the weighted mean of ρ cos θ_i."""
    y = samples.rho * samples.cos_i[:, None]
    return 0.01 * float(np.sum(samples.weight[:, None] * y) / (3.0 * np.sum(samples.weight)))


def rel_rms(samples: FitSamples, model_rho: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Cosine-weighted relative RMS error of ρ cos θ_i (module docstring)."""
    w, c = samples.weight, samples.cos_i
    y, m = samples.rho, np.asarray(model_rho)
    if mask is not None:
        w, c, y, m = w[mask], c[mask], y[mask], m[mask]
    num = np.sum(w[:, None] * ((m - y) * c[:, None]) ** 2)
    den = np.sum(w[:, None] * (y * c[:, None]) ** 2)
    return float(np.sqrt(num / den)) if den > 0 else float("nan")


def log_rms(
    samples: FitSamples, model_rho: np.ndarray, mask: np.ndarray | None = None, eps: float | None = None
) -> float:
    """RMS of ln(ε + ρ cos θ_i) differences (module docstring)."""
    eps = log_epsilon(samples) if eps is None else eps
    w, c = samples.weight, samples.cos_i
    y, m = samples.rho, np.asarray(model_rho)
    if mask is not None:
        w, c, y, m = w[mask], c[mask], y[mask], m[mask]
    if len(w) == 0:
        return float("nan")
    d = np.log(eps + np.maximum(m, 0.0) * c[:, None]) - np.log(eps + y * c[:, None])
    return float(np.sqrt(np.sum(w[:, None] * d**2) / (3.0 * np.sum(w))))


def error_metrics(samples: FitSamples, model_rho: np.ndarray) -> dict[str, float]:
    """All metrics by name: ``{"rel_rms": ..., "log_rms": ...}``."""
    return {"rel_rms": rel_rms(samples, model_rho), "log_rms": log_rms(samples, model_rho)}


def lsq_weights(samples: FitSamples, metric: str) -> np.ndarray:
    """Per-sample, per-channel weights W (n, 3) of the residual (m − y) cos θ_i.

    Normalized so that Σ W ((m − y) cos θ_i)² is rel_rms² (``rel``) or approximately
    log_rms² (``log``).
    """
    w, c, y = samples.weight, samples.cos_i, samples.rho
    if metric == "rel":
        den = np.sum(w[:, None] * (y * c[:, None]) ** 2)
        return np.broadcast_to((w / den)[:, None], y.shape).copy()
    if metric == "log":
        eps = log_epsilon(samples)
        return w[:, None] / (eps + y * c[:, None]) ** 2 / (3.0 * np.sum(w))
    raise ValueError(f"unknown metric {metric!r}; choose one of {METRICS}")
