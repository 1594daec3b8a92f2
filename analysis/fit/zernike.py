"""Koenderink's Zernike-basis BRDF representation and its linear least-squares fit.

Koenderink, van Doorn & Stavridi (1996) expand a BRDF over the product of the incident and
the exit hemisphere in products of Zernike polynomials, after mapping each hemisphere onto
the unit disc; CURET published its BRDF fits in this basis (Dana et al. 1999, with 5 and 55
coefficients) and RH02 (Fig. 8) analysed those fits.

The basis, the model (:class:`~shrmkit.brdf_io.zernike.ZernikeBRDF`) and its spec string live in
``brdf_io/zernike.py`` (a model that ``load_brdf`` reads back); this module fits it.

Fit
---
:func:`fit_zernike` solves the linear least-squares problem on the samples of
:func:`~shrmkit.analysis.fit.sampling.collect_samples` (the measurements themselves for
scattered data such as CURET; quadrature-weighted Sobol pairs for anything evaluable), one
right-hand side per RGB channel. ``metric="rho"`` (default) minimizes Σ w (ρ_model − ρ)² — the
BRDF itself, as the CURET fits; ``metric="rel"`` minimizes Σ w ((ρ_model − ρ) cos θ_i)², the
objective of :func:`~shrmkit.analysis.fit.fit_brdf` (relative RMS of ρ̂). Where the samples
leave some combinations undetermined (rank < terms) the minimum-norm solution is returned
and ``rank`` says so; ``ridge`` adds Tikhonov damping. A polynomial fit is not constrained
to be positive: outside the measured directions (CURET: θ above 83.9°) it extrapolates, and
may go negative; :meth:`ZernikeBRDF.negative_fraction` measures how much.

References
----------
J. J. Koenderink, A. J. van Doorn, M. Stavridi, "Bidirectional reflection distribution
function expressed in terms of surface scattering modes", ECCV 1996, LNCS 1065, pp. 28–39,
doi:10.1007/3-540-61123-1_125.
K. J. Dana, B. van Ginneken, S. K. Nayar, J. J. Koenderink, "Reflectance and texture of
real-world surfaces", ACM Trans. Graph. 18(1), 1999, doi:10.1145/300776.300778 (CURET).
M. Born, E. Wolf, *Principles of Optics*, Appendix VII (Zernike circle polynomials).
R. Ramamoorthi, P. Hanrahan, "Frequency Space Environment Map Rendering", SIGGRAPH 2002
(RH02), doi:10.1145/566654.566611, Fig. 8.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.specs import load_brdf
from ...brdf_io.zernike import (
    EVAL_BLOCK,
    MAX_ORDER,
    TERMS_PER_ORDER,
    ZernikeBRDF,
    check_order,
    basis_count,
    basis_terms,
    disc_radius,
    order_for_count,
    zernike,
    zernike_basis,
    zernike_radial,
)
from .metrics import error_metrics
from .sampling import FitSamples, collect_samples
from .summary import BandError, band_errors

__all__ = [
    "EVAL_BLOCK",
    "MAX_ORDER",
    "TERMS_PER_ORDER",
    "ZERNIKE_METRICS",
    "disc_radius",
    "zernike_radial",
    "zernike",
    "basis_terms",
    "basis_count",
    "order_for_count",
    "zernike_basis",
    "ZernikeBRDF",
    "ZernikeFit",
    "fit_zernike",
]

ZERNIKE_METRICS = ("rho", "rel")


@dataclass(frozen=True, eq=False)
class ZernikeFit:
    """Outcome of :func:`fit_zernike`.

    Attributes
    ----------
    brdf
        The fitted :class:`ZernikeBRDF` (evaluable everywhere).
    n_max, n_coeffs
        Order and number of coefficients.
    errors
        ``{"rel_rms": ..., "log_rms": ...}`` on the samples (``metrics.py``: ρ cos θ_i,
        relative / log), as the other fits report.
    rel_rms_rho
        Relative RMS of ρ itself over the samples: √(Σ w Σ_c (m − y)² / Σ w Σ_c y²).
    bands
        Errors per view-elevation band (``summary.band_errors``).
    rank
        Rank of the (weighted) least-squares matrix; < ``n_coeffs`` means the samples do not
        determine every coefficient (minimum-norm solution, see ``message``).
    metric, ridge, max_theta_deg
        Options of the fit.
    n_samples, n_dropped
        Samples used, sampled points dropped for lack of data.
    seconds
        Wall time.
    message
        A sentence for people.
    """

    brdf: ZernikeBRDF
    n_max: int
    n_coeffs: int
    errors: dict[str, float]
    rel_rms_rho: float
    bands: tuple[BandError, ...]
    rank: int
    metric: str
    ridge: float
    max_theta_deg: float
    n_samples: int
    n_dropped: int
    seconds: float
    message: str
    options: dict[str, Any] = field(default_factory=dict)

    @property
    def coefficients(self) -> np.ndarray:
        """(n_coeffs, 3) fitted coefficients."""
        return self.brdf.coefficients


def fit_zernike(
    brdf: BRDF | str | Path,
    n_max: int | None = None,
    *,
    n_coeffs: int | None = None,
    metric: str = "rho",
    ridge: float = 0.0,
    max_theta_deg: float = 90.0,
    n_samples: int = 32768,
    seed: int = 0,
    samples: FitSamples | None = None,
    name: str | None = None,
) -> ZernikeFit:
    """Fit Koenderink's reciprocal isotropic Zernike expansion by linear least squares.

    Parameters
    ----------
    brdf
        Scattered measurements (CURET, Cornell, gonioreflectometer CSV: their own samples) or
        any evaluable BRDF (sampled as in ``sampling.py``), or a spec/path for ``load_brdf``.
    n_max
        Order (module table). Give this or ``n_coeffs``; default 8 (55 coefficients).
    n_coeffs
        Number of coefficients instead of the order: one of 1, 2, 5, 8, 14, 20, 30, 40, 55, ...
    metric
        ``"rho"`` (default): least squares on ρ (CURET's fits); ``"rel"``: on ρ cos θ_i
        (``fit_brdf``'s relative-RMS objective). Both error metrics are reported.
    ridge
        Tikhonov damping, relative to the largest squared singular value of the matrix
        (0 = plain least squares).
    max_theta_deg
        Samples with θ_i or θ_o above this are not used (default 90: the basis covers the
        whole hemisphere, and CURET reaches 83.9°).
    n_samples, seed
        Sobol pairs drawn for a non-scattered BRDF (``collect_samples``).
    samples
        Use these samples instead (rho finite and >= 0).
    name
        Name of the fitted BRDF (default ``"<source> zernike<n_coeffs>"``).

    Returns
    -------
    ZernikeFit

    Raises
    ------
    BadInputError
        Both or invalid ``n_max``/``n_coeffs``, unknown metric, negative ridge, a BRDF without
        usable samples (fewer than 64, negative or infinite values: ``collect_samples``), given
        ``samples`` with negative or non-finite rho.
    """
    t0 = time.perf_counter()
    if n_max is not None and n_coeffs is not None:
        raise BadInputError(None, "give the Zernike order n_max or the coefficient count n_coeffs, not both")
    n_max = 8 if n_max is None and n_coeffs is None else (order_for_count(n_coeffs) if n_max is None else n_max)
    n_max = check_order(n_max)
    if metric not in ZERNIKE_METRICS:
        raise BadInputError(None, f"unknown Zernike fit metric {metric!r}; choose one of {', '.join(ZERNIKE_METRICS)}")
    if not (np.isfinite(ridge) and ridge >= 0):
        raise BadInputError(None, f"ridge must be a finite number >= 0, got {ridge!r}")
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    if samples is None:
        samples = collect_samples(brdf, n_samples=n_samples, seed=seed, max_theta_deg=max_theta_deg)
    elif not np.all(np.isfinite(samples.rho)) or np.any(samples.rho < 0):
        raise BadInputError(samples.source, "fit samples must hold finite, non-negative rho (collect_samples clamps)")
    A = zernike_basis(samples.L, samples.V, n_max)
    K = A.shape[1]
    w = samples.weight * (samples.cos_i**2 if metric == "rel" else 1.0)
    sw = np.sqrt(w)[:, None]
    Aw, yw = A * sw, samples.rho * sw
    if ridge > 0:
        top = np.linalg.norm(Aw, 2)
        Aw = np.concatenate([Aw, np.sqrt(ridge) * top * np.eye(K)])
        yw = np.concatenate([yw, np.zeros((K, yw.shape[1]))])
    coeffs, _, rank, _ = np.linalg.lstsq(Aw, yw, rcond=None)
    label = name or f"{samples.source} zernike{K}"
    fitted = ZernikeBRDF(coeffs, n_max, name=label)
    model_rho = A @ coeffs
    errors = error_metrics(samples, model_rho)
    den = float(np.sum(samples.weight[:, None] * samples.rho**2))
    rel_rho = float(np.sqrt(np.sum(samples.weight[:, None] * (model_rho - samples.rho) ** 2) / den)) if den > 0 \
        else float("nan")
    bands = band_errors(samples, model_rho)
    rank = int(rank)
    message = f"{K} coefficients (order {n_max}) fitted to {len(samples)} samples: relative RMS of rho {rel_rho:.3g}"
    if rank < K:
        message += f"; the samples determine only {rank} of {K} combinations (minimum-norm solution)"
    return ZernikeFit(
        brdf=fitted, n_max=n_max, n_coeffs=K, errors=errors, rel_rms_rho=rel_rho, bands=bands, rank=rank,
        metric=metric, ridge=float(ridge), max_theta_deg=float(max_theta_deg), n_samples=len(samples),
        n_dropped=samples.n_dropped, seconds=time.perf_counter() - t0, message=message,
        options={"model": "zernike", "n_max": n_max, "metric": metric, "ridge": float(ridge),
                 "max_theta_deg": float(max_theta_deg), "seed": int(seed), "n_samples": int(n_samples)},
    )
