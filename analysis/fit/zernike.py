"""Koenderink's Zernike-basis BRDF representation and its linear least-squares fit.

Koenderink, van Doorn & Stavridi [Koe96] expand a BRDF over the product of the incident and
the exit hemisphere in products of Zernike polynomials, after mapping each hemisphere onto
the unit disc; CURET published its BRDF fits in this basis ([CURET99], with 5 and 55
coefficients) and [RH02] (Fig. 8) analysed those fits.

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

References: [Koe96] (the basis), [CURET99], [RH02] Fig. 8; the model: :mod:`shrmkit.brdf_io.zernike`.
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
    basis_count,
    basis_terms,
    check_order,
    disc_radius,
    order_for_count,
    zernike,
    zernike_basis,
    zernike_radial,
)
from .crossval import DEFAULT_FOLDS, fold_of
from .metrics import error_metrics, rel_rms
from .optimize import FitResult
from .sampling import FitSamples, collect_samples
from .summary import FIT_FAIL_BAND_REL_RMS, BandError, band_errors, worst_band

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
    "CV_RIDGES",
    "CV_MAX_ORDER",
    "ZERNIKE_STATUS",
    "ZernikeCVPoint",
    "zernike_cv_grid",
    "fit_zernike_cv",
    "ridge_solutions",
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
    if n_max is None:
        n_max = 8 if n_coeffs is None else order_for_count(n_coeffs)
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


# ------------------------------------------------------------------------------ cross-validation

#: Ridge values tried by :func:`fit_zernike_cv`, relative to the largest squared singular value
#: of the weighted basis matrix (as ``fit_zernike``'s ``ridge``; 0 = plain least squares).
CV_RIDGES = (0.0, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1)
#: Largest order :func:`fit_zernike_cv` tries by default (140 terms; fewer where the training
#: folds hold fewer samples than terms: order 10, 91 terms, for CURET's 164 per fold).
CV_MAX_ORDER = 12
#: The ``status`` of a Zernike fit: a closed-form linear least-squares solution, no iterations.
ZERNIKE_STATUS = "LINEAR_LSQ"


@dataclass(frozen=True)
class ZernikeCVPoint:
    """The held-out errors of one (order, ridge) setting.

    Attributes
    ----------
    n_max, n_coeffs, ridge
        The setting.
    rel_rms
        Held-out cosine-weighted relative RMS over all samples (``metrics.rel_rms``).
    worst
        Held-out worst view band (``summary.worst_band``), None without a band of enough samples.
    """

    n_max: int
    n_coeffs: int
    ridge: float
    rel_rms: float
    worst: BandError | None

    @property
    def score(self) -> float:
        """What the choice minimizes: the worst band's held-out relative RMS (else ``rel_rms``)."""
        return self.rel_rms if self.worst is None else self.worst.rel_rms

    def as_dict(self) -> dict[str, Any]:
        return {"n_max": self.n_max, "n_coeffs": self.n_coeffs, "ridge": self.ridge, "rel_rms": self.rel_rms,
                "worst_band": None if self.worst is None else self.worst.as_dict()}


def ridge_solutions(Aw: np.ndarray, yw: np.ndarray, ridges: tuple[float, ...]) -> list[np.ndarray]:
    """argmin ‖Aw c − yw‖² + λ s_max² ‖c‖² for each λ in ``ridges``, from one eigendecomposition
    of the K × K normal matrix AwᵀAw (s_max² its largest eigenvalue). λ = 0 is the minimum-norm
    least-squares solution on the eigenvalues above 10⁻¹³ s_max² (singular values above
    3·10⁻⁷ s_max: the normal matrix squares the condition number). The small K × K problem is
    used instead of an SVD of the n × K matrix: on this project's shared 2-core machine a
    threaded SVD of 1400 × 140 took 2.8 s, the normal matrix and its eigh 10 ms."""
    G = Aw.T @ Aw
    b = Aw.T @ yw
    e, Q = np.linalg.eigh(0.5 * (G + G.T))
    top = float(max(e[-1], 0.0)) if e.size else 0.0
    Qb = Q.T @ b
    out = []
    for lam in ridges:
        if lam == 0:
            keep = e > 1e-13 * top
            f = np.where(keep, 1.0 / np.where(keep, e, 1.0), 0.0)
        else:
            f = 1.0 / (np.maximum(e, 0.0) + lam * top)
        out.append(Q @ (f[:, None] * Qb))
    return out


def zernike_cv_grid(
    samples: FitSamples,
    *,
    orders: tuple[int, ...] | None = None,
    ridges: tuple[float, ...] = CV_RIDGES,
    metric: str = "rel",
    folds: int = DEFAULT_FOLDS,
    seed: int = 0,
) -> tuple[list[ZernikeCVPoint], dict[tuple[int, float], np.ndarray]]:
    """Held-out errors of Zernike fits for every (order, ridge) of a grid (``crossval.py``).

    Parameters
    ----------
    samples
        The measurements (n); weights as ``sampling.py``.
    orders
        Orders tried (default 0..:data:`CV_MAX_ORDER`, those with at most as many terms as the
        smallest training fold has samples).
    ridges
        Ridge values tried (:data:`CV_RIDGES`).
    metric
        Least-squares weighting of each training fit (``fit_zernike``'s ``metric``).
    folds, seed
        Cross-validation folds and the seed of their split (``crossval.fold_of``).

    Returns
    -------
    points, predictions
        One :class:`ZernikeCVPoint` per setting, and the held-out ρ (n, 3) per (n_max, ridge).

    Raises
    ------
    BadInputError
        No order with at most as many terms as a training fold has samples; a bad ridge or metric.
    """
    if metric not in ZERNIKE_METRICS:
        raise BadInputError(None, f"unknown Zernike fit metric {metric!r}; choose one of {', '.join(ZERNIKE_METRICS)}")
    if not ridges or any(not (np.isfinite(r) and r >= 0) for r in ridges):
        raise BadInputError(None, f"ridge values must be finite numbers >= 0, got {list(ridges)!r}")
    fold = fold_of(len(samples), folds, seed=seed)
    n_train = len(samples) - int(np.max(np.bincount(fold)))
    if orders is None:
        orders = tuple(n for n in range(CV_MAX_ORDER + 1) if basis_count(n) <= n_train)
    orders = tuple(check_order(n) for n in orders)
    if not orders or min(basis_count(n) for n in orders) > n_train:
        raise BadInputError(samples.source, f"{n_train} samples per training fold: too few for the Zernike "
                            f"orders {list(orders)} ({[basis_count(n) for n in orders]} terms)")
    A = zernike_basis(samples.L, samples.V, max(orders))
    w = samples.weight * (samples.cos_i**2 if metric == "rel" else 1.0)
    sw = np.sqrt(w)[:, None]
    preds = {(n, float(r)): np.empty_like(samples.rho) for n in orders for r in ridges}
    for k in range(folds):
        test, train = fold == k, fold != k
        for n in orders:
            K = basis_count(n)
            sols = ridge_solutions(A[train, :K] * sw[train], samples.rho[train] * sw[train], tuple(ridges))
            for r, c in zip(ridges, sols, strict=True):
                preds[(n, float(r))][test] = A[test, :K] @ c
    points = []
    for (n, r), pred in preds.items():
        bands = band_errors(samples, pred)
        points.append(ZernikeCVPoint(n_max=n, n_coeffs=basis_count(n), ridge=r, rel_rms=rel_rms(samples, pred),
                                     worst=worst_band(bands)))
    return points, preds


def fit_zernike_cv(
    brdf: BRDF | str | Path,
    *,
    n_max: int | None = None,
    ridge: float | None = None,
    metric: str = "rel",
    folds: int = DEFAULT_FOLDS,
    seed: int = 0,
    max_theta_deg: float = 80.0,
    n_samples: int = 32768,
    samples: FitSamples | None = None,
) -> FitResult:
    """A Zernike fit whose order and ridge are chosen by held-out error, reported as a fit.

    Every (order, ridge) of the grid (``n_max`` fixes the order, ``ridge`` the ridge) is scored
    by ``folds``-fold cross-validation over the samples (:func:`zernike_cv_grid`); the setting
    with the smallest held-out worst-view-band relative RMS (fewer terms on a tie) is fitted to
    all samples (:func:`fit_zernike`). The errors, bands, worst band and verdict of the result
    are the **held-out** ones (the training errors are in ``params["training"]``), so a Zernike
    fit is judged as the nlopt fits are (``summary.FIT_FAIL_BAND_REL_RMS``) but cannot pass by
    following the noise of its own samples.

    Parameters
    ----------
    brdf
        Scattered measurements (their own samples) or any evaluable BRDF (Sobol samples), or a
        spec/path for ``load_brdf``.
    n_max, ridge
        Fix the order (0..20) or the ridge (>= 0) instead of choosing it.
    metric
        Least-squares weighting: ``"rel"`` (default: ρ cos θ_i, the objective of ``fit_brdf``
        and the error every fit reports) or ``"rho"`` (ρ itself, CURET's published fits).
    folds, seed
        Cross-validation folds (default 5) and the seed of the split.
    max_theta_deg, n_samples, samples
        As :func:`~shrmkit.analysis.fit.fit_brdf` (default cut 80°, the same samples as the
        other fits).

    Returns
    -------
    FitResult
        ``model`` ``"zernike"``, ``brdf`` a :class:`ZernikeBRDF`, ``status``
        :data:`ZERNIKE_STATUS`, ``evaluations`` the least-squares solves, ``params``: ``n_max``,
        ``n_coeffs``, ``ridge``, ``rank``, ``terms``, ``coefficients`` (K × 3, 1/sr),
        ``negative_fraction``, ``training`` (errors and worst band on the fitted samples) and
        ``cv`` (folds, seed, the grid's held-out errors); ``at_bounds`` names a chosen order or
        ridge at the end of the grid.

    Raises
    ------
    BadInputError
        Bad options, too few samples for any order, or a BRDF without usable samples.
    """
    t0 = time.perf_counter()
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    if samples is None:
        samples = collect_samples(brdf, n_samples=n_samples, seed=seed, max_theta_deg=max_theta_deg)
    if ridge is not None and not (np.isfinite(ridge) and ridge >= 0):
        raise BadInputError(None, f"ridge must be a finite number >= 0, got {ridge!r}")
    orders = None if n_max is None else (check_order(n_max),)
    ridges = CV_RIDGES if ridge is None else (float(ridge),)
    points, preds = zernike_cv_grid(samples, orders=orders, ridges=ridges, metric=metric, folds=folds, seed=seed)
    best = min(points, key=lambda p: (p.score, p.n_coeffs, -p.ridge))
    fit = fit_zernike(brdf, best.n_max, metric=metric, ridge=best.ridge, samples=samples,
                      name=f"{samples.source} zernike{best.n_coeffs}")
    held = preds[(best.n_max, best.ridge)]
    errors = error_metrics(samples, held)
    bands = band_errors(samples, held)
    worst = worst_band(bands)
    at_bounds = []
    tried_orders = sorted({p.n_max for p in points})
    if n_max is None and best.n_max == tried_orders[-1] and len(tried_orders) > 1:
        at_bounds.append(f"order n_max at the largest tried, {best.n_max} ({best.n_coeffs} terms)")
    if ridge is None and best.ridge == max(ridges):
        at_bounds.append(f"ridge at the largest tried, {best.ridge:g}")
    usable = bool(np.any(fit.coefficients != 0)) and all(np.isfinite(v) for v in errors.values())
    success = usable and (worst is None or worst.rel_rms <= FIT_FAIL_BAND_REL_RMS)
    setting = (f"order {best.n_max} ({best.n_coeffs} terms), ridge {best.ridge:g}, chosen by {folds}-fold "
               f"cross-validation over {len(samples)} samples")
    if worst is None:
        head = f"held-out rel. RMS {errors['rel_rms']:.3g} (no view band with enough samples to judge)"
    else:
        where = f"held-out rel. RMS {worst.rel_rms:.3g} in the {worst.lo_deg:g}–{worst.hi_deg:g}° view band"
        head = (f"failed: {where} (above {FIT_FAIL_BAND_REL_RMS:g}; " if worst.rel_rms > FIT_FAIL_BAND_REL_RMS
                else f"worst band {where}; ") + f"{errors['rel_rms']:.3g} over all samples held out"
        head += ")" if head.startswith("failed") else ""
    train_worst = worst_band(fit.bands)
    message = (f"{head}; {setting}; training rel. RMS {fit.errors['rel_rms']:.3g}"
               + ("" if not at_bounds else f"; {'; '.join(at_bounds)}"))
    params = {
        "n_max": fit.n_max, "n_coeffs": fit.n_coeffs, "ridge": best.ridge, "rank": fit.rank,
        "terms": [list(t) for t in fit.brdf.terms], "coefficients": fit.coefficients.tolist(),
        "negative_fraction": fit.brdf.negative_fraction(),
        "training": {"errors": fit.errors, "rel_rms_rho": fit.rel_rms_rho,
                     "worst_band": None if train_worst is None else train_worst.as_dict()},
        "cv": {"folds": int(folds), "seed": int(seed), "grid": [p.as_dict() for p in points]},
    }
    options = {"model": "zernike", "n_max": n_max, "ridge": ridge, "metric": metric, "folds": int(folds),
               "seed": int(seed), "n_samples": int(n_samples), "max_theta_deg": float(max_theta_deg)}
    return FitResult(
        model="zernike", brdf=fit.brdf, params=params, errors=errors, bands=bands, status=ZERNIKE_STATUS,
        success=success, message=message, evaluations=folds * len(points) + 1,
        seconds=time.perf_counter() - t0, n_samples=len(samples), n_dropped=samples.n_dropped, options=options,
        worst=worst, converged=True, at_bounds=tuple(at_bounds), usable=usable,
    )
