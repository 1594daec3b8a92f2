"""The pixel rule: F_B raised until the reflected field is accurate per direction, not only on
average (issue 23: "a stated error holds where a user reads it").

The order rules (RH02's energy rule and the per-view-band rule of :mod:`.view_bands`) bound an
*energy* fraction: the error of a map, weighted by where its reflection is bright. Under a high
dynamic range map (a cathedral's windows beside dark stone) the truncation error of the bright
parts spreads over the dark ones as ringing, and there the *relative* error of a pixel can be 100 %
while the energy error is 3 % (Grace + Phong s = 200 at the energy rule's F_B = 28: per-pixel
relative error median 0.17, 90th percentile 0.62 against brute force).

Rule. With tolerance ε the relative RMS the tolerance stands for is √ε; the pixel rule takes the
smallest F >= F_B (on a fixed ladder of orders, so that the choice is monotone in ε) whose
*per-direction* relative error of the reflected luminance has its 90th percentile (:data:`QUANTILE`)
at most √ε, over a sample of reflection directions R (a :data:`ROWS` × 2·ROWS lat-long grid of pixel
centres) at the normal view V = R and, for P > 0, the oblique views of
:data:`~shrmkit.analysis.synthesis.LOCAL_VIEWS_DEG` (up to θ_v = 80°). The error of order F is
measured against the same field at a reference order F_ref = min(top, 4 F + 32) (top: the largest
order the lighting and the BRDF coefficients hold); the reference is raised with the choice when it
falls below 3 F + 12.
Directions whose reference luminance is below 10⁻⁴ of the sample's largest (black: nothing to be
relatively wrong about) do not count.

The sample is the reflection of the map the SHRM holds: with lights taken out as explicit lights
(:mod:`.lights`), of the residual map, relative to its own reflection — a conservative statement
for the whole, since the lights only add (exactly shaded) signal. The synthesis is exact at the
sample points (a coarse grid of an exact band-limited field; measured: the 48-row statistics agree
with the full-resolution sample's within 0.01 for Grace, sky, Venice under Phong, microfacet and
GGX lobes).

The statement is an estimate, not a bound: it leaves out the maps' bilinear lookup (stated per band
in ``view_bands``), the view orders' truncation and fit (P_B; the sample is compared at the same P)
and what the reference order itself misses. Against brute force on 600 pixels of a rendered sphere
the measured 90th percentile was 0.75–1.07 × the estimate (sky, Grace, Venice; README, "Per pixel
as well as per band"). Over issue 23's matrix (``benchmarks/lights_matrix.py``: sky, Venice, Grace
and three lamps at 128 rows × 8 BRDFs, 300 sphere pixels each) it was 0.07–2.05 × (median 0.86),
above the estimate in 9 of 32 cells (Grace: σ = 0.1 2.05 ×, σ = 0.3 1.59 ×, the RGL table 1.37 ×;
Venice Phong s = 512 1.21 ×), and above √ε itself in two (Grace σ = 0.3 0.247, RGL 0.231). Under the
one-pixel sun the residual is a constant sky: the estimate is 4·10⁻⁵–6·10⁻⁴ while brute force
measures up to 0.012 (the view orders' error, which the sample does not see).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..brdf_io.exr import luminance_weights
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients
from .synthesis import local_view_field, windowed

__all__ = [
    "QUANTILE", "ROWS", "PixelCheck", "pixel_errors", "pixel_line", "pixel_orders", "pixel_sampler", "pixel_statement",
]

#: The quantile of the per-direction relative error the rule bounds by √ε.
QUANTILE = 0.9
#: Rows of the lat-long sample of reflection directions (2·ROWS columns).
ROWS = 48
#: Directions darker than this fraction of the sample's brightest reference do not count.
DARK = 1e-4
#: References raised at most this many times while the choice approaches them.
MAX_REFERENCE_RAISES = 3


def _reference_order(F: int, top: int) -> int:
    """The reference order for a field of order F: min(top, 4 F + 32)."""
    return int(min(top, 4 * F + 32))


def _reference_holds(F_ref: int, F: int, top: int) -> bool:
    """A reference is high enough for order F when it is at least 3 F + 12 (or the top order)."""
    return F_ref >= min(top, 3 * F + 12)


def _global_ladder(top: int) -> list[int]:
    """0, 1, 2, …: steps of max(1, ⌈f/8⌉) (growing with f), up to ``top``: one ladder for every F and ε."""
    out, f = [], 0
    while f < top:
        out.append(f)
        f += max(1, int(np.ceil(f / 8.0)))
    return out


#: Every this-many rungs of the global ladder are tried first; the rungs between the last failing and
#: the first passing one are then tried in order.
STRIDE = 4


def _ladder(F: int, top: int) -> list[tuple[int, bool]]:
    """The orders tried from F: F itself, the global ladder's rungs above it, ``top``; each with whether
    it is a coarse rung (every :data:`STRIDE`-th of the global ladder, and both ends)."""
    rungs = [(int(F), True)]
    rungs += [(g, k % STRIDE == 0) for k, g in enumerate(_global_ladder(top)) if F < g < top]
    if top > F:
        rungs.append((int(top), True))
    return rungs


def _first_on_ladder(ladder: list[tuple[int, bool]], passes) -> int | None:
    """The first rung of ``ladder`` for which ``passes`` holds, trying the coarse rungs and then the
    rungs between the last failing and the first passing one: a bottom-up scan's answer whenever
    ``passes`` is monotone, and for any ``passes`` never a lower rung for a stricter predicate (one that
    passes only where ``passes`` does) — what makes the rule monotone in ε."""
    previous = -1
    for k, (order, coarse) in enumerate(ladder):
        if not coarse:
            continue
        if passes(order):
            for j in range(previous + 1, k):
                if passes(ladder[j][0]):
                    return ladder[j][0]
            return order
        previous = k
    return None


@dataclass(frozen=True)
class PixelCheck:
    """The pixel rule's result.

    Attributes
    ----------
    F
        The order chosen (>= the energy rule's F_B).
    F_reference
        The reference order the errors were measured against.
    median, p90
        Median and 90th percentile of the per-direction relative error at ``F`` (luminance).
    tolerance
        √ε, the bound on ``p90``.
    capped
        True when no order below the reference meets the tolerance: F is then the reference's
        order, the largest the lighting and coefficients hold, and its error cannot be measured
        (``median``, ``p90`` NaN).
    samples
        Directions × views counted (those not dark).
    evaluations
        Fields synthesized (the cost).
    """

    F: int
    F_reference: int
    median: float
    p90: float
    tolerance: float
    capped: bool
    samples: int
    evaluations: int

    def to_dict(self) -> dict:
        """JSON-ready; an error that could not be measured (no higher reference order) is None."""
        known = lambda x: None if not np.isfinite(x) else float(x)  # noqa: E731
        return {"F": self.F, "F_reference": self.F_reference, "median": known(self.median), "p90": known(self.p90),
                "quantile": QUANTILE, "tolerance": self.tolerance, "capped": self.capped, "samples": self.samples,
                "rows": ROWS}


class _Fields:
    """Luminance of the reflected field on the sample, per order (and window), computed once."""

    def __init__(self, lighting: LightingCoefficients, coefficients: BRDFCoefficients, P: int,
                 q_max: int | None, nthreads: int) -> None:
        self.lighting, self.coefficients, self.P, self.q_max, self.nthreads = lighting, coefficients, P, q_max, nthreads
        self.luma = luminance_weights()
        self.cache: dict[tuple[int, bytes | None], np.ndarray] = {}
        self.count = 0

    def __call__(self, F: int, sigma: np.ndarray | None = None) -> np.ndarray:
        key = (int(F), None if sigma is None else np.asarray(sigma, dtype=np.float64).tobytes())
        if key not in self.cache:
            self.count += 1
            self.cache[key] = local_view_field(
                self.lighting, windowed(self.coefficients, sigma, F, self.P), F, self.P, ROWS, q_max=self.q_max,
                nthreads=self.nthreads, channel_weights=self.luma)[0]
        return self.cache[key]


def pixel_sampler(lighting: LightingCoefficients, coefficients: BRDFCoefficients, P: int, *,
                  q_max: int | None = None, nthreads: int = 1) -> _Fields:
    """The sample's luminance per order, ``sampler(F, sigma=None)`` (:data:`ROWS` rows; computed once
    per order and window), to share between :func:`pixel_orders` and :func:`pixel_statement`."""
    return _Fields(lighting, coefficients, P, q_max, nthreads)


def pixel_errors(value: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """|value − reference| / reference over the directions whose reference is not dark
    (>= :data:`DARK` × the largest): the per-direction relative errors, 1-D."""
    ref = np.asarray(reference, dtype=np.float64)
    keep = ref > DARK * max(float(ref.max(initial=0.0)), 1e-300)
    return np.abs(np.asarray(value, dtype=np.float64)[keep] - ref[keep]) / ref[keep]


def _stats(errors: np.ndarray) -> tuple[float, float]:
    if errors.size == 0:
        return 0.0, 0.0
    return float(np.median(errors)), float(np.quantile(errors, QUANTILE))


def pixel_orders(
    lighting: LightingCoefficients, coefficients: BRDFCoefficients, F: int, P: int, eps: float, *, top: int,
    q_max: int | None = None, nthreads: int = 1, fields: _Fields | None = None,
) -> PixelCheck:
    """The smallest order >= ``F`` of the ladder (F, F + ⌈F/8⌉, …, ``top``) whose per-direction
    relative error has its :data:`QUANTILE` at most √``eps`` (module docs).

    Parameters
    ----------
    lighting, coefficients
        L_lm (to at least ``top``) and the ρ̂_lpq the map is made of (for P, l <= ``top``).
    F, P
        The energy rule's F_B and P_B.
    eps
        The tolerance ε in (0, 1).
    top
        The largest order the lighting and coefficients hold.
    q_max
        0 for the azimuth-free SHRM.
    fields
        A :func:`pixel_sampler` of the same lighting and coefficients to share its fields with
        :func:`pixel_statement`.
    """
    fields = fields or pixel_sampler(lighting, coefficients, P, q_max=q_max, nthreads=nthreads)
    tolerance = float(np.sqrt(eps))
    F, top = int(F), int(max(top, F))
    F_ref = _reference_order(F, top)
    for _ in range(MAX_REFERENCE_RAISES + 1):
        reference = fields(F_ref)
        def passes(f: int, reference: np.ndarray = reference) -> bool:
            return _stats(pixel_errors(fields(f), reference))[1] <= tolerance

        found = _first_on_ladder(_ladder(F, F_ref), passes)
        chosen = F_ref if found is None else found
        # the reference must stay well above the choice (its own error at the choice's scale)
        if _reference_holds(F_ref, chosen, top) or F_ref >= top:
            break
        F_ref = _reference_order(chosen, top)
    errors = pixel_errors(fields(chosen), reference)
    median, p90 = _stats(errors) if chosen < F_ref else (float("nan"), float("nan"))  # never "0" against itself
    return PixelCheck(F=int(chosen), F_reference=int(F_ref), median=median, p90=p90, tolerance=tolerance,
                      capped=bool(chosen >= F_ref > F), samples=int(errors.size), evaluations=fields.count)


def pixel_statement(
    lighting: LightingCoefficients, coefficients: BRDFCoefficients, F: int, P: int, sigma: np.ndarray | None,
    eps: float, *, top: int, q_max: int | None = None, nthreads: int = 1, fields: _Fields | None = None,
    F_reference: int | None = None,
) -> PixelCheck:
    """The per-direction errors of the map as made (order ``F``, window ``sigma``) against the
    reference order of :func:`pixel_orders` (``F_reference`` when given and high enough for F: the
    rule's own, already synthesized): what a user reads per pixel (module docs)."""
    fields = fields or pixel_sampler(lighting, coefficients, P, q_max=q_max, nthreads=nthreads)
    top = max(top, F)
    F_ref = F_reference if F_reference is not None and _reference_holds(F_reference, F, top) else \
        _reference_order(F, top)
    errors = pixel_errors(fields(F, sigma), fields(F_ref))
    # no higher order to measure against: unknown, not 0
    median, p90 = _stats(errors) if F_ref > F else (float("nan"), float("nan"))
    return PixelCheck(F=int(F), F_reference=int(F_ref), median=median, p90=p90, tolerance=float(np.sqrt(eps)),
                      capped=False, samples=int(errors.size), evaluations=fields.count)


def pixel_line(meta: dict) -> str:
    """One line for a terminal from an SHRM's ``meta`` (``pixel_errors``, ``pixel_rule``): the
    per-direction statement and what the pixel rule did."""
    stated = meta.get("pixel_errors") or {}
    if stated.get("p90") is None:
        text = "per pixel: not measured (no higher order than F to measure against)"
    else:
        # an estimate on a sample against a higher order, not a bound: brute force on a sphere measured
        # 0.75–1.07 × the estimated 90th percentile (sky, Grace, Venice; README)
        text = (f"per pixel: relative error median {stated['median']:.3g}, 90th percentile {stated['p90']:.3g} "
                f"(sqrt(eps) {stated['tolerance']:.3g}; estimated on {stated['samples']} sampled directions x views "
                f"against F {stated['F_reference']})")
    rule = meta.get("pixel_rule")
    if rule and rule["F"] > rule["F_from"]:
        text += f"; the pixel rule raised F_B {rule['F_from']} -> {rule['F']}"
    elif rule:
        text += "; the pixel rule's check passed at F_B"
    return text
