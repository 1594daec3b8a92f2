"""How far scattered measurements are from isotropic: the held-out energy of the φ-dependent part.

:func:`measure_isotropy` fits the isotropic Zernike expansion ([Koe96]; the isotropic subset keeps
m' = m with cos m(φ_i − φ_o)) and the same plus reciprocal anisotropic terms
(:func:`anisotropic_basis`) to the same samples, scores both by held-out error, and measures how
much of the isotropic misfit only the true azimuths predict, against a control at turned
geometries (:class:`Isotropy`). Made for CURET's 205 geometries ([CURET99]; [RH02] §6.2: the
CURET surfaces their isotropic fits could not represent).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ...brdf_io.errors import BadInputError
from ...brdf_io.zernike import basis_count, disc_radius, zernike_basis, zernike_radial
from .crossval import DEFAULT_FOLDS, fold_of
from .metrics import rel_rms
from .sampling import FitSamples
from .summary import FIT_FAIL_BAND_REL_RMS
from .zernike import ridge_solutions

__all__ = ["ANISO_ORDER", "ANISOTROPIC_ABOVE", "Isotropy", "anisotropic_basis", "measure_isotropy"]

#: Largest Zernike degree of either factor of the anisotropic terms (16 reciprocal terms at 2).
ANISO_ORDER = 2
#: Residual share S above which (and A above three control spreads) the material is called
#: anisotropic: half of the isotropic model's held-out misfit predicted only by the true azimuths
#: (synthetic isotropic lobes at CURET's geometries: S <= 0.2; tests/analysis/fit/test_isotropy.py).
ANISOTROPIC_ABOVE = 0.5
_RIDGES = (1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1)


def _aniso_terms(n_max: int) -> list[tuple[int, int, int, int, str]]:
    """(n, a, n', b, trig) with a + b > 0, one per reciprocal pair (n, a) <= (n', b)."""
    single = [(n, a) for n in range(n_max + 1) for a in range(-n, n + 1, 2)]
    out = []
    for i, (n, a) in enumerate(single):
        for n2, b in single[i:]:
            if a + b > 0:
                out += [(n, a, n2, b, "cos"), (n, a, n2, b, "sin")]
    return out


def anisotropic_basis(L: np.ndarray, V: np.ndarray, n_max: int = ANISO_ORDER) -> np.ndarray:
    """The reciprocal anisotropic terms (:func:`measure_isotropy`) at direction pairs.

    Parameters
    ----------
    L, V
        Unit directions (n, 3), local frame (normal +z), both above the surface.
    n_max
        Largest Zernike degree of either factor.

    Returns
    -------
    numpy.ndarray
        (n, K) values of R_n^|a|(ρ_i) R_n'^|b|(ρ_o) t(a φ_i + b φ_o) + (i ↔ o), t = cos or sin,
        a + b > 0 (K = 16 for n_max = 2); each unchanged when L and V swap, none unchanged by a
        common rotation about the normal.
    """
    rho_i, rho_o = disc_radius(L[:, 2]), disc_radius(V[:, 2])
    phi_i, phi_o = np.arctan2(L[:, 1], L[:, 0]), np.arctan2(V[:, 1], V[:, 0])
    trig = {"cos": np.cos, "sin": np.sin}
    cols = []
    for n, a, n2, b, t in _aniso_terms(n_max):
        f = trig[t]
        cols.append(zernike_radial(n, a, rho_i) * zernike_radial(n2, b, rho_o) * f(a * phi_i + b * phi_o)
                    + zernike_radial(n, a, rho_o) * zernike_radial(n2, b, rho_i) * f(a * phi_o + b * phi_i))
    return np.stack(cols, axis=-1)


@dataclass(frozen=True)
class Isotropy:
    """The outcome of :func:`measure_isotropy`.

    Attributes
    ----------
    anisotropy
        A = max(0, e_turned² − e_aniso²): the fraction of the measured energy (Σ w (ρ cos θ_i)²)
        that only the φ-dependent terms at the true azimuths predict out of sample.
    held_out_isotropic, held_out_anisotropic, held_out_turned
        Held-out relative RMS over all samples of the isotropic model, of the model with the
        φ-dependent terms, and of the control (the terms at turned geometries; RMS over turns).
    null_spread
        Standard deviation of e² over the control's turns.
    residual_share
        S = A / e_turned²: the share of the misfit that is φ-dependent.
    judged
        False when the isotropic model fails (held-out relative RMS above 0.5): its misfit then
        dominates both errors and A says little.
    fitted_anisotropic_energy
        Energy of the anisotropic part of the anisotropic model fitted to all samples, as a
        fraction of the data's (in-sample; not a verdict: noise fills it too).
    n_max, n_aniso_terms, folds
        The isotropic order, the anisotropic terms added, the cross-validation folds.
    anisotropic
        S > :data:`ANISOTROPIC_ABOVE` and A > 3 ``null_spread``.
    """

    anisotropy: float
    held_out_isotropic: float
    held_out_anisotropic: float
    fitted_anisotropic_energy: float
    n_max: int
    n_aniso_terms: int
    folds: int
    anisotropic: bool
    held_out_turned: float = float("nan")
    null_spread: float = float("nan")
    residual_share: float = float("nan")
    judged: bool = True

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def line(self) -> str:
        """One phrase for people, e.g. ``"anisotropy 0.0031 of the energy, 74 % of the isotropic misfit
        (ANISOTROPIC)"``."""
        verdict = ("not judged: the isotropic model fails" if not self.judged
                   else "ANISOTROPIC" if self.anisotropic else "isotropic")
        return (f"anisotropy {self.anisotropy:.2g} of the energy, {self.residual_share:.0%} of the isotropic "
                f"misfit ({verdict})")


def _turn(d: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Directions (n, 3) turned by angles alpha (n,) about the normal +z."""
    c, s = np.cos(alpha), np.sin(alpha)
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=-1)


def _cv_error(samples: FitSamples, A: np.ndarray, fold: np.ndarray, folds: int) -> tuple[float, float]:
    """(smallest held-out rel_rms over the ridge grid, its ridge) of the linear model A c (weights
    w cos² θ_i, as ``fit_zernike(metric="rel")``)."""
    sw = np.sqrt(samples.weight * samples.cos_i**2)[:, None]
    preds = {r: np.empty_like(samples.rho) for r in _RIDGES}
    for k in range(folds):
        test, train = fold == k, fold != k
        for r, c in zip(_RIDGES, ridge_solutions(A[train] * sw[train], samples.rho[train] * sw[train], _RIDGES),
                        strict=True):
            preds[r][test] = A[test] @ c
    return min((rel_rms(samples, p), r) for r, p in preds.items())


def measure_isotropy(
    samples: FitSamples,
    n_max: int,
    *,
    aniso_order: int = ANISO_ORDER,
    folds: int = DEFAULT_FOLDS,
    seed: int = 0,
    n_null: int = 8,
) -> Isotropy:
    """How far scattered measurements are from isotropic.

    An isotropic BRDF depends on the azimuths only through φ_i − φ_o: it is unchanged when light
    and view turn together about the normal. Measurements that hold both azimuths (CURET's 205
    geometries: the sample is turned on its stage, so each geometry has its own φ_i) can test
    that. CURET has no two geometries that isotropy makes equal (none within 2° in θ_i, θ_o and
    |φ_i − φ_o|), so the comparison goes through two fits to the same samples:

    * the isotropic model: Koenderink's reciprocal isotropic Zernike expansion of order N
      (``brdf_io/zernike.py``), every term a function of (ρ_i, ρ_o, φ_i − φ_o);
    * the same plus **anisotropic terms**: products of Zernike radial polynomials and
      cos/sin(a φ_i + b φ_o) with total azimuthal frequency a + b ≠ 0 — exactly the products
      Z_n^a(ρ_i, φ_i) Z_n'^b(ρ_o, φ_o) that change under a common rotation φ → φ + α — made
      reciprocal by adding the same with i ↔ o, up to degree n, n' <= :data:`ANISO_ORDER`.

    Both are scored by held-out error (``crossval.py``; the ridge of each chosen from the same
    grid). Extra terms also add plain flexibility: on a scattered geometry set the absolute azimuths
    correlate with the invariants, so φ-dependent terms can fit part of an isotropic model's misfit.
    The **control** measures that: the same terms evaluated at the geometries turned by random
    common angles about the normal (an isotropic BRDF has exactly the data's values there; an
    anisotropic one loses its pattern), averaged over ``n_null`` turns. With e the held-out
    cosine-weighted relative RMS over all samples (``metrics.rel_rms``; e_turned² the control's mean):

        anisotropy      A = max(0, e_turned² − e_aniso²)    a fraction of Σ w (ρ cos θ_i)², the energy
                                                             that only the true azimuths predict;
        residual share  S = A / e_turned²                   the share of the isotropic misfit that is
                                                             φ-dependent.

    The material is called anisotropic when S > :data:`ANISOTROPIC_ABOVE` and A exceeds three
    standard deviations of the control's spread. Measured at CURET's geometries
    (tests/analysis/fit/test_isotropy.py): synthetic isotropic lobes give S <= 0.2, a Lambertian
    surface with a grain ρ = kd/π (1 + ½ sin²θ_h cos 2φ_h) gives S = 0.99; the real felt 0.13,
    corduroy 0.74. A is a lower bound on the φ-dependent energy: what the low-order terms cannot hold
    (a sharp anisotropic Ward lobe, α = 0.3 × 0.8, is mostly missed: S = 0.26) and what the
    geometries cannot tell apart is not counted. When the isotropic model itself fails (held-out
    relative RMS above 0.5) its misfit dominates and ``judged`` is False.

    Parameters
    ----------
    samples
        Measurements with both azimuths (L and V as measured; CURET, Cornell and gonioreflectometer
        data give them), weights as ``sampling.py``.
    n_max
        Order of the isotropic Zernike model (the cross-validated choice of
        ``fit_zernike_cv``: ``params["n_max"]``).
    aniso_order
        Largest degree of the anisotropic terms (:data:`ANISO_ORDER`).
    folds, seed
        Cross-validation (``crossval.fold_of``); ``seed`` also draws the control's turns.
    n_null
        Turns of the control.

    Returns
    -------
    Isotropy

    Raises
    ------
    BadInputError
        Fewer training samples per fold than terms of the anisotropic model.
    """
    an = anisotropic_basis(samples.L, samples.V, aniso_order)
    fold = fold_of(len(samples), folds, seed=seed)
    n_train = len(samples) - int(np.max(np.bincount(fold)))
    # the isotropic order lowered until both models have fewer terms than a training fold has samples
    while n_max > 0 and basis_count(n_max) + an.shape[1] > n_train:
        n_max -= 1
    if basis_count(n_max) + an.shape[1] > n_train:
        raise BadInputError(samples.source, f"{n_train} samples per training fold: too few for an isotropy test "
                            f"with {basis_count(n_max)} + {an.shape[1]} terms")
    iso = zernike_basis(samples.L, samples.V, n_max)
    # each anisotropic column scaled to the RMS of the isotropic columns, so one ridge fits both
    scale = np.sqrt(np.mean(iso**2)) / np.maximum(np.sqrt(np.mean(an**2, axis=0)), 1e-300)
    full = np.concatenate([iso, an * scale], axis=1)
    e_iso, _ = _cv_error(samples, iso, fold, folds)
    e_an, ridge = _cv_error(samples, full, fold, folds)
    # the control: the same anisotropic terms at geometries turned by random common angles about
    # the normal. An isotropic BRDF has the same values there, so what the terms predict at the
    # turned geometries is flexibility, not anisotropy; an anisotropic one loses its pattern
    rng = np.random.default_rng(seed)
    null = []
    for _ in range(n_null):
        alpha = rng.uniform(0.0, 2.0 * np.pi, len(samples))
        turned = anisotropic_basis(_turn(samples.L, alpha), _turn(samples.V, alpha), aniso_order)
        null.append(_cv_error(samples, np.concatenate([iso, turned * scale], axis=1), fold, folds)[0])
    e_null = np.asarray(null)
    sw = np.sqrt(samples.weight * samples.cos_i**2)[:, None]
    c = ridge_solutions(full * sw, samples.rho * sw, (ridge,))[0]
    part = (full[:, iso.shape[1]:] @ c[iso.shape[1]:]) * samples.cos_i[:, None]
    den = float(np.sum(samples.weight[:, None] * (samples.rho * samples.cos_i[:, None]) ** 2))
    fitted = float(np.sum(samples.weight[:, None] * part**2) / den) if den > 0 else float("nan")
    turned2 = float(np.mean(e_null**2))
    a = max(0.0, turned2 - e_an**2)
    spread = float(np.std(e_null**2))
    share = a / turned2 if turned2 > 0 else 0.0
    return Isotropy(anisotropy=a, held_out_isotropic=e_iso, held_out_anisotropic=e_an,
                    fitted_anisotropic_energy=fitted, n_max=int(n_max), n_aniso_terms=int(an.shape[1]),
                    folds=int(folds), anisotropic=share > ANISOTROPIC_ABOVE and a > 3.0 * spread,
                    held_out_turned=float(np.sqrt(turned2)), null_spread=spread, residual_share=share,
                    judged=e_iso <= FIT_FAIL_BAND_REL_RMS)
