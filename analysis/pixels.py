"""The pixel rule: F_B raised until the reflected field is accurate per direction, not only on
average (issue 23: "a stated error holds where a user reads it").

The order rules ([RH02]'s energy rule and the per-view-band rule of :mod:`.view_bands`) bound an
*energy* fraction: the error of a map, weighted by where its reflection is bright. Under a high
dynamic range map (a cathedral's windows beside dark stone) the truncation error of the bright
parts spreads over the dark ones as ringing, and there the *relative* error of a pixel can be 100 %
while the energy error is 3 % (Grace + Phong s = 200 at the energy rule's F_B = 28: per-pixel
relative error median 0.17, 90th percentile 0.62 against brute force).

:func:`pixel_orders` takes the smallest F >= F_B on a fixed ladder whose per-direction relative error
of the reflected luminance has its 90th percentile (:data:`QUANTILE`) at most √ε, over a sample of
reflection directions (:func:`pixel_sampler`) against a higher reference order; :func:`pixel_statement`
states that error for the map as made (an estimate, not a bound), :func:`pixel_line` says it in one
line, and :func:`region_bounds` reads the per-band statement over a region of reflection directions.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..brdf_io.exr import luminance_weights
from ..brdf_io.latlong import pixel_directions, row_solid_angles
from .brdf_coeffs import BRDFCoefficients
from .lighting import LightingCoefficients
from .records import PrefilterInfo
from .synthesis import local_view_field, windowed

__all__ = [
    "QUANTILE", "ROWS", "PixelCheck", "pixel_errors", "pixel_line", "pixel_orders", "pixel_sampler", "pixel_statement",
    "REGION_SEED", "region_bounds",
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
    relative error has its :data:`QUANTILE` at most √``eps``.

    With tolerance ε the relative RMS the tolerance stands for is √ε; the pixel rule takes the
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
    rule's own, already synthesized): what a user reads per pixel (the sample: :func:`pixel_orders`).

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
    fields = fields or pixel_sampler(lighting, coefficients, P, q_max=q_max, nthreads=nthreads)
    top = max(top, F)
    F_ref = F_reference if F_reference is not None and _reference_holds(F_reference, F, top) else \
        _reference_order(F, top)
    errors = pixel_errors(fields(F, sigma), fields(F_ref))
    # no higher order to measure against: unknown, not 0
    median, p90 = _stats(errors) if F_ref > F else (float("nan"), float("nan"))
    return PixelCheck(F=int(F), F_reference=int(F_ref), median=median, p90=p90, tolerance=float(np.sqrt(eps)),
                      capped=False, samples=int(errors.size), evaluations=fields.count)


def pixel_line(info: PrefilterInfo | Mapping[str, Any]) -> str:
    """One line for a terminal from an SHRM's ``info`` (or its ``meta``; ``pixel_errors``,
    ``pixel_rule``): the per-direction statement and what the pixel rule did."""
    info = PrefilterInfo.of(info)
    stated = info.pixel_errors or {}
    if stated.get("p90") is None:
        text = "per pixel: not measured (no higher order than F to measure against)"
    else:
        # an estimate on a sample against a higher order, not a bound: brute force on a sphere measured
        # 0.75–1.07 × the estimated 90th percentile (sky, Grace, Venice; README)
        text = (f"per pixel: relative error median {stated['median']:.3g}, 90th percentile {stated['p90']:.3g} "
                f"(sqrt(eps) {stated['tolerance']:.3g}; estimated on {stated['samples']} sampled directions x views "
                f"against F {stated['F_reference']})")
    rule = info.pixel_rule
    if rule and rule["F"] > rule["F_from"]:
        text += f"; the pixel rule raised F_B {rule['F_from']} -> {rule['F']}"
    elif rule:
        text += "; the pixel rule's check passed at F_B"
    return text


# ----------------------------------------------------------------------------------------
# Per-region statements: the band bound read over a region of reflection directions
# ----------------------------------------------------------------------------------------

#: Seed of :func:`region_bounds`' view draws.
REGION_SEED = 0


def _pairs_at(R: np.ndarray, theta_v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """V at angle 2θ_v from each unit R, uniform azimuth (the statements' law, ``analysis.pairs``)."""
    helper = np.where(np.abs(R[:, 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    t = np.cross(R, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(R, t)
    psi = rng.random(R.shape[0]) * 2.0 * np.pi
    two = 2.0 * theta_v[:, None]
    V = np.cos(two) * R + np.sin(two) * (np.cos(psi)[:, None] * t + np.sin(psi)[:, None] * b)
    return V / np.linalg.norm(V, axis=1, keepdims=True)


def _band_energies(shrm, region: np.ndarray, edges_rad: np.ndarray, rng: np.random.Generator
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Per band: E_b|B_part|² over the sphere and E_b[|B_part|² 1_D] (channel-mean squares), by
    quadrature over R at the mask's pixel centres (exact solid angles) with one (θ_v, ψ) per pixel and
    band, θ_v stratified over the pixels (uniform in the band), ψ uniform."""
    h, w = region.shape
    R = pixel_directions(h, w).reshape(-1, 3)
    omega = np.broadcast_to(row_solid_angles(h, w)[:, None], (h, w)).ravel() / (4.0 * np.pi)
    inside = region.ravel()
    whole, part = np.zeros(edges_rad.size - 1), np.zeros(edges_rad.size - 1)
    chunk = 1 << 14
    for k, (lo, hi) in enumerate(zip(edges_rad[:-1], edges_rad[1:], strict=True)):
        theta_v = lo + (hi - lo) * (rng.permutation(R.shape[0]) + rng.random(R.shape[0])) / R.shape[0]
        V = _pairs_at(R, theta_v, rng)
        sq = np.empty(R.shape[0])
        for s in range(0, R.shape[0], chunk):
            value = shrm.radiance(R[s:s + chunk], V[s:s + chunk], lights=False)
            sq[s:s + chunk] = np.mean(value * value, axis=1)
        whole[k] = float(np.sum(omega * sq))
        part[k] = float(np.sum((omega * sq)[inside]))
    return whole, part


def region_bounds(shrm, region: np.ndarray, *, seed: int = REGION_SEED) -> list[dict]:
    """The per-band statement read over a **region of reflection directions** (a dark part of the map,
    any part a user reads): a bound on the region's relative RMS that holds wherever the band's bound
    holds (issue 23: "statements that hold where they are read").

    It reads an SHRM's per-band statement over a region of reflection directions (a dark part of
    the map, where the band bound, an energy average, is exceeded 1.3–35× in
    20 of the matrix's 32 dark cells): a bound guaranteed wherever the band's bound holds, and a tighter
    reading with the error spread evenly over R that brute force did not exceed in any band of those
    cells (``data_specs/lights.md``).

    The quantity bounded, per view band b (the law of ``data_specs/view_bands.md``: R uniform, θ_v
    uniform in the band, view azimuth uniform), is the region's relative RMS against the exact
    reflection B_ref of the whole map (lights included)

        r_D² = E_b[|B − B_ref|² 1_D(R)] / E_b[|B_ref|² 1_D(R)],

    what ``benchmarks/lights_matrix.py`` measures per region. The band's own statement bounds the
    whole sphere's error energy: E_b|B_part − B_res|² ≤ X_res² with X_res = c_b · RMS_b(B_res) (c_b
    the band's ``bound_rel_rms_residual``, or ``bound_rel_rms`` without lights; B_res the exact
    reflection of the map the SHRM holds) and the merged lights' error X_L = 1.5 ·
    ``lights_rel_rms_residual`` · RMS_b(B_res). The region holds at most all of it (E[·1_D] ≤ E[·]),
    and RMS_b(B_res) ≤ RMS_b(B_part) + X_res (Minkowski), so

        X = (c_b + 1.5 ℓ_b) · RMS_b(B_part) / (1 − c_b − 1.5 ℓ_b)        (∞ when c_b + 1.5 ℓ_b ≥ 1).

    The lights' exact reflection only adds non-negative radiance, so |B_ref| ≥ |B_res,ref| ≥ |B_part|
    − |error| and, by Minkowski over the region, √E_b[|B_ref|² 1_D] ≥ S_D − X with S_D² =
    E_b[|B_part|² 1_D]. Hence

        r_D ≤ X / (S_D − X)        (``bound_rel_rms``; ∞, "nothing known", when X ≥ S_D).

    No assumption beyond the band's bound (which ``benchmarks/lights_matrix.py`` checks over all
    directions) and two means of the SHRM part alone (no brute force), RMS_b(B_part) and S_D: a
    quadrature over R at the mask's pixel centres (exact solid angles), one view per pixel and band
    (θ_v stratified over the pixels, azimuth uniform; seeded) — 9 · h · w evaluations of
    ``SHRM.radiance`` (0.1–0.5 s CPU for a 128 × 256 mask). Independent (θ_v, ψ) draws move the
    stated bounds by a few per cent under the matrix's maps (one pixel's view is one draw; the R
    quadrature, where a map's sharp reflections would make a Monte Carlo jump, is deterministic). It is
    loose where the region holds little of the band's reflected energy: the factor over the band's
    bound is ≈ 1/√(``signal_share``), the price of putting all of the band's error in the region.

    Beside it, two readings that assume the band's error **spread evenly over R** (the error image's
    model, ``analysis.error_image``), so that the region holds its solid-angle ``share`` of it:
    ``spread_bound_rel_rms`` = X_s / (S_D − X_s), X_s = √share · X, and ``predicted_rel_rms`` =
    √share · e_b / S_D with e_b = √(predicted² + ℓ_b²) · RMS_b(B_part). Not guaranteed — ringing or a
    horizon can gather more than the region's share of the error — but measured: over issue 23's matrix
    (``benchmarks/lights_matrix.py``: the dark fifth of sky, venice_sunset, Grace and three lamps at 128
    rows × 8 BRDFs) brute force stayed within ``spread_bound_rel_rms`` + 2 s.e. in every band, where
    the bound is informative (< 1) in the most cells; the guaranteed ``bound_rel_rms`` is ≈ 1/√share
    (2.2× for a fifth of the sphere) above it, ∞ where the region is nearly black.

    Parameters
    ----------
    shrm
        An :class:`~shrmkit.analysis.shrm.SHRM` with ``meta["view_bands"]`` (``prefilter``, ``load_shrm``).
    region
        (h, w) bool lat-long mask of the reflection directions, any resolution, in the SHRM's frame
        (z-up, pixel centres θ = (i + ½)π/h, φ = 2π(j + ½)/w; the environment map's own frame).
    seed
        Seed of the view draws.

    Returns
    -------
    list of dict, one per band of ``meta["view_bands"]``: ``theta_v_deg``, ``inside``, ``share`` (the
    region's solid-angle fraction), ``signal_share`` (S_D² / E_b|B_part|²), ``bound_rel_rms`` (guaranteed
    wherever the band's bound holds; ∞ when nothing is known), ``spread_bound_rel_rms`` (measured to
    hold), ``predicted_rel_rms``.

    Raises
    ------
    ValueError
        An SHRM without per-band statements, or a mask that is not 2-D.

    Examples
    --------
    >>> m = prefilter("builtin:sky,height=64", "phong:s=32")                      # doctest: +SKIP
    >>> ground = pixel_directions(64, 128)[..., 2] < -0.2                           # doctest: +SKIP
    >>> [round(b["bound_rel_rms"], 3) for b in region_bounds(m, ground)][:2]        # doctest: +SKIP
    """
    bands = (getattr(shrm, "meta", None) or {}).get("view_bands")
    if not bands:
        raise ValueError("this SHRM states no per-band errors (meta['view_bands']): prefilter it with shrmkit")
    region = np.asarray(region, dtype=bool)
    if region.ndim != 2:
        raise ValueError(f"region must be an (h, w) lat-long mask, got shape {region.shape}")
    h, w = region.shape
    share = float(np.sum(np.where(region, row_solid_angles(h, w)[:, None], 0.0)) / (4.0 * np.pi))
    edges = np.radians([b["theta_v_deg"][0] for b in bands] + [bands[-1]["theta_v_deg"][1]])
    whole_hi, inside_lo = _band_energies(shrm, region, edges, np.random.default_rng(seed))
    has_lights = bool(getattr(shrm, "has_lights", False))
    out = []
    for k, band in enumerate(bands):
        key = "rel_rms_residual" if has_lights else "rel_rms"
        c = float(band.get(f"bound_{key}", band["bound_rel_rms"]))
        p = float(band.get(f"predicted_{key}", band["predicted_rel_rms"]))
        light = float(band.get("lights_rel_rms_residual", 0.0)) if has_lights else 0.0
        total = c + 1.5 * light
        rms = float(np.sqrt(whole_hi[k]))
        S_D = float(np.sqrt(inside_lo[k]))
        X = total * rms / (1.0 - total) if total < 1.0 else float("inf")
        bound = X / (S_D - X) if S_D > X else float("inf")
        X_spread = np.sqrt(share) * X  # the band's bound error spread evenly over R
        spread = X_spread / (S_D - X_spread) if S_D > X_spread else float("inf")
        e_pred = float(np.hypot(p, light)) * rms
        predicted = np.sqrt(share) * e_pred / S_D if S_D > 0.0 else float("inf")
        out.append({"theta_v_deg": list(band["theta_v_deg"]), "inside": bool(band.get("inside", True)),
                    "share": share, "signal_share": float(inside_lo[k] / whole_hi[k]) if whole_hi[k] > 0 else 0.0,
                    "bound_rel_rms": float(bound), "spread_bound_rel_rms": float(spread),
                    "predicted_rel_rms": float(predicted)})
    return out
