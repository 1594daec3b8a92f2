"""One representation for scattered measurements, chosen by held-out error.

Scattered measurements (CURET, Cornell, gonioreflectometer CSV) hold ρ only at the measured
direction pairs; every analysis that needs ρ everywhere (orders, SHRMs, renders) goes through
a representation fitted to them, and its orders describe that representation — so the one used
is the one that predicts the measurements best. :func:`choose_representation` fits each
candidate — one-lobe Lafortune and Cook–Torrance (``optimize.fit_brdf``, nlopt) and Koenderink's
reciprocal isotropic Zernike expansion with its order and ridge chosen by cross-validation
(``zernike.fit_zernike_cv``) — scores each by its **held-out** error (``crossval.py``: every
measurement predicted by a fit that did not see it, on one sample set and one fold split for
all candidates), and returns the one with the smallest held-out worst-view-band relative RMS
(``summary.worst_band``) — or, when no candidate's worst band is at most 0.5, the one with the
smallest held-out relative RMS over all samples — with every candidate's errors and, where the measurements hold the
azimuth of incidence, how far the material is from isotropic (``isotropy.py``).

A chosen representation whose held-out worst band is above
:data:`~shrmkit.analysis.fit.summary.FIT_FAIL_BAND_REL_RMS` is still returned (the best there
is), with ``success`` False: its orders then describe the representation, not the material.

Public objects: :func:`choose_representation`, :class:`RepresentationChoice`,
:class:`CandidateError`, :data:`CANDIDATES`.

Reference: [RH02] §6.2 and Fig. 8 (CURET analysed through fitted Zernike expansions).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...brdf_io.brdf import BRDF
from ...brdf_io.errors import BadInputError
from ...brdf_io.models import AnalyticModel
from ...brdf_io.specs import load_brdf
from ...brdf_io.zernike import ZernikeBRDF
from ..defaults import REPRESENTATION_CANDIDATES as CANDIDATES  # numpy-free home, for the CLI's parsers
from ..threads import single_threaded_blas
from .crossval import DEFAULT_FOLDS, held_out
from .isotropy import Isotropy, measure_isotropy
from .metrics import rel_rms
from .optimize import FitResult, fit_brdf
from .sampling import FitSamples, collect_samples
from .summary import FIT_FAIL_BAND_REL_RMS, BandError, band_errors, worst_band
from .zernike import fit_zernike_cv

__all__ = ["CANDIDATES", "CandidateError", "RepresentationChoice", "choose_representation",
           "incident_azimuths_vary"]

#: Local runs of each fold's nlopt fit (then the polish). The fold's starting points are the
#: fit to all samples' optimum and its global stage's seeds (``fit_brdf(start=...)``), ranked on
#: the fold's own samples. Against the per-fold global stage and 2 runs this replaces, on the 61
#: CURET samples, 5 Cornell paints and 4 NIST PTFE wavelengths: the same choice for all 70, the
#: same held-out worst band (to 10⁻⁴) for 136 of the 140 nlopt candidates; 4 moved (CURET
#: brick-a Lafortune 0.299 → 0.255, pebbles and salt crystals Cook–Torrance by 0.003, Cornell
#: cayman Lafortune 6.8 → 3.3), each fold fit at about 40 % of the cost
#: (benchmarks/chooser_speed.py for the whole chooser).
FOLD_STARTS = 1
#: Local runs of a fold fit that has no fit to all samples to start from (its own global stage).
FOLD_STARTS_GLOBAL = 2


@dataclass(frozen=True)
class CandidateError:
    """One candidate's errors, held out and on its own samples.

    Attributes
    ----------
    model
        ``"lafortune"``, ``"cook-torrance"`` or ``"zernike"``.
    held_out_worst
        The worst view band of the held-out predictions (relative RMS of ρ cos θ_i), or None.
    held_out_rel_rms
        Held-out relative RMS over all samples.
    training_rel_rms, training_worst
        The same for the fit to all samples, on those samples (flattering).
    success
        Held-out worst band at most ``FIT_FAIL_BAND_REL_RMS`` (0.5).
    detail
        The fitted model's setting (Zernike order, terms and ridge; nlopt's stop reason).
    error
        Why the candidate could not be fitted (then the errors are NaN), else None.
    """

    model: str
    held_out_worst: BandError | None
    held_out_rel_rms: float
    training_rel_rms: float
    training_worst: BandError | None
    success: bool
    detail: str = ""
    error: str | None = None

    @property
    def score(self) -> float:
        """What the choice minimizes: the held-out worst band (else all samples; inf if it failed to run)."""
        if self.error is not None or not np.isfinite(self.held_out_rel_rms):
            return float("inf")
        return self.held_out_rel_rms if self.held_out_worst is None else self.held_out_worst.rel_rms

    def band_text(self) -> str:
        """``"0.2 (70–80°)"``: the held-out worst band for people."""
        if self.error is not None:
            return "not fitted"
        if self.held_out_worst is None:
            return f"{self.held_out_rel_rms:.3g} (all views)"
        w = self.held_out_worst
        return f"{w.rel_rms:.3g} ({w.lo_deg:g}–{w.hi_deg:g}°)"

    def as_dict(self) -> dict[str, Any]:
        return {"model": self.model, "held_out_worst_band": None if self.held_out_worst is None
                else self.held_out_worst.as_dict(), "held_out_rel_rms": self.held_out_rel_rms,
                "training_rel_rms": self.training_rel_rms, "training_worst_band": None if self.training_worst is None
                else self.training_worst.as_dict(), "success": self.success, "detail": self.detail,
                "error": self.error}


@dataclass(frozen=True, eq=False)
class RepresentationChoice:
    """The outcome of :func:`choose_representation`.

    Attributes
    ----------
    brdf
        The chosen representation, fitted to all samples: evaluable everywhere.
    model
        Its name (a member of :data:`CANDIDATES`).
    fit
        Its fit to all samples (a :class:`~shrmkit.analysis.fit.FitResult`).
    candidates
        Every candidate's errors, in :data:`CANDIDATES` order.
    isotropy
        How far the measurements are from isotropic (``isotropy.measure_isotropy``), None when
        they hold a single axis of incidence (Cornell: φ_i = 0) or no Zernike fit ran.
    isotropy_note
        Why ``isotropy`` is None ("" otherwise).
    folds, seed, n_samples, seconds
        Cross-validation folds and seed, samples used, wall time.
    """

    brdf: AnalyticModel | ZernikeBRDF
    model: str
    fit: FitResult
    candidates: tuple[CandidateError, ...]
    isotropy: Isotropy | None
    isotropy_note: str
    folds: int
    seed: int
    n_samples: int
    seconds: float
    options: dict[str, Any] = field(default_factory=dict)

    @property
    def chosen(self) -> CandidateError:
        """The chosen candidate's errors."""
        return next(c for c in self.candidates if c.model == self.model)

    @property
    def success(self) -> bool:
        """Whether the chosen representation's held-out worst band is at most 0.5."""
        return self.chosen.success

    def label(self) -> str:
        """``"zernike order 6 (30 terms, ridge 1e-06)"`` or ``"lafortune"``."""
        if self.model == "zernike":
            p = self.fit.params
            return f"zernike order {p['n_max']} ({p['n_coeffs']} terms, ridge {p['ridge']:g})"
        return self.model

    def line(self) -> str:
        """One line for people: the chosen representation, its held-out worst band, the others',
        and the anisotropy."""
        c = self.chosen
        verdict = "" if c.success else f", FAILED (above {FIT_FAIL_BAND_REL_RMS:g}: the orders describe the fit)"
        others = ", ".join(f"{o.model} {o.band_text()}" for o in self.candidates if o.model != self.model)
        iso = self.isotropy.line() if self.isotropy is not None else f"isotropy not measured ({self.isotropy_note})"
        return (f"analysed through {self.label()}: held-out worst view band rel. RMS {c.band_text()}{verdict}; "
                f"{others}; {iso}")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: ``model``, ``label``, ``spec``, ``success``, ``held_out_worst_band``,
        ``candidates``, ``isotropy``, ``isotropy_note``, ``folds``, ``seed``, ``n_samples``, ``seconds``,
        ``line`` (``data_specs/representation_json.md``)."""
        c = self.chosen
        return {"model": self.model, "label": self.label(), "spec": self.brdf.to_spec(), "success": self.success,
                "held_out_worst_band": None if c.held_out_worst is None else c.held_out_worst.as_dict(),
                "held_out_rel_rms": c.held_out_rel_rms,
                "candidates": [o.as_dict() for o in self.candidates],
                "isotropy": None if self.isotropy is None else self.isotropy.as_dict(),
                "isotropy_note": self.isotropy_note, "folds": self.folds, "seed": self.seed,
                "n_samples": self.n_samples, "seconds": self.seconds, "line": self.line()}


def incident_azimuths_vary(samples: FitSamples, min_theta_deg: float = 5.0) -> bool:
    """Whether the measurements hold more than one axis of incidence: the mean resultant length
    of e^{2iφ_i} over samples with θ_i above ``min_theta_deg`` is below 0.95 (φ_i and φ_i + π
    are one axis; Cornell's φ_i = 0 and a gonioreflectometer's ±θ_i plane are one)."""
    L = samples.L[samples.L[:, 2] < np.cos(np.radians(min_theta_deg))]
    if len(L) < 2:
        return False
    phi = np.arctan2(L[:, 1], L[:, 0])
    return bool(np.abs(np.mean(np.exp(2j * phi))) < 0.95)


def _candidate(model: str, samples: FitSamples, held: np.ndarray, full: FitResult, detail: str) -> CandidateError:
    worst = worst_band(band_errors(samples, held))
    err = rel_rms(samples, held)
    score = err if worst is None else worst.rel_rms
    return CandidateError(model=model, held_out_worst=worst, held_out_rel_rms=err,
                          training_rel_rms=float(full.errors["rel_rms"]), training_worst=full.worst,
                          success=bool(np.isfinite(score) and score <= FIT_FAIL_BAND_REL_RMS), detail=detail)


def choose_representation(
    brdf: BRDF | str | Path,
    *,
    candidates: tuple[str, ...] = CANDIDATES,
    folds: int = DEFAULT_FOLDS,
    seed: int = 0,
    max_theta_deg: float = 80.0,
    fits: Mapping[str, FitResult] | None = None,
    isotropy: bool = True,
) -> RepresentationChoice:
    """Fit every candidate to scattered measurements and keep the successful one with the smallest
    held-out worst-view-band error, else the one with the smallest held-out error over all samples
    (module docstring).

    Parameters
    ----------
    brdf
        Scattered measurements (``kind == "scattered"``), or a spec/path for ``load_brdf``.
    candidates
        Names from :data:`CANDIDATES`.
    folds, seed
        Cross-validation folds and the seed of the split (the same split for every candidate),
        of the nlopt fits and of the isotropy control.
    max_theta_deg
        Samples with θ_i or θ_o above this are not used (the default fit cut, 80°).
    fits
        Fits of the nlopt candidates to all samples already made (``{"lafortune": result}``,
        e.g. by the report) with the same samples: reused instead of fitted again.
    isotropy
        Measure the anisotropy (``isotropy.measure_isotropy``) where the azimuths of incidence vary.

    Returns
    -------
    RepresentationChoice

    Raises
    ------
    BadInputError
        A BRDF that is not scattered (analyse it directly), an unknown candidate, no candidate
        that could be fitted, or too few samples.
    """
    # the chooser's matrices are small (at most 140 terms, 205 CURET samples): OpenBLAS's threads
    # cost more than they save, and on a busy machine much more (analysis/threads.py)
    with single_threaded_blas():
        return _choose(brdf, candidates=candidates, folds=folds, seed=seed, max_theta_deg=max_theta_deg, fits=fits,
                       isotropy=isotropy)


def _choose(
    brdf: BRDF | str | Path, *, candidates: tuple[str, ...], folds: int, seed: int, max_theta_deg: float,
    fits: Mapping[str, FitResult] | None, isotropy: bool,
) -> RepresentationChoice:
    t0 = time.perf_counter()
    if isinstance(brdf, str | Path):
        brdf = load_brdf(brdf)
    name = getattr(brdf, "name", "brdf")
    if getattr(brdf, "kind", None) != "scattered":
        raise BadInputError(name, "not scattered measurements: it is evaluable everywhere, analyse it directly")
    unknown = [c for c in candidates if c not in CANDIDATES]
    if unknown or not candidates:
        raise BadInputError(None, f"unknown representation(s) {unknown}; choose from {', '.join(CANDIDATES)}")
    samples = collect_samples(brdf, max_theta_deg=max_theta_deg)
    results: list[CandidateError] = []
    full_fits: dict[str, FitResult] = {}
    for model in candidates:
        try:
            if model == "zernike":
                result, full = _zernike_candidate(brdf, samples, folds, seed, max_theta_deg)
            else:
                result, full = _nlopt_candidate(brdf, model, samples, folds, seed, max_theta_deg, fits)
            results.append(result)
            full_fits[model] = full
        except BadInputError as err:
            results.append(CandidateError(model=model, held_out_worst=None, held_out_rel_rms=float("nan"),
                                          training_rel_rms=float("nan"), training_worst=None, success=False,
                                          error=err.problem))
    usable = [r for r in results if r.error is None and full_fits[r.model].usable and np.isfinite(r.score)]
    if not usable:
        reasons = "; ".join(f"{r.model}: {r.error or 'not usable'}" for r in results)
        raise BadInputError(name, f"no representation could be fitted to the measurements ({reasons})")
    # the successful candidate with the smallest held-out worst band; when none succeeds, the one with
    # the smallest held-out error over all samples: a worst band near 1 is also what a heavily damped
    # expansion that predicts almost nothing in that band scores (Cornell cayman: Zernike at ridge 0.1,
    # 1.02, against Cook–Torrance's 2.0 that overshoots a peak), while the energy-weighted error still
    # ranks the models by how much of the material they hold
    best = min(usable, key=lambda r: (not r.success, r.score if r.success else r.held_out_rel_rms))
    iso, note = _isotropy(samples, isotropy, full_fits, folds, seed)
    return RepresentationChoice(
        brdf=full_fits[best.model].brdf, model=best.model, fit=full_fits[best.model], candidates=tuple(results),
        isotropy=iso, isotropy_note=note, folds=int(folds), seed=int(seed), n_samples=len(samples),
        seconds=time.perf_counter() - t0, options={"candidates": list(candidates), "max_theta_deg": max_theta_deg},
    )


def _zernike_candidate(brdf: BRDF, samples: FitSamples, folds: int, seed: int, max_theta_deg: float
                       ) -> tuple[CandidateError, FitResult]:
    """The Zernike expansion, its order and ridge chosen by cross-validation on the split (its
    errors are already held out on it)."""
    full = fit_zernike_cv(brdf, samples=samples, folds=folds, seed=seed, max_theta_deg=max_theta_deg)
    # fit_zernike_cv's errors are already held out on the same split
    worst, err = full.worst, float(full.errors["rel_rms"])
    tw = full.params["training"]["worst_band"]
    return CandidateError(
        model="zernike", held_out_worst=worst, held_out_rel_rms=err,
        training_rel_rms=float(full.params["training"]["errors"]["rel_rms"]),
        training_worst=None if tw is None else BandError(**tw), success=full.success,
        detail=f"order {full.params['n_max']} ({full.params['n_coeffs']} terms), "
        f"ridge {full.params['ridge']:g}"), full


def _nlopt_candidate(brdf: BRDF, model: str, samples: FitSamples, folds: int, seed: int, max_theta_deg: float,
                     fits: Mapping[str, FitResult] | None) -> tuple[CandidateError, FitResult]:
    """An nlopt model fitted to all samples (or the given fit), its held-out error from a fit per fold."""
    given = (fits or {}).get(model)
    full = given if given is not None else fit_brdf(brdf, model, samples=samples, seed=seed,
                                                    max_theta_deg=max_theta_deg)

    # the folds start from the whole set's optimum and its global stage's seeds, ranked
    # on the fold (the global stage, 32 · dim evaluations, is not repeated per fold)
    shared: dict[str, Any] = {} if full.shape is None else {"start": [full.shape, *full.seeds], "starts": FOLD_STARTS}

    def predict(train: FitSamples, test: FitSamples) -> np.ndarray:
        fold_fit = fit_brdf(brdf, model, samples=train, seed=seed, max_theta_deg=max_theta_deg,
                            **({"starts": FOLD_STARTS_GLOBAL} | shared))
        return fold_fit.brdf.eval(test.L, test.V)

    held = held_out(samples, predict, folds, seed=seed)
    return _candidate(model, samples, held, full, f"nlopt {full.status}"), full


def _isotropy(samples: FitSamples, isotropy: bool, full_fits: Mapping[str, FitResult], folds: int, seed: int
              ) -> tuple[Isotropy | None, str]:
    """The anisotropy measure (None when not asked, not measurable or refused) and a note saying why not."""
    iso, note = None, ""
    if not isotropy:
        note = "not asked"
    elif not incident_azimuths_vary(samples):
        note = "the measurements hold one axis of incidence"
    else:
        n_max = full_fits["zernike"].params["n_max"] if "zernike" in full_fits else 6
        try:
            iso = measure_isotropy(samples, n_max, folds=folds, seed=seed)
        except BadInputError as err:
            note = err.problem
    return iso, note
