"""Per-pixel error of an SHRM: the predicted relative error at each (R, V), from its per-band statements.

An SHRM states its error per band of the view angle θ_v = angle(N, V) (``SHRM.meta["view_bands"]``,
``data_specs/view_bands.md``) as a relative RMS over reflection directions R uniform on the sphere.
A render is read per pixel, where the local radiance can be far below that average (dark regions)
or far above it (near a light). :func:`predicted_error` turns the statements into a relative error
at each (R, V) pair — what ``shrm render --error-image`` writes per pixel: the band's absolute error
e(θ_v) = rel_b · RMS_b(B_part) (:func:`band_errors`, :func:`band_signal`) over the pixel's radiance,
capped at :data:`ERROR_CAP`; or, with ``bound=True``, a per-pixel reading of the bound that at most
a share :data:`BOUND_LEVEL` of a band's pairs exceed (Chebyshev). The model, its assumptions and
how it compares with brute force: :func:`predicted_error`.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from .pairs import sample_pairs_focused
from .records import PrefilterInfo, ViewBand

__all__ = [
    "ERROR_CAP",
    "BOUND_LEVEL",
    "SIGNAL_PAIRS_PER_BAND",
    "SIGNAL_SEED",
    "BandSignal",
    "band_signal",
    "band_errors",
    "view_angle",
    "channel_norm",
    "predicted_error",
    "stated_view_bands",
]

#: Largest relative error reported: where the radiance is ~0 any absolute error is "everything".
ERROR_CAP = 10.0
#: Share of a band's (R, V) pairs allowed above the bound version (Chebyshev).
BOUND_LEVEL = 0.1
#: Monte Carlo pairs per view band for the SHRM part's RMS (:func:`band_signal`).
SIGNAL_PAIRS_PER_BAND = 2048
#: Seed of those pairs.
SIGNAL_SEED = 0
#: Radiance norms below this are treated as zero (the relative error is the cap).
_TINY = 1e-30
#: Rows evaluated at once (the SHRM's bilinear lookup holds (rows, (P+1)², 3) float64).
_CHUNK = 1 << 14

_CACHE: weakref.WeakKeyDictionary[Any, BandSignal] = weakref.WeakKeyDictionary()


@dataclass(frozen=True, eq=False)
class BandSignal:
    """The RMS of an SHRM's own reflection per view band (:func:`band_signal`).

    Attributes
    ----------
    edges_deg
        (n_bands + 1,) band edges in θ_v, degrees (from ``SHRM.meta["view_bands"]``).
    rms
        (n_bands,) RMS over the band's pairs of ``SHRM.radiance(R, V, lights=False)``, channel-RMS norm.
    pairs_per_band, seed
        The Monte Carlo sample (``analysis.pairs.sample_pairs_focused`` without centres: R uniform
        on the sphere, θ_v uniform in the band, the view azimuth uniform).
    """

    edges_deg: np.ndarray
    rms: np.ndarray
    pairs_per_band: int
    seed: int

    @property
    def centres_deg(self) -> np.ndarray:
        """(n_bands,) band centres in θ_v, degrees: where :func:`predicted_error` takes each band's e_b."""
        return 0.5 * (self.edges_deg[:-1] + self.edges_deg[1:])


def stated_view_bands(shrm: Any) -> tuple[ViewBand, ...]:
    """The SHRM's statements per view band (:class:`~shrmkit.analysis.records.ViewBand`): its ``info``,
    or read from its ``meta`` (an object that holds only the serialized form, as an SHRM-like stand-in
    may).

    Raises
    ------
    ValueError
        Neither states per-band errors.
    """
    bands = PrefilterInfo.of(shrm).view_bands
    if not bands:
        raise ValueError("this SHRM states no per-band errors (meta['view_bands']): prefilter it with shrmkit")
    return bands


def _edges(bands: tuple[ViewBand, ...]) -> np.ndarray:
    edges = [band.theta_v_deg or (np.nan, np.nan) for band in bands]
    return np.array([lo for lo, _ in edges] + [edges[-1][1]], dtype=np.float64)


def _statement(band: ViewBand, kind: str, residual: bool) -> float | None:
    """A band's ``predicted``/``bound`` relative RMS: of the residual beside the lights when
    ``residual`` and the band states one, else the whole."""
    whole = band.predicted_rel_rms if kind == "predicted" else band.bound_rel_rms
    if not residual:
        return whole
    part = band.predicted_rel_rms_residual if kind == "predicted" else band.bound_rel_rms_residual
    return whole if part is None else part


def channel_norm(rgb: np.ndarray) -> np.ndarray:
    """|x| = sqrt(mean over channels of x²) per row of an (n, 3) array: (n,)."""
    rgb = np.asarray(rgb, dtype=np.float64)
    return np.sqrt(np.mean(rgb * rgb, axis=-1))


def view_angle(R: np.ndarray, V: np.ndarray) -> np.ndarray:
    """θ_v = angle(N, V) in degrees, N = normalize(R + V), for unit (n, 3) R and V: (n,).

    From cos 2θ_v = R·V (R is V mirrored about N): cos θ_v = sqrt((1 + R·V)/2), defined at the
    grazing limit R = −V too (θ_v = 90°).
    """
    c = np.sum(np.asarray(R, dtype=np.float64) * np.asarray(V, dtype=np.float64), axis=-1)
    return np.degrees(np.arccos(np.sqrt(np.clip(0.5 * (1.0 + c), 0.0, 1.0))))


def _radiance(shrm: Any, R: np.ndarray, V: np.ndarray, lights: bool) -> np.ndarray:
    out = np.empty((R.shape[0], 3))
    for s in range(0, R.shape[0], _CHUNK):
        out[s:s + _CHUNK] = shrm.radiance(R[s:s + _CHUNK], V[s:s + _CHUNK], lights=lights)
    return out


def band_signal(shrm: Any, *, pairs_per_band: int = SIGNAL_PAIRS_PER_BAND, seed: int = SIGNAL_SEED) -> BandSignal:
    """RMS_b of the SHRM part's reflection in each view band, by a seeded Monte Carlo.

    Parameters
    ----------
    shrm
        An :class:`~shrmkit.analysis.shrm.SHRM` with ``meta["view_bands"]``.
    pairs_per_band, seed
        The sample: ``pairs_per_band`` pairs per band of :func:`~.pairs.sample_pairs_focused` (no
        centres: R uniform, θ_v uniform in the band, azimuth uniform) — the distribution the
        statements average over. 2048 pairs put the RMS within a few per cent for smooth maps.

    Returns
    -------
    BandSignal
        Cached on the SHRM object for the default sample (computed once per object).

    Raises
    ------
    ValueError
        An SHRM without per-band statements, or ``pairs_per_band`` < 1.
    """
    default = (pairs_per_band, seed) == (SIGNAL_PAIRS_PER_BAND, SIGNAL_SEED)
    if default and shrm in _CACHE:
        return _CACHE[shrm]
    if pairs_per_band < 1:
        raise ValueError(f"pairs_per_band must be >= 1, got {pairs_per_band}")
    edges = _edges(stated_view_bands(shrm))
    R, V, theta_v, _ = sample_pairs_focused(int(pairs_per_band), edges, seed=int(seed))
    norm = channel_norm(_radiance(shrm, R, V, lights=False))
    band = np.repeat(np.arange(edges.size - 1), int(pairs_per_band))  # the sampler's order: band by band
    rms = np.sqrt(np.bincount(band, weights=norm * norm, minlength=edges.size - 1) / int(pairs_per_band))
    signal = BandSignal(edges, rms, int(pairs_per_band), int(seed))
    if default:
        _CACHE[shrm] = signal
    return signal


def band_errors(
    shrm: Any, *, bound: bool = False, level: float = BOUND_LEVEL, signal: BandSignal | None = None
) -> np.ndarray:
    """e_b, the absolute error per view band: rel_b · RMS_b(B_part) (:func:`predicted_error`, Notes), (n_bands,).

    rel_b is the band's residual statement with explicit lights, the whole one without;
    ``bound=True`` takes the ``bound_*`` statement divided by √``level``. A band whose statement
    is missing or not finite gets ``inf`` (the pixels there get the cap).
    """
    bands = stated_view_bands(shrm)
    if bound and not 0.0 < level <= 1.0:
        raise ValueError(f"level must be in (0, 1], got {level}")
    signal = band_signal(shrm) if signal is None else signal
    if signal.rms.size != len(bands):
        raise ValueError(f"signal has {signal.rms.size} bands, the SHRM states {len(bands)}")
    kind = "bound" if bound else "predicted"
    has_lights = bool(getattr(shrm, "has_lights", False))
    rel = np.array([_statement(b, kind, has_lights) for b in bands], dtype=np.float64)
    light = np.array([(b.lights_rel_rms_residual or 0.0) if has_lights else 0.0 for b in bands], dtype=np.float64)
    rel = np.where(np.isfinite(rel), rel + 1.5 * light if bound else np.hypot(rel, light), np.inf)  # merged lights
    e = rel * signal.rms
    if bound:
        e = e / np.sqrt(level)
    return np.where(np.isnan(e), np.inf, e)


def predicted_error(
    shrm: Any,
    R: np.ndarray,
    V: np.ndarray,
    *,
    bound: bool = False,
    level: float = BOUND_LEVEL,
    cap: float = ERROR_CAP,
    signal: BandSignal | None = None,
    radiance: np.ndarray | None = None,
) -> np.ndarray:
    """Predicted relative error of ``shrm.radiance`` at each (R, V) pair, from the per-band statements.

    Parameters
    ----------
    shrm
        An :class:`~shrmkit.analysis.shrm.SHRM` (``prefilter``, ``load_shrm``).
    R, V
        Unit reflection and view directions (n, 3), z-up frame (as ``SHRM.radiance``).
    bound
        False (default): the prediction, e(θ_v)/|B| with the ``predicted_*`` statements (the error's
        typical size: its band RMS). True: the bound version, ``bound_*`` statements divided by
        √``level`` (exceeded on at most a share ``level`` of a band's pairs if the band's bound holds).
    level
        The bound version's share, in (0, 1] (default :data:`BOUND_LEVEL`).
    cap
        Largest value returned (default :data:`ERROR_CAP`), where the radiance is ~0.
    signal
        The SHRM part's band RMS (:func:`band_signal`; default: measured once and cached).
    radiance
        B(R, V) (n, 3) when already computed (``shrm.radiance(R, V)``); computed here otherwise.

    Returns
    -------
    (n,) float64 relative errors in [0, cap]: the channel-RMS norm of the error over that of B
    (Notes).

    Raises
    ------
    ValueError
        An SHRM without per-band statements, mismatched shapes, ``level`` or ``cap`` out of range.

    Notes
    -----
    The statement of band b is an RMS relative to the reflection of the map the SHRM holds (the map
    without its explicit lights when it has some: ``*_residual``), so the SHRM part's **absolute**
    error in band b has the RMS

        e_b = rel_b · RMS_b(B_part),

    with rel_b the band's ``predicted_rel_rms_residual`` (or ``predicted_rel_rms`` without lights) and
    RMS_b(B_part) the RMS of the SHRM part ``SHRM.radiance(R, V, lights=False)`` over R uniform on the
    sphere, the view azimuth uniform and θ_v uniform in the band — the statement's own distribution —
    measured once per SHRM by a seeded Monte Carlo (:func:`band_signal`, cached per object). The
    explicit lights are shaded exactly and add no error. Between band centres e(θ_v) is interpolated
    linearly in θ_v (constant before the first and after the last centre). The predicted relative
    error at (R, V) is then

        err(R, V) = min( e(θ_v) / |B(R, V)|, cap ),

    with B the whole radiance (``SHRM.radiance(R, V)``: SHRM part + lights) and cap = :data:`ERROR_CAP`
    where the radiance is (nearly) zero.

    **Colour.** Every norm is the RMS over the three channels, |x| = sqrt((x_R² + x_G² + x_B²)/3): the
    statements pool the channels the same way, so err is the per-pixel analogue of the stated number.

    **Assumptions.** (1) Within a band the absolute error is spread evenly over R: a pixel gets the
    band's RMS, not its own error; where the error concentrates (a horizon, a sharp edge of the map,
    what ringing the window left) the pixel's error is larger than predicted, elsewhere smaller.
    Measured against brute force per pixel (``tests/analysis/test_error_image.py``: 48² spheres
    under ``builtin:sky`` and a one-pixel sun; ``benchmarks/error_image_figure.py``: the README's
    ``venice_sunset`` sphere): the measured/predicted ratio has a median of 0.5–0.85 and a 90th
    percentile of 1.4–2.0; the error concentrates beside the sky's horizon step (ratio up to 4) and is
    over-predicted toward the rim on ``venice_sunset`` (median 0.3 at θ_v > 75°). (2) The SHRM
    part's RMS stands for the RMS of the exact reflection of the map it holds (they differ by the
    stated error). (3) The statements hold (a band with missing measured data, ``bound_holds`` false,
    only predicts).

    **Bound version** (``bound=True``). e_b from ``bound_rel_rms[_residual]``, divided by √level: if
    the band's bound holds, Chebyshev's inequality (Markov's on the squared error) lets at most a share
    ``level`` (default :data:`BOUND_LEVEL` = 10 %) of the band's (R, V) pairs exceed it. An RMS bound
    alone is no per-pixel bound: the RMS itself is exceeded on roughly a third of the pixels.

    Examples
    --------
    >>> import numpy as np, shrmkit                                          # doctest: +SKIP
    >>> m = shrmkit.prefilter("builtin:sky,height=32", "phong:s=32")        # doctest: +SKIP
    >>> R = V = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])                # doctest: +SKIP
    >>> predicted_error(m, R, V)          # zenith sky, horizon: ~0.02, ~0.2  # doctest: +SKIP
    """
    if not cap > 0.0:
        raise ValueError(f"cap must be positive, got {cap}")
    R = np.atleast_2d(np.asarray(R, dtype=np.float64))
    V = np.atleast_2d(np.asarray(V, dtype=np.float64))
    if R.ndim != 2 or R.shape[1] != 3 or R.shape != V.shape:
        raise ValueError(f"R and V must both have shape (n, 3), got {R.shape} and {V.shape}")
    signal = band_signal(shrm) if signal is None else signal
    e_b = band_errors(shrm, bound=bound, level=level, signal=signal)
    B = _radiance(shrm, R, V, lights=True) if radiance is None else np.asarray(radiance, dtype=np.float64)
    if B.shape != R.shape:
        raise ValueError(f"radiance must have shape {R.shape}, got {B.shape}")
    theta = view_angle(R, V)
    with np.errstate(invalid="ignore"):  # inf - inf between two unstated bands: NaN, set to the cap below
        e = np.interp(theta, signal.centres_deg, e_b)
    norm = channel_norm(B)
    out = np.full(R.shape[0], float(cap))
    ok = (norm > _TINY) & np.isfinite(e)
    out[ok] = np.minimum(e[ok] / norm[ok], cap)
    return out
