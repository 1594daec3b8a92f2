"""``fit_brdf``: fit Lafortune, Cook–Torrance or [RH02]'s simplified microfacet model with nlopt.

Pipeline
--------
1. Samples (``sampling.py``): low-discrepancy pairs in half/difference angles for analytic and
   tabulated BRDFs (points without data dropped), the measurements for scattered ones.
2. Objective (``objective.py``): variable projection — the colour weights (diffuse albedo,
   lobe weights, specular colour and Fresnel f0) are solved in closed form under their
   physical bounds for every trial shape, so nlopt only searches the shape parameters
   (lobe direction ψ and ln n per Lafortune lobe; ln α; ln σ).
3. Global stage (deterministic multi-start): the objective is evaluated at the model's
   physically motivated starts plus a low-discrepancy set (shifted Kronecker sequence) over the parameter box (seeded by
   ``seed``); the ``starts`` best distinct points seed the local stage.
4. Local stage: nlopt ``LN_BOBYQA`` (derivative-free, bound constrained) from each seed,
   then a final polish of the best point with a small initial step. ``status`` is nlopt's
   termination reason of that final run.

The same inputs and ``seed`` give the same result: every random choice is seeded and
nlopt's own generator is seeded with ``nlopt.srand(seed)``.

Reference: [RH02] (``data_specs/bibliography.md``).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import nlopt
import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.models import AnalyticModel
from ...brdf_io.specs import load_brdf
from ...brdf_io.zernike import ZernikeBRDF
from .metrics import METRICS, error_metrics
from .models_param import MODELS, ModelParam, make_param
from .objective import ProjectedObjective
from .sampling import FitSamples, collect_samples, kronecker_points
from .summary import FIT_FAIL_BAND_REL_RMS, BandError, band_errors, worst_band

__all__ = ["FitResult", "fit_brdf", "STATUS_NAMES"]

STATUS_NAMES = {
    nlopt.SUCCESS: "SUCCESS",
    nlopt.STOPVAL_REACHED: "STOPVAL_REACHED",
    nlopt.FTOL_REACHED: "FTOL_REACHED",
    nlopt.XTOL_REACHED: "XTOL_REACHED",
    nlopt.MAXEVAL_REACHED: "MAXEVAL_REACHED",
    nlopt.MAXTIME_REACHED: "MAXTIME_REACHED",
    nlopt.FAILURE: "FAILURE",
    nlopt.INVALID_ARGS: "INVALID_ARGS",
    nlopt.OUT_OF_MEMORY: "OUT_OF_MEMORY",
    nlopt.ROUNDOFF_LIMITED: "ROUNDOFF_LIMITED",
    nlopt.FORCED_STOP: "FORCED_STOP",
}
_CONVERGED = {nlopt.SUCCESS, nlopt.STOPVAL_REACHED, nlopt.FTOL_REACHED, nlopt.XTOL_REACHED, nlopt.ROUNDOFF_LIMITED}

ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class FitResult:
    """Outcome of :func:`fit_brdf`; falsy when the fit failed.

    Attributes
    ----------
    model
        ``"lafortune"``, ``"cook-torrance"`` or ``"microfacet"``.
    params
        Fitted parameters; colour parameters are RGB lists (see ``data_specs/fit_json.md``).
    brdf
        The fitted model, a ``shrmkit.brdf_io.models`` object (``to_spec()`` works).
    errors
        ``{"rel_rms": ..., "log_rms": ...}`` on the fit samples (``metrics.py``).
    bands
        Errors per view-elevation band (``summary.py``).
    status, success, message
        nlopt's termination reason of the final local run (a reason, not a verdict), whether
        the fit represents the data — finite errors, not the zero BRDF, and a relative RMS of at
        most :data:`~shrmkit.analysis.fit.summary.FIT_FAIL_BAND_REL_RMS` in every view band
        (``summary.worst_band``) — and a sentence for people that leads with the worst band.
    evaluations, seconds
        Objective evaluations over all stages, and wall time (sampling included).
    n_samples, n_dropped
        Samples used, and sampled points dropped for lack of data.
    options
        The options the fit ran with (model, lobes, metric, seed, ...).
    worst
        The view band with the largest relative RMS (None without bands of enough samples).
    converged
        Whether nlopt's last local run ended on a tolerance (``status`` in FTOL/XTOL/…), not on
        its evaluation budget: reported, not part of ``success``.
    usable
        False for the zero BRDF or non-finite errors (nothing to analyse through); a failed fit
        can be usable (the best this model gives, with its worst band stated).
    at_bounds
        Sentences naming the parameters that ended at a bound of the search (an exponent at its
        cap, Fresnel f0 at 1, the energy-conservation constraint met with equality, an unused lobe).
    shape
        The optimizer's shape parameters x at the optimum (canonical form, ``models_param.py``:
        (ψ, ln n) per Lafortune lobe, ln α, ln σ), dimensionless; ``fit_brdf(start=...)`` takes
        them back. None for fits not made by nlopt (Zernike).
    seeds
        The starting points of the local stage, (k, dim) as tuples (``shape``'s units).
    """

    model: str
    params: dict[str, Any]
    brdf: AnalyticModel | ZernikeBRDF
    errors: dict[str, float]
    bands: tuple[BandError, ...]
    status: str
    success: bool
    message: str
    evaluations: int
    seconds: float
    n_samples: int
    n_dropped: int
    options: dict[str, Any] = field(default_factory=dict)
    worst: BandError | None = None
    converged: bool = True
    at_bounds: tuple[str, ...] = ()
    usable: bool = True
    shape: tuple[float, ...] | None = None
    seeds: tuple[tuple[float, ...], ...] = ()

    def __bool__(self) -> bool:
        return self.success


def _check_options(model: str, lobes: int, metric: str, distribution: str, starts: int, n_samples: int) -> None:
    if model not in MODELS:
        raise BadInputError(None, f"unknown model {model!r}; choose one of {', '.join(MODELS)}")
    if metric not in METRICS:
        raise BadInputError(None, f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")
    if model == "lafortune" and not (isinstance(lobes, int | np.integer) and 1 <= lobes <= 4):
        raise BadInputError(None, f"lobes must be an integer in 1..4, got {lobes!r}")
    if distribution not in ("beckmann", "ggx"):
        raise BadInputError(None, f"distribution must be 'beckmann' or 'ggx', got {distribution!r}")
    if not (isinstance(starts, int | np.integer) and starts >= 1):
        raise BadInputError(None, f"starts must be a positive integer, got {starts!r}")
    if not (isinstance(n_samples, int | np.integer) and n_samples >= 256):
        raise BadInputError(None, f"n_samples must be an integer >= 256, got {n_samples!r}")


def _global_candidates(param: ModelParam, seed: int, n_sobol: int) -> np.ndarray:
    m = int(np.ceil(np.log2(max(n_sobol, 2))))
    u = kronecker_points(1 << m, param.dim, seed)
    sobol = param.lower + u * (param.upper - param.lower)
    starts = np.clip(param.starts(), param.lower, param.upper)
    return np.concatenate([starts, sobol])


def _pick_distinct(xs: np.ndarray, fs: np.ndarray, param: ModelParam, k: int) -> list[np.ndarray]:
    span = param.upper - param.lower
    chosen: list[np.ndarray] = []
    for i in np.argsort(fs, kind="stable"):
        x = param.canonical(xs[i])
        if all(np.max(np.abs(x - y) / span) > 0.02 for y in chosen):
            chosen.append(x)
        if len(chosen) == k:
            break
    return chosen


def _local(
    objective: ProjectedObjective, param: ModelParam, x0: np.ndarray, step: np.ndarray, xtol_rel: float,
    max_evals: int,
) -> tuple[np.ndarray, float, int]:
    opt = nlopt.opt(nlopt.LN_BOBYQA, param.dim)
    opt.set_lower_bounds(param.lower)
    opt.set_upper_bounds(param.upper)
    opt.set_min_objective(objective)
    opt.set_xtol_rel(xtol_rel)
    opt.set_xtol_abs(np.full(param.dim, 1e-9))
    opt.set_ftol_rel(1e-13)
    opt.set_stopval(1e-22)
    opt.set_maxeval(max_evals)
    opt.set_initial_step(step)
    before_best = objective.best_f
    x0 = np.clip(x0, param.lower, param.upper)
    try:
        x = np.asarray(opt.optimize(x0))
        f = opt.last_optimum_value()
    except (nlopt.RoundoffLimited, RuntimeError, ValueError):
        x, f = x0, objective(x0)
    code = opt.last_optimize_result()
    # nlopt may hand back a point worse than one it saw (or nothing, on failure): keep the best
    if objective.best_x is not None and objective.best_f < min(f, before_best):
        x, f = objective.best_x.copy(), objective.best_f
    return x, f, code


def fit_brdf(
    brdf: BRDF | str | Path,
    model: str = "lafortune",
    *,
    lobes: int = 1,
    distribution: str = "beckmann",
    metric: str = "rel",
    seed: int = 0,
    n_samples: int = 32768,
    starts: int = 4,
    max_theta_deg: float = 80.0,
    energy_conserving: bool = True,
    xtol_rel: float = 1e-7,
    max_evals: int = 1000,
    samples: FitSamples | None = None,
    progress: ProgressCallback | None = None,
    start: np.ndarray | Sequence[Sequence[float]] | None = None,
) -> FitResult:
    """Fit an analytic model to a BRDF (tabulated, analytic or scattered).

    Parameters
    ----------
    brdf
        A BRDF object, or a spec string / file path for ``shrmkit.load_brdf``.
    model
        ``"lafortune"`` (kd/π + ``lobes`` isotropic generalized-cosine lobes, Lafortune et
        al. 1997, shape shared by the channels, RGB lobe weights), ``"cook-torrance"``
        (Lambert + Cook–Torrance with ``distribution`` Beckmann or GGX, Schlick Fresnel,
        Smith G; RGB kd, ks, f0) or ``"microfacet"`` (RH02 eq. 11, RGB ks).
    lobes
        Number of Lafortune lobes (1–4).
    distribution
        Cook–Torrance microfacet distribution: ``"beckmann"`` or ``"ggx"``.
    metric
        Error the fit minimizes: ``"rel"`` (cosine-weighted relative RMS of ρ cos θ_i) or
        ``"log"`` (its log-space counterpart, robust to huge grazing values); both are
        reported (``metrics.py``).
    seed
        Seed of the direction samples and the global stage; fits are deterministic.
    n_samples
        Direction pairs drawn for analytic/tabulated BRDFs (before the grazing cut).
    starts
        Number of multi-start seeds refined by the local optimizer.
    max_theta_deg
        Samples with θ_i or θ_o above this are not used (``sampling.py``).
    energy_conserving
        Constrain the colour weights to conserve energy (``models_param.py``); switch off to
        reproduce published fits that do not.
    xtol_rel, max_evals
        Local-stage tolerances: relative step in the shape parameters, evaluations per run.
    samples
        Use these samples instead of drawing them (e.g. to compare models on one set).
    progress
        Called as ``progress(done, total)`` after each local run.
    start
        Candidate starting points (k, dim) of the shape parameters (e.g. ``FitResult.shape`` and
        ``FitResult.seeds`` of a fit of the same model and lobes) that replace the global stage:
        they are evaluated on these samples and the ``starts`` best distinct ones seed the
        local stage. For fits to subsets of samples already fitted as a whole (cross-validation
        folds, ``representation.py``): the whole set's optimum and the seeds its global stage
        found cover the basins a subset's optimum lies in, for k objective evaluations instead
        of the global stage's 32 · dim.

    Returns
    -------
    FitResult

    Raises
    ------
    BadInputError
        Unknown model/metric, bad option values, a ``start`` of the wrong length or not finite,
        or a BRDF without usable data.
    """
    t0 = time.perf_counter()
    _check_options(model, lobes, metric, distribution, starts, n_samples)
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    nlopt.srand(int(seed))
    if samples is None:
        samples = collect_samples(brdf, n_samples=n_samples, seed=seed, max_theta_deg=max_theta_deg)
    param = make_param(model, lobes=int(lobes), distribution=distribution)
    objective = ProjectedObjective(param, samples, metric, energy_conserving)
    if start is not None:
        start = np.atleast_2d(np.asarray(start, dtype=np.float64))
        seeds = _given_seeds(start, model, starts, param, objective)
    else:
        seeds = _global_seeds(brdf, model, lobes, metric, seed, starts, max_theta_deg, energy_conserving, xtol_rel,
                              max_evals, samples, param, objective)
    x, code = _local_stage(objective, param, seeds, xtol_rel, max_evals, progress)
    options = {
        "model": model,
        "lobes": int(lobes) if model == "lafortune" else None,
        "distribution": distribution if model == "cook-torrance" else None,
        "metric": metric,
        "seed": int(seed),
        "n_samples": int(n_samples),
        "starts": int(starts),
        "max_theta_deg": float(max_theta_deg),
        "energy_conserving": bool(energy_conserving),
    }
    if start is not None:  # the local stage ran from given points, not from the global stage's seeds
        options["start"] = np.asarray(start, dtype=np.float64).tolist()
    return _fit_result(model, param, objective, samples, x, code, seeds, options, t0)


def _given_seeds(start: np.ndarray, model: str, starts: int, param: ModelParam, objective: ProjectedObjective
                 ) -> list[np.ndarray]:
    """The ``starts`` best distinct of the given starting points (k, dim), clipped to the box."""
    if start.ndim != 2 or start.shape[1] != param.dim or len(start) == 0 or not np.all(np.isfinite(start)):
        raise BadInputError(None, f"start must hold rows of {param.dim} finite shape parameters of {model}, "
                            f"got shape {start.shape}")
    candidates = np.clip(start, param.lower, param.upper)
    return _pick_distinct(candidates, np.array([objective(x) for x in candidates]), param, starts)


def _local_stage(objective: ProjectedObjective, param: ModelParam, seeds: list[np.ndarray], xtol_rel: float,
                 max_evals: int, progress: ProgressCallback | None) -> tuple[np.ndarray, int]:
    """BOBYQA from each seed (initial step 5 % of the box), then a polish of the best (0.1 %, 100×
    tighter tolerance): the optimum's shape parameters and nlopt's result code of the polish."""
    total = len(seeds) + 1
    span = param.upper - param.lower
    best_x, best_f = seeds[0], np.inf
    for i, x0 in enumerate(seeds):
        x, f, _ = _local(objective, param, x0, 0.05 * span, xtol_rel, max_evals)
        if f < best_f:
            best_x, best_f = x, f
        if progress is not None:
            progress(i + 1, total)
    x, f, code = _local(objective, param, best_x, 1e-3 * span, xtol_rel * 1e-2, max_evals)
    if progress is not None:
        progress(total, total)
    return x, code


def _fit_result(model: str, param: ModelParam, objective: ProjectedObjective, samples: FitSamples, x: np.ndarray,
                code: int, seeds: list[np.ndarray], options: dict[str, Any], t0: float) -> FitResult:
    """The fitted model at the optimum x, its errors (overall and by view band), nlopt's status and
    the verdict."""
    x = param.canonical(x)
    _, c = objective.weights(x)
    fitted, params = param.build(x, c)
    model_rho = fitted.eval(samples.L, samples.V)
    errors = error_metrics(samples, model_rho)
    bands = band_errors(samples, model_rho)
    status = STATUS_NAMES.get(code, f"UNKNOWN({code})")
    converged = code in _CONVERGED
    worst = worst_band(bands)
    at_bounds = tuple(param.bounds_reached(x, c))
    nonzero, finite = bool(np.any(c > 0)), all(np.isfinite(v) for v in errors.values())
    message, success = _verdict(errors, worst, nonzero, finite, status, converged, objective.evaluations, at_bounds)
    return FitResult(
        model=model,
        params=params,
        brdf=fitted,
        errors=errors,
        bands=bands,
        status=status,
        success=success,
        message=message,
        evaluations=objective.evaluations,
        seconds=time.perf_counter() - t0,
        n_samples=len(samples),
        n_dropped=samples.n_dropped,
        options=options,
        worst=worst,
        converged=converged,
        at_bounds=at_bounds,
        usable=nonzero and finite,
        shape=tuple(float(v) for v in x),
        seeds=tuple(tuple(float(v) for v in seed_x) for seed_x in seeds),
    )


def _global_seeds(
    brdf: BRDF, model: str, lobes: int, metric: str, seed: int, starts: int, max_theta_deg: float,
    energy_conserving: bool, xtol_rel: float, max_evals: int, samples: FitSamples, param: ModelParam,
    objective: ProjectedObjective,
) -> list[np.ndarray]:
    """The global stage: the ``starts`` best distinct of the physically motivated starts and
    32 · dim low-discrepancy points over the box; a K-lobe Lafortune fit also starts from the (K-1)-lobe
    optimum plus each single-lobe start, so adding a lobe never makes the fit worse (the new
    lobe's weight can be 0)."""
    candidates = _global_candidates(param, seed, n_sobol=32 * param.dim)
    if model == "lafortune" and lobes > 1:
        previous = fit_brdf(
            brdf, model, lobes=int(lobes) - 1, metric=metric, seed=seed, starts=starts,
            max_theta_deg=max_theta_deg, energy_conserving=energy_conserving, xtol_rel=xtol_rel,
            max_evals=max_evals, samples=samples,
        )
        x_prev = np.concatenate([[np.arctan2(lobe["cz"], lobe["cxy"]), np.log(lobe["n"])]
                                 for lobe in previous.params["lobes"]])
        singles = make_param(model, lobes=1).starts()
        nested = np.clip([np.concatenate([x_prev, one]) for one in singles], param.lower, param.upper)
        candidates = np.concatenate([nested, candidates])
    values = np.array([objective(x) for x in candidates])
    return _pick_distinct(candidates, values, param, starts)


def _verdict(errors: dict[str, float], worst: BandError | None, nonzero: bool, finite: bool, status: str,
             converged: bool, evaluations: int, at_bounds: tuple[str, ...]) -> tuple[str, bool]:
    """(message, success): the worst band first, then how nlopt stopped and the bounds reached."""
    stop = (f"nlopt stopped with {status} after {evaluations} evaluations"
            + ("" if converged else " (its evaluation budget, not a tolerance)"))
    tail = f"; {stop}" + (f"; {'; '.join(at_bounds)}" if at_bounds else "")
    if not nonzero:
        return "failed: the best fit is the zero BRDF: the model cannot represent this data" + tail, False
    if not finite:
        return "failed: non-finite errors" + tail, False
    if worst is None:
        return f"rel. RMS {errors['rel_rms']:.3g} (no view band with enough samples to judge)" + tail, True
    where = f"rel. RMS {worst.rel_rms:.3g} in the {worst.lo_deg:g}–{worst.hi_deg:g}° view band"
    if worst.rel_rms > FIT_FAIL_BAND_REL_RMS:
        return (f"failed: {where} (above {FIT_FAIL_BAND_REL_RMS:g}; {errors['rel_rms']:.3g} over all samples)"
                + tail), False
    return f"worst band {where}; {errors['rel_rms']:.3g} over all samples" + tail, True
